//! An independent Monte Carlo estimator of the volume integrals of docs/design.md §2 (delta tracking
//! for the free paths, ratio tracking for transmittances), with its own brute-force geometry: it
//! shares nothing with the renderer but the scene types and `Light::incident_at`. The exact
//! reference must agree with it within 4 standard errors on random overlapping scenes.

use crate::support::volume::*;
use glam::DVec3;
use pgt::geometry::Ray;
use pgt::optics::{models, LightWeight, Model, Particle};
use pgt::reference::Integrator;
use pgt::scene::Scene;
use std::f64::consts::PI;

struct MonteCarlo<'a> {
    scene: &'a Scene,
}

impl MonteCarlo<'_> {
    /// σ(x), E(x) and α(x) by summing over every particle that contains x.
    fn medium_at(&self, x: DVec3) -> (f64, DVec3, DVec3) {
        let (mut s, mut e, mut a) = (0.0, DVec3::ZERO, DVec3::ZERO);
        for p in &self.scene.particles {
            if (x - p.center).length_squared() < p.radius * p.radius {
                s += p.sigma;
                e += p.sigma * p.color;
                a += p.sigma * p.albedo;
            }
        }
        if s > 0.0 {
            (s, e / s, a / s)
        } else {
            (0.0, DVec3::ZERO, DVec3::ZERO)
        }
    }

    /// A majorant σ̄ along the segment (sum of σ of every sphere the line meets, textbook
    /// quadratic) and the end of the medium on it.
    fn majorant(&self, o: DVec3, d: DVec3, t_max: f64) -> (f64, f64) {
        let (mut bound, mut t_end) = (0.0, 0.0f64);
        for p in &self.scene.particles {
            let f = o - p.center;
            let b = f.dot(d);
            let disc = b * b - (f.length_squared() - p.radius * p.radius);
            if disc > 0.0 {
                let t1 = -b + disc.sqrt();
                if t1 > 0.0 {
                    bound += p.sigma;
                    t_end = t_end.max(t1);
                }
            }
        }
        (bound, t_end.min(t_max))
    }

    /// Delta tracking: the first real collision on (0, t_max) with its medium, or `None`.
    fn track(
        &self,
        o: DVec3,
        d: DVec3,
        t_max: f64,
        rng: &mut Rng,
    ) -> Option<(DVec3, f64, DVec3, DVec3)> {
        let (bound, t_end) = self.majorant(o, d, t_max);
        if bound <= 0.0 {
            return None;
        }
        let mut t = 0.0;
        loop {
            t -= (1.0 - rng.uniform()).ln() / bound;
            if t >= t_end {
                return None;
            }
            let x = o + t * d;
            let (s, e, a) = self.medium_at(x);
            if rng.uniform() * bound < s {
                return Some((x, s, e, a));
            }
        }
    }

    /// Ratio tracking: an unbiased estimate of the transmittance of (0, t_max).
    fn transmittance(&self, o: DVec3, d: DVec3, t_max: f64, rng: &mut Rng) -> f64 {
        let (bound, t_end) = self.majorant(o, d, t_max);
        if bound <= 0.0 {
            return 1.0;
        }
        let (mut t, mut tr) = (0.0, 1.0);
        loop {
            t -= (1.0 - rng.uniform()).ln() / bound;
            if t >= t_end {
                return tr;
            }
            tr *= 1.0 - self.medium_at(o + t * d).0 / bound;
        }
    }

    /// One sample of L along the camera ray: collide with probability density T·σ, then score Q
    /// (each L_l itself estimated by tracking the shadow ray), or the background on escape.
    fn sample(&self, ray: &Ray, rng: &mut Rng) -> DVec3 {
        let render = &self.scene.render;
        let Some((x, _, e, albedo)) = self.track(ray.origin, ray.direction, f64::INFINITY, rng)
        else {
            return render.background;
        };
        let m = self.scene.lights.len();
        // By name, with its own formulas: the oracle does not use the models' code.
        match render.model.name() {
            "emission" => e,
            "lit" => {
                let w = match render.light_weight {
                    LightWeight::Mean => 1.0 / m as f64,
                    LightWeight::Sum => 1.0,
                };
                let mut q = DVec3::ZERO;
                for light in &self.scene.lights {
                    let inc = light.incident_at(x).unwrap();
                    q += match self.track(x, inc.toward, inc.distance, rng) {
                        Some((_, _, e2, _)) => e2,
                        None => inc.irradiance,
                    };
                }
                w * q
            }
            "single-scatter" => {
                let mut inscatter = DVec3::ZERO;
                for light in &self.scene.lights {
                    let inc = light.incident_at(x).unwrap();
                    inscatter +=
                        inc.irradiance * self.transmittance(x, inc.toward, inc.distance, rng);
                }
                render.emission_weight * e + albedo * inscatter / (4.0 * PI)
            }
            other => panic!("the Monte Carlo oracle has no formula for the model `{other}`"),
        }
    }
}

fn mean_and_standard_error(samples: &[DVec3]) -> (DVec3, DVec3) {
    let n = samples.len() as f64;
    let mean = samples.iter().copied().sum::<DVec3>() / n;
    let var = samples
        .iter()
        .map(|s| (*s - mean) * (*s - mean))
        .sum::<DVec3>()
        / (n - 1.0);
    (mean, (var / n).powf(0.5))
}

fn agree_on_random_scenes(model: Model) {
    const SAMPLES: usize = 40_000;
    // The model's place in the registry (0, 1, 2: the old enum's discriminants, so the random
    // scenes are the ones this test has always drawn).
    let index = models::ALL.iter().position(|m| *m == model).unwrap();
    let mut rng = Rng::new(0xC0FFEE ^ index as u64);
    let mut compared = 0;
    let mut non_trivial = 0;
    for scene_seed in 0..3 {
        let particles = random_particles(&mut rng, 4 + scene_seed);
        let mut s = scene(model, particles, two_lights(), 1);
        s.render.tol = 1e-7;
        if scene_seed == 1 {
            s.render.light_weight = LightWeight::Sum;
            s.render.emission_weight = 0.0;
        }
        if scene_seed == 2 {
            // A point light inside a particle: its shadow rays start and end in gas.
            let inside = s.particles[0].center + DVec3::new(0.1, 0.05, 0.0) * s.particles[0].radius;
            s.lights[1] = pgt::optics::Light::Point {
                position: inside,
                intensity: DVec3::new(0.5, 0.3, 0.8),
                falloff: pgt::optics::Falloff::InverseSquare,
            };
        }
        let mc = MonteCarlo { scene: &s };
        for _ in 0..5 {
            let target = rng.vec3(-0.8, 0.8);
            let origin = rng.unit() * 6.0;
            let ray = Ray::new(origin, target - origin);
            let exact = radiance(&s, Integrator::Adaptive, &ray);
            let samples: Vec<DVec3> = (0..SAMPLES).map(|_| mc.sample(&ray, &mut rng)).collect();
            let (mean, se) = mean_and_standard_error(&samples);
            for c in 0..3 {
                let diff = (exact.radiance[c] - mean[c]).abs();
                assert!(
                    diff <= 4.0 * se[c] + exact.error[c] + 1e-9,
                    "{model:?} scene {scene_seed} channel {c}: exact {} MC {} ± {} (ray {ray:?})",
                    exact.radiance[c],
                    mean[c],
                    se[c]
                );
            }
            compared += 1;
            non_trivial += (se.max_element() > 1e-4) as u32;
        }
    }
    assert_eq!(compared, 15);
    assert!(
        non_trivial >= 10,
        "too few rays met the particles: {non_trivial}"
    );
}

#[test]
fn monte_carlo_agrees_with_the_emission_model() {
    agree_on_random_scenes(models::EMISSION);
}

#[test]
fn monte_carlo_agrees_with_the_lit_model() {
    agree_on_random_scenes(models::LIT);
}

#[test]
fn monte_carlo_agrees_with_the_single_scatter_model() {
    agree_on_random_scenes(models::SINGLE_SCATTER);
}

/// The oracle itself is checked on the one case with a closed form: one sphere, emission model.
#[test]
fn monte_carlo_oracle_reproduces_the_one_sphere_closed_form() {
    let p: Particle = particle(DVec3::ZERO, 1.0, DVec3::new(1.0, 0.2, 0.6), 0.8);
    let s = scene(models::EMISSION, vec![p], vec![], 1);
    let mc = MonteCarlo { scene: &s };
    let ray = Ray::new(DVec3::new(0.3, 0.0, -5.0), DVec3::Z);
    let t = (-0.8 * 2.0 * (1.0f64 - 0.09).sqrt()).exp();
    let expected = s.render.background * t + p.color * (1.0 - t);
    let mut rng = Rng::new(3);
    let samples: Vec<DVec3> = (0..40_000).map(|_| mc.sample(&ray, &mut rng)).collect();
    let (mean, se) = mean_and_standard_error(&samples);
    assert!(
        ((mean - expected).abs() - 4.0 * se).max_element() <= 0.0,
        "{mean} ± {se} vs {expected}"
    );
}
