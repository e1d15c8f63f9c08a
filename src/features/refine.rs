//! Across-line refinement of grown polylines (deviation from paper 5,
//! section 5, named): the paper's growth points are the extreme
//! projections of the few unused points within `gamma_max` ahead, so a
//! vertex inherits the sideways scatter of a handful of smoothed points
//! and the tilt of their axis at the far end (measured on the wavy sheet
//! at noise 0.1 sp: smoothed points 93 % within 1 sp of the crest, growth
//! vertices 89.5 %). Each vertex is moved onto the principal axis of all
//! the cell's smoothed points (used or not) within `radius` of it that lie
//! within `width` of the line through it along its polyline's tangent (the
//! width keeps the points of a line crossing at a corner out), when they
//! are elongated like a line (Lee's `|rho| >= 0.6`, as in section 4).
//! The points are those the cell's growth used, so the result depends on
//! the cell alone and no tiling changes it.

use super::smooth::elongation;
use crate::spatial::BallGrid;
use glam::DVec3;

/// Elongation the refinement's points must reach (section 4's 0.6).
const MIN_ELONGATION: f64 = 0.6;

/// Whether a point lies past an end of `line` (within `radius` of the end
/// vertex, ahead of it along the end's direction): at a corner those are
/// the other lines' points, and they would pull the end's vertices
/// sideways (stepped block: the refined ridges lost 2-8 sp from each
/// corner). `None` for a line of fewer than two vertices.
fn ends_beyond(line: &[DVec3], radius: f64) -> Option<impl Fn(DVec3) -> bool> {
    let n = line.len();
    if n < 2 {
        return None;
    }
    let ends = [
        (line[0], (line[0] - line[1]).normalize_or_zero()),
        (line[n - 1], (line[n - 1] - line[n - 2]).normalize_or_zero()),
    ];
    let r2 = radius * radius;
    Some(move |p: DVec3| {
        ends.iter()
            .any(|&(e, o)| (p - e).length_squared() <= r2 && (p - e).dot(o) > 0.0)
    })
}

/// Moves every vertex of `lines` as the module doc says; `grid` indexes
/// the smoothed points the lines grew through. Vertices are refined from
/// the original positions (a pass, not a sequence).
pub fn refine_lines(lines: &mut [Vec<DVec3>], grid: &BallGrid, radius: f64, width: f64) {
    if radius <= 0.0 {
        return;
    }
    let points = grid.points();
    let mut found = Vec::new();
    let mut near = Vec::new();
    for line in lines.iter_mut() {
        let old = line.clone();
        let Some(beyond) = ends_beyond(&old, radius) else {
            continue;
        };
        for (i, v) in line.iter_mut().enumerate() {
            let (a, b) = (old[i.saturating_sub(1)], old[(i + 1).min(old.len() - 1)]);
            let t = (b - a).normalize_or_zero();
            if t == DVec3::ZERO {
                continue;
            }
            grid.within(*v, radius, None, &mut found);
            near.clear();
            near.extend(found.iter().map(|n| points[n.index as usize]).filter(|p| {
                let d = *p - old[i];
                (d - t * d.dot(t)).length() <= width && !beyond(*p)
            }));
            if near.len() < 3 {
                continue;
            }
            let (rho, axis, centre) = elongation(&near);
            if rho >= MIN_ELONGATION {
                *v = centre + axis * (old[i] - centre).dot(axis);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn off_line(line: &[DVec3]) -> f64 {
        line.iter().map(|v| v.y.hypot(v.z)).fold(0.0, f64::max)
    }

    #[test]
    fn vertices_move_onto_the_points_line_and_keep_clear_of_a_corner() {
        let mut rng = Rng::new(11);
        // Points along the x axis for x in [0, 10], and a line along y
        // from the origin (a corner): the refined vertices of a zig-zag
        // polyline along x come within the points' noise of the axis.
        let mut pts: Vec<DVec3> = (0..2000)
            .map(|_| DVec3::new(rng.range(0.0, 10.0), 0.0, 0.0) + rng.gaussian_vector(0.05))
            .collect();
        pts.extend((0..400).map(|_| DVec3::new(0.0, rng.range(0.0, 5.0), 0.0)));
        let ids: Vec<u64> = (0..pts.len() as u64).collect();
        let grid = BallGrid::new(&pts, &ids, 1.0).unwrap();
        let zigzag: Vec<DVec3> = (0..9)
            .map(|i| DVec3::new(0.5 + f64::from(i), if i % 2 == 0 { 0.3 } else { -0.3 }, 0.0))
            .collect();
        let mut lines = vec![zigzag.clone()];
        refine_lines(&mut lines, &grid, 3.0, 1.0);
        assert!(off_line(&zigzag) > 0.29);
        assert!(off_line(&lines[0]) < 0.06, "{:?}", lines[0]);
        // Radius 0: untouched.
        let mut same = vec![zigzag.clone()];
        refine_lines(&mut same, &grid, 0.0, 1.0);
        assert_eq!(same[0], zigzag);
    }
}
