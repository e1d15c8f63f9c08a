//! Adaptive tile planning: kd-splits of the coarse occupancy histogram so that
//! every tile holds at most a target number of points. Core boxes are integer
//! boxes of histogram cells, so they partition space exactly.

/// One occupied histogram cell and its point count.
pub type CellCount = ([u32; 3], u64);

/// A planned tile: half-open cell box `[lo, hi)` and its point count.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedTile {
    /// Lower corner of the core box, in grid cells.
    pub lo: [u32; 3],
    /// Upper corner (exclusive) of the core box, in grid cells.
    pub hi: [u32; 3],
    /// Points in the tile.
    pub count: u64,
}

/// The kd-tree of splits, used to send a cell to its tile.
#[derive(Clone, Debug)]
pub struct TilePlan {
    /// The tiles, in store order.
    pub tiles: Vec<PlannedTile>,
    nodes: Vec<Node>,
}

#[derive(Clone, Copy, Debug)]
enum Node {
    Leaf(u32),
    Split {
        axis: u8,
        at: u32,
        left: u32,
        right: u32,
    },
}

impl TilePlan {
    /// Tile of the cell `c` (cells outside the grid go to the nearest tile).
    pub fn tile_of(&self, c: [u32; 3]) -> u32 {
        let mut n = 0usize;
        loop {
            match self.nodes[n] {
                Node::Leaf(t) => return t,
                Node::Split {
                    axis,
                    at,
                    left,
                    right,
                } => n = if c[axis as usize] < at { left } else { right } as usize,
            }
        }
    }
}

/// Splits the grid `[0, dims)` until each tile holds at most `target` points
/// (a single cell is never split, so a cell denser than `target` makes an
/// oversized tile). Tiles come out in depth-first order, left before right.
/// `cells` may come in any order: every choice depends on the set only.
pub fn plan_tiles(mut cells: Vec<CellCount>, dims: [u32; 3], target: u64) -> TilePlan {
    let mut plan = TilePlan {
        tiles: Vec::new(),
        nodes: Vec::new(),
    };
    split(&mut plan, &mut cells, [0; 3], dims, target.max(1));
    plan
}

fn split(
    plan: &mut TilePlan,
    cells: &mut [CellCount],
    lo: [u32; 3],
    hi: [u32; 3],
    target: u64,
) -> u32 {
    let id = plan.nodes.len() as u32;
    let total: u64 = cells.iter().map(|c| c.1).sum();
    let choice = if total > target {
        choose_split(cells, lo, hi)
    } else {
        None
    };
    let Some((axis, at)) = choice else {
        plan.nodes.push(Node::Leaf(plan.tiles.len() as u32));
        plan.tiles.push(PlannedTile {
            lo,
            hi,
            count: total,
        });
        return id;
    };
    plan.nodes.push(Node::Leaf(0));
    let a = axis as usize;
    let mid = partition(cells, a, at);
    let (left_cells, right_cells) = cells.split_at_mut(mid);
    let (mut lhi, mut rlo) = (hi, lo);
    lhi[a] = at;
    rlo[a] = at;
    let left = split(plan, left_cells, lo, lhi, target);
    let right = split(plan, right_cells, rlo, hi, target);
    plan.nodes[id as usize] = Node::Split {
        axis,
        at,
        left,
        right,
    };
    id
}

/// Moves the cells below `at` on axis `a` to the front; returns how many.
/// Linear, unlike the sort of all cells per split it replaces (on 10M
/// points, that sort and draining a hash map took 1.8 s before the scatter).
fn partition(cells: &mut [CellCount], a: usize, at: u32) -> usize {
    let mut mid = 0;
    for i in 0..cells.len() {
        if cells[i].0[a] < at {
            cells.swap(mid, i);
            mid += 1;
        }
    }
    mid
}

/// The most balanced split plane across the longest splittable axis, with
/// points on both sides; `None` when all points share one cell.
fn choose_split(cells: &[CellCount], lo: [u32; 3], hi: [u32; 3]) -> Option<(u8, u32)> {
    let mut axes = [0usize, 1, 2];
    axes.sort_by_key(|&a| std::cmp::Reverse(hi[a] - lo[a]));
    axes.into_iter()
        .find_map(|a| median_plane(cells, a, lo[a], hi[a]).map(|at| (a as u8, at)))
}

fn median_plane(cells: &[CellCount], a: usize, lo: u32, hi: u32) -> Option<u32> {
    if hi - lo < 2 {
        return None;
    }
    let mut slabs = vec![0u64; (hi - lo) as usize];
    for c in cells {
        slabs[(c.0[a] - lo) as usize] += c.1;
    }
    let total: u64 = slabs.iter().sum();
    let mut best: Option<(u64, u32)> = None;
    let mut left = 0u64;
    for (i, s) in slabs.iter().enumerate().take(slabs.len() - 1) {
        left += s;
        if left == 0 || left == total {
            continue;
        }
        let imbalance = left.abs_diff(total - left);
        if best.is_none_or(|(b, _)| imbalance < b) {
            best = Some((imbalance, lo + i as u32 + 1));
        }
    }
    best.map(|(_, at)| at)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cells_line(n: u32) -> Vec<CellCount> {
        (0..n).map(|i| ([i, 0, 0], 10)).collect()
    }

    #[test]
    fn tiles_partition_and_respect_target() {
        let plan = plan_tiles(cells_line(100), [100, 1, 1], 95);
        let total: u64 = plan.tiles.iter().map(|t| t.count).sum();
        assert_eq!(total, 1000);
        assert!(plan.tiles.iter().all(|t| t.count <= 95));
        let mut covered = 0;
        for t in &plan.tiles {
            covered += (t.hi[0] - t.lo[0]) as u64;
        }
        assert_eq!(covered, 100);
        for i in 0..100 {
            let t = &plan.tiles[plan.tile_of([i, 0, 0]) as usize];
            assert!(t.lo[0] <= i && i < t.hi[0]);
        }
    }

    #[test]
    fn plan_does_not_depend_on_cell_order() {
        for seed in 0..6u64 {
            let mut rng = crate::rng::Rng::new(seed);
            let mut cells: Vec<CellCount> = (0..2000)
                .map(|_| ([0u32; 3].map(|_| rng.below(40) as u32), 1 + rng.below(9)))
                .collect();
            cells.sort_unstable();
            cells.dedup_by_key(|c| c.0);
            let sorted = plan_tiles(cells.clone(), [40; 3], 500);
            for i in (1..cells.len()).rev() {
                cells.swap(i, rng.below(i as u64 + 1) as usize);
            }
            let shuffled = plan_tiles(cells.clone(), [40; 3], 500);
            assert_eq!(sorted.tiles, shuffled.tiles, "seed {seed}");
            assert!(sorted.tiles.len() > 8, "seed {seed}");
            for (c, _) in &cells {
                let t = &sorted.tiles[sorted.tile_of(*c) as usize];
                assert!(
                    (0..3).all(|a| t.lo[a] <= c[a] && c[a] < t.hi[a]),
                    "seed {seed}"
                );
                assert_eq!(sorted.tile_of(*c), shuffled.tile_of(*c), "seed {seed}");
            }
        }
    }

    #[test]
    fn one_dense_cell_is_one_tile() {
        let plan = plan_tiles(vec![([3, 3, 3], 1000)], [8, 8, 8], 10);
        let nonempty: Vec<_> = plan.tiles.iter().filter(|t| t.count > 0).collect();
        assert_eq!(nonempty.len(), 1);
        assert_eq!(nonempty[0].count, 1000);
    }

    #[test]
    fn under_target_is_one_tile() {
        let plan = plan_tiles(cells_line(10), [10, 1, 1], 1000);
        assert_eq!(plan.tiles.len(), 1);
        assert_eq!(plan.tiles[0].hi, [10, 1, 1]);
    }
}
