//! `thesis-cpu`: the `thesis` approximation (docs/design.md §4, thesis chapter 5) on the CPU in f64,
//! step for step as `shaders/thesis.wgsl` does it: the particles a camera ray crosses, sorted by
//! entry, composited one particle at a time (overlaps ignored); the first `n_exact` with the lit
//! model (docs/design.md §2, eq. 4.17) by `samples` midpoint samples per chord, each with one shadow
//! ray per light along which the emission model is composited per particle; the rest with the
//! emission closed form L = L_behind·T + C·(1−T).
//!
//! It exists to tell float32 apart from the scheme's other approximations: `thesis` and
//! `thesis-cpu` with the same parameters differ only in the arithmetic (f32 on the GPU, f64
//! here), which is the `float32` stage of the error attribution (see [`crate::sweep`]).
//! Particles with Θmax = 1 (σ = ∞) are refused (the GPU's surface limit is not mirrored here).
//!
//! | parameter | default | meaning |
//! |-----------|---------|---------|
//! | `samples` | 100     | midpoint samples per particle chord |
//! | `n_exact` | all     | particles from the eye that get the lit model; the rest the simplified model |
//! | `rest_model` | 0    | the simplified model of the particles past `n_exact`: 0 the emission closed form C·(1−T) (as the shader), 1 absorption only (the particle dims what is behind it and adds nothing), 2 the lit model without shadow rays, w·Σ_l E_l·(1−T) |
//!
//! The thesis says the particles past N get "the simplified model" and no more; `rest_model`
//! lets `reports/thesis/` measure what the readings of that sentence are worth.

use super::method::{
    value_of, ParamDefault, ParamValue, RunImage, SweepContext, SweepMethod, SweepParam,
};
use crate::error::{PgtError, Result};
use crate::geometry::{Bvh, Hit, Ray};
use crate::image_io::RgbImage;
use crate::optics::light::light_weight;
use crate::optics::models;
use crate::scene::{Particle, RenderMode, Scene};
use glam::DVec3;
use rayon::prelude::*;

/// The thesis's scheme in f64 on the CPU.
pub struct ThesisCpu;

/// The one instance the method table holds.
pub static THESIS_CPU: ThesisCpu = ThesisCpu;

const PARAMS: [SweepParam; 3] = [
    SweepParam {
        name: "samples",
        default: ParamDefault::Value(ParamValue::Count(100)),
        min: 1,
        // As the GPU `thesis` allows, so that the two can be swept over the same values.
        max: 1 << 24,
        accepts_all: false,
        quiet_default: false,
        doc: "midpoint samples per particle chord",
    },
    SweepParam {
        name: "n_exact",
        default: ParamDefault::Value(ParamValue::All),
        min: 0,
        max: u32::MAX - 1,
        accepts_all: true,
        quiet_default: false,
        doc: "particles from the eye that get the lit model; the rest get the emission model",
    },
    SweepParam {
        name: "rest_model",
        default: ParamDefault::Value(ParamValue::Count(REST_EMISSION)),
        min: REST_EMISSION,
        max: REST_UNSHADOWED,
        accepts_all: false,
        quiet_default: true,
        doc: "model of the particles past n_exact: 0 emission C(1-T), 1 absorption only, 2 lit without shadow rays",
    },
];

/// `rest_model` values (see the module documentation).
const REST_EMISSION: u32 = 0;
const REST_ABSORPTION: u32 = 1;
const REST_UNSHADOWED: u32 = 2;

/// What every pixel needs.
struct Shading<'a> {
    scene: &'a Scene,
    bvh: Bvh,
    samples: u32,
    n_exact: u32,
    rest_model: u32,
    lit: bool,
    /// w of the lit model: 1/m or 1 (docs/design.md §2).
    weight: f64,
}

impl Shading<'_> {
    /// docs/design.md §2, emission model composited per particle back to front along (t_min, t_max),
    /// the light's irradiance as the background: what the thesis's shadow rays carry.
    fn emission_along(
        &self,
        ray: &Ray,
        t_max: f64,
        background: DVec3,
        hits: &mut Vec<Hit>,
    ) -> DVec3 {
        self.bvh.all_hits(ray, 0.0, t_max, hits);
        let mut radiance = background;
        for h in hits.iter().rev() {
            let p = &self.scene.particles[h.index as usize];
            let length = (h.chord.t_exit.min(t_max) - h.chord.t_enter.max(0.0)).max(0.0);
            let t = (-p.sigma * length).exp();
            radiance = radiance * t + p.color * (1.0 - t);
        }
        radiance
    }

    /// Q(x) of the lit model (docs/design.md §2, thesis eq. 4.17): w·Σ_l L_l(x).
    fn lit_source(&self, x: DVec3, hits: &mut Vec<Hit>) -> DVec3 {
        let mut q = DVec3::ZERO;
        for light in &self.scene.lights {
            if let Some(inc) = light.incident_at(x) {
                let ray = Ray::new(x, inc.toward);
                q += self.emission_along(&ray, inc.distance, inc.irradiance, hits);
            }
        }
        self.weight * q
    }

    /// Σ_j Q(x_j)·σ·e^{−σ(t_j − t0)}·Δt, t_j = t0 + (j + ½)Δt: the midpoint rule for ∫ σQT dt
    /// over one particle's chord (the σ factor of docs/design.md §8).
    fn lit_samples(&self, ray: &Ray, sigma: f64, t0: f64, t1: f64, hits: &mut Vec<Hit>) -> DVec3 {
        let dt = (t1 - t0) / self.samples as f64;
        let mut sum = DVec3::ZERO;
        for j in 0..self.samples {
            let t = t0 + (j as f64 + 0.5) * dt;
            sum += self.lit_source(ray.at(t), hits) * (sigma * (-sigma * (t - t0)).exp() * dt);
        }
        sum
    }

    /// The source S of a particle past `n_exact` (its radiance is S·(1−T)): its colour, nothing,
    /// or the light arriving at its centre unoccluded, weighed as the lit model weighs it.
    fn rest_source(&self, p: &Particle) -> DVec3 {
        match self.rest_model {
            REST_ABSORPTION => DVec3::ZERO,
            REST_UNSHADOWED => {
                let lights = self.scene.lights.iter();
                let incident = lights.filter_map(|l| l.incident_at(p.center));
                self.weight * incident.map(|i| i.irradiance).sum::<DVec3>()
            }
            _ => p.color,
        }
    }

    /// One pixel: L = Σ_i P_i·S_i + P·L_bg, P_i the transmittance in front of particle i.
    fn pixel(&self, px: u32, py: u32, camera_hits: &mut Vec<Hit>, hits: &mut Vec<Hit>) -> DVec3 {
        let ray = self.scene.camera.pixel_ray(px, py);
        self.bvh.all_hits(&ray, 0.0, f64::INFINITY, camera_hits);
        let n_lit = if self.lit {
            (self.n_exact as usize).min(camera_hits.len())
        } else {
            0
        };
        let mut radiance = DVec3::ZERO;
        let mut front = 1.0;
        for (k, h) in camera_hits.iter().enumerate() {
            let p = &self.scene.particles[h.index as usize];
            let t0 = h.chord.t_enter.max(0.0);
            let t1 = h.chord.t_exit;
            let transmittance = (-p.sigma * (t1 - t0).max(0.0)).exp();
            radiance += front
                * if k < n_lit {
                    self.lit_samples(&ray, p.sigma, t0, t1, hits)
                } else {
                    self.rest_source(p) * (1.0 - transmittance)
                };
            front *= transmittance;
            if front <= 0.0 {
                break;
            }
        }
        radiance + front * self.scene.render.background
    }
}

impl SweepMethod for ThesisCpu {
    fn name(&self) -> &'static str {
        "thesis-cpu"
    }

    fn params(&self) -> &[SweepParam] {
        &PARAMS
    }

    fn check_scene(&self, scene: &Scene) -> Result<()> {
        let model = scene.render.model;
        if scene.render.mode == RenderMode::Opaque
            || (model != models::EMISSION && model != models::LIT)
        {
            return Err(PgtError::Usage(
                "thesis-cpu renders volume-mode scenes with the emission or lit model".into(),
            ));
        }
        if scene.particles.iter().any(|p| !p.sigma.is_finite()) {
            return Err(PgtError::Usage(
                "thesis-cpu does not handle particles with opacity 1 (σ = ∞); use the GPU method `thesis`".into(),
            ));
        }
        Ok(())
    }

    fn render(
        &self,
        ctx: &mut SweepContext,
        scene: &Scene,
        values: &[(&'static str, u32)],
    ) -> Result<RunImage> {
        let shading = Shading {
            scene,
            bvh: scene.build_bvh(),
            samples: value_of(values, "samples", 100).max(1),
            n_exact: value_of(values, "n_exact", u32::MAX),
            rest_model: value_of(values, "rest_model", REST_EMISSION),
            lit: scene.render.model == models::LIT,
            weight: light_weight(scene.render.light_weight, scene.lights.len()),
        };
        let (w, h) = (scene.camera.width, scene.camera.height);
        let run = || {
            (0..h)
                .into_par_iter()
                .map(|py| {
                    let (mut camera_hits, mut hits) = (Vec::new(), Vec::new());
                    (0..w)
                        .map(|px| {
                            let l = shading.pixel(px, py, &mut camera_hits, &mut hits);
                            l.as_vec3().to_array()
                        })
                        .collect::<Vec<_>>()
                })
                .collect::<Vec<_>>()
        };
        let rows = match ctx.threads {
            Some(n) => rayon::ThreadPoolBuilder::new()
                .num_threads(n.max(1))
                .build()
                .map_err(|e| PgtError::Usage(format!("cannot start {n} threads: {e}")))?
                .install(run),
            None => run(),
        };
        let mut image = RgbImage::new(w, h);
        image.pixels = rows.into_iter().flatten().collect();
        Ok(RunImage {
            image,
            gpu_seconds: None,
            warnings: Vec::new(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SceneLoadOptions;
    use std::path::Path;

    /// One sphere (Θmax 0.6, colour (0.9, 0.5, 0.1)) in front of a grey background, one
    /// directional light of irradiance (0.2, 0.4, 0.8), a 1×1 image whose one ray crosses the
    /// sphere's diameter, so that its transmittance is exactly 1 − Θmax.
    fn one_sphere() -> Scene {
        let text = r#"
[camera]
position = [0.0, 0.0, -10.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 10.0
width = 1
height = 1
[render]
model = "lit"
background = [0.3, 0.3, 0.3]
[[lights]]
type = "directional"
direction = [0.0, -1.0, 0.0]
irradiance = [0.2, 0.4, 0.8]
[[particles]]
center = [0.0, 0.0, 0.0]
radius = 1.0
color = [0.9, 0.5, 0.1]
opacity = 0.6
"#;
        Scene::from_toml_str(text, Path::new("one.toml"), &SceneLoadOptions::default()).unwrap()
    }

    fn pixel(scene: &Scene, rest_model: u32) -> [f32; 3] {
        let values = [("samples", 8), ("n_exact", 0), ("rest_model", rest_model)];
        let out = ThesisCpu
            .render(&mut SweepContext::new(Some(1)), scene, &values)
            .unwrap();
        out.image.pixels[0]
    }

    #[test]
    fn past_n_each_rest_model_gives_its_closed_form() {
        let scene = one_sphere();
        let (theta, bg) = (0.6, 0.3);
        let expect = |source: [f64; 3]| source.map(|s| (s * theta + bg * (1.0 - theta)) as f32);
        let close = |a: [f32; 3], b: [f32; 3]| a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-6);
        // 0: the particle's colour; 1: nothing, only the background dimmed; 2: the light's
        // irradiance (one light: w = 1 for `mean` as for `sum`) with no shadow.
        for (rest, source) in [
            (REST_EMISSION, [0.9, 0.5, 0.1]),
            (REST_ABSORPTION, [0.0, 0.0, 0.0]),
            (REST_UNSHADOWED, [0.2, 0.4, 0.8]),
        ] {
            let got = pixel(&scene, rest);
            assert!(
                close(got, expect(source)),
                "rest_model {rest}: {got:?} vs {:?}",
                expect(source)
            );
        }
    }
}
