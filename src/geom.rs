//! Plain geometric value types shared by every layer: the scalar, boxes.

use glam::DVec3;

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
