//! The paper's depth-first order ([`super::propagate::Order::Stacks`],
//! paper 5 step 2, items 2-5), for the in-memory propagation only: one
//! stack per source (CSX, CSX-, CSY, CSY-, CSZ, CSZ-), taking turns in that
//! order. A stack pops until it finds a point whose propagation pairs do not
//! all lead to adjusted points (bNVisited false); that point adjusts every
//! unadjusted partner in decreasing `w` (ties by ids) and pushes them in
//! reverse, so the largest `w` ends on top. When every stack is empty, the
//! rest step ([`super::propagate`]) adjusts one point, which gets a stack of
//! its own.
//!
//! Deviation: "neighbourhood all adjusted" counts only propagation partners
//! (`w >= tau`). A popped point whose only unadjusted neighbours have
//! `w < tau` would adjust nobody, so the result is the paper's.

use super::pairs::propagates;
use super::state::State;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// A propagation partner: (edge key, point, flips).
type Partner = ((u64, u32, u32), u32, bool);

pub(crate) fn run(st: &mut State, started: Vec<usize>) {
    let mut visited = vec![false; st.done.len()];
    let mut rest: BinaryHeap<Reverse<(Partner, u32)>> = BinaryHeap::new();
    let mut stacks: Vec<Vec<u32>> = started.iter().map(|&s| vec![s as u32]).collect();
    let mut active: Vec<usize> = (0..stacks.len()).collect();
    loop {
        for &s in &active {
            if let Some((o, partners)) = pop_source(st, &mut stacks[s], &mut visited, &mut rest) {
                for &(_, j, flips) in &partners {
                    st.adjust(j as usize, o, flips);
                }
                stacks[s].extend(partners.iter().rev().map(|p| p.1));
                visited[o] = true;
            }
        }
        active.retain(|&s| !stacks[s].is_empty());
        if !active.is_empty() {
            continue;
        }
        let Some(j) = rest_step(st, &mut rest).or_else(|| st.next_root()) else {
            return;
        };
        stacks.push(vec![j as u32]);
        active.push(stacks.len() - 1);
    }
}

/// Pops until a point with unadjusted propagation partners appears and
/// returns it with those partners, strongest first.
fn pop_source(
    st: &State,
    stack: &mut Vec<u32>,
    visited: &mut [bool],
    rest: &mut BinaryHeap<Reverse<(Partner, u32)>>,
) -> Option<(usize, Vec<Partner>)> {
    while let Some(p) = stack.pop() {
        let p = p as usize;
        if visited[p] {
            continue;
        }
        let mut partners = Vec::new();
        for &j in st.c.graph.of(p) {
            if st.done[j as usize] {
                continue;
            }
            let Some(e) = st.edge(p, j as usize) else {
                continue;
            };
            let partner = (e.key(), j, e.flips());
            if propagates(&e) {
                partners.push(partner);
            } else {
                rest.push(Reverse((partner, p as u32)));
            }
        }
        if !partners.is_empty() {
            partners.sort_unstable();
            return Some((p, partners));
        }
        visited[p] = true;
    }
    None
}

/// The cheapest remaining bridge from an adjusted point adjusts its other
/// end, which becomes a new source.
fn rest_step(st: &mut State, rest: &mut BinaryHeap<Reverse<(Partner, u32)>>) -> Option<usize> {
    while let Some(Reverse(((_, j, flips), o))) = rest.pop() {
        let j = j as usize;
        if !st.done[j] {
            st.adjust(j, o as usize, flips);
            return Some(j);
        }
    }
    None
}
