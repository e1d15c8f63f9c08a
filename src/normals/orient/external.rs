//! Orientation by the spanning tree when its per-point union-find does not
//! fit the memory budget: the same flips as [`super::orient_by_forest`], from
//! the labels [`ForestLabels`] leaves on disk.
//!
//! The sign vote and the island rule need, per component, its size, its
//! highest point and its highest voters. A component labelled by a store
//! index lies in one tile, so its facts are complete once that tile is read
//! and nothing about it is kept: the passes below recompute them per tile
//! and settle its sign there. Only node components (which may span tiles)
//! keep their facts in memory, one entry each, with their columns' voters while
//! the census gathers them (16 bytes each), settled to a sign after it. The
//! island rule (orient the component of the highest point, then the others
//! by size while at least 1/1000 of the points are left) needs only the
//! census of sizes, and, when the cut falls inside one size class, which
//! members of that class come first (by smallest top id).

use super::{rewrite_signs, tile_components, Columns, Component, Gathered, OrientStats, Sign};
use crate::normals::labels::ForestLabels;
use crate::normals::runs::EdgeRuns;
use crate::normals::NormalsError;
use crate::pipeline::Progress;
use crate::store::{PointStore, TileEntry};
use rayon::prelude::*;
use std::cmp::Reverse;
use std::collections::{BTreeMap, BinaryHeap};
use std::sync::Mutex;

/// Orients the store's normals by the merged tile forests in `runs`, with
/// memory that does not grow with the points.
pub fn orient_external(
    store: &PointStore,
    mut runs: EdgeRuns,
    columns: Columns,
    progress: &dyn Progress,
) -> Result<OrientStats, NormalsError> {
    let labels = ForestLabels::solve(store, &mut runs, &[], progress)?;
    drop(runs);
    let facts = TileFacts {
        store,
        labels: &labels,
        columns,
    };
    let (normals, flags) = (columns.normals, columns.flags);
    progress.begin("orient: components", store.len());
    let census = Census::take(&facts, progress)?;
    progress.end();
    let cut = census.cut(&facts)?;
    progress.begin("orient: write", store.len());
    let counts: Vec<u64> = store
        .tiles()
        .par_iter()
        .map(|t| {
            let local = facts.settled(t)?;
            let mut read = Vec::new();
            labels.read_tile(t, &mut read)?;
            let n = rewrite_signs(t, normals, flags, |i| {
                let (label, parity) = split(read[(i - t.start) as usize]);
                let c = match labels.node_component(label) {
                    Some(k) => census.spanning[k],
                    None => find(&local, label),
                };
                match cut.orients(label, &c) {
                    true => Sign::Reached(parity ^ c.sign),
                    false => Sign::Island(parity ^ c.sign),
                }
            });
            progress.advance(t.count);
            n
        })
        .collect::<Result<_, _>>()?;
    progress.end();
    Ok(OrientStats {
        components: census.components,
        unoriented: counts.iter().sum(),
    })
}

/// A stored label word: the label and the parity (bit 63).
fn split(word: u64) -> (u64, bool) {
    (word & !(1 << 63), word >> 63 == 1)
}

/// What the component facts of a tile are computed from.
struct TileFacts<'a> {
    store: &'a PointStore,
    labels: &'a ForestLabels,
    columns: Columns<'a>,
}

/// A tile's component facts: the node components' shares (to be merged
/// over tiles) and its own components' settled facts, each by label,
/// sorted.
type TileShare = (Vec<(u64, Gathered)>, Vec<(u64, Component)>);

impl TileFacts<'_> {
    /// Tile `t`'s component facts, split as [`TileShare`].
    fn of(&self, t: &TileEntry) -> Result<TileShare, NormalsError> {
        let mut read = Vec::new();
        self.labels.read_tile(t, &mut read)?;
        let mut part = tile_components(self.store, t, self.columns, |i| {
            split(read[(i - t.start) as usize])
        })?;
        part.sort_unstable_by_key(|p| p.0);
        let (nodes, own): (Vec<_>, Vec<_>) = part
            .into_iter()
            .partition(|(label, _)| self.labels.node_component(*label).is_some());
        let own = own.into_iter().map(|(l, c)| (l, c.settle())).collect();
        Ok((nodes, own))
    }

    /// The settled facts of the components that lie in tile `t` alone.
    fn settled(&self, t: &TileEntry) -> Result<Vec<(u64, Component)>, NormalsError> {
        Ok(self.of(t)?.1)
    }
}

fn find(part: &[(u64, Component)], label: u64) -> Component {
    part.binary_search_by_key(&label, |p| p.0)
        .map_or(Component::default(), |i| part[i].1)
}

/// Sizes of every component, the facts of the node components, and the
/// component of the highest point.
struct Census {
    /// Components by size (the first one excluded once known).
    sizes: BTreeMap<u32, u64>,
    /// The node components' settled facts, by number.
    spanning: Vec<Component>,
    /// Label and facts of the component of the highest point.
    first: Option<(u64, Component)>,
    total: u64,
    components: usize,
}

impl Census {
    fn take(facts: &TileFacts, progress: &dyn Progress) -> Result<Self, NormalsError> {
        let (store, labels) = (facts.store, facts.labels);
        let census = Census {
            sizes: BTreeMap::new(),
            spanning: Vec::new(),
            first: None,
            total: 0,
            components: 0,
        };
        // Tiles in parallel, each folded in as it comes: a component's
        // facts are order-free (sums, maxima under total orders, the
        // highest voters), so no tile's share waits for the others.
        let spanning = vec![Gathered::default(); labels.node_components];
        let folded = Mutex::new((census, spanning));
        store.tiles().par_iter().try_for_each(|t| {
            let (nodes, own) = facts.of(t)?;
            let mut guard = folded.lock().unwrap_or_else(|e| e.into_inner());
            let (census, spanning) = &mut *guard;
            for (label, c) in nodes {
                if let Some(k) = labels.node_component(label) {
                    spanning[k].absorb(&c);
                }
            }
            for (label, c) in own {
                census.add(label, c);
            }
            progress.advance(t.count);
            Ok::<_, NormalsError>(())
        })?;
        let (mut census, spanning) = folded.into_inner().unwrap_or_else(|e| e.into_inner());
        let mut spanning: Vec<Component> = spanning.iter().map(Gathered::settle).collect();
        // The sky's component faces as its anchors do (`super::anchors`).
        let sky = labels.sky();
        if let Some((label, parity)) = sky {
            if let Some(k) = labels.node_component(label) {
                spanning[k].sign = parity;
            }
        }
        for (k, c) in spanning.iter().enumerate() {
            census.add(store.len() + k as u64, *c);
        }
        census.spanning = spanning;
        if let Some((label, _)) = sky {
            if let Some(k) = labels.node_component(label) {
                census.first = Some((label, census.spanning[k]));
            }
        }
        if let Some((_, c)) = census.first {
            if let Some(n) = census.sizes.get_mut(&c.size) {
                *n -= 1;
            }
        }
        Ok(census)
    }

    fn add(&mut self, label: u64, c: Component) {
        if c.size == 0 {
            return;
        }
        *self.sizes.entry(c.size).or_default() += 1;
        self.total += u64::from(c.size);
        self.components += 1;
        if self.first.as_ref().is_none_or(|(_, f)| c.top > f.top) {
            self.first = Some((label, c));
        }
    }

    /// Where the island rule stops (see the module doc).
    fn cut(&self, facts: &TileFacts) -> Result<Cut, NormalsError> {
        let Some((first, f)) = self.first else {
            return Ok(Cut::none());
        };
        let mut left = self.total - u64::from(f.size);
        for (&size, &count) in self.sizes.iter().rev() {
            // Members of this class taken while left * 1000 >= total.
            let room = (left * 1000).saturating_sub(self.total) / 1000;
            let taken = if left * 1000 >= self.total {
                (room / u64::from(size) + 1).min(count)
            } else {
                0
            };
            left -= taken * u64::from(size);
            if taken < count {
                let last_id = match taken {
                    0 => None,
                    _ => Some(self.kth_smallest_top(facts, size, first, taken)?),
                };
                return Ok(Cut {
                    first,
                    size,
                    last_id,
                });
            }
        }
        Ok(Cut {
            first,
            size: 0,
            last_id: None,
        })
    }

    /// The `k`-th smallest top id among the components of `size` other
    /// than `first`, holding only the smaller side of the split in memory.
    fn kth_smallest_top(
        &self,
        facts: &TileFacts,
        size: u32,
        first: u64,
        k: u64,
    ) -> Result<u32, NormalsError> {
        let store = facts.store;
        let count = self.sizes.get(&size).copied().unwrap_or(0);
        let mut keep = OrderStatistic::new(k, count);
        let spanning = self.spanning.iter().enumerate();
        for (label, c) in spanning.map(|(i, c)| (store.len() + i as u64, *c)) {
            if c.size == size && label != first {
                keep.offer(c.top.id());
            }
        }
        for t in store.tiles() {
            for (label, c) in facts.settled(t)? {
                if c.size == size && label != first {
                    keep.offer(c.top.id());
                }
            }
        }
        Ok(keep.value())
    }
}

/// The `k`-th smallest of `count` values offered one by one, holding only
/// the smaller side: the `k` smallest (the answer is their largest), or the
/// `count - k + 1` largest (the answer is their smallest).
struct OrderStatistic {
    from_below: bool,
    keep: usize,
    below: BinaryHeap<u32>,
    above: BinaryHeap<Reverse<u32>>,
}

impl OrderStatistic {
    fn new(k: u64, count: u64) -> Self {
        let from_below = k <= count - k;
        OrderStatistic {
            from_below,
            keep: if from_below { k } else { count - k + 1 } as usize,
            below: BinaryHeap::new(),
            above: BinaryHeap::new(),
        }
    }

    fn offer(&mut self, v: u32) {
        if self.from_below {
            self.below.push(v);
            if self.below.len() > self.keep {
                self.below.pop();
            }
        } else {
            self.above.push(Reverse(v));
            if self.above.len() > self.keep {
                self.above.pop();
            }
        }
    }

    fn value(&self) -> u32 {
        if self.from_below {
            self.below.peek().copied().unwrap_or(u32::MAX)
        } else {
            self.above.peek().map_or(u32::MAX, |r| r.0)
        }
    }
}

/// The island rule's verdict: the first component, all components larger
/// than `size`, and those of `size` whose top id is at most `last_id`.
#[derive(Clone, Copy, Debug)]
struct Cut {
    first: u64,
    size: u32,
    last_id: Option<u32>,
}

impl Cut {
    fn none() -> Self {
        Cut {
            first: u64::MAX,
            size: u32::MAX,
            last_id: None,
        }
    }

    fn orients(&self, label: u64, c: &Component) -> bool {
        label == self.first
            || c.size > self.size
            || (c.size == self.size && self.last_id.is_some_and(|id| c.top.id() <= id))
    }
}
