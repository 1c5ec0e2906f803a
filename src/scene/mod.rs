//! The scene model of docs/design.md §1: particles, lights, camera and render settings, already
//! validated and resolved (σ computed, defaults applied). `file` holds the TOML format and
//! `load` turns it into a [`Scene`], step by step, with errors that name the file, line and
//! field; `provenance` keeps where the settings were chosen, for the errors of renderers that
//! refuse a combination of them.

pub mod export;
mod file;
mod frames;
mod framing;
mod load;
mod provenance;
pub mod summary;
mod view_color;

pub use crate::formats::{ColorBy, IncludeSpec, ParticleRecord};
pub use frames::SceneFrames;
pub use framing::{bounding_sphere, default_camera, thesis_lights};
pub use load::checked_tol_override;
pub use provenance::{Origin, ParticleOrigin, ParticleSource, Provenance, Setting};
// The light physics, the resolved particle and the optical models live in `optics` (the scene
// builds on optics, never the reverse); re-exported so that `scene::Light` etc. keep working.
pub use crate::optics::light::{Falloff, Incident, Light, LightWeight};
pub use crate::optics::model::Model;
pub use crate::optics::particle::{Particle, Profile};

use crate::error::{PgtError, Result};
use crate::geometry::Camera;
use glam::DVec3;
use std::path::{Path, PathBuf};

/// `mode` (docs/design.md §1): opaque spheres or spheres of gas.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize, clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum RenderMode {
    /// Solid spheres: the first hit, Lambert + Blinn–Phong, hard shadows.
    Opaque,
    /// Spheres of glowing, absorbing gas (the optical model says how they glow).
    Volume,
}

/// Global render settings, `[render]` of the scene file with the command-line overrides applied.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderSettings {
    pub mode: RenderMode,
    /// The optical model of the volume mode, an entry of `optics::models::ALL`.
    pub model: Model,
    /// L_bg, linear RGB.
    pub background: DVec3,
    /// λ ∈ (0, 1].
    pub lambda: f64,
    pub light_weight: LightWeight,
    /// Single-scatter emission weight a.
    pub emission_weight: f64,
    /// Opaque-mode ambient term (ambient·C).
    pub ambient: f64,
    /// Absolute radiance tolerance of the reference quadrature, per pixel and channel.
    pub tol: f64,
    /// k, the standard deviations at which the reference cuts Gaussian particles
    /// (docs/design.md §9); `None`: chosen from `tol`.
    pub gaussian_cutoff: Option<f64>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            mode: RenderMode::Volume,
            model: crate::optics::models::LIT,
            background: DVec3::ZERO,
            lambda: 1.0,
            light_weight: LightWeight::Mean,
            emission_weight: 1.0,
            ambient: 0.0,
            tol: 1e-5,
            gaussian_cutoff: None,
        }
    }
}

/// A loaded, validated scene.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The file it came from (for messages).
    pub source: PathBuf,
    pub camera: Camera,
    pub render: RenderSettings,
    pub lights: Vec<Light>,
    pub particles: Vec<Particle>,
    /// Non-fatal remarks for the user (an empty scene, skipped shapes, …).
    pub warnings: Vec<String>,
    /// Where the mode, the model and the particles' densities were chosen, for the messages of
    /// renderers that refuse a combination of them ([`Scene::gaussians_refused`]); the default
    /// (nothing chosen anywhere) for a scene a program builds.
    pub provenance: Provenance,
}

/// Command-line overrides of the scene (docs/design.md §1: flags override the scene).
#[derive(Debug, Clone, Default)]
pub struct SceneLoadOptions {
    pub size: Option<(u32, u32)>,
    pub mode: Option<RenderMode>,
    pub model: Option<Model>,
    pub tol: Option<f64>,
    /// `--format`: the format of a bare particle file whatever its extension (a scene file
    /// names the format of each include with `format = "…"`).
    pub format: Option<&'static crate::formats::Format>,
    /// `--density`: the density profile of a bare file's particles (a scene file sets
    /// `density` in `[defaults]`, `[[particles]]` or an include).
    pub density: Option<crate::optics::Profile>,
    /// `--background`: L_bg (linear RGB, ≥ 0), overriding the scene.
    pub background: Option<[f64; 3]>,
    /// `--sh`: the colour of a bare 3D Gaussian splatting PLY, the DC term or the view-dependent
    /// SH from the eye (a scene file sets `sh` on its include).
    pub sh: Option<crate::formats::ShColor>,
}

/// One particle given by a program rather than a file (the Python package's
/// `Scene.from_arrays`): the fields of an inline `[[particles]]` table, checked as that is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParticleInput {
    pub center: [f64; 3],
    /// The sphere's radius; ignored where `semi_axes` makes the particle an ellipsoid.
    pub radius: f64,
    /// An ellipsoid's semi-axes (docs/design.md §9), instead of the radius.
    pub semi_axes: Option<[f64; 3]>,
    /// An ellipsoid's orientation as a quaternion (w, x, y, z), normalised; with `semi_axes`.
    pub rotation: Option<[f64; 4]>,
    /// Linear RGB; `None`: `[defaults]`' colour.
    pub color: Option<[f64; 3]>,
    /// Θmax; set this or `kappa` or neither (then `[defaults]`' or 0.5).
    pub opacity: Option<f64>,
    pub kappa: Option<f64>,
}

/// Largest image side pgt accepts; beyond it a typo (`--size 5120000x512`) would allocate
/// gigabytes before anything useful happens.
pub const MAX_IMAGE_SIDE: u32 = 32768;
/// Largest pixel count (8192²): the reference keeps the image, its error layer and the tile
/// results in memory, about 40 bytes a pixel.
pub const MAX_PIXELS: u64 = 1 << 26;

/// Checks an image size against [`MAX_IMAGE_SIDE`] and [`MAX_PIXELS`]; the error text says why.
pub fn check_image_size(width: i64, height: i64) -> std::result::Result<(u32, u32), String> {
    let max = MAX_IMAGE_SIDE as i64;
    if width < 1
        || height < 1
        || width > max
        || height > max
        || (width * height) as u64 > MAX_PIXELS
    {
        return Err(format!(
            "image size must be between 1 and {MAX_IMAGE_SIDE} pixels on each side and at most {MAX_PIXELS} pixels, got {width}x{height}"
        ));
    }
    Ok((width as u32, height as u32))
}

impl Scene {
    /// Loads a scene: a TOML scene file (`.toml`), or a bare particle file that gets the default
    /// scene of docs/design.md §1.
    pub fn load(path: &Path, options: &SceneLoadOptions) -> Result<Scene> {
        let is_toml = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
        if let (true, Some(format)) = (is_toml, options.format) {
            return Err(PgtError::Usage(format!(
                "--format {} applies to a bare particle file; {} is a scene file, which names the format of each file it includes (`format = \"{}\"` in its [[include]])",
                format.name,
                path.display(),
                format.name
            )));
        }
        if is_toml {
            let text = std::fs::read_to_string(path).map_err(|e| PgtError::io(path, e))?;
            Scene::from_toml_str(&text, path, options)
        } else {
            load::bare_particle_file(path, options)
        }
    }

    /// Parses and validates scene TOML text; `path` names it in messages and anchors includes.
    pub fn from_toml_str(text: &str, path: &Path, options: &SceneLoadOptions) -> Result<Scene> {
        load::scene_from_toml(text, path, options)
    }

    /// A scene from settings and particles given by a program (the Python package's
    /// `Scene.from_arrays`): `settings` is scene-file TOML (camera, render, lights, defaults),
    /// `name` names it in messages, `particles` are checked as inline `[[particles]]` tables
    /// are, and with `default_lights` settings without `[[lights]]` get the thesis's two lights
    /// of a bare particle file (docs/design.md §1).
    pub fn from_settings_and_particles(
        settings: &str,
        name: &Path,
        options: &SceneLoadOptions,
        particles: impl IntoIterator<Item = ParticleInput>,
        default_lights: bool,
    ) -> Result<Scene> {
        load::scene_from_toml_and_particles(
            settings,
            name,
            options,
            particles.into_iter(),
            default_lights,
        )
    }

    /// A BVH over the scene's particles (indices are positions in `particles`).
    pub fn build_bvh(&self) -> crate::geometry::Bvh {
        self.bvh_over(|_| true)
    }

    /// A BVH over the particles with σ > 0 (indices are positions in `particles`): all that
    /// the volume reference sees, since a particle with σ = 0 neither absorbs nor emits.
    pub fn build_gas_bvh(&self) -> crate::geometry::Bvh {
        self.bvh_over(|i| self.particles[i].sigma > 0.0)
    }

    /// Whether any particle is an ellipsoid (docs/design.md §9).
    pub fn has_ellipsoids(&self) -> bool {
        self.particles.iter().any(|p| p.ellipsoid.is_some())
    }

    /// Whether any particle has a Gaussian density (docs/design.md §9).
    pub fn has_gaussians(&self) -> bool {
        self.particles
            .iter()
            .any(|p| p.profile == Profile::Gaussian)
    }

    /// The camera as a rasterising engine wants it (`pgt camera`, docs/design.md §7): eye, basis,
    /// fov, size, the view matrix and a projection matrix per graphics API, with near/far from the
    /// particles' bounds ([`crate::geometry::projection`]).
    pub fn camera_json(&self) -> crate::geometry::projection::CameraJson {
        crate::geometry::projection::CameraJson::new(
            &self.camera,
            self.particles
                .iter()
                .map(|p| (p.center, framing::extent_radius(p))),
            self.render.background,
        )
    }

    /// "11032 spheres", "4 particles, 3 of them ellipsoids" or "1971 Gaussians": the particles of a
    /// summary line.
    pub fn particles_text(&self) -> String {
        let n = self.particles.len();
        if n > 0
            && self
                .particles
                .iter()
                .all(|p| p.profile == Profile::Gaussian)
        {
            return format!("{n} Gaussians");
        }
        let ellipsoids = self
            .particles
            .iter()
            .filter(|p| p.ellipsoid.is_some())
            .count();
        match ellipsoids {
            0 => format!("{} spheres", self.particles.len()),
            n => format!("{} particles, {n} of them ellipsoids", self.particles.len()),
        }
    }

    fn bvh_over(&self, keep: impl Fn(usize) -> bool) -> crate::geometry::Bvh {
        let ellipsoids = if self.has_ellipsoids() {
            self.particles.iter().map(|p| p.ellipsoid).collect()
        } else {
            Vec::new()
        };
        crate::geometry::Bvh::build_shapes(
            self.particles.iter().map(|p| p.center).collect(),
            self.particles.iter().map(|p| p.radius).collect(),
            ellipsoids,
            keep,
        )
    }
}
