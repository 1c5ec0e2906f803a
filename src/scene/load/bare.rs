//! A bare particle file (no scene file): the default scene of docs/design.md §1 "A bare
//! particle file" around the file's particles: the framed camera, the thesis's two lights,
//! `[render]` and `[defaults]` at their defaults, the command line's overrides.

use super::super::file::ParticleDefaults;
use super::super::framing::{default_camera, thesis_lights, DEFAULT_SIZE};
use super::super::provenance::{Origin, ParticleOrigin, ParticleSource, Provenance};
use super::super::{IncludeSpec, RenderSettings, Scene, SceneLoadOptions};
use super::defaults::ResolvedDefaults;
use super::particles::record_particle;
use super::{camera, render, IncludeGroup, Loaded, ParticleMaker};
use crate::error::{At, Location, Result};
use crate::geometry::CameraPath;
use std::path::Path;

/// The default scene around the particle file `path` (read as `options.format`, else by its
/// extension), with what a sequence of frames needs ([`Loaded`]).
pub(in crate::scene) fn load_bare(path: &Path, options: &SceneLoadOptions) -> Result<Loaded> {
    let whole = At::whole(path);
    let mut provenance = Provenance::default();
    let render = render::apply_overrides(RenderSettings::default(), options, &mut provenance)?;
    let defaults = ResolvedDefaults::new(&whole, &ParticleDefaults::default())?;
    let spec = IncludeSpec {
        format: options.format,
        ..IncludeSpec::bare(path)
    };
    let loaded = crate::formats::load_particles(&spec)?;
    let particles = loaded
        .records
        .iter()
        .map(|rec| record_particle(path, rec, &defaults, render.lambda, None))
        .collect::<Result<Vec<_>>>()?;
    provenance.push_particles(ParticleOrigin {
        source: ParticleSource::File,
        line: None,
        profile: defaults.density,
        density: Origin::Default,
    });
    let mut warnings = loaded.warnings;
    if particles.is_empty() {
        warnings.push(format!(
            "{}: the file has no particles; it renders the background",
            path.display()
        ));
    }
    let (w, h) = options.size.unwrap_or(DEFAULT_SIZE);
    camera::check_size(&whole, w as i64, h as i64)?;
    let camera = default_camera(&particles, w, h);
    let range = 0..particles.len();
    Ok(Loaded {
        scene: Scene {
            source: path.to_path_buf(),
            camera,
            render,
            lights: thesis_lights(),
            particles,
            warnings,
            provenance,
        },
        camera_path: CameraPath::Fixed(camera),
        includes: vec![IncludeGroup {
            spec: IncludeSpec::bare(path),
            location: Location::File,
            range,
        }],
        maker: ParticleMaker {
            defaults,
            lambda: render.lambda,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::models;
    use crate::scene::RenderMode;

    fn csv(dir: &Path) -> std::path::PathBuf {
        let path = dir.join("p.csv");
        std::fs::write(&path, "x,y,z,radius\n0,0,0,1\n3,0,0,0.5\n").unwrap();
        path
    }

    #[test]
    fn a_bare_file_gets_the_default_scene() {
        let dir = tempfile::tempdir().unwrap();
        let path = csv(dir.path());
        let s = Scene::load(&path, &SceneLoadOptions::default()).unwrap();
        assert_eq!(s.particles.len(), 2);
        assert_eq!(s.lights, thesis_lights());
        assert_eq!(s.render, RenderSettings::default());
        assert_eq!((s.camera.width, s.camera.height), DEFAULT_SIZE);
        assert_eq!(s.camera, default_camera(&s.particles, 512, 512));
        // Θmax = 0.5 over radius 1.
        assert!((s.particles[0].sigma - 2f64.ln() / 2.0).abs() < 1e-15);
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        assert_eq!(s.provenance.particles[0].source, ParticleSource::File);
    }

    #[test]
    fn overrides_apply_and_are_remembered_as_flags() {
        let dir = tempfile::tempdir().unwrap();
        let path = csv(dir.path());
        let o = SceneLoadOptions {
            size: Some((16, 8)),
            mode: Some(RenderMode::Opaque),
            model: Some(models::EMISSION),
            tol: Some(1e-3),
            format: None,
        };
        let s = Scene::load(&path, &o).unwrap();
        assert_eq!((s.camera.width, s.camera.height), (16, 8));
        assert_eq!(
            (s.render.mode, s.render.model, s.render.tol),
            (RenderMode::Opaque, models::EMISSION, 1e-3)
        );
        assert_eq!(
            (s.provenance.mode, s.provenance.model),
            (Origin::Flag("--mode"), Origin::Flag("--model"))
        );
        let e = Scene::load(
            &path,
            &SceneLoadOptions {
                size: Some((0, 8)),
                ..SceneLoadOptions::default()
            },
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with(&format!("{}: image size", path.display())),
            "{e}"
        );
    }

    #[test]
    fn a_refusal_names_the_file_and_the_flag() {
        let dir = tempfile::tempdir().unwrap();
        let path = csv(dir.path());
        let o = SceneLoadOptions {
            mode: Some(RenderMode::Opaque),
            ..SceneLoadOptions::default()
        };
        let mut s = Scene::load(&path, &o).unwrap();
        // A bare file's particles are of constant density; made Gaussian here to see the message.
        s.provenance.particles[0].profile = crate::optics::Profile::Gaussian;
        let e = s
            .gaussians_refused(crate::scene::Setting::Mode, "no surface")
            .to_string();
        assert_eq!(
            e,
            format!(
                "{}: --mode opaque: no surface; the Gaussians: the particle file (the default)",
                path.display()
            )
        );
    }
}
