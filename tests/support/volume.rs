//! Scene builders shared by the volume tests.
#![allow(dead_code)]

use glam::DVec3;
use pgt::formats::random::SplitMix64;
use pgt::geometry::{Camera, Ray};
use pgt::optics::{models, Falloff, Light, LightWeight, Model, Particle};
use pgt::reference::volume::VolumeRenderer;
use pgt::reference::{Integrator, RadianceEstimator, Sample};
use pgt::scene::{RenderMode, RenderSettings, Scene};

/// The library's deterministic SplitMix64 (the one `pgt gen random` uses), with the draws the
/// volume tests need.
pub struct Rng(SplitMix64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(SplitMix64::new(seed))
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0.next_u64()
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0.next_f64()
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
    pub fn vec3(&mut self, lo: f64, hi: f64) -> DVec3 {
        DVec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }
    pub fn unit(&mut self) -> DVec3 {
        loop {
            let v = self.vec3(-1.0, 1.0);
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

pub fn particle(center: DVec3, radius: f64, color: DVec3, sigma: f64) -> Particle {
    Particle {
        ellipsoid: None,
        profile: pgt::optics::Profile::Constant,
        center,
        radius,
        color,
        sigma,
        albedo: color,
        ks: 0.0,
        shininess: 32.0,
    }
}

pub fn scene(model: Model, particles: Vec<Particle>, lights: Vec<Light>, size: u32) -> Scene {
    Scene {
        source: "test".into(),
        camera: Camera::new(
            DVec3::new(0.0, 0.0, -8.0),
            DVec3::ZERO,
            DVec3::Y,
            30.0,
            size,
            size,
        ),
        render: RenderSettings {
            mode: RenderMode::Volume,
            model,
            background: DVec3::new(0.05, 0.1, 0.2),
            light_weight: LightWeight::Mean,
            emission_weight: 1.0,
            tol: 1e-8,
            ..RenderSettings::default()
        },
        lights,
        particles,
        warnings: vec![],
        provenance: Default::default(),
    }
}

/// A directional light and a point light, as in the thesis's scenes but with some colour.
pub fn two_lights() -> Vec<Light> {
    vec![
        Light::Directional {
            direction: DVec3::new(0.2, -1.0, 0.3).normalize(),
            irradiance: DVec3::new(0.2, 1.0, 0.4),
        },
        Light::Point {
            position: DVec3::new(2.5, 1.0, -2.0),
            intensity: DVec3::new(6.0, 3.0, 9.0),
            falloff: Falloff::InverseSquare,
        },
    ]
}

/// `n` overlapping particles in [−1.2, 1.2]³ with random colours and σ in [0.2, 3].
pub fn random_particles(rng: &mut Rng, n: usize) -> Vec<Particle> {
    (0..n)
        .map(|_| {
            let mut p = particle(
                rng.vec3(-1.2, 1.2),
                rng.range(0.4, 1.1),
                rng.vec3(0.0, 1.0),
                rng.range(0.2, 3.0),
            );
            p.albedo = rng.vec3(0.0, 1.0);
            p
        })
        .collect()
}

pub fn radiance(scene: &Scene, integrator: Integrator, ray: &Ray) -> Sample {
    VolumeRenderer::new(scene, integrator).radiance(ray)
}

pub const MODELS: [Model; 3] = [models::EMISSION, models::LIT, models::SINGLE_SCATTER];
