//! The camera of docs/design.md §1 as the matrices a rasterising engine wants: a right-handed view
//! matrix and a perspective projection per graphics API, with near/far planes from the scene's
//! bounds, so that an outside renderer draws exactly the frame pgt's reference draws.
//!
//! Every matrix acts on column vectors, clip = P·V·(x, y, z, 1)ᵀ. After the perspective divide
//! ndc = clip.xyz / clip.w, each API maps ndc to window coordinates in its own way (see
//! [`GraphicsApi::pixel_of_ndc`]); in all of them the pixel (px, py) of pgt's image, py down, has
//! its centre at window coordinate (px + 0.5, py + 0.5) measured from the image's top-left corner,
//! which is exactly where docs/design.md §1 sends its ray and where rasterisers sample fragments.
//!
//! The projection is derived from pgt's frame, not the other way round: with view-space
//! coordinates (x, y, z) = (r·v, u·v, −f·v) of a vector v from the eye, the reference's ray
//! direction f + a·r + b·u gives x/(−z) = a and y/(−z) = b, so ndc.x = a / (aspect·tan(fov_y/2))
//! and ndc.y = b / tan(fov_y/2) reproduce a = (2x_pix/W − 1)·aspect·tan(fov_y/2) and
//! b = (1 − 2y_pix/H)·tan(fov_y/2).

use super::Camera;
use glam::{DMat3, DMat4, DQuat, DVec3, DVec4};

/// A graphics API's clip-space conventions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GraphicsApi {
    /// OpenGL: ndc z in [−1, 1], ndc y up, window origin bottom-left.
    OpenGl,
    /// Vulkan: ndc z in [0, 1], ndc y **down** (the projection flips y), framebuffer origin
    /// top-left.
    Vulkan,
    /// WebGPU (and Metal): ndc z in [0, 1], ndc y up, framebuffer origin top-left.
    WebGpu,
    /// Direct3D 11/12: ndc z in [0, 1], ndc y up, viewport origin top-left (the same matrix as
    /// WebGPU for a right-handed view).
    Direct3D,
}

impl GraphicsApi {
    /// Every API, in the order `pgt camera` prints them.
    pub const ALL: [GraphicsApi; 4] = [
        GraphicsApi::OpenGl,
        GraphicsApi::Vulkan,
        GraphicsApi::WebGpu,
        GraphicsApi::Direct3D,
    ];

    /// The key used in `pgt camera --json`.
    pub fn key(self) -> &'static str {
        match self {
            GraphicsApi::OpenGl => "opengl",
            GraphicsApi::Vulkan => "vulkan",
            GraphicsApi::WebGpu => "webgpu",
            GraphicsApi::Direct3D => "direct3d",
        }
    }

    /// The depth range of ndc z.
    pub fn depth_range(self) -> (f64, f64) {
        match self {
            GraphicsApi::OpenGl => (-1.0, 1.0),
            _ => (0.0, 1.0),
        }
    }

    /// Continuous pgt image coordinates (x right, y down from the top-left corner, in pixels)
    /// of a normalised device coordinate, following the API's viewport transform for a viewport
    /// covering the whole W×H image.
    pub fn pixel_of_ndc(self, ndc: DVec3, width: u32, height: u32) -> (f64, f64) {
        let (w, h) = (width as f64, height as f64);
        let x = (ndc.x + 1.0) * 0.5 * w;
        let y = match self {
            // Vulkan's projection already flipped y, so ndc y grows downwards like the rows.
            GraphicsApi::Vulkan => (ndc.y + 1.0) * 0.5 * h,
            // OpenGL's window y grows upwards (row H − 1 − py); WebGPU and Direct3D flip y in
            // the viewport transform. Either way the image row counted from the top is this.
            _ => (1.0 - ndc.y) * 0.5 * h,
        };
        (x, y)
    }

    /// How window coordinates relate to pgt's pixels, in words.
    pub fn convention(self) -> &'static str {
        match self {
            GraphicsApi::OpenGl => {
                "clip z in [-1, 1]; ndc y up; window origin bottom-left: pgt pixel (px, py) is \
                 the fragment with gl_FragCoord.xy = (px + 0.5, H - py - 0.5); read the image back \
                 bottom-up (glReadPixels) and flip it to get pgt's row order"
            }
            GraphicsApi::Vulkan => {
                "clip z in [0, 1]; the matrix flips y (Vulkan's ndc y points down) so that with a \
                 viewport (0, 0, W, H) pgt pixel (px, py) is the fragment at FragCoord.xy = \
                 (px + 0.5, py + 0.5), row 0 at the top"
            }
            GraphicsApi::WebGpu => {
                "clip z in [0, 1]; ndc y up; the viewport maps ndc y = 1 to the top row: pgt pixel \
                 (px, py) is the fragment at @builtin(position).xy = (px + 0.5, py + 0.5)"
            }
            GraphicsApi::Direct3D => {
                "clip z in [0, 1]; ndc y up; the viewport maps ndc y = 1 to the top row: pgt pixel \
                 (px, py) is the pixel at SV_Position.xy = (px + 0.5, py + 0.5); the same matrix \
                 as WebGPU (right-handed view). DirectXMath multiplies row vectors (v·M): its \
                 XMFLOAT4X4 is the transpose, i.e. the column_major numbers in order"
            }
        }
    }
}

/// Fraction of the scene's depth extent added in front of and behind it, so that spheres that
/// touch the near or far bound are not clipped by float rounding in the engine.
const DEPTH_MARGIN: f64 = 0.01;
/// The near plane is never closer than this fraction of the far plane: an eye inside the
/// particles' bounds would otherwise get near → 0 and no depth precision at all.
const MIN_NEAR_OVER_FAR: f64 = 1e-4;
/// Near and far planes of a scene without a particle in front of the camera (metres).
const EMPTY_NEAR_FAR: (f64, f64) = (0.01, 1000.0);

/// Near and far clip distances (along the viewing direction f) that enclose every sphere in
/// front of the eye: near = min(f·(c − eye) − r), far = max(f·(c − eye) + r), widened by
/// [`DEPTH_MARGIN`], with near ≥ [`MIN_NEAR_OVER_FAR`]·far (parts of spheres closer than that,
/// or behind the eye, are clipped; the reference sees them only when the eye is inside them).
pub fn near_far(camera: &Camera, spheres: impl IntoIterator<Item = (DVec3, f64)>) -> (f64, f64) {
    let (mut near, mut far) = (f64::INFINITY, f64::NEG_INFINITY);
    for (c, r) in spheres {
        let d = camera.forward.dot(c - camera.position);
        near = near.min(d - r);
        far = far.max(d + r);
    }
    if !far.is_finite() || far <= 0.0 {
        return EMPTY_NEAR_FAR;
    }
    let extent = (far - near.max(0.0)).max(far * MIN_NEAR_OVER_FAR);
    let far = far + DEPTH_MARGIN * extent;
    let near = (near - DEPTH_MARGIN * extent).max(far * MIN_NEAR_OVER_FAR);
    (near, far)
}

/// The view matrix of docs/design.md §1's camera frame: world → view space, right-handed, the camera
/// at the origin looking down −z with +x = r (right) and +y = u (up). Rows: r, u, −f, with the
/// translation −(r·eye, u·eye, −f·eye). Equal to glam's `look_at_rh(eye, look_at, up)`.
pub fn view_matrix(camera: &Camera) -> DMat4 {
    let (r, u, f, e) = (camera.right, camera.up, camera.forward, camera.position);
    DMat4::from_cols(
        DVec4::new(r.x, u.x, -f.x, 0.0),
        DVec4::new(r.y, u.y, -f.y, 0.0),
        DVec4::new(r.z, u.z, -f.z, 0.0),
        DVec4::new(-r.dot(e), -u.dot(e), f.dot(e), 1.0),
    )
}

/// The perspective projection of `api` for the camera's lens and W/H, mapping view depth
/// −z = near to the API's near depth and −z = far to its far depth. A fov_y camera's is built
/// from tan(fov_y/2) itself (not from fov_y through tan ∘ atan) so that pixels land where the
/// reference's rays go to the last bit: ndc.x = x / (−z · aspect · tan(fov_y/2)),
/// ndc.y = ±y / (−z · tan(fov_y/2)). With intrinsics, x_pix = cx + fx·x/(−z) and
/// y_pix = cy − fy·y/(−z) give ndc.x = 2x_pix/W − 1 = (2fx/W)·x/(−z) + (2cx/W − 1) and
/// ndc.y = 1 − 2y_pix/H = (2fy/H)·y/(−z) + (1 − 2cy/H): the offsets sit in the z column.
pub fn projection_matrix(camera: &Camera, api: GraphicsApi, near: f64, far: f64) -> DMat4 {
    let (sx, sy, ox, oy) = match &camera.intrinsics {
        None => {
            let aspect = camera.width as f64 / camera.height as f64;
            let sy = 1.0 / camera.tan_half_fov;
            (sy / aspect, sy, 0.0, 0.0)
        }
        Some(k) => {
            let (w, h) = (camera.width as f64, camera.height as f64);
            (
                2.0 * k.fx / w,
                2.0 * k.fy / h,
                1.0 - 2.0 * k.cx / w,
                2.0 * k.cy / h - 1.0,
            )
        }
    };
    // Vulkan's ndc y points down. 0 − oy keeps a centred camera's entry +0, not −0.
    let (sy, oy) = if api == GraphicsApi::Vulkan {
        (-sy, 0.0 - oy)
    } else {
        (sy, oy)
    };
    // Depth: ndc z = (A·z + B) / (−z) with z = −near ↦ z_lo and z = −far ↦ z_hi.
    let (a, b) = match api {
        GraphicsApi::OpenGl => ((far + near) / (near - far), 2.0 * far * near / (near - far)),
        _ => (far / (near - far), far * near / (near - far)),
    };
    DMat4::from_cols(
        DVec4::new(sx, 0.0, 0.0, 0.0),
        DVec4::new(0.0, sy, 0.0, 0.0),
        DVec4::new(ox, oy, a, -1.0),
        DVec4::new(0.0, 0.0, b, 0.0),
    )
}

/// Projects a world point with `api`'s matrices to continuous pgt image coordinates (x, y in
/// pixels from the top-left corner) and ndc depth; `None` behind the eye (clip w ≤ 0).
pub fn project(
    camera: &Camera,
    api: GraphicsApi,
    near: f64,
    far: f64,
    point: DVec3,
) -> Option<(f64, f64, f64)> {
    let clip = projection_matrix(camera, api, near, far) * view_matrix(camera) * point.extend(1.0);
    if clip.w <= 0.0 {
        return None;
    }
    let ndc = clip.truncate() / clip.w;
    let (x, y) = api.pixel_of_ndc(ndc, camera.width, camera.height);
    Some((x, y, ndc.z))
}

/// A 4×4 matrix written out both ways.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct MatrixJson {
    /// The 16 entries column after column (OpenGL `glUniformMatrix4fv(…, GL_FALSE, …)`, glam,
    /// GLSL/WGSL/HLSL default packing).
    pub column_major: [f64; 16],
    /// The 16 entries row after row (a C array `m[row][col]`).
    pub row_major: [[f64; 4]; 4],
}

impl MatrixJson {
    /// Both layouts of `m`.
    pub fn of(m: &DMat4) -> Self {
        let t = m.transpose();
        MatrixJson {
            column_major: m.to_cols_array(),
            row_major: [
                t.x_axis.to_array(),
                t.y_axis.to_array(),
                t.z_axis.to_array(),
                t.w_axis.to_array(),
            ],
        }
    }

    /// The matrix back from its column-major entries.
    pub fn to_mat4(&self) -> DMat4 {
        DMat4::from_cols_array(&self.column_major)
    }
}

/// One API's projection.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct ProjectionJson {
    /// ndc depth of the near and far planes.
    pub depth_range: [f64; 2],
    /// The window-coordinate convention in words.
    pub convention: String,
    pub matrix: MatrixJson,
}

/// What `pgt camera --json` prints: docs/design.md §1's camera and the matrices of every API.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct CameraJson {
    /// Eye position (world, metres).
    pub eye: [f64; 3],
    /// eye + f: the point one unit in front of the eye on the view axis. It is not the scene's
    /// `look_at` (which may lie anywhere on that axis, and which a framed or moving camera does
    /// not have); as the target of a look-at function it gives the same view matrix.
    pub eye_plus_forward: [f64; 3],
    /// Unit viewing direction f (the scene's normalize(look_at − position)).
    pub forward: [f64; 3],
    /// Unit r = normalize(f × up): image x grows along it.
    pub right: [f64; 3],
    /// Unit u = r × f: image y (rows) grows against it.
    pub up: [f64; 3],
    /// Full vertical field of view, degrees.
    pub fov_y_deg: f64,
    /// Full horizontal field of view, degrees: 2·atan(aspect·tan(fov_y/2)).
    pub fov_x_deg: f64,
    /// tan(fov_y/2), exactly as the reference uses it.
    pub tan_half_fov_y: f64,
    pub width: u32,
    pub height: u32,
    /// width / height.
    pub aspect: f64,
    /// Clip distances along f, from the scene's bounds ([`near_far`]).
    pub near: f64,
    pub far: f64,
    /// The sampling convention in words.
    pub pixel_convention: String,
    /// How the matrices multiply and how they are written out.
    pub matrix_convention: String,
    /// World → view (right-handed, camera looks down −z).
    pub view: MatrixJson,
    /// Keyed by API: `opengl`, `vulkan`, `webgpu`, `direct3d`.
    pub projection: std::collections::BTreeMap<String, ProjectionJson>,
    /// The scene's background radiance L_bg (linear RGB): what an engine clears to.
    pub background: [f64; 3],
    /// Focal lengths and principal point, pixels (docs/design.md §1 "Intrinsics"); a fov_y
    /// camera's are fx = fy = (H/2)/tan(fov_y/2), cx = W/2, cy = H/2.
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    /// The intrinsic matrix [[fx, 0, cx], [0, fy, cy], [0, 0, 1]], row by row.
    #[serde(rename = "K")]
    pub k: [[f64; 3]; 3],
    /// The OpenCV world-to-camera rotation (camera x right, y down, z forward), row by row: its
    /// rows are r, −u, f. A scene's `[camera] R` with `position = eye` is this camera again.
    #[serde(rename = "R")]
    pub r: [[f64; 3]; 3],
    /// The OpenCV world-to-camera translation t = −R·eye (x_cam = R·x_world + t).
    pub t: [f64; 3],
    /// COLMAP's `images.txt` pose: the unit quaternion (w, x, y, z) of R, w ≥ 0.
    pub colmap_qvec: [f64; 4],
    /// COLMAP's tvec: t.
    pub colmap_tvec: [f64; 3],
    /// The camera-to-world matrix of NeRF's and nerfstudio's `transforms.json` (OpenGL camera
    /// axes: x right, y up, z back), row by row: columns r, u, −f and the eye.
    pub nerfstudio_camera_to_world: [[f64; 4]; 4],
}

/// docs/design.md §1's pixel-centre convention, in words.
pub const PIXEL_CONVENTION: &str = "pixel (px, py), px to the right and py down (row 0 is the \
top), is sampled by one ray through its centre (px + 0.5, py + 0.5): a = (2(px+0.5)/W - 1)·\
(W/H)·tan(fov_y/2), b = (1 - 2(py+0.5)/H)·tan(fov_y/2), direction = normalize(f + a·r + b·u); \
this is where rasterisers put fragment centres, so no half-pixel offset is needed";

/// How the matrices are to be read, in words.
pub const MATRIX_CONVENTION: &str = "column vectors: clip = projection · view · (x, y, z, 1)^T, \
ndc = clip.xyz / clip.w; `column_major` lists the 16 entries column after column (OpenGL with \
transpose = GL_FALSE, glam, GLSL/WGSL/HLSL default packing), `row_major` lists the rows \
(m[row][col]); view space is right-handed with the camera looking down -z";

impl CameraJson {
    /// The camera and its matrices; `spheres` (centre, radius) set near and far.
    pub fn new(
        camera: &Camera,
        spheres: impl IntoIterator<Item = (DVec3, f64)>,
        background: DVec3,
    ) -> Self {
        let (near, far) = near_far(camera, spheres);
        let aspect = camera.width as f64 / camera.height as f64;
        let projection = GraphicsApi::ALL
            .iter()
            .map(|&api| {
                let (lo, hi) = api.depth_range();
                (
                    api.key().to_string(),
                    ProjectionJson {
                        depth_range: [lo, hi],
                        convention: api.convention().to_string(),
                        matrix: MatrixJson::of(&projection_matrix(camera, api, near, far)),
                    },
                )
            })
            .collect();
        let k = camera.pinhole();
        let rotation = camera.world_to_camera_rotation();
        let t = -(rotation * camera.position);
        let (r, u, f, e) = (camera.right, camera.up, camera.forward, camera.position);
        let (fov_y_deg, fov_x_deg) = match camera.intrinsics {
            None => (
                2.0 * camera.tan_half_fov.atan().to_degrees(),
                2.0 * (aspect * camera.tan_half_fov).atan().to_degrees(),
            ),
            Some(k) => (
                span_deg(k.cy, camera.height, k.fy),
                span_deg(k.cx, camera.width, k.fx),
            ),
        };
        CameraJson {
            eye: camera.position.to_array(),
            eye_plus_forward: (camera.position + camera.forward).to_array(),
            forward: camera.forward.to_array(),
            right: camera.right.to_array(),
            up: camera.up.to_array(),
            fov_y_deg,
            fov_x_deg,
            tan_half_fov_y: camera.tan_half_fov,
            width: camera.width,
            height: camera.height,
            aspect,
            near,
            far,
            pixel_convention: PIXEL_CONVENTION.to_string(),
            matrix_convention: MATRIX_CONVENTION.to_string(),
            view: MatrixJson::of(&view_matrix(camera)),
            projection,
            background: background.to_array(),
            fx: k.fx,
            fy: k.fy,
            cx: k.cx,
            cy: k.cy,
            k: [[k.fx, 0.0, k.cx], [0.0, k.fy, k.cy], [0.0, 0.0, 1.0]],
            r: [rotation.row(0), rotation.row(1), rotation.row(2)].map(|v| v.to_array()),
            t: t.to_array(),
            colmap_qvec: colmap_qvec(rotation),
            colmap_tvec: t.to_array(),
            nerfstudio_camera_to_world: [
                [r.x, u.x, -f.x, e.x],
                [r.y, u.y, -f.y, e.y],
                [r.z, u.z, -f.z, e.z],
                [0.0, 0.0, 0.0, 1.0],
            ],
        }
    }
}

/// The full angle (degrees) that the pixels [0, size] span about the principal point c with
/// focal length f: atan(c/f) + atan((size − c)/f).
fn span_deg(c: f64, size: u32, f: f64) -> f64 {
    ((c / f).atan() + ((size as f64 - c) / f).atan()).to_degrees()
}

/// COLMAP's qvec (w, x, y, z) of the rotation R, with w ≥ 0.
pub fn colmap_qvec(rotation: DMat3) -> [f64; 4] {
    let q = DQuat::from_mat3(&rotation).normalize();
    let q = if q.w < 0.0 { -q } else { q };
    [q.w, q.x, q.y, q.z]
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn camera() -> Camera {
        Camera::new(
            DVec3::new(1.0, 2.0, -10.0),
            DVec3::new(0.5, 0.0, 0.0),
            DVec3::Y,
            40.0,
            64,
            48,
        )
    }

    #[test]
    fn view_matrix_is_glams_look_at_rh() {
        let cam = camera();
        let want = DMat4::look_at_rh(cam.position, DVec3::new(0.5, 0.0, 0.0), DVec3::Y);
        assert!(view_matrix(&cam).abs_diff_eq(want, 1e-12));
    }

    #[test]
    fn projections_match_glam_for_the_same_fov() {
        let cam = camera();
        let (n, f) = (0.5, 40.0);
        let fov = 2.0 * cam.tan_half_fov.atan();
        let aspect = 64.0 / 48.0;
        let gl = DMat4::perspective_rh_gl(fov, aspect, n, f);
        assert!(projection_matrix(&cam, GraphicsApi::OpenGl, n, f).abs_diff_eq(gl, 1e-12));
        let zo = DMat4::perspective_rh(fov, aspect, n, f);
        assert!(projection_matrix(&cam, GraphicsApi::WebGpu, n, f).abs_diff_eq(zo, 1e-12));
        assert!(projection_matrix(&cam, GraphicsApi::Direct3D, n, f).abs_diff_eq(zo, 1e-12));
    }

    #[test]
    fn near_and_far_planes_map_to_the_depth_range() {
        let cam = camera();
        let (n, f) = (0.5, 40.0);
        for api in GraphicsApi::ALL {
            let (lo, hi) = api.depth_range();
            let at = |d: f64| project(&cam, api, n, f, cam.position + d * cam.forward).unwrap();
            assert_relative_eq!(at(n).2, lo, epsilon = 1e-12);
            assert_relative_eq!(at(f).2, hi, epsilon = 1e-12);
        }
    }

    #[test]
    fn near_far_enclose_the_spheres() {
        let cam = camera();
        let spheres = [(DVec3::ZERO, 1.0), (DVec3::new(0.0, 0.0, 5.0), 2.0)];
        let (n, f) = near_far(&cam, spheres);
        for (c, r) in spheres {
            let d = cam.forward.dot(c - cam.position);
            assert!(n < d - r && d + r < f, "{n} {f} {d} {r}");
        }
        assert_eq!(near_far(&cam, []), EMPTY_NEAR_FAR);
    }
}
