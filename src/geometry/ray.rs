use glam::DVec3;

/// A ray x(t) = origin + t·direction; `direction` is unit length, so t is a distance in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    pub origin: DVec3,
    pub direction: DVec3,
}

impl Ray {
    /// A ray with the direction normalised. The caller guarantees a non-zero, finite direction.
    pub fn new(origin: DVec3, direction: DVec3) -> Self {
        Ray {
            origin,
            direction: direction.normalize(),
        }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + t * self.direction
    }
}
