//! Byte sizes for humans: parsing `256MiB`-style budgets (CLI `--mem`,
//! `peak-rss --budget`) and printing byte counts.

/// Why a size string was not understood.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum UnitError {
    /// The size string is empty.
    #[error("empty size")]
    Empty,
    /// The size string is not a number with an optional unit.
    #[error("size `{0}`: expected a number, optionally followed by B, KB, MB, GB, TB, KiB, MiB, GiB or TiB")]
    Malformed(
        /// The size as the user typed it (free text: kept as given).
        String,
    ),
    /// The unit (second field) of the size string (first field) is not one scanmesh knows.
    #[error("size `{0}`: unknown unit `{1}` (use B, KB, MB, GB, TB, KiB, MiB, GiB or TiB)")]
    UnknownUnit(
        /// The size as the user typed it (free text: kept as given).
        String,
        /// The unit as typed, which names none scanmesh knows (free text).
        String,
    ),
    /// The size does not fit in 64 bits of bytes.
    #[error("size `{0}` is too large (more than 2^64 - 1 bytes)")]
    Overflow(
        /// The size as the user typed it (free text: kept as given).
        String,
    ),
}

/// Bytes per unit; decimal units are powers of 1000, binary ones of 1024.
/// Units are case-insensitive (`mib`, `MB`, `k`); a bare `K`/`M`/`G`/`T`
/// means the binary unit, as in most memory flags.
fn unit_factor(unit: &str) -> Option<u64> {
    const K: u64 = 1000;
    const KI: u64 = 1024;
    Some(match unit.to_ascii_lowercase().as_str() {
        "" | "b" => 1,
        "kb" => K,
        "mb" => K * K,
        "gb" => K * K * K,
        "tb" => K * K * K * K,
        "k" | "kib" => KI,
        "m" | "mib" => KI * KI,
        "g" | "gib" => KI * KI * KI,
        "t" | "tib" => KI * KI * KI * KI,
        _ => return None,
    })
}

/// Parses `"1048576"`, `"256MiB"`, `"1.5 GiB"`, `"500MB"`, `"64k"` into
/// bytes. Fractions are allowed with a unit and rounded down to whole bytes.
pub fn parse_size(s: &str) -> Result<u64, UnitError> {
    let t = s.trim();
    if t.is_empty() {
        return Err(UnitError::Empty);
    }
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == '_'))
        .unwrap_or(t.len());
    let (number, unit) = (t[..split].replace('_', ""), t[split..].trim());
    if number.is_empty() || number == "." {
        return Err(UnitError::Malformed(s.to_string()));
    }
    let factor =
        unit_factor(unit).ok_or_else(|| UnitError::UnknownUnit(s.to_string(), unit.to_string()))?;
    if let Ok(whole) = number.parse::<u64>() {
        return whole
            .checked_mul(factor)
            .ok_or_else(|| UnitError::Overflow(s.to_string()));
    }
    let value: f64 = number
        .parse()
        .map_err(|_| UnitError::Malformed(s.to_string()))?;
    let bytes = value * factor as f64;
    // 2^64 is exactly representable; anything at or above it overflows u64.
    if !(bytes.is_finite() && bytes < 18_446_744_073_709_551_616.0) {
        return Err(UnitError::Overflow(s.to_string()));
    }
    Ok(bytes as u64)
}

/// `x` with three significant digits and a k/M/G suffix (a rate as a
/// progress bar shows it: `7.84M`, where `{x}` prints `7841517.0193`).
pub fn short_count(x: f64) -> String {
    let (v, unit) = match x.abs() {
        a if a >= 1e9 => (x / 1e9, "G"),
        a if a >= 1e6 => (x / 1e6, "M"),
        a if a >= 1e3 => (x / 1e3, "k"),
        _ => (x, ""),
    };
    let digits = if v.abs() >= 100.0 {
        0
    } else if v.abs() >= 10.0 {
        1
    } else {
        2
    };
    format!("{v:.digits$}{unit}")
}

/// `1536` -> `"1.50KiB"`, `512` -> `"512B"`: binary units, 3 significant
/// figures, no space (so it fits `key=value` reports; [`parse_size`] reads
/// it back).
pub fn human_bytes(bytes: u64) -> String {
    const UNITS: [&str; 6] = ["KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    if bytes < 1024 {
        return format!("{bytes}B");
    }
    let mut value = bytes as f64 / 1024.0;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    let decimals = if value < 10.0 {
        2
    } else if value < 100.0 {
        1
    } else {
        0
    };
    format!("{value:.decimals$}{}", UNITS[unit])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_read_short() {
        assert_eq!(short_count(7_841_517.019), "7.84M");
        assert_eq!(short_count(12_345.0), "12.3k");
        assert_eq!(short_count(999.0), "999");
        assert_eq!(short_count(0.5), "0.50");
        assert_eq!(short_count(2.5e9), "2.50G");
    }

    #[test]
    fn parses_plain_and_units() {
        let cases: [(&str, u64); 12] = [
            ("0", 0),
            ("1048576", 1 << 20),
            ("256MiB", 256 << 20),
            ("256 mib", 256 << 20),
            ("1.5GiB", 3 << 29),
            ("500MB", 500_000_000),
            ("2KB", 2000),
            ("2KiB", 2048),
            ("64k", 65536),
            ("3G", 3 << 30),
            ("1_000B", 1000),
            ("0.5KiB", 512),
        ];
        for (s, want) in cases {
            assert_eq!(parse_size(s), Ok(want), "{s}");
        }
    }

    #[test]
    fn rejects_bad_sizes() {
        assert_eq!(parse_size("  "), Err(UnitError::Empty));
        assert!(matches!(parse_size("MiB"), Err(UnitError::Malformed(_))));
        assert!(matches!(
            parse_size("1.2.3MB"),
            Err(UnitError::Malformed(_))
        ));
        assert!(matches!(parse_size("-5MB"), Err(UnitError::Malformed(_))));
        assert!(matches!(
            parse_size("12 furlongs"),
            Err(UnitError::UnknownUnit(..))
        ));
        assert!(matches!(
            parse_size("17000000000TiB"),
            Err(UnitError::Overflow(_))
        ));
        assert!(matches!(
            parse_size("99999999999999999999"),
            Err(UnitError::Malformed(_) | UnitError::Overflow(_))
        ));
        assert!(parse_size("1e30GB").is_err());
    }

    #[test]
    fn human_round_trips_roughly() {
        assert_eq!(human_bytes(0), "0B");
        assert_eq!(human_bytes(1023), "1023B");
        assert_eq!(human_bytes(1536), "1.50KiB");
        assert_eq!(human_bytes(200 << 20), "200MiB");
        assert_eq!(human_bytes(u64::MAX), "16.0EiB");
        for bytes in [1u64 << 10, 3 << 20, 123_456_789, 5 << 40] {
            let back = parse_size(&human_bytes(bytes)).unwrap_or(0);
            let err = (back as f64 - bytes as f64).abs() / bytes as f64;
            assert!(err < 0.01, "{bytes} -> {} -> {back}", human_bytes(bytes));
        }
    }
}
