//! Opaque mode (docs/design.md §2 "Opaque mode", thesis task 1): opaque spheres and ellipsoids
//! (§9), Lambertian C/π with optional Blinn–Phong, hard global shadows from every particle, an
//! ambient term.

use super::{RadianceEstimator, Sample};
use crate::geometry::{Bvh, Ray, Shape};
use crate::optics::light::Light;
use crate::optics::particle::Particle;
use crate::scene::Scene;
use glam::DVec3;
use std::f64::consts::PI;

/// Shadow rays start at the surface point itself; spheres other than the hit one count as
/// blockers only where their chord reaches beyond this relative distance, so round-off in the
/// hit point cannot shadow a point with a sphere it merely touches.
const SHADOW_EPSILON: f64 = 1e-9;

pub struct OpaqueRenderer<'a> {
    scene: &'a Scene,
    bvh: Bvh,
}

impl<'a> OpaqueRenderer<'a> {
    pub fn new(scene: &'a Scene) -> Self {
        OpaqueRenderer {
            scene,
            bvh: scene.build_bvh(),
        }
    }

    /// Whether the segment from `x` (on the surface of sphere `own`) towards the light is
    /// blocked by another sphere. The own sphere needs no ray: a shadow ray leaving a sphere's
    /// surface re-enters it iff it points inwards, which the caller has already ruled out —
    /// that is why there is no self-shadowing acne.
    fn occluded(&self, x: DVec3, toward: DVec3, distance: f64, own: u32) -> bool {
        let ray = Ray {
            origin: x,
            direction: toward,
        };
        let eps =
            SHADOW_EPSILON * (x.abs().max_element() + self.scene.particles[own as usize].radius);
        self.bvh.any_hit(&ray, eps, distance, |i| i == own)
    }

    /// docs/design.md §2, opaque mode, at the surface point of `p` with facing normal `n`, seen along
    /// `view` (unit, from the eye): L = Σ_l V_l·E_l·[(C/π)·max(0, n·ω_l) + specular] + ambient·C.
    /// Specular is normalised Blinn–Phong, ks·(s+8)/(8π)·max(0, n·h)^s·max(0, n·ω_l), h the half
    /// vector of ω_l and −view (docs/design.md leaves the normalisation open; this one conserves
    /// energy for ks ≤ 1).
    fn shade(
        &self,
        p: &Particle,
        own: u32,
        x: DVec3,
        n: DVec3,
        entering: bool,
        view: DVec3,
    ) -> (DVec3, u64) {
        let mut radiance = self.scene.render.ambient * p.color;
        let mut rays = 0;
        for light in &self.scene.lights {
            let Some(inc) = light.incident_at(x) else {
                continue;
            };
            let cos = n.dot(inc.toward);
            // An interior surface (the eye is inside the sphere) is lit only by a point light
            // inside the same sphere (docs/design.md §2, opaque mode): light from outside would have
            // to pass through the opaque sphere. From outside, a light inside this sphere lies
            // behind the surface (cos < 0); one inside another sphere is blocked by it below.
            if cos <= 0.0 || (!entering && !light_inside(light, p)) {
                continue;
            }
            rays += 1;
            if self.occluded(x, inc.toward, inc.distance, own) {
                continue;
            }
            let mut brdf_cos = p.color / PI * cos;
            if p.ks > 0.0 {
                let h = (inc.toward - view).normalize_or_zero();
                let nh = n.dot(h).max(0.0);
                brdf_cos += DVec3::splat(
                    p.ks * (p.shininess + 8.0) / (8.0 * PI) * nh.powf(p.shininess) * cos,
                );
            }
            radiance += inc.irradiance * brdf_cos;
        }
        (radiance, rays)
    }
}

/// Whether `light` is a point light strictly inside particle `p`.
fn light_inside(light: &Light, p: &Particle) -> bool {
    match *light {
        Light::Point { position, .. } => p.shape().contains(position),
        Light::Directional { .. } => false,
    }
}

impl RadianceEstimator for OpaqueRenderer<'_> {
    fn radiance(&self, ray: &Ray) -> Sample {
        let Some((index, t, entering)) = self.bvh.first_hit(ray, 0.0, f64::INFINITY) else {
            return Sample {
                radiance: self.scene.render.background,
                ..Sample::default()
            };
        };
        let p = &self.scene.particles[index as usize];
        // Snap the point onto the surface so the shadow ray starts exactly there.
        let (x, outward) = match p.shape() {
            Shape::Sphere { center, radius } => {
                let outward = (ray.at(t) - center).normalize();
                (center + outward * radius, outward)
            }
            shape => {
                let x = shape.snap_to_surface(ray.at(t));
                (x, shape.normal(x))
            }
        };
        let n = if entering { outward } else { -outward };
        let (radiance, shadow_rays) = self.shade(p, index, x, n, entering, ray.direction);
        Sample {
            radiance,
            error: DVec3::ZERO,
            shadow_rays,
            unconverged: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Camera;
    use crate::optics::light::Falloff;
    use crate::scene::{RenderMode, RenderSettings};
    use approx::assert_relative_eq;

    fn particle(center: DVec3, radius: f64) -> Particle {
        Particle {
            ellipsoid: None,
            profile: crate::optics::Profile::Constant,
            center,
            radius,
            color: DVec3::ONE,
            sigma: f64::INFINITY,
            albedo: DVec3::ONE,
            ks: 0.0,
            shininess: 32.0,
        }
    }

    fn scene(particles: Vec<Particle>, lights: Vec<Light>) -> Scene {
        Scene {
            source: "test".into(),
            camera: Camera::new(
                DVec3::new(0.0, 0.0, -10.0),
                DVec3::ZERO,
                DVec3::Y,
                30.0,
                9,
                9,
            ),
            render: RenderSettings {
                mode: RenderMode::Opaque,
                ..RenderSettings::default()
            },
            lights,
            particles,
            warnings: vec![],
            provenance: Default::default(),
        }
    }

    fn centre_radiance(s: &Scene) -> DVec3 {
        let r = OpaqueRenderer::new(s);
        r.radiance(&Ray::new(DVec3::new(0.0, 0.0, -10.0), DVec3::Z))
            .radiance
    }

    #[test]
    fn white_sphere_facing_a_directional_light_is_e_over_pi() {
        let e = DVec3::new(2.0, 3.0, 5.0);
        let s = scene(
            vec![particle(DVec3::ZERO, 1.0)],
            vec![Light::Directional {
                direction: DVec3::Z,
                irradiance: e,
            }],
        );
        assert_relative_eq!(centre_radiance(&s), e / PI, max_relative = 1e-14);
    }

    #[test]
    fn point_light_gives_i_over_d2_cos_over_pi() {
        // Surface point (0,0,−1), normal −z; light at (3,0,−5): d = 5, cosθ = 4/5.
        let i = DVec3::splat(7.0);
        let light = |falloff| Light::Point {
            position: DVec3::new(3.0, 0.0, -5.0),
            intensity: i,
            falloff,
        };
        let s = scene(
            vec![particle(DVec3::ZERO, 1.0)],
            vec![light(Falloff::InverseSquare)],
        );
        assert_relative_eq!(
            centre_radiance(&s),
            i / 25.0 * 0.8 / PI,
            max_relative = 1e-14
        );
        let s = scene(vec![particle(DVec3::ZERO, 1.0)], vec![light(Falloff::None)]);
        assert_relative_eq!(centre_radiance(&s), i * 0.8 / PI, max_relative = 1e-14);
    }

    #[test]
    fn a_sphere_in_anothers_shadow_is_black_and_lit_when_the_occluder_moves() {
        let light = Light::Directional {
            direction: DVec3::Z,
            irradiance: DVec3::ONE,
        };
        let occluder = |x: f64| particle(DVec3::new(x, 0.0, -5.0), 1.5);
        let mut s = scene(vec![particle(DVec3::ZERO, 1.0), occluder(0.0)], vec![light]);
        // The eye ray passes through the occluder too: look from the side instead.
        let view = Ray::new(DVec3::new(0.0, -10.0, -0.5), DVec3::Y);
        let lit = |s: &Scene| OpaqueRenderer::new(s).radiance(&view).radiance;
        assert_eq!(lit(&s), DVec3::ZERO);
        s.particles[1] = occluder(10.0);
        assert!(lit(&s).min_element() > 0.1);
        s.render.ambient = 0.25;
        s.particles[1] = occluder(0.0);
        assert_relative_eq!(lit(&s), DVec3::splat(0.25), max_relative = 1e-15);
    }

    #[test]
    fn no_self_shadowing_acne_on_a_lit_hemisphere() {
        let light = Light::Directional {
            direction: DVec3::new(0.3, -0.2, 1.0).normalize(),
            irradiance: DVec3::ONE,
        };
        let mut s = scene(
            vec![particle(DVec3::new(123.4, -56.7, 8.9), 3.0)],
            vec![light],
        );
        s.camera = Camera::new(
            DVec3::new(123.4, -56.7, -20.0),
            DVec3::new(123.4, -56.7, 8.9),
            DVec3::Y,
            20.0,
            64,
            64,
        );
        let r = OpaqueRenderer::new(&s);
        let mut lit_pixels = 0;
        for py in 0..64 {
            for px in 0..64 {
                let ray = s.camera.pixel_ray(px, py);
                if let Some((_, t, _)) = r.bvh.first_hit(&ray, 0.0, f64::INFINITY) {
                    let n = (ray.at(t) - s.particles[0].center).normalize();
                    let cos = n.dot(-light_dir(&s));
                    let got = r.radiance(&ray).radiance.x;
                    let expected = cos.max(0.0) / PI;
                    assert!(
                        (got - expected).abs() < 1e-9,
                        "pixel {px},{py}: {got} vs {expected}"
                    );
                    lit_pixels += (cos > 0.0) as u32;
                }
            }
        }
        assert!(lit_pixels > 1000);
    }

    fn light_dir(s: &Scene) -> DVec3 {
        match s.lights[0] {
            Light::Directional { direction, .. } => direction,
            _ => unreachable!(),
        }
    }

    #[test]
    fn blinn_phong_peaks_at_the_mirror_direction() {
        // An eye ray hitting the unit sphere off-centre: the highlight lobe (radiance over the
        // cosine factor) is largest when the light sits in the mirror direction of the eye about
        // the normal, where it is ks·(s+8)/(8π).
        let mut p = particle(DVec3::ZERO, 1.0);
        p.ks = 1.0;
        p.shininess = 64.0;
        p.color = DVec3::ZERO;
        let eye = Ray::new(DVec3::new(0.5, 0.2, -10.0), DVec3::Z);
        let x = eye.at(intersect_t(&eye));
        let n = x.normalize();
        let v = -eye.direction;
        let mirror = 2.0 * n.dot(v) * n - v;
        let axis = n.cross(v).normalize();
        let spec_for = |toward: DVec3| {
            let s = scene(
                vec![p],
                vec![Light::Directional {
                    direction: -toward,
                    irradiance: DVec3::ONE,
                }],
            );
            OpaqueRenderer::new(&s).radiance(&eye).radiance.x / n.dot(toward)
        };
        let peak = spec_for(mirror);
        assert_relative_eq!(peak, (64.0 + 8.0) / (8.0 * PI), max_relative = 1e-9);
        for angle in [-0.2, -0.05, -0.01, 0.01, 0.05, 0.2] {
            let rotated = glam::DQuat::from_axis_angle(axis, angle) * mirror;
            let off = spec_for(rotated);
            assert!(off < peak, "angle {angle}: {off} ≥ {peak}");
        }
    }

    fn intersect_t(ray: &Ray) -> f64 {
        crate::geometry::intersect_sphere(ray, DVec3::ZERO, 1.0)
            .unwrap()
            .t_enter
    }

    #[test]
    fn camera_inside_a_sphere_sees_its_dark_inner_wall_and_ambient() {
        let mut s = scene(
            vec![particle(DVec3::ZERO, 50.0)],
            vec![Light::Directional {
                direction: DVec3::Z,
                irradiance: DVec3::ONE,
            }],
        );
        s.render.ambient = 0.5;
        let got = centre_radiance(&s);
        assert_relative_eq!(got, DVec3::splat(0.5), max_relative = 1e-15);
    }

    #[test]
    fn eye_and_point_light_inside_one_sphere_light_the_inner_wall_and_nothing_outside() {
        // Eye at the centre of a sphere of radius 2 looking +z: the inner wall at (0, 0, 2),
        // inward normal −z. A point light at (0, 0, 1): d = 1, cosθ = 1, L = I/d²·cosθ·C/π.
        let i = DVec3::new(3.0, 5.0, 7.0);
        let light = Light::Point {
            position: DVec3::new(0.0, 0.0, 1.0),
            intensity: i,
            falloff: Falloff::InverseSquare,
        };
        let mut s = scene(
            vec![
                particle(DVec3::ZERO, 2.0),
                particle(DVec3::new(0.0, 6.0, 0.0), 1.0),
            ],
            vec![light],
        );
        s.particles[0].color = DVec3::new(0.5, 1.0, 0.25);
        let r = OpaqueRenderer::new(&s);
        let wall = r.radiance(&Ray::new(DVec3::ZERO, DVec3::Z)).radiance;
        assert_relative_eq!(wall, i * s.particles[0].color / PI, max_relative = 1e-14);
        // Off-axis: the wall at (0, 2 sin a, 2 cos a); the light reaches it at an angle.
        let dir = DVec3::new(0.0, 0.6, 0.8);
        let x = dir * 2.0;
        let to_light = DVec3::new(0.0, 0.0, 1.0) - x;
        let cos = (-dir).dot(to_light.normalize());
        let expected = i / to_light.length_squared() * cos * s.particles[0].color / PI;
        let got = r.radiance(&Ray::new(DVec3::ZERO, dir)).radiance;
        assert_relative_eq!(got, expected, max_relative = 1e-12);
        // A directional light does not reach the inner wall.
        s.lights.push(Light::Directional {
            direction: DVec3::Z,
            irradiance: DVec3::ONE,
        });
        let r = OpaqueRenderer::new(&s);
        let both = r.radiance(&Ray::new(DVec3::ZERO, DVec3::Z)).radiance;
        assert_relative_eq!(both, wall, max_relative = 1e-14);
        // The sphere at (0, 6, 0), seen from outside, gets nothing from the light inside the
        // big sphere (its lit side faces the light, but the big sphere is in the way).
        s.lights.pop();
        let r = OpaqueRenderer::new(&s);
        let outside = r
            .radiance(&Ray::new(DVec3::new(0.0, 6.0, -10.0), DVec3::Z))
            .radiance;
        assert_eq!(outside, DVec3::ZERO);
        let below = r
            .radiance(&Ray::new(DVec3::new(0.0, 3.0, 0.0), DVec3::Y))
            .radiance;
        assert_eq!(below, DVec3::ZERO);
    }
}
