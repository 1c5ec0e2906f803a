//! Scene loading: a TOML scene file (or a bare particle file) becomes a [`Scene`], or an error
//! that names the file, the line and the field (docs/design.md §6 "Bad input"). One module per
//! step, in the order a scene file is loaded:
//!
//! 1. `[render]` and the command-line overrides ([`render`]);
//! 2. `[defaults]`, checked once ([`defaults`]);
//! 3. the inline `[[particles]]` (and particles a program gives), and the records a file
//!    delivers, as particles ([`particles`]);
//! 4. each `[[include]]`'s files, read ([`includes`]);
//! 5. `[[lights]]` ([`lights`]);
//! 6. the camera of every frame: fixed, orbiting or keyframed ([`camera`], [`orbit`],
//!    [`keyframes`]);
//!
//! and [`bare`], the default scene around a bare particle file. What a sequence of frames needs
//! besides frame 0 ([`Loaded`]) is kept for `scene::frames`.

mod bare;
mod camera;
mod dataset_camera;
mod defaults;
mod includes;
mod keyframes;
mod lights;
mod orbit;
mod particles;
mod render;

pub(super) use bare::load_bare;
pub use render::checked_tol_override;

use super::file::SceneFile;
use super::provenance::Provenance;
use super::{IncludeSpec, ParticleInput, ParticleRecord, Scene, SceneLoadOptions};
use crate::error::{toml_error, Location, Result, SourceText};
use crate::geometry::CameraPath;
use crate::optics::particle::{Particle, Profile};
use defaults::ResolvedDefaults;
use std::path::Path;

/// A validated scene file with what a sequence of frames needs besides frame 0: the camera of
/// every frame, where each include's particles sit in `scene.particles`, and the defaults that
/// turn a file's records into particles.
pub(super) struct Loaded {
    /// Frame 0.
    pub scene: Scene,
    pub camera_path: CameraPath,
    /// The particles of each include, in order, as ranges of `scene.particles` (the inline
    /// particles come first, before every include).
    pub includes: Vec<IncludeGroup>,
    pub maker: ParticleMaker,
}

/// An include and where its frame-0 particles are.
pub(super) struct IncludeGroup {
    /// The include, its paths joined to the scene file's folder.
    pub spec: IncludeSpec,
    /// The scene file's line of the include (the whole file for a bare particle file).
    pub location: Location,
    pub range: std::ops::Range<usize>,
    /// The SH coefficients of its frame-0 particles, where the include asks for the
    /// view-dependent colour (`sh = "view"`, [`super::view_color`]).
    pub sh: Option<std::sync::Arc<crate::formats::ShCoefficients>>,
}

/// Turns a format's records into particles with the scene's `[defaults]` and λ.
pub(super) struct ParticleMaker {
    defaults: ResolvedDefaults,
    lambda: f64,
}

impl ParticleMaker {
    /// A particle of the file `path`, checked with the location the format recorded.
    pub fn particle(
        &self,
        path: &Path,
        rec: &ParticleRecord,
        density: Option<Profile>,
    ) -> Result<Particle> {
        particles::record_particle(path, rec, &self.defaults, self.lambda, density)
    }

    /// Whether a particle's albedo is its colour (no `[defaults] albedo`), so that the albedo
    /// follows a view-dependent colour ([`super::view_color::recolor`]).
    pub fn albedo_follows(&self) -> bool {
        self.defaults.albedo.is_none()
    }
}

/// Gives the particles of every include with SH coefficients the colour seen from `eye` (frame
/// 0's camera position; [`super::view_color`]).
pub(super) fn color_for_eye(
    particles: &mut [Particle],
    includes: &[IncludeGroup],
    eye: glam::DVec3,
    albedo_follows: bool,
) {
    for g in includes {
        if let Some(sh) = &g.sh {
            super::view_color::recolor(&mut particles[g.range.clone()], sh, eye, albedo_follows);
        }
    }
}

/// Scene TOML text as frame 0 ([`Scene::from_toml_str`]).
pub(super) fn scene_from_toml(
    text: &str,
    path: &Path,
    options: &SceneLoadOptions,
) -> Result<Scene> {
    load_toml(text, path, options).map(|l| l.scene)
}

/// Validates scene TOML into frame 0 and what the other frames need ([`Loaded`]).
pub(super) fn load_toml(text: &str, path: &Path, options: &SceneLoadOptions) -> Result<Loaded> {
    load_toml_and_particles(text, path, options, std::iter::empty(), false)
}

/// [`scene_from_toml`] plus `given` particles, each checked as an inline `[[particles]]` table
/// (and numbered after them in messages); with `default_lights`, settings without `[[lights]]`
/// get the thesis's two lights, as a bare particle file does. The settings are a program's
/// text, not a file the user wrote: the scene's [`Provenance`] names no lines.
pub(super) fn scene_from_toml_and_particles(
    text: &str,
    path: &Path,
    options: &SceneLoadOptions,
    given: impl Iterator<Item = ParticleInput>,
    default_lights: bool,
) -> Result<Scene> {
    let mut scene = load_toml_and_particles(text, path, options, given, default_lights)?.scene;
    scene.provenance = std::mem::take(&mut scene.provenance).without_lines();
    Ok(scene)
}

/// A bare particle file with the default scene of docs/design.md §1 ([`bare::load_bare`]).
pub(super) fn bare_particle_file(path: &Path, options: &SceneLoadOptions) -> Result<Scene> {
    load_bare(path, options).map(|l| l.scene)
}

/// `--density` and `--sh` choose for a bare particle file; a scene file says it with its keys.
fn refuse_bare_file_flags(path: &Path, options: &SceneLoadOptions) -> Result<()> {
    let flag = match (options.density, options.sh) {
        (Some(_), _) => "--density: a scene file sets density = \"gaussian\" or \"constant\" in [defaults], [[particles]] or an [[include]]",
        (None, Some(_)) => "--sh: a scene file sets sh = \"view\" or \"dc\" on its [[include]] of a 3D Gaussian splatting PLY",
        (None, None) => return Ok(()),
    };
    Err(crate::error::PgtError::in_file(
        path,
        format!("{flag} (the flag applies to a bare particle file)"),
    ))
}

/// [`load_toml`] with the particles and lights of [`scene_from_toml_and_particles`], step by
/// step (the module doc).
fn load_toml_and_particles(
    text: &str,
    path: &Path,
    options: &SceneLoadOptions,
    given: impl Iterator<Item = ParticleInput>,
    default_lights: bool,
) -> Result<Loaded> {
    let file: SceneFile = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
    refuse_bare_file_flags(path, options)?;
    let source = SourceText { path, text };
    let mut provenance = Provenance::default();
    let render = render::settings(&source, &file.render, options, &mut provenance)?;
    let defaults = defaults::resolve(&source, &file.defaults)?;
    let mut particles = particles::inline(
        &source,
        &file.particles,
        given,
        &defaults,
        render.lambda,
        &mut provenance,
    )?;
    let (includes, mut warnings) = includes::read_all(
        &source,
        &file,
        &defaults,
        render.lambda,
        &mut particles,
        &mut provenance,
    )?;
    let lights = lights::lights(&source, &file.lights, default_lights)?;
    let camera_path = camera::path(&source, &file.camera, options, &particles)?;
    let camera = camera::first(&source, &camera_path, &file.camera)?;
    color_for_eye(
        &mut particles,
        &includes,
        camera.position,
        defaults.albedo.is_none(),
    );
    if particles.is_empty() {
        warnings.push(format!(
            "{}: the scene has no particles; it renders the background",
            path.display()
        ));
    } else {
        warnings.extend(lights::unlit_warning(path, &render, &lights));
    }
    Ok(Loaded {
        scene: Scene {
            source: path.to_path_buf(),
            camera,
            render,
            lights,
            particles,
            warnings,
            provenance,
        },
        camera_path,
        includes,
        maker: ParticleMaker {
            defaults,
            lambda: render.lambda,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(text: &str) -> Result<Scene> {
        Scene::from_toml_str(text, Path::new("s.toml"), &SceneLoadOptions::default())
    }

    #[test]
    fn full_design_example_parses() {
        let text = r#"
[camera]
position = [0.0, 0.0, -10.0]
look_at  = [0.0, 0.0, 0.0]
up       = [0.0, 1.0, 0.0]
fov_y    = 40.0
width    = 64
height   = 32

[render]
mode  = "volume"
model = "lit"
background = [0.0, 0.0, 0.0]
lambda = 1.0
light_weight = "mean"
emission_weight = 0.0
ambient = 0.0
tol = 1e-5

[[lights]]
type = "directional"
direction  = [0.0, -1.0, 0.0]
irradiance = [0.0, 1.0, 0.0]

[[lights]]
type = "point"
position  = [0.0, 5.0, 0.0]
intensity = [10.0, 10.0, 10.0]
falloff   = "inverse-square"

[defaults]
color = [1.0, 1.0, 1.0]
opacity = 0.5
ks = 0.0
shininess = 32.0

[[particles]]
center = [0.0, 0.0, 0.0]
radius = 1.0
color  = [1.0, 0.2, 0.2]
opacity = 0.8
"#;
        let s = load(text).unwrap();
        assert_eq!((s.camera.width, s.camera.height), (64, 32));
        assert_eq!(s.lights.len(), 2);
        let p = s.particles[0];
        assert!((p.sigma - (-(0.2f64).ln() / 2.0)).abs() < 1e-15);
        assert_eq!(p.albedo, p.color);
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    }

    #[test]
    fn a_toml_syntax_error_names_the_line() {
        let e = load("[render]\nmodle = \"lit\"\n").unwrap_err().to_string();
        assert!(e.starts_with("s.toml:2:") && e.contains("modle"), "{e}");
        let e = load("[render]\nmodel = \"glow\"\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("s.toml:2:") && e.contains("glow"), "{e}");
        assert!(e.contains("`emission`, `lit`, `single-scatter`"), "{e}");
    }

    #[test]
    fn empty_scene_is_valid_with_a_warning() {
        // One warning: a scene without particles has nothing that lights could show.
        let s = load("").unwrap();
        assert!(s.particles.is_empty());
        assert_eq!(s.warnings.len(), 1);
        assert!(s.warnings[0].contains("no particles"), "{:?}", s.warnings);
    }

    #[test]
    fn the_provenance_follows_the_steps() {
        let text = "[render]\nmodel = \"emission\"\n[defaults]\ndensity = \"gaussian\"\n[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n";
        let s = load(text).unwrap();
        use crate::scene::provenance::{Origin, ParticleSource};
        assert_eq!(s.provenance.mode, Origin::Default);
        assert_eq!(
            s.provenance.model,
            Origin::Key {
                table: "render",
                key: "model",
                line: Some(1)
            }
        );
        let run = s.provenance.particles[0];
        assert_eq!(run.source, ParticleSource::Inline);
        assert_eq!((run.line, run.profile), (Some(5), Profile::Gaussian));
        assert_eq!(run.density.line(), Some(3));
        // Settings a program gives as text keep their keys, not their lines.
        let s = Scene::from_settings_and_particles(
            text,
            Path::new("program"),
            &SceneLoadOptions::default(),
            std::iter::empty(),
            false,
        )
        .unwrap();
        assert_eq!(s.provenance.model.line(), None);
        assert!(s.provenance.particles.iter().all(|p| p.line.is_none()));
    }
}
