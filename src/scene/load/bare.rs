//! A bare particle file (no scene file): the default scene of docs/design.md §1 "A bare
//! particle file" around the file's particles: the framed camera, the thesis's two lights,
//! `[render]` and `[defaults]` at their defaults, the command line's overrides. A PLY in the
//! layout of 3D Gaussian splatting gets what a splatting rasteriser draws of it instead
//! (docs/design.md §1): Gaussian density, the emission model, the SH colour seen from the eye,
//! a black background, framed by the Gaussians' 3σ extent; `--density`, `--model`, `--sh` and
//! `--background` say otherwise.

use super::super::file::ParticleDefaults;
use super::super::framing::{default_camera, thesis_lights, DEFAULT_SIZE};
use super::super::provenance::{Origin, ParticleOrigin, ParticleSource, Provenance};
use super::super::{IncludeSpec, RenderSettings, Scene, SceneLoadOptions};
use super::defaults::ResolvedDefaults;
use super::particles::record_particle;
use super::{camera, render, IncludeGroup, Loaded, ParticleMaker};
use crate::error::{At, Location, Result};
use crate::formats::ShColor;
use crate::geometry::CameraPath;
use crate::optics::Profile;
use std::path::Path;

/// Whether `path`, read as `options.format` or by its extension, is a PLY of 3D Gaussian
/// splatting.
fn is_splatting(path: &Path, options: &SceneLoadOptions) -> bool {
    let ply = match options.format {
        Some(f) => f.name == "ply",
        None => path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("ply")),
    };
    ply && crate::formats::ply::is_splatting_file(path)
}

/// The default scene around the particle file `path` (read as `options.format`, else by its
/// extension), with what a sequence of frames needs ([`Loaded`]).
pub(in crate::scene) fn load_bare(path: &Path, options: &SceneLoadOptions) -> Result<Loaded> {
    let whole = At::whole(path);
    let splatting = is_splatting(path, options);
    let mut provenance = Provenance::default();
    let mut render = render::apply_overrides(RenderSettings::default(), options, &mut provenance)?;
    if splatting {
        // What 3DGS draws: emission on black, unless the flags say otherwise.
        if options.model.is_none() {
            render.model = crate::optics::models::EMISSION;
        }
        if options.background.is_none() {
            render.background = glam::DVec3::ZERO;
        }
    }
    let mut defaults = ResolvedDefaults::new(&whole, &ParticleDefaults::default())?;
    let density_origin = match options.density {
        Some(d) => {
            defaults.density = d;
            Origin::Flag("--density")
        }
        None if splatting => {
            defaults.density = Profile::Gaussian;
            Origin::Default
        }
        None => Origin::Default,
    };
    defaults.density_origin = density_origin;
    let sh = options.sh.unwrap_or(if splatting {
        ShColor::View
    } else {
        ShColor::Dc
    });
    if options.sh.is_some() && !splatting {
        return Err(whole.err(
            "--sh applies to a PLY file of 3D Gaussian splatting (its SH coefficients); this file has none",
        ));
    }
    // With `sh = "view"` the records come with the DC colour and their coefficients, evaluated
    // below for the eye the framing places (`super::color_for_eye`).
    let spec = IncludeSpec {
        format: options.format,
        density: Some(defaults.density),
        sh: (splatting && sh == ShColor::View).then_some(ShColor::View),
        ..IncludeSpec::bare(path)
    };
    let mut loaded = crate::formats::load_particles(&spec)?;
    let mut particles = loaded
        .records
        .iter()
        .map(|rec| record_particle(path, rec, &defaults, render.lambda, None))
        .collect::<Result<Vec<_>>>()?;
    provenance.push_particles(ParticleOrigin {
        source: ParticleSource::File,
        line: None,
        profile: defaults.density,
        density: density_origin,
    });
    let mut warnings = std::mem::take(&mut loaded.warnings);
    if particles.is_empty() {
        warnings.push(format!(
            "{}: the file has no particles; it renders the background",
            path.display()
        ));
    }
    let (w, h) = options.size.unwrap_or(DEFAULT_SIZE);
    camera::check_size(&whole, w as i64, h as i64)?;
    // Gaussians are framed by their 3σ extent (`framing::extent_radius`), as in a scene file.
    let camera = default_camera(&particles, w, h);
    let range = 0..particles.len();
    let includes = vec![IncludeGroup {
        spec,
        location: Location::File,
        range,
        sh: loaded.sh.take().map(std::sync::Arc::new),
    }];
    super::color_for_eye(
        &mut particles,
        &includes,
        camera.position,
        defaults.albedo.is_none(),
    );
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
            ..SceneLoadOptions::default()
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

    /// A 3D Gaussian splatting PLY (ascii) of two Gaussians with SH degree 1.
    fn splatting_ply(dir: &Path) -> std::path::PathBuf {
        let path = dir.join("g.ply");
        let mut text = String::from("ply\nformat ascii 1.0\nelement vertex 2\n");
        for n in [
            "x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "f_rest_0", "f_rest_1", "f_rest_2",
            "f_rest_3", "f_rest_4", "f_rest_5", "f_rest_6", "f_rest_7", "f_rest_8", "opacity",
            "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3",
        ] {
            text += &format!("property float {n}\n");
        }
        text += "end_header\n";
        text += "0 0 0 0.5 0.2 0.1 0 0 0 0 0 0 0.4 0.3 0.2 0 -1 -1 -1 1 0 0 0\n";
        text += "2 0 0 0.1 0.2 0.5 0 0 0 0 0 0 0.1 0.2 0.3 1 -2 -1 -1 1 0 0 0\n";
        std::fs::write(&path, text).unwrap();
        path
    }

    /// A bare splatting PLY renders as 3DGS draws it: Gaussians of standard deviations
    /// exp(scale), the emission model, black, the SH seen from the framed eye; the flags say
    /// otherwise one at a time.
    #[test]
    fn a_bare_splatting_file_is_gaussians_in_the_emission_model_seen_from_the_eye() {
        let dir = tempfile::tempdir().unwrap();
        let path = splatting_ply(dir.path());
        let s = Scene::load(&path, &SceneLoadOptions::default()).unwrap();
        assert_eq!(s.render.model, models::EMISSION);
        assert_eq!(s.render.background, glam::DVec3::ZERO);
        assert!(s.particles.iter().all(|p| p.profile == Profile::Gaussian));
        assert!((s.particles[0].radius - (-1f64).exp()).abs() < 1e-6);
        // The colour is the SH seen from the camera (f_rest_6..8: blue's degree-1 terms, in
        // the channel-major order).
        let eye = s.camera.position;
        let rest: Vec<glam::DVec3> = [0.4, 0.3, 0.2]
            .iter()
            .map(|&b| glam::DVec3::new(0.0, 0.0, b))
            .collect();
        let want = crate::formats::ply::view_color(
            glam::DVec3::new(0.5, 0.2, 0.1),
            &rest,
            s.particles[0].center - eye,
        )
        .max(glam::DVec3::ZERO);
        assert!(
            (s.particles[0].color - want).length() < 1e-6,
            "{}",
            s.particles[0].color
        );
        // Framed by the 3σ extent (framing::extent_radius) once, as a scene file of the same
        // Gaussians is: farther than the framing of the same ellipsoids' 1σ bounds.
        assert_eq!(s.camera, default_camera(&s.particles, 512, 512));
        let one_sigma: Vec<_> = s
            .particles
            .iter()
            .map(|p| crate::scene::Particle {
                profile: Profile::Constant,
                ..*p
            })
            .collect();
        let one_sigma = default_camera(&one_sigma, 512, 512);
        assert!(
            eye.distance(s.particles[0].center)
                > one_sigma.position.distance(s.particles[0].center)
        );
        let flags = SceneLoadOptions {
            density: Some(Profile::Constant),
            model: Some(models::LIT),
            sh: Some(ShColor::Dc),
            background: Some([0.1, 0.2, 0.3]),
            ..SceneLoadOptions::default()
        };
        let old = Scene::load(&path, &flags).unwrap();
        assert_eq!(old.render.model, models::LIT);
        assert_eq!(old.render.background, glam::DVec3::new(0.1, 0.2, 0.3));
        assert!(old.particles.iter().all(|p| p.profile == Profile::Constant));
        // The file's values are f32: 0.2 and 0.1 as f32.
        let dc = glam::DVec3::new(0.5, 0.2f32 as f64, 0.1f32 as f64);
        assert_eq!(
            old.particles[0].color,
            dc * crate::formats::ply::SH_C0 + 0.5
        );
        assert_eq!(
            old.provenance.particles[0].density,
            Origin::Flag("--density")
        );
    }

    #[test]
    fn sh_is_refused_for_a_file_without_sh_and_density_flags_for_a_scene_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = csv(dir.path());
        let sh = SceneLoadOptions {
            sh: Some(ShColor::View),
            ..SceneLoadOptions::default()
        };
        let e = Scene::load(&path, &sh).unwrap_err().to_string();
        assert!(
            e.contains("--sh") && e.contains(&path.display().to_string()),
            "{e}"
        );
        let toml = dir.path().join("s.toml");
        std::fs::write(
            &toml,
            "[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n",
        )
        .unwrap();
        let density = SceneLoadOptions {
            density: Some(Profile::Gaussian),
            ..SceneLoadOptions::default()
        };
        let e = Scene::load(&toml, &density).unwrap_err().to_string();
        assert!(
            e.contains("--density") && e.contains("density = \"gaussian\""),
            "{e}"
        );
    }
}
