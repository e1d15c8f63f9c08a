//! A scene of points, feature lines and a mesh drawn into one picture:
//! points as grey splats darkening with depth, ridges red, valleys blue
//! (drawn over the surface they lie on), triangles shaded grey.

use super::{Camera, Canvas};
use crate::features::lines::LineGraph;
use crate::geom::LineKind;
use glam::DVec3;

/// What to draw.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Points, drawn as discs.
    pub points: Vec<DVec3>,
    /// Feature lines, coloured by kind.
    pub lines: Option<LineGraph>,
    /// A mesh (vertices, triangles), shaded.
    pub mesh: Option<(Vec<DVec3>, Vec<[u32; 3]>)>,
}

/// How to draw it.
#[derive(Clone, Copy, Debug)]
pub struct Style {
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
    /// Viewing direction and up.
    pub forward: DVec3,
    /// Which way is up in the image.
    pub up: DVec3,
    /// Disc radius of a point, pixels.
    pub point_radius: f64,
    /// Line width, pixels.
    pub line_width: f64,
}

pub(crate) const RIDGE: [u8; 3] = [214, 39, 40];
pub(crate) const VALLEY: [u8; 3] = [31, 90, 200];
const BACKGROUND: [u8; 3] = [255, 255, 255];

impl Scene {
    fn bounds(&self) -> Option<(DVec3, DVec3)> {
        let mesh = self.mesh.iter().flat_map(|m| m.0.iter());
        let lines = self.lines.iter().flat_map(|l| l.vertices.iter());
        let all = self
            .points
            .iter()
            .chain(mesh)
            .chain(lines)
            .filter(|p| p.is_finite());
        all.fold(None, |b, p| match b {
            None => Some((*p, *p)),
            Some((lo, hi)) => Some((lo.min(*p), hi.max(*p))),
        })
    }

    /// Draws the scene; `None` when there is nothing finite to frame or the
    /// view is degenerate.
    pub fn draw(&self, style: &Style) -> Option<Canvas> {
        let (lo, hi) = self.bounds()?;
        let cam = Camera::framing(
            style.forward,
            style.up,
            lo,
            hi,
            style.width,
            style.height,
            0.03,
        )?;
        let mut c = Canvas::new(cam, BACKGROUND);
        let depth = |p: DVec3| cam.project(p).2;
        let (dmin, dmax) = self
            .points
            .iter()
            .map(|p| depth(*p))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), d| {
                (a.min(d), b.max(d))
            });
        let span = (dmax - dmin).max(1e-300);
        for p in &self.points {
            let t = ((depth(*p) - dmin) / span).clamp(0.0, 1.0);
            let g = (200.0 - 120.0 * t) as u8;
            c.point(*p, style.point_radius, [g, g, g]);
        }
        if let Some((v, tris)) = &self.mesh {
            for t in tris {
                let [a, b, d] = t.map(|i| v.get(i as usize).copied());
                if let (Some(a), Some(b), Some(d)) = (a, b, d) {
                    c.triangle(a, b, d, [190, 190, 190]);
                }
            }
        }
        if let Some(l) = &self.lines {
            // Lines lie on the surface; a small depth bias keeps them over it.
            let bias = 2.0 * style.point_radius / cam.scale;
            for &(a, b, kind) in &l.edges {
                let color = if kind == LineKind::Ridge {
                    RIDGE
                } else {
                    VALLEY
                };
                let (pa, pb) = (l.vertices[a as usize], l.vertices[b as usize]);
                c.line(pa, pb, style.line_width, bias, color);
            }
        }
        Some(c)
    }
}
