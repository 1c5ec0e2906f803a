//! The pinhole camera of docs/design.md §1 "Camera convention".

use super::Ray;
use glam::DVec3;

/// A pinhole camera: f = normalize(look_at − position), r = normalize(f × up), u = r × f.
/// Pixel (px, py), py down, is sampled at continuous coordinates (x, y); the pixel centre is
/// (px + 0.5, py + 0.5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub position: DVec3,
    pub forward: DVec3,
    pub right: DVec3,
    pub up: DVec3,
    /// tan(fov_y / 2).
    pub tan_half_fov: f64,
    pub width: u32,
    pub height: u32,
}

impl Camera {
    /// Builds the frame. `forward` and `up` must be non-zero and not parallel (validated by the
    /// scene loader, which reports the file and line).
    pub fn new(
        position: DVec3,
        look_at: DVec3,
        up: DVec3,
        fov_y_deg: f64,
        width: u32,
        height: u32,
    ) -> Self {
        let forward = (look_at - position).normalize();
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        Camera {
            position,
            forward,
            right,
            up,
            tan_half_fov: (fov_y_deg.to_radians() * 0.5).tan(),
            width,
            height,
        }
    }

    /// fov_y in degrees from a focal length f (thesis eq. 3.7): fov_y = 2·atan(1/f).
    pub fn fov_y_from_focal_length(focal_length: f64) -> f64 {
        2.0 * (1.0 / focal_length).atan().to_degrees()
    }

    /// The ray through continuous image coordinates (x, y), x right and y down, in pixels:
    /// a = (2x/W − 1)·(W/H)·tan(fov_y/2), b = (1 − 2y/H)·tan(fov_y/2),
    /// direction = normalize(f + a·r + b·u).
    #[inline]
    pub fn ray_at(&self, x: f64, y: f64) -> Ray {
        let w = self.width as f64;
        let h = self.height as f64;
        let a = (2.0 * x / w - 1.0) * (w / h) * self.tan_half_fov;
        let b = (1.0 - 2.0 * y / h) * self.tan_half_fov;
        Ray::new(self.position, self.forward + a * self.right + b * self.up)
    }

    /// The ray through the centre of pixel (px, py).
    #[inline]
    pub fn pixel_ray(&self, px: u32, py: u32) -> Ray {
        self.ray_at(px as f64 + 0.5, py as f64 + 0.5)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn centre_pixel_of_odd_image_looks_at_target() {
        let cam = Camera::new(
            DVec3::new(0.0, 0.0, -10.0),
            DVec3::ZERO,
            DVec3::Y,
            40.0,
            5,
            5,
        );
        let r = cam.pixel_ray(2, 2);
        assert_relative_eq!(r.direction, DVec3::Z, epsilon = 1e-15);
    }

    #[test]
    fn right_handed_frame_and_row_zero_is_top() {
        // Looking down +z with +y up: right = f × up = z × y = −x.
        let cam = Camera::new(
            DVec3::new(0.0, 0.0, -10.0),
            DVec3::ZERO,
            DVec3::Y,
            90.0,
            2,
            2,
        );
        assert_relative_eq!(cam.right, -DVec3::X, epsilon = 1e-15);
        let top_left = cam.pixel_ray(0, 0).direction;
        assert!(top_left.y > 0.0 && top_left.x > 0.0);
        // The pixel centre at (0.5, 0.5) of a 2×2 image with fov 90°: a = −0.5, b = 0.5.
        let expected = (DVec3::Z + -0.5 * -DVec3::X + 0.5 * DVec3::Y).normalize();
        assert_relative_eq!(top_left, expected, epsilon = 1e-15);
    }

    #[test]
    fn image_edge_spans_fov() {
        let cam = Camera::new(DVec3::ZERO, DVec3::Z, DVec3::Y, 60.0, 100, 50);
        let top = cam.ray_at(50.0, 0.0).direction;
        assert_relative_eq!(top.y.atan2(top.z).to_degrees(), 30.0, epsilon = 1e-12);
        let right = cam.ray_at(100.0, 25.0).direction;
        // Horizontal half-angle: atan(aspect · tan 30°).
        let expected = (2.0 * (30.0f64).to_radians().tan()).atan();
        assert_relative_eq!((-right.x).atan2(right.z), expected, epsilon = 1e-12);
    }

    #[test]
    fn focal_length_conversion() {
        assert_relative_eq!(Camera::fov_y_from_focal_length(1.0), 90.0, epsilon = 1e-12);
    }
}
