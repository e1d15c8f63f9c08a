//! Plain geometric value types shared by every layer: the scalar, boxes,
//! the pseudo-angle that orders planar directions without `atan2`, and a
//! point written as text (`x,y,z`: a viewpoint, a view direction).

use glam::{DVec2, DVec3};

/// Why a point's text `x,y,z` names none.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum XyzTextError {
    /// A coordinate is not a number.
    #[error("{0}")]
    Number(std::num::ParseFloatError),
    /// Not three coordinates, or one not finite.
    #[error("expected three finite numbers x,y,z")]
    NotThree,
}

/// The point `text` writes as `x,y,z` (blanks round a number allowed).
pub fn parse_xyz(text: &str) -> Result<DVec3, XyzTextError> {
    let v: Vec<f64> = text
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(XyzTextError::Number)?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(DVec3::new(*x, *y, *z)),
        _ => Err(XyzTextError::NotThree),
    }
}

/// The scalar of all geometry that must be exact or reproducible.
pub type Real = f64;

/// Axis-aligned box, `min <= max` on every axis once a point was added.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Corner of smallest coordinates.
    pub min: DVec3,
    /// Corner of largest coordinates.
    pub max: DVec3,
}

impl Aabb {
    /// The empty box: adding any point makes it that point.
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    /// The box from `min` to `max` (not checked: `min > max` on an axis makes it empty).
    pub fn new(min: DVec3, max: DVec3) -> Self {
        Aabb { min, max }
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// Grows the box to contain `p`.
    pub fn add(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub(crate) fn union(&self, o: &Aabb) -> Aabb {
        Aabb::new(self.min.min(o.min), self.max.max(o.max))
    }

    pub(crate) fn extent(&self) -> DVec3 {
        if self.is_empty() {
            DVec3::ZERO
        } else {
            self.max - self.min
        }
    }

    pub(crate) fn center(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    /// The box grown by `m` on every side.
    pub fn expanded(&self, m: f64) -> Aabb {
        Aabb::new(self.min - DVec3::splat(m), self.max + DVec3::splat(m))
    }

    /// Closed containment test.
    pub fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    pub(crate) fn intersects(&self, o: &Aabb) -> bool {
        self.min.cmple(o.max).all() && o.min.cmple(self.max).all()
    }
}

/// Pseudo-angle of direction `d` in `[0, 4)`: 0 along +x, 1 along +y, 2
/// along -x, 3 along -y, monotone in the angle in between. The zero vector
/// gets 0.
pub fn pseudo_angle(d: DVec2) -> f64 {
    let s = d.x.abs() + d.y.abs();
    if s == 0.0 {
        return 0.0;
    }
    let p = d.y / s;
    if d.x < 0.0 {
        2.0 - p
    } else if d.y < 0.0 {
        4.0 + p
    } else {
        p
    }
}

/// Which side a feature line bends to (paper 5's ridges and valleys; the
/// kind of a line `features` finds and of a true line `synth` knows).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum LineKind {
    /// Convex (PLY `kind` 1).
    Ridge = 1,
    /// Concave (PLY `kind` 2).
    Valley = 2,
}
