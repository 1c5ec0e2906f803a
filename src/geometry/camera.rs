//! The pinhole camera of docs/design.md §1 "Camera convention": a frame (eye, f, r, u) and a
//! lens, either fov_y with the principal point at the image centre or pinhole intrinsics
//! fx, fy, cx, cy in pixels. The two lenses keep their own formulas, so that a fov_y camera's
//! rays are the same bits they were before intrinsics existed.

use super::Ray;
use glam::{DMat3, DVec3};

/// Pinhole intrinsics in pixels (docs/design.md §1 "Intrinsics"): x right, y down, pixel centres
/// at +0.5, so the image point (x, y) is seen along f + a·r + b·u with a = (x − cx)/fx and
/// b = (cy − y)/fy. The matrix K = [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] maps OpenCV camera
/// coordinates (x right, y down, z forward) to (x, y, 1)·z.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    /// Focal lengths, pixels, > 0.
    pub fx: f64,
    pub fy: f64,
    /// Principal point, pixels from the image's top-left corner.
    pub cx: f64,
    pub cy: f64,
}

impl Intrinsics {
    /// The same view at another image size: fx and cx scale with the width, fy and cy with the
    /// height (`--size` on a camera with intrinsics, docs/design.md §1).
    pub fn scaled(self, (from_w, from_h): (u32, u32), (to_w, to_h): (u32, u32)) -> Intrinsics {
        if (from_w, from_h) == (to_w, to_h) {
            return self;
        }
        let sx = to_w as f64 / from_w as f64;
        let sy = to_h as f64 / from_h as f64;
        Intrinsics {
            fx: self.fx * sx,
            fy: self.fy * sy,
            cx: self.cx * sx,
            cy: self.cy * sy,
        }
    }
}

/// The tolerance of [`check_rotation`]: a rotation read from a file may be rounded (NeRF's
/// `transforms.json` holds f32 values, ~6e-8), never skewed by more than this.
pub const ROTATION_TOLERANCE: f64 = 1e-5;

/// Whether `rotation` (a world-to-camera R, or its transpose) is a proper rotation: every entry
/// of R·Rᵀ − I within [`ROTATION_TOLERANCE`] and det R > 0; the message says what is wrong.
pub fn check_rotation(rotation: DMat3) -> Result<(), String> {
    if !rotation.is_finite() {
        return Err("is not finite".into());
    }
    let d = rotation * rotation.transpose() - DMat3::IDENTITY;
    let off = d.to_cols_array().iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if off > ROTATION_TOLERANCE {
        return Err(format!(
            "is not a rotation: R·Rᵀ differs from the identity by {off:.3e} (at most {ROTATION_TOLERANCE:e})"
        ));
    }
    if rotation.determinant() <= 0.0 {
        return Err("is a reflection (determinant < 0), not a rotation".into());
    }
    Ok(())
}

/// A camera's lens: fov_y in degrees with the principal point at the centre, or intrinsics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Lens {
    FovY(f64),
    Pinhole(Intrinsics),
}

/// A pinhole camera: f = normalize(look_at − position), r = normalize(f × up), u = r × f.
/// Pixel (px, py), py down, is sampled at continuous coordinates (x, y); the pixel centre is
/// (px + 0.5, py + 0.5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub position: DVec3,
    pub forward: DVec3,
    pub right: DVec3,
    pub up: DVec3,
    /// tan(fov_y / 2) of a fov_y camera; with intrinsics (H/2)/fy, the vertical half-angle's
    /// tangent of the centred camera with that fy.
    pub tan_half_fov: f64,
    pub width: u32,
    pub height: u32,
    /// Pinhole intrinsics; `None` for a fov_y camera (principal point at the centre, square
    /// pixels), whose rays keep the fov_y formula of [`Camera::ray_at`].
    pub intrinsics: Option<Intrinsics>,
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
            intrinsics: None,
        }
    }

    /// The camera at `position` whose OpenCV world-to-camera rotation is `rotation` (rows r, −u, f,
    /// used as given: a rotation the caller checked with [`check_rotation`]).
    pub fn from_rotation(
        position: DVec3,
        rotation: DMat3,
        lens: Lens,
        width: u32,
        height: u32,
    ) -> Self {
        let axes = [rotation.row(0), -rotation.row(1), rotation.row(2)];
        match lens {
            Lens::Pinhole(k) => Camera::from_axes(position, axes, k, width, height),
            Lens::FovY(fov_y_deg) => Camera {
                position,
                right: axes[0],
                up: axes[1],
                forward: axes[2],
                tan_half_fov: (fov_y_deg.to_radians() * 0.5).tan(),
                width,
                height,
                intrinsics: None,
            },
        }
    }

    /// The eye of the OpenCV pose (R, t): x_cam = R·x_world + t is 0 at eye = −Rᵀ·t.
    pub fn eye_of(rotation: DMat3, t: DVec3) -> DVec3 {
        -(rotation.transpose() * t)
    }

    /// This camera with `lens`.
    pub fn with_lens(self, lens: Lens) -> Self {
        match lens {
            Lens::Pinhole(k) => self.with_intrinsics(k),
            Lens::FovY(fov_y_deg) => Camera {
                tan_half_fov: (fov_y_deg.to_radians() * 0.5).tan(),
                intrinsics: None,
                ..self
            },
        }
    }

    /// A camera with intrinsics from its frame as given (unit r, u, f with u = r × f, checked
    /// by the caller): the rows of the OpenCV world-to-camera rotation are r, −u, f.
    pub fn from_axes(
        position: DVec3,
        [right, up, forward]: [DVec3; 3],
        intrinsics: Intrinsics,
        width: u32,
        height: u32,
    ) -> Self {
        Camera {
            position,
            forward,
            right,
            up,
            tan_half_fov: 0.5 * height as f64 / intrinsics.fy,
            width,
            height,
            intrinsics: Some(intrinsics),
        }
    }

    /// This camera's frame with `intrinsics` as its lens.
    pub fn with_intrinsics(self, intrinsics: Intrinsics) -> Self {
        Camera::from_axes(
            self.position,
            [self.right, self.up, self.forward],
            intrinsics,
            self.width,
            self.height,
        )
    }

    /// The lens as intrinsics: a fov_y camera's are fx = fy = (H/2)/tan(fov_y/2), cx = W/2,
    /// cy = H/2 (docs/design.md §1), the same rays up to rounding.
    pub fn pinhole(&self) -> Intrinsics {
        self.intrinsics.unwrap_or_else(|| {
            let f = 0.5 * self.height as f64 / self.tan_half_fov;
            Intrinsics {
                fx: f,
                fy: f,
                cx: 0.5 * self.width as f64,
                cy: 0.5 * self.height as f64,
            }
        })
    }

    /// The OpenCV world-to-camera rotation R (rows r, −u, f: camera x right, y down, z forward),
    /// as a matrix acting on column vectors.
    pub fn world_to_camera_rotation(&self) -> DMat3 {
        DMat3::from_cols(self.right, -self.up, self.forward).transpose()
    }

    /// fov_y in degrees from a focal length f (thesis eq. 3.7): fov_y = 2·atan(1/f).
    pub fn fov_y_from_focal_length(focal_length: f64) -> f64 {
        2.0 * (1.0 / focal_length).atan().to_degrees()
    }

    /// The ray through continuous image coordinates (x, y), x right and y down, in pixels:
    /// a = (2x/W − 1)·(W/H)·tan(fov_y/2), b = (1 − 2y/H)·tan(fov_y/2) for a fov_y camera,
    /// a = (x − cx)/fx, b = (cy − y)/fy with intrinsics; direction = normalize(f + a·r + b·u).
    #[inline]
    pub fn ray_at(&self, x: f64, y: f64) -> Ray {
        let (a, b) = match &self.intrinsics {
            None => {
                let w = self.width as f64;
                let h = self.height as f64;
                (
                    (2.0 * x / w - 1.0) * (w / h) * self.tan_half_fov,
                    (1.0 - 2.0 * y / h) * self.tan_half_fov,
                )
            }
            Some(k) => ((x - k.cx) / k.fx, (k.cy - y) / k.fy),
        };
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
    fn the_centred_intrinsics_of_a_fov_camera_send_the_same_rays() {
        let cam = Camera::new(
            DVec3::new(1.0, 2.0, -9.0),
            DVec3::ZERO,
            DVec3::Y,
            37.0,
            31,
            17,
        );
        let k = cam.pinhole();
        let pinhole = cam.with_intrinsics(k);
        for (x, y) in [(0.5, 0.5), (30.5, 16.5), (12.25, 3.75), (0.0, 17.0)] {
            let (p, q) = (cam.ray_at(x, y).direction, pinhole.ray_at(x, y).direction);
            assert_relative_eq!(p, q, epsilon = 1e-14);
        }
        assert_relative_eq!(pinhole.tan_half_fov, cam.tan_half_fov, epsilon = 1e-15);
    }

    #[test]
    fn an_off_centre_principal_point_and_unequal_focal_lengths() {
        // Looking down +z from the origin: r = −x, u = +y. The principal point (cx, cy) is seen
        // along f; one pixel right of it along f + r/fx; one pixel down along f − u/fy.
        let base = Camera::new(DVec3::ZERO, DVec3::Z, DVec3::Y, 40.0, 64, 48);
        let k = Intrinsics {
            fx: 100.0,
            fy: 50.0,
            cx: 20.0,
            cy: 30.0,
        };
        let cam = base.with_intrinsics(k);
        assert_relative_eq!(cam.ray_at(20.0, 30.0).direction, DVec3::Z, epsilon = 1e-15);
        let right = cam.ray_at(21.0, 30.0).direction;
        assert_relative_eq!(
            right,
            DVec3::new(-0.01, 0.0, 1.0).normalize(),
            epsilon = 1e-15
        );
        let down = cam.ray_at(20.0, 31.0).direction;
        assert_relative_eq!(
            down,
            DVec3::new(0.0, -0.02, 1.0).normalize(),
            epsilon = 1e-15
        );
        // R's rows are r, −u, f: R·f = (0, 0, 1).
        let r = cam.world_to_camera_rotation();
        assert_relative_eq!(r * cam.forward, DVec3::Z, epsilon = 1e-15);
        assert_relative_eq!(r * cam.up, -DVec3::Y, epsilon = 1e-15);
    }

    #[test]
    fn scaled_intrinsics_keep_the_view() {
        let k = Intrinsics {
            fx: 100.0,
            fy: 50.0,
            cx: 20.0,
            cy: 30.0,
        };
        let half = k.scaled((64, 48), (32, 24));
        assert_eq!(
            (half.fx, half.fy, half.cx, half.cy),
            (50.0, 25.0, 10.0, 15.0)
        );
        assert_eq!(k.scaled((64, 48), (64, 48)), k);
    }

    #[test]
    fn focal_length_conversion() {
        assert_relative_eq!(Camera::fov_y_from_focal_length(1.0), 90.0, epsilon = 1e-12);
    }
}
