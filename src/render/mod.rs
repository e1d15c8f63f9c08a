//! A small software rasteriser for pictures of clouds, feature lines and
//! meshes: an orthographic camera, a depth buffer, round point splats,
//! depth-tested lines and Lambert-shaded triangles, written as PNG
//! (`png`). No GPU, no window: the project draws its own figures.
//!
//! Depth is the distance along the viewing direction (smaller is nearer);
//! every primitive is depth-tested per pixel, so drawing order only matters
//! for exact ties (the first drawn wins).

pub(crate) mod png;
pub mod scene;

use glam::DVec3;

/// An orthographic camera looking along `forward`, framing a box.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    right: DVec3,
    up: DVec3,
    forward: DVec3,
    /// Pixels per unit length.
    scale: f64,
    /// World position of the image centre.
    centre: DVec3,
    width: usize,
    height: usize,
}

impl Camera {
    /// A camera looking along `forward` with `up` roughly up, scaled so
    /// that the box `[min, max]` fills `width x height` less a margin of
    /// `margin` (a fraction of the smaller side). `None` for a degenerate
    /// direction or an empty image.
    pub(crate) fn framing(
        forward: DVec3,
        up: DVec3,
        min: DVec3,
        max: DVec3,
        width: usize,
        height: usize,
        margin: f64,
    ) -> Option<Camera> {
        let forward = forward.try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        let up = right.cross(forward);
        if width == 0 || height == 0 {
            return None;
        }
        // Extent of the box's corners across the view.
        let centre = (min + max) * 0.5;
        let (mut w, mut h) = (0.0f64, 0.0f64);
        for i in 0..8 {
            let c = DVec3::new(
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            ) - centre;
            w = w.max(c.dot(right).abs() * 2.0);
            h = h.max(c.dot(up).abs() * 2.0);
        }
        let usable = 1.0 - 2.0 * margin.clamp(0.0, 0.45);
        let scale =
            (width as f64 * usable / w.max(1e-300)).min(height as f64 * usable / h.max(1e-300));
        scale.is_finite().then_some(Camera {
            right,
            up,
            forward,
            scale,
            centre,
            width,
            height,
        })
    }

    /// Pixel coordinates (x right, y down) and depth of `p`.
    pub(crate) fn project(&self, p: DVec3) -> (f64, f64, f64) {
        let d = p - self.centre;
        (
            self.width as f64 * 0.5 + d.dot(self.right) * self.scale,
            self.height as f64 * 0.5 - d.dot(self.up) * self.scale,
            d.dot(self.forward),
        )
    }

    /// The direction light comes from for shading: over the viewer's
    /// shoulder (up and to the left of the viewing direction).
    fn light(&self) -> DVec3 {
        (-self.forward + self.up * 0.6 - self.right * 0.4).normalize()
    }
}

/// An RGB image with a depth buffer.
#[derive(Clone, Debug)]
pub struct Canvas {
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
    /// Pixels row by row from the top left.
    pub rgb: Vec<[u8; 3]>,
    depth: Vec<f64>,
    camera: Camera,
}

impl Canvas {
    pub(crate) fn new(camera: Camera, background: [u8; 3]) -> Canvas {
        let n = camera.width * camera.height;
        Canvas {
            width: camera.width,
            height: camera.height,
            rgb: vec![background; n],
            depth: vec![f64::INFINITY; n],
            camera,
        }
    }

    /// The camera the image was drawn with.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Writes `color` at pixel `(x, y)` if `z` is nearer than what is there.
    fn plot(&mut self, x: i64, y: i64, z: f64, color: [u8; 3]) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return;
        }
        let i = y as usize * self.width + x as usize;
        if z < self.depth[i] {
            self.depth[i] = z;
            self.rgb[i] = color;
        }
    }

    /// A round splat of `radius` pixels at `p`.
    pub(crate) fn point(&mut self, p: DVec3, radius: f64, color: [u8; 3]) {
        let (x, y, z) = self.camera.project(p);
        let r = radius.max(0.5);
        let (x0, x1) = ((x - r).floor() as i64, (x + r).ceil() as i64);
        let (y0, y1) = ((y - r).floor() as i64, (y + r).ceil() as i64);
        for py in y0..=y1 {
            for px in x0..=x1 {
                let (dx, dy) = (px as f64 + 0.5 - x, py as f64 + 0.5 - y);
                if dx * dx + dy * dy <= r * r {
                    self.plot(px, py, z, color);
                }
            }
        }
    }

    /// A line `width` pixels wide from `a` to `b`, depth interpolated;
    /// `bias` is subtracted from its depth so lines lying on a surface
    /// win over it.
    pub(crate) fn line(&mut self, a: DVec3, b: DVec3, width: f64, bias: f64, color: [u8; 3]) {
        let (ax, ay, az) = self.camera.project(a);
        let (bx, by, bz) = self.camera.project(b);
        let steps = (bx - ax).abs().max((by - ay).abs()).ceil().max(1.0) as usize;
        let r = (width * 0.5).max(0.5);
        for s in 0..=steps {
            let t = s as f64 / steps as f64;
            let (x, y, z) = (
                ax + (bx - ax) * t,
                ay + (by - ay) * t,
                az + (bz - az) * t - bias,
            );
            let (x0, x1) = ((x - r).round() as i64, (x + r).round() as i64);
            let (y0, y1) = ((y - r).round() as i64, (y + r).round() as i64);
            for py in y0..=y1.max(y0) {
                for px in x0..=x1.max(x0) {
                    self.plot(px, py, z, color);
                }
            }
        }
    }

    /// A filled triangle, Lambert-shaded by its normal (two-sided) from
    /// the camera's light, over an ambient term.
    pub(crate) fn triangle(&mut self, a: DVec3, b: DVec3, c: DVec3, color: [u8; 3]) {
        let Some(n) = (b - a).cross(c - a).try_normalize() else {
            return;
        };
        let lambert = n.dot(self.camera.light()).abs();
        let shade = 0.25 + 0.75 * lambert;
        let col = color.map(|v| (v as f64 * shade).round().clamp(0.0, 255.0) as u8);
        let (p, q, r) = (
            self.camera.project(a),
            self.camera.project(b),
            self.camera.project(c),
        );
        let area = (q.0 - p.0) * (r.1 - p.1) - (q.1 - p.1) * (r.0 - p.0);
        if area == 0.0 {
            return;
        }
        let x0 = p.0.min(q.0).min(r.0).floor().max(0.0) as i64;
        let x1 = p.0.max(q.0).max(r.0).ceil().min(self.width as f64) as i64;
        let y0 = p.1.min(q.1).min(r.1).floor().max(0.0) as i64;
        let y1 = p.1.max(q.1).max(r.1).ceil().min(self.height as f64) as i64;
        for py in y0..y1 {
            for px in x0..x1 {
                let (x, y) = (px as f64 + 0.5, py as f64 + 0.5);
                // Barycentric weights from the edge functions.
                let w0 = ((q.0 - x) * (r.1 - y) - (q.1 - y) * (r.0 - x)) / area;
                let w1 = ((r.0 - x) * (p.1 - y) - (r.1 - y) * (p.0 - x)) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0 {
                    self.plot(px, py, w0 * p.2 + w1 * q.2 + w2 * r.2, col);
                }
            }
        }
    }

    /// The colour at pixel `(x, y)`.
    pub fn pixel(&self, x: usize, y: usize) -> [u8; 3] {
        self.rgb[y * self.width + x]
    }

    /// Writes the image as PNG.
    pub fn write_png(&self, path: &std::path::Path) -> Result<(), crate::io::IoError> {
        png::write_rgb(path, self.width, self.height, &self.rgb)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        // Looking down -z at the unit square.
        Camera::framing(-DVec3::Z, DVec3::Y, DVec3::ZERO, DVec3::ONE, 100, 100, 0.0).unwrap()
    }

    #[test]
    fn nearer_primitives_hide_farther_ones() {
        let mut c = Canvas::new(camera(), [0; 3]);
        // Far red triangle over the whole square, near green one over half.
        let z = |v: f64| v;
        c.triangle(
            DVec3::new(0.0, 0.0, z(0.0)),
            DVec3::new(1.0, 0.0, z(0.0)),
            DVec3::new(0.0, 1.0, z(0.0)),
            [255, 0, 0],
        );
        c.triangle(
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(0.5, 0.0, 1.0),
            DVec3::new(0.0, 0.5, 1.0),
            [0, 255, 0],
        );
        // Looking along -z, larger z is nearer. Pixel (10, 90) is near the
        // square's (0.1, 0.1): both cover it, green wins.
        let p = c.pixel(10, 90);
        assert!(p[1] > 0 && p[0] == 0, "{p:?}");
        // (0.7, 0.1): only red.
        let p = c.pixel(70, 90);
        assert!(p[0] > 0 && p[1] == 0, "{p:?}");
        // Outside both: background.
        assert_eq!(c.pixel(90, 10), [0, 0, 0]);
    }

    #[test]
    fn lines_and_points_land_where_projected() {
        let mut c = Canvas::new(camera(), [0; 3]);
        c.line(
            DVec3::new(0.0, 0.5, 0.0),
            DVec3::new(1.0, 0.5, 0.0),
            1.0,
            0.0,
            [9, 9, 9],
        );
        assert_eq!(c.pixel(50, 50), [9, 9, 9]);
        assert_eq!(c.pixel(50, 40), [0, 0, 0]);
        c.point(DVec3::new(0.25, 0.75, 0.0), 2.0, [7, 7, 7]);
        assert_eq!(c.pixel(25, 25), [7, 7, 7]);
    }
}
