//! Cameras that move (docs/design.md §10): the camera of scene frame t (t = 0, 1, 2, …) as a
//! fixed camera, an orbit or interpolated keyframes. Every frame's camera is a [`Camera`] of
//! docs/design.md §1 built from a position p, a look-at point l, an up vector u and fov_y.
//!
//! **Fixed**: the same camera in every frame.
//!
//! **Orbit** about the centre c (by default the centre of the particles' bounding sphere at frame
//! 0, [`crate::scene::bounding_sphere`]), around the unit axis a, θ degrees per frame: with
//! R_φ the rotation by φ about a (Rodrigues: R_φ v = v cos φ + (a × v) sin φ + a (a·v)(1 − cos φ)),
//!
//!   p(t) = c + R_{tθ}(p₀ − c),   l(t) = c + R_{tθ}(l₀ − c),   u(t) = R_{tθ} u₀,   fov_y(t) = fov_y₀,
//!
//! where p₀, l₀, u₀, fov_y₀ are the frame-0 camera (frame 0 is that camera exactly, without
//! the rounding of the rotation). A positive θ turns counter-clockwise seen
//! from the tip of a (right-handed). Rotation keeps angles, so a valid frame-0 camera is valid
//! in every frame.
//!
//! **Keyframes** k = 0 … n−1 (n ≥ 2) at integer frames f₀ < f₁ < … with values P_k (each of p,
//! l, u as vectors, fov_y as a number). Before f₀ the camera holds keyframe 0, after f_{n−1} the
//! last. For f_k ≤ t ≤ f_{k+1}, with h = f_{k+1} − f_k and s = (t − f_k)/h:
//!
//! * `linear`: P(t) = (1 − s)·P_k + s·P_{k+1};
//! * `catmull-rom` (p, l and u; fov_y stays linear): the cubic Hermite curve
//!   P(t) = h₀₀(s)·P_k + h₁₀(s)·h·m_k + h₀₁(s)·P_{k+1} + h₁₁(s)·h·m_{k+1}, with
//!   h₀₀ = 2s³ − 3s² + 1, h₁₀ = s³ − 2s² + s, h₀₁ = −2s³ + 3s², h₁₁ = s³ − s², and tangents
//!   (per frame) m_k = (P_{k+1} − P_{k−1}) / (f_{k+1} − f_{k−1}) inside, one-sided at the ends:
//!   m₀ = (P₁ − P₀)/(f₁ − f₀), m_{n−1} = (P_{n−1} − P_{n−2})/(f_{n−1} − f_{n−2}). For evenly
//!   spaced keyframes this is the uniform Catmull–Rom spline (m_k = (P_{k+1} − P_{k−1})/2 per
//!   unit spacing); the curve passes through every keyframe.
//!
//! The interpolated u is normalised by the camera (r = normalize(f × u)); a frame where l = p or
//! u is parallel to the viewing direction is an error naming the frame.

use super::{Camera, Intrinsics};
use glam::DVec3;

/// How keyframe values are interpolated between keyframes (fov_y is always linear).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Interpolation {
    /// Straight lines between keyframes.
    #[default]
    Linear,
    /// The Catmull–Rom spline of the module doc.
    CatmullRom,
}

/// The camera values of a keyframe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Keyframe {
    /// The scene frame it holds at.
    pub frame: u64,
    pub position: DVec3,
    pub look_at: DVec3,
    pub up: DVec3,
    /// Degrees.
    pub fov_y: f64,
}

/// The camera of every frame (see the module doc).
#[derive(Debug, Clone, PartialEq)]
pub enum CameraPath {
    /// One camera for all frames.
    Fixed(Camera),
    /// A turn about an axis through a centre.
    Orbit {
        /// The frame-0 camera's position, look-at point, up vector and fov_y (degrees).
        start: Keyframe,
        center: DVec3,
        /// Unit axis.
        axis: DVec3,
        degrees_per_frame: f64,
        width: u32,
        height: u32,
        /// The frame-0 camera's intrinsics, kept in every frame (`None`: fov_y).
        intrinsics: Option<Intrinsics>,
    },
    /// Interpolated keyframes (at least two, frames strictly increasing).
    Keyframes {
        keys: Vec<Keyframe>,
        interpolation: Interpolation,
        width: u32,
        height: u32,
    },
    /// One camera per frame, as a dataset lists them (docs/design.md §1 "Cameras of datasets");
    /// the scene has as many frames as cameras.
    Sequence(Vec<Camera>),
}

/// Rodrigues' rotation of `v` by `angle` radians about the unit `axis`.
pub fn rotate(v: DVec3, axis: DVec3, angle: f64) -> DVec3 {
    let (s, c) = angle.sin_cos();
    v * c + axis.cross(v) * s + axis * axis.dot(v) * (1.0 - c)
}

/// The Hermite basis h₀₀, h₁₀, h₀₁, h₁₁ at s.
fn hermite(s: f64) -> [f64; 4] {
    let (s2, s3) = (s * s, s * s * s);
    [
        2.0 * s3 - 3.0 * s2 + 1.0,
        s3 - 2.0 * s2 + s,
        -2.0 * s3 + 3.0 * s2,
        s3 - s2,
    ]
}

/// The tangent (per frame) of keyframe `k` of `values` at `frames`, as the module doc defines.
fn tangent(values: &[DVec3], frames: &[f64], k: usize) -> DVec3 {
    let last = values.len() - 1;
    let (a, b) = if k == 0 {
        (0, 1)
    } else if k == last {
        (last - 1, last)
    } else {
        (k - 1, k + 1)
    };
    (values[b] - values[a]) / (frames[b] - frames[a])
}

impl CameraPath {
    /// The camera of scene frame `frame`, or a message when it is degenerate there.
    pub fn camera_at(&self, frame: usize) -> Result<Camera, String> {
        let mut intrinsics = None;
        let (p, l, u, fov, w, h) = match self {
            CameraPath::Fixed(camera) => return Ok(*camera),
            CameraPath::Sequence(cameras) => {
                return cameras.get(frame).copied().ok_or_else(|| {
                    format!(
                    "frame {frame} requested, but the camera sequence has {} camera(s) (0-based)",
                    cameras.len()
                )
                })
            }
            CameraPath::Orbit {
                start,
                width,
                height,
                intrinsics: k,
                ..
            } if frame == 0 => {
                intrinsics = *k;
                (
                    start.position,
                    start.look_at,
                    start.up,
                    start.fov_y,
                    *width,
                    *height,
                )
            }
            CameraPath::Orbit {
                start,
                center,
                axis,
                degrees_per_frame,
                width,
                height,
                intrinsics: k,
            } => {
                intrinsics = *k;
                let angle = (frame as f64 * degrees_per_frame).to_radians();
                (
                    *center + rotate(start.position - *center, *axis, angle),
                    *center + rotate(start.look_at - *center, *axis, angle),
                    rotate(start.up, *axis, angle),
                    start.fov_y,
                    *width,
                    *height,
                )
            }
            CameraPath::Keyframes {
                keys,
                interpolation,
                width,
                height,
            } => {
                let k = interpolate(keys, *interpolation, frame as f64)?;
                (k.position, k.look_at, k.up, k.fov_y, *width, *height)
            }
        };
        let forward = l - p;
        if forward.length() == 0.0 || !forward.is_finite() {
            return Err(format!(
                "the camera's look_at equals its position at frame {frame}"
            ));
        }
        if u.length() == 0.0
            || !u.is_finite()
            || forward.normalize().cross(u.normalize()).length() < 1e-9
        {
            return Err(format!(
                "the camera's up is zero or parallel to the viewing direction at frame {frame}"
            ));
        }
        if !(fov > 0.0 && fov < 180.0) {
            return Err(format!(
                "fov_y is {fov}° at frame {frame}, outside (0, 180)"
            ));
        }
        let camera = Camera::new(p, l, u, fov, w, h);
        Ok(match intrinsics {
            Some(k) => camera.with_intrinsics(k),
            None => camera,
        })
    }

    /// The number of frames the path itself has: a sequence's camera count; `None` for the
    /// others, which give a camera for every frame.
    pub fn frame_count(&self) -> Option<usize> {
        match self {
            CameraPath::Sequence(cameras) => Some(cameras.len()),
            _ => None,
        }
    }
}

/// The keyframe values at frame `t` (the module doc's interpolation).
pub fn interpolate(
    keys: &[Keyframe],
    interpolation: Interpolation,
    t: f64,
) -> Result<Keyframe, String> {
    let (Some(first), Some(last)) = (keys.first(), keys.last()) else {
        return Err("a keyframe path needs at least two keyframes".into());
    };
    if keys.len() < 2 {
        return Err("a keyframe path needs at least two keyframes".into());
    }
    if t <= first.frame as f64 {
        return Ok(Keyframe {
            frame: t as u64,
            ..*first
        });
    }
    if t >= last.frame as f64 {
        return Ok(Keyframe {
            frame: t as u64,
            ..*last
        });
    }
    let k = keys
        .windows(2)
        .position(|w| (w[0].frame as f64) <= t && t <= w[1].frame as f64)
        .ok_or_else(|| "keyframes out of order".to_string())?;
    let (a, b) = (keys[k], keys[k + 1]);
    let h = (b.frame - a.frame) as f64;
    let s = (t - a.frame as f64) / h;
    let fov_y = (1.0 - s) * a.fov_y + s * b.fov_y;
    let frames: Vec<f64> = keys.iter().map(|key| key.frame as f64).collect();
    let along = |get: fn(&Keyframe) -> DVec3| -> DVec3 {
        match interpolation {
            Interpolation::Linear => (1.0 - s) * get(&a) + s * get(&b),
            Interpolation::CatmullRom => {
                let values: Vec<DVec3> = keys.iter().map(get).collect();
                let [h00, h10, h01, h11] = hermite(s);
                h00 * values[k]
                    + h10 * h * tangent(&values, &frames, k)
                    + h01 * values[k + 1]
                    + h11 * h * tangent(&values, &frames, k + 1)
            }
        }
    };
    Ok(Keyframe {
        frame: t as u64,
        position: along(|k| k.position),
        look_at: along(|k| k.look_at),
        up: along(|k| k.up),
        fov_y,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn key(frame: u64, x: f64) -> Keyframe {
        Keyframe {
            frame,
            position: DVec3::new(x, 0.0, -10.0),
            look_at: DVec3::ZERO,
            up: DVec3::Y,
            fov_y: 30.0 + x,
        }
    }

    #[test]
    fn rodrigues_quarter_turn() {
        assert_relative_eq!(
            rotate(DVec3::X, DVec3::Z, std::f64::consts::FRAC_PI_2),
            DVec3::Y,
            epsilon = 1e-15
        );
        assert_relative_eq!(rotate(DVec3::Z, DVec3::Z, 1.234), DVec3::Z, epsilon = 1e-15);
    }

    #[test]
    fn orbit_turns_about_the_centre_and_keeps_the_distance() {
        let start = Keyframe {
            frame: 0,
            position: DVec3::new(1.0, 2.0, -8.0),
            look_at: DVec3::new(1.0, 2.0, 0.0),
            up: DVec3::Y,
            fov_y: 40.0,
        };
        let path = CameraPath::Orbit {
            start,
            center: DVec3::new(1.0, 2.0, 0.0),
            axis: DVec3::Y,
            degrees_per_frame: 90.0,
            width: 8,
            height: 8,
            intrinsics: None,
        };
        let c1 = path.camera_at(1).expect("ok");
        // −z side turned by +90° about +y goes to the −x side.
        assert_relative_eq!(c1.position, DVec3::new(-7.0, 2.0, 0.0), epsilon = 1e-12);
        assert_relative_eq!(c1.forward, DVec3::X, epsilon = 1e-12);
        let c4 = path.camera_at(4).expect("ok");
        assert_relative_eq!(c4.position, start.position, epsilon = 1e-12);
    }

    #[test]
    fn linear_keyframes_hold_outside_and_interpolate_inside() {
        let keys = [key(10, 0.0), key(20, 10.0)];
        let at = |t| interpolate(&keys, Interpolation::Linear, t).expect("ok");
        assert_eq!(at(0.0).position.x, 0.0);
        assert_eq!(at(25.0).position.x, 10.0);
        assert_relative_eq!(at(12.5).position.x, 2.5, epsilon = 1e-12);
        assert_relative_eq!(at(12.5).fov_y, 32.5, epsilon = 1e-12);
    }

    #[test]
    fn catmull_rom_passes_through_keys_and_matches_the_uniform_spline() {
        let keys = [key(0, 0.0), key(1, 1.0), key(2, 4.0), key(3, 9.0)];
        for k in &keys {
            let v = interpolate(&keys, Interpolation::CatmullRom, k.frame as f64).expect("ok");
            assert_relative_eq!(v.position, k.position, epsilon = 1e-12);
        }
        // Uniform Catmull–Rom on P0..P3 at s = 0.5 of the middle segment:
        // 0.5·(2P1 + (−P0 + P2)s + (2P0 − 5P1 + 4P2 − P3)s² + (−P0 + 3P1 − 3P2 + P3)s³).
        let (p0, p1, p2, p3, s) = (0.0, 1.0, 4.0, 9.0, 0.5f64);
        let uniform = 0.5
            * (2.0 * p1
                + (-p0 + p2) * s
                + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * s * s
                + (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * s * s * s);
        let v = interpolate(&keys, Interpolation::CatmullRom, 1.5).expect("ok");
        assert_relative_eq!(v.position.x, uniform, epsilon = 1e-12);
        // fov_y stays linear.
        assert_relative_eq!(v.fov_y, 32.5, epsilon = 1e-12);
    }

    #[test]
    fn degenerate_frames_are_errors_naming_the_frame() {
        let mut b = key(10, 0.0);
        b.position = DVec3::new(0.0, 10.0, 0.0);
        b.up = DVec3::Y;
        let path = CameraPath::Keyframes {
            keys: vec![key(0, 0.0), b],
            interpolation: Interpolation::Linear,
            width: 4,
            height: 4,
        };
        assert!(path.camera_at(3).is_ok());
        let e = path.camera_at(10).unwrap_err();
        assert!(e.contains("frame 10") && e.contains("parallel"), "{e}");
    }
}
