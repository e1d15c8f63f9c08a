//! The grid's row table: occupied rows of cells (fixed y, z) by key
//! `y + ny * z`, each mapped to its range of cells.
//!
//! A dense array when the key space is small next to the point count (the
//! usual case: rows adjacent in y are adjacent in memory, so the 9 rows of a
//! 27-cell block touch three cache lines); an open-addressing hash otherwise
//! (sparse clouds in huge boxes). Only looked up, never iterated, so neither
//! layout can leak into results.

/// Dense tables are used while they need at most this many slots per point
/// (plus a constant), i.e. at most 8 bytes per point.
const DENSE_SLOTS_PER_POINT: u64 = 1;
const DENSE_SLOTS_EXTRA: u64 = 4096;
const EMPTY_ROW: u64 = u64::MAX;

pub(super) enum RowTable {
    /// `slots[key]` = (first cell, end cell); empty rows have first == end.
    Dense(Vec<(u32, u32)>),
    /// Linear probing over (key, first, end); `shift` maps the hash to a slot.
    Hashed {
        slots: Vec<(u64, u32, u32)>,
        shift: u32,
    },
}

impl Default for RowTable {
    fn default() -> Self {
        RowTable::Dense(Vec::new())
    }
}

impl RowTable {
    /// `rows` are (key, first cell, end cell), keys below `key_space`.
    pub(super) fn new(rows: &[(u64, u32, u32)], key_space: u64, points: usize) -> Self {
        let dense_limit = DENSE_SLOTS_PER_POINT * points as u64 + DENSE_SLOTS_EXTRA;
        if key_space <= dense_limit {
            let mut slots = vec![(0, 0); key_space as usize];
            for &(key, first, end) in rows {
                if let Some(slot) = slots.get_mut(key as usize) {
                    *slot = (first, end);
                }
            }
            return RowTable::Dense(slots);
        }
        let cap = (rows.len() * 2).next_power_of_two().max(2);
        let shift = 64 - cap.trailing_zeros();
        let mut slots = vec![(EMPTY_ROW, 0, 0); cap];
        for &row in rows {
            let mut i = home(row.0, shift);
            while slots[i].0 != EMPTY_ROW {
                i = (i + 1) & (cap - 1);
            }
            slots[i] = row;
        }
        RowTable::Hashed { slots, shift }
    }

    /// The (first, end) cell range of row `key`, if it holds any points.
    #[inline]
    pub(super) fn get(&self, key: u64) -> Option<(u32, u32)> {
        match self {
            RowTable::Dense(slots) => {
                let &(first, end) = slots.get(usize::try_from(key).ok()?)?;
                (first < end).then_some((first, end))
            }
            RowTable::Hashed { slots, shift } => {
                let mask = slots.len().checked_sub(1)?;
                let mut i = home(key, *shift);
                loop {
                    let (k, first, end) = *slots.get(i)?;
                    if k == key {
                        return Some((first, end));
                    }
                    if k == EMPTY_ROW {
                        return None;
                    }
                    i = (i + 1) & mask;
                }
            }
        }
    }
}

#[inline]
fn home(key: u64, shift: u32) -> usize {
    (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> shift) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dense_and_hashed_tables_agree() {
        let rows = [(3, 0, 2), (7, 2, 3), (1000, 3, 9)];
        let dense = RowTable::new(&rows, 1001, 10);
        let hashed = RowTable::new(&rows, u64::MAX / 2, 10);
        assert!(matches!(dense, RowTable::Dense(_)));
        assert!(matches!(hashed, RowTable::Hashed { .. }));
        for key in [0, 3, 4, 7, 999, 1000, 1001, u64::MAX / 4] {
            let want = rows.iter().find(|r| r.0 == key).map(|r| (r.1, r.2));
            assert_eq!(dense.get(key), want, "dense, key {key}");
            assert_eq!(hashed.get(key), want, "hashed, key {key}");
        }
    }
}
