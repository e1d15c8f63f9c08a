//! `run-job`'s tile sets as its flags spell them (`--emit`'s scripts write
//! them).

use scanmesh::store::TileSet;

/// `--tiles FIRST-LAST` (or one tile).
pub fn parse_range(s: &str) -> Result<TileSet, String> {
    let (a, b) = s.split_once('-').unwrap_or((s, s));
    let first = a.trim().parse().map_err(|e| format!("{s}: {e}"))?;
    let last = b.trim().parse().map_err(|e| format!("{s}: {e}"))?;
    if last < first {
        return Err(format!("{s}: the last tile comes before the first"));
    }
    Ok(TileSet::Range { first, last })
}

/// `--share INDEX/COUNT`.
pub fn parse_share(s: &str) -> Result<TileSet, String> {
    let (a, b) = s
        .split_once('/')
        .ok_or(format!("{s}: expected INDEX/COUNT"))?;
    let index: usize = a.trim().parse().map_err(|e| format!("{s}: {e}"))?;
    let count: usize = b.trim().parse().map_err(|e| format!("{s}: {e}"))?;
    if count == 0 || index >= count {
        return Err(format!("{s}: INDEX must be below COUNT"));
    }
    Ok(TileSet::Share { index, count })
}
