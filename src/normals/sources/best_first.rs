//! Best-first order ([`super::propagate::Order::BestFirst`], the default):
//! one queue of pairs (adjusted `o`, unadjusted `j`) over all sources,
//! cheapest first by the edge key (propagation pairs by decreasing `w`,
//! then bridges by distance, ties by ids). A popped pair whose `j` is still
//! unadjusted adjusts it (bNormal) and queues `j`'s pairs, once (bNVisited).
//! This is Prim's algorithm with every source joined to one root, so its
//! flips are the parities along the minimum spanning forest of the pairs
//! ([`Edge`](crate::normals::forest::Edge) order).

use super::state::State;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// (edge key, unadjusted end, adjusted end, whether one of them flips).
type Queued = Reverse<((u64, u32, u32), u32, u32, bool)>;

pub(crate) fn run(st: &mut State, started: Vec<usize>) {
    let mut queue: BinaryHeap<Queued> = BinaryHeap::new();
    for s in started {
        expand(st, s, &mut queue);
    }
    loop {
        while let Some(Reverse((_, j, o, flips))) = queue.pop() {
            let j = j as usize;
            if !st.done[j] {
                st.adjust(j, o as usize, flips);
                expand(st, j, &mut queue);
            }
        }
        match st.next_root() {
            Some(r) => expand(st, r, &mut queue),
            None => return,
        }
    }
}

/// Queues the pairs from the newly adjusted `o` to unadjusted points.
fn expand(st: &State, o: usize, queue: &mut BinaryHeap<Queued>) {
    for &j in st.c.graph.of(o) {
        if st.done[j as usize] {
            continue;
        }
        if let Some(e) = st.edge(o, j as usize) {
            queue.push(Reverse((e.key(), j, o as u32, e.flips())));
        }
    }
}
