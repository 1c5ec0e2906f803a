//! The TOML scene file of docs/design.md §1, as serde types. Every table denies unknown fields so a
//! misspelt key is an error, not a silently ignored setting. Tables are `Spanned` so validation
//! can name the line.

use super::{Falloff, LightWeight, Model, RenderMode};
use crate::formats::IncludeSpec;
use crate::geometry::Interpolation;
use serde::Deserialize;
use toml::Spanned;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    pub camera: Option<Spanned<CameraTable>>,
    pub render: Option<Spanned<RenderTable>>,
    #[serde(default)]
    pub lights: Vec<Spanned<LightTable>>,
    pub defaults: Option<Spanned<ParticleDefaults>>,
    #[serde(default)]
    pub particles: Vec<Spanned<ParticleTable>>,
    #[serde(default)]
    pub include: Vec<Spanned<IncludeSpec>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraTable {
    pub position: Option<[f64; 3]>,
    pub look_at: Option<[f64; 3]>,
    pub up: Option<[f64; 3]>,
    pub fov_y: Option<f64>,
    pub focal_length: Option<f64>,
    /// Pinhole intrinsics in pixels, instead of fov_y (docs/design.md §1 "Intrinsics").
    pub fx: Option<f64>,
    pub fy: Option<f64>,
    pub cx: Option<f64>,
    pub cy: Option<f64>,
    /// The OpenCV world-to-camera rotation, row by row, instead of look_at and up.
    #[serde(rename = "R")]
    pub r: Option<[[f64; 3]; 3]>,
    /// The OpenCV world-to-camera translation, with `R`, instead of position.
    pub t: Option<[f64; 3]>,
    /// A dataset's cameras (docs/design.md §1 "Cameras of datasets"): a COLMAP model folder, a
    /// NeRF `transforms.json` or a 3DGS `cameras.json`, relative to the scene file.
    pub from: Option<String>,
    /// With `from`: the one image whose camera this is; without it every image is a frame.
    pub image: Option<String>,
    /// With `from` a `transforms.json`: nerfstudio's `dataparser_transforms.json` of the trained
    /// model, which maps the dataset's cameras into the model's frame (relative to the scene
    /// file).
    pub dataparser: Option<String>,
    pub width: Option<i64>,
    pub height: Option<i64>,
    /// `[camera.orbit]`: the camera turns about an axis (docs/design.md §10).
    pub orbit: Option<Spanned<OrbitTable>>,
    /// `[[camera.keyframes]]`: the camera follows interpolated keyframes (docs/design.md §10).
    #[serde(default)]
    pub keyframes: Vec<Spanned<KeyframeTable>>,
    /// How keyframes are interpolated: `"linear"` (default) or `"catmull-rom"`.
    pub interpolation: Option<Interpolation>,
}

/// `[camera.orbit]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct OrbitTable {
    pub axis: [f64; 3],
    pub degrees_per_frame: f64,
    /// The centre of the turn; default the particles' centre at frame 0.
    pub center: Option<[f64; 3]>,
}

/// One `[[camera.keyframes]]` table.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct KeyframeTable {
    pub frame: i64,
    pub position: [f64; 3],
    pub look_at: [f64; 3],
    pub up: Option<[f64; 3]>,
    pub fov_y: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RenderTable {
    pub mode: Option<RenderMode>,
    pub model: Option<Model>,
    pub background: Option<[f64; 3]>,
    pub lambda: Option<f64>,
    pub light_weight: Option<LightWeight>,
    pub emission_weight: Option<f64>,
    pub ambient: Option<f64>,
    pub tol: Option<f64>,
    pub gaussian_cutoff: Option<f64>,
}

/// One `[[lights]]` table. A flat struct rather than a tagged enum: serde buffers tagged enums,
/// which loses the line of a bad field; the per-type requirements are checked in validation.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LightTable {
    #[serde(rename = "type")]
    pub kind: LightKind,
    pub direction: Option<[f64; 3]>,
    pub irradiance: Option<[f64; 3]>,
    pub position: Option<[f64; 3]>,
    pub intensity: Option<[f64; 3]>,
    pub falloff: Option<Falloff>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub(super) enum LightKind {
    Directional,
    Point,
}

/// `[defaults]`: values for every particle that does not set its own.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ParticleDefaults {
    pub color: Option<[f64; 3]>,
    pub opacity: Option<f64>,
    pub kappa: Option<f64>,
    pub albedo: Option<[f64; 3]>,
    pub ks: Option<f64>,
    pub shininess: Option<f64>,
    /// The density profile (docs/design.md §9), `"constant"` by default.
    pub density: Option<crate::optics::Profile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ParticleTable {
    pub center: [f64; 3],
    /// A sphere's radius; an ellipsoid gives `semi_axes` instead (docs/design.md §9).
    pub radius: Option<f64>,
    pub semi_axes: Option<[f64; 3]>,
    /// The ellipsoid's orientation (w, x, y, z), body to world; normalised, identity if absent.
    pub rotation: Option<[f64; 4]>,
    pub color: Option<[f64; 3]>,
    pub opacity: Option<f64>,
    pub kappa: Option<f64>,
    pub albedo: Option<[f64; 3]>,
    pub ks: Option<f64>,
    pub shininess: Option<f64>,
    pub density: Option<crate::optics::Profile>,
}
