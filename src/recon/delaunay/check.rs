//! `sanity_check`: the whole triangulation's invariants, for tests and
//! fuzzing. Every cell positively oriented (hull cells: their hull face
//! faces away from their finite neighbour), neighbour links symmetric and
//! on equal faces, the empty-sphere property against each neighbour's far
//! vertex (local Delaunay, which implies global Delaunay), every distinct
//! point a vertex, and the Euler characteristic of the 3-sphere
//! (`V - E + F - C = 0` counting the vertex at infinity).

use super::predicates::orient;
use super::triangulation::{Delaunay, INFINITE};

/// The first broken invariant, in words.
pub fn sanity_check(d: &Delaunay) -> Result<(), String> {
    let cells = d.cell_slots();
    let mut edges = Vec::new();
    let mut live = 0usize;
    for (c, cell) in cells.iter().enumerate() {
        if cell.is_free() {
            continue;
        }
        live += 1;
        let c = c as u32;
        check_orientation(d, c)?;
        for j in 0..4 {
            check_link(d, c, j)?;
            check_empty(d, c, j)?;
            for k in j + 1..4 {
                let (a, b) = (cell.v[j], cell.v[k]);
                edges.push((a.min(b), a.max(b)));
            }
        }
    }
    if live != d.cell_count() {
        return Err(format!("{live} live cells, {} counted", d.cell_count()));
    }
    for v in 0..d.vertex_count() as u32 {
        let c = d.vertex_cell(v);
        if !d
            .cell_slots()
            .get(c as usize)
            .is_some_and(|cell| cell.v.contains(&v))
        {
            return Err(format!("vertex {v}: its cell {c} does not hold it"));
        }
    }
    if d.vertex_count() != d.points().len() {
        return Err(format!(
            "{} vertices of {} points",
            d.vertex_count(),
            d.points().len()
        ));
    }
    edges.sort_unstable();
    edges.dedup();
    let v = d.vertex_count() as i64 + 1;
    let (e, c) = (edges.len() as i64, live as i64);
    let f = 2 * c;
    if v - e + f - c != 0 {
        return Err(format!("Euler: V {v} - E {e} + F {f} - C {c} != 0"));
    }
    Ok(())
}

fn check_orientation(d: &Delaunay, c: u32) -> Result<(), String> {
    let cell = d.cell(c);
    let p = |v: u32| d.points()[v as usize];
    match cell.infinite_slot() {
        None => {
            let o = orient(p(cell.v[0]), p(cell.v[1]), p(cell.v[2]), p(cell.v[3]));
            if o <= 0.0 {
                return Err(format!("cell {c} {:?} has orientation {o}", cell.v));
            }
        }
        Some(k) => {
            if cell.v.iter().filter(|&&v| v == INFINITE).count() != 1 {
                return Err(format!("cell {c} {:?}: several infinite vertices", cell.v));
            }
            // The finite neighbour's far vertex must lie inside the hull.
            let (nb, f) = (cell.n[k] >> 2, (cell.n[k] & 3) as usize);
            let apex = d.cell(nb).v[f];
            if apex == INFINITE {
                return Err(format!("hull cell {c} faces another hull cell"));
            }
            let mut w = cell.v.map(|v| if v == INFINITE { p(apex) } else { p(v) });
            w[k] = p(apex);
            if orient(w[0], w[1], w[2], w[3]) >= 0.0 {
                return Err(format!("hull cell {c} {:?} faces inward", cell.v));
            }
        }
    }
    Ok(())
}

fn check_link(d: &Delaunay, c: u32, j: usize) -> Result<(), String> {
    let cell = d.cell(c);
    let (nb, f) = (cell.n[j] >> 2, (cell.n[j] & 3) as usize);
    let other = d
        .cell_slots()
        .get(nb as usize)
        .ok_or_else(|| format!("cell {c} face {j}: neighbour {nb} out of range"))?;
    if other.is_free() {
        return Err(format!("cell {c} face {j}: neighbour {nb} is free"));
    }
    if other.n[f] != c << 2 | j as u32 {
        return Err(format!("cell {c} face {j}: link to {nb}.{f} not returned"));
    }
    let face = |v: [u32; 4], skip: usize| {
        let mut s: Vec<u32> = (0..4).filter(|&k| k != skip).map(|k| v[k]).collect();
        s.sort_unstable();
        s
    };
    if face(cell.v, j) != face(other.v, f) {
        return Err(format!(
            "cells {c} and {nb} are linked across unequal faces"
        ));
    }
    Ok(())
}

fn check_empty(d: &Delaunay, c: u32, j: usize) -> Result<(), String> {
    let cell = d.cell(c);
    let (nb, f) = (cell.n[j] >> 2, (cell.n[j] & 3) as usize);
    let far = d.cell(nb).v[f];
    if far == INFINITE {
        return Ok(());
    }
    if d.conflicts(c, far) {
        return Err(format!(
            "cell {c} {:?}: neighbour {nb}'s far vertex {far} is inside its sphere",
            cell.v
        ));
    }
    Ok(())
}
