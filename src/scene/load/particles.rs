//! Step 3: particles. The scene file's `[[particles]]` tables and the particles a program gives
//! as such tables ([`inline`]), and the records a file format delivers ([`record_particle`]),
//! each checked and resolved with `[defaults]` and λ into a [`Particle`] (docs/design.md §1, §9).

use super::super::file::ParticleTable;
use super::super::provenance::{Origin, ParticleOrigin, ParticleSource, Provenance};
use super::super::{ParticleInput, ParticleRecord};
use super::defaults::ResolvedDefaults;
use crate::error::{At, Result, SourceText};
use crate::formats::EllipsoidRecord;
use crate::geometry::Ellipsoid;
use crate::optics::particle::{Particle, Profile};
use glam::DVec3;
use std::path::Path;
use toml::Spanned;

/// The scene file's `[[particles]]` tables, then the `given` particles checked as tables of
/// the same kind (numbered after them, named with the whole file: no line wrote them);
/// `provenance` learns where each one's density was chosen.
pub(super) fn inline(
    source: &SourceText,
    tables: &[Spanned<ParticleTable>],
    given: impl Iterator<Item = ParticleInput>,
    defaults: &ResolvedDefaults,
    lambda: f64,
    provenance: &mut Provenance,
) -> Result<Vec<Particle>> {
    let mut particles = Vec::with_capacity(tables.len());
    for (i, p) in tables.iter().enumerate() {
        let line = source.line(p);
        let particle = inline_particle(&source.at(p.span()), i, p.get_ref(), defaults, lambda)?;
        provenance.push_particles(ParticleOrigin {
            source: ParticleSource::Inline,
            line: Some(line),
            profile: particle.profile,
            density: match p.get_ref().density {
                Some(_) => Origin::Key {
                    table: "particles",
                    key: "density",
                    line: Some(line),
                },
                None => defaults.density_origin,
            },
        });
        particles.push(particle);
    }
    let whole = source.whole();
    for (k, p) in given.enumerate() {
        let i = tables.len() + k;
        let particle = inline_particle(&whole, i, &given_table(p), defaults, lambda)?;
        provenance.push_particles(ParticleOrigin {
            source: ParticleSource::Inline,
            line: None,
            profile: particle.profile,
            density: defaults.density_origin,
        });
        particles.push(particle);
    }
    Ok(particles)
}

/// A particle given by a program as the inline table it stands for.
fn given_table(p: ParticleInput) -> ParticleTable {
    ParticleTable {
        center: p.center,
        radius: p.semi_axes.is_none().then_some(p.radius),
        semi_axes: p.semi_axes,
        rotation: p.rotation,
        color: p.color,
        opacity: p.opacity,
        kappa: p.kappa,
        albedo: None,
        ks: None,
        shininess: None,
        density: None,
    }
}

/// The `i`-th `[[particles]]` table, checked at `at`.
fn inline_particle(
    at: &At,
    i: usize,
    p: &ParticleTable,
    d: &ResolvedDefaults,
    lambda: f64,
) -> Result<Particle> {
    let name = |f: &str| format!("particles[{i}].{f}");
    let center = at.vec3(&name("center"), p.center)?;
    let (radius, ellipsoid) = inline_shape(at, i, p)?;
    // Θmax is the opacity along the shortest diameter (docs/design.md §9).
    let sigma_radius = ellipsoid.map_or(radius, |e| e.shortest_semi_axis());
    if p.opacity.is_some() && p.kappa.is_some() {
        return Err(at.err(format!("particles[{i}]: set opacity or kappa, not both")));
    }
    let opacity = p
        .opacity
        .map(|o| at.in_range(&name("opacity"), o, 0.0, 1.0, "in [0, 1]"))
        .transpose()?;
    let kappa = p
        .kappa
        .map(|k| at.in_range(&name("kappa"), k, 0.0, f64::MAX, "≥ 0"))
        .transpose()?;
    let color = p
        .color
        .map_or(Ok(d.color), |c| at.non_negative3(&name("color"), c))?;
    let profile = p.density.unwrap_or(d.density);
    check_gaussian_opacity(at, &name("opacity"), profile, opacity.or(d.opacity))?;
    Ok(Particle {
        center,
        radius,
        color,
        sigma: d.sigma(opacity, kappa, sigma_radius, lambda, profile),
        albedo: p.albedo.map_or(Ok(d.albedo.unwrap_or(color)), |a| {
            at.non_negative3(&name("albedo"), a)
        })?,
        ks: p.ks.map_or(Ok(d.ks), |v| {
            at.in_range(&name("ks"), v, 0.0, f64::MAX, "≥ 0")
        })?,
        shininess: p.shininess.map_or(Ok(d.shininess), |v| {
            at.in_range(&name("shininess"), v, 0.0, f64::MAX, "≥ 0")
        })?,
        ellipsoid,
        profile,
    })
}

/// A table's sphere (`radius`) or ellipsoid (`semi_axes`, `rotation`): the particle's radius
/// and its ellipsoid, if it is one.
fn inline_shape(at: &At, i: usize, p: &ParticleTable) -> Result<(f64, Option<Ellipsoid>)> {
    let name = |f: &str| format!("particles[{i}].{f}");
    match (p.radius, p.semi_axes) {
        (Some(radius), None) => {
            if p.rotation.is_some() {
                return Err(at.err(format!(
                    "{} turns an ellipsoid: give semi_axes = [a, b, c] instead of radius",
                    name("rotation")
                )));
            }
            let radius = at.finite(&name("radius"), radius)?;
            if radius <= 0.0 {
                return Err(at.err(format!("{} must be > 0, got {radius}", name("radius"))));
            }
            Ok((radius, None))
        }
        (None, Some(semi_axes)) => {
            let record = EllipsoidRecord {
                semi_axes: DVec3::from(semi_axes),
                rotation: p.rotation.unwrap_or([1.0, 0.0, 0.0, 0.0]),
            };
            let axes = [0, 1, 2].map(|k| name(&format!("semi_axes[{k}]")));
            if let Some(problem) =
                record.problem(axes.each_ref().map(|s| s.as_str()), &name("rotation"))
            {
                return Err(at.err(problem));
            }
            Ok(resolve_ellipsoid(&record))
        }
        (Some(_), Some(_)) => Err(at.err(format!(
            "particles[{i}]: give radius (a sphere) or semi_axes (an ellipsoid), not both"
        ))),
        (None, None) => Err(at.err(format!(
            "particles[{i}]: give radius = r (a sphere) or semi_axes = [a, b, c] (an ellipsoid)"
        ))),
    }
}

/// A particle from a file format, checked with the location the format recorded; `density` is
/// its include's (`None`: `[defaults]`').
pub(super) fn record_particle(
    path: &Path,
    rec: &ParticleRecord,
    d: &ResolvedDefaults,
    lambda: f64,
    density: Option<Profile>,
) -> Result<Particle> {
    let at = At {
        path,
        location: rec.location.clone(),
    };
    let center = at.vec3("particle position", rec.center.to_array())?;
    let (radius, ellipsoid) = match &rec.ellipsoid {
        Some(e) => {
            if let Some(problem) = e.problem(["sx", "sy", "sz"], "the rotation qw, qx, qy, qz") {
                return Err(at.err(format!("the particle's {problem}")));
            }
            resolve_ellipsoid(e)
        }
        None => (at.finite("particle radius", rec.radius)?, None),
    };
    if radius <= 0.0 {
        return Err(at.err(format!("particle radius must be > 0, got {radius}")));
    }
    // Θmax is the opacity along the shortest diameter (docs/design.md §9).
    let sigma_radius = ellipsoid.map_or(radius, |e| e.shortest_semi_axis());
    let color = rec.color.map_or(Ok(d.color), |c| {
        at.non_negative3("particle colour", c.to_array())
    })?;
    let opacity = rec
        .opacity
        .map(|o| at.in_range("particle opacity", o, 0.0, 1.0, "in [0, 1]"))
        .transpose()?;
    let profile = density.unwrap_or(d.density);
    if rec.sigma.is_none() {
        check_gaussian_opacity(&at, "particle opacity", profile, opacity.or(d.opacity))?;
    }
    Ok(Particle {
        center,
        radius,
        color,
        // A σ the file gives is the particle's σ exactly (crate::formats::xyz_csv, "σ and opacity").
        sigma: rec
            .sigma
            .unwrap_or_else(|| d.sigma(opacity, None, sigma_radius, lambda, profile)),
        albedo: d.albedo.unwrap_or(color),
        ks: d.ks,
        shininess: d.shininess,
        ellipsoid,
        profile,
    })
}

/// A Gaussian's opacity must be < 1: Θmax = 1 would be an infinite peak density, which has no
/// meaning for a density without an edge (docs/design.md §9).
fn check_gaussian_opacity(
    at: &At,
    field: &str,
    profile: Profile,
    opacity: Option<f64>,
) -> Result<()> {
    match (profile, opacity) {
        (Profile::Gaussian, Some(o)) if o >= 1.0 => Err(at.err(format!(
            "{field} is {o}: a Gaussian particle's opacity must be < 1 (1 would be an infinite peak density)"
        ))),
        _ => Ok(()),
    }
}

/// The shape an ellipsoid record describes, checked by [`EllipsoidRecord::problem`] first: the
/// radius of the particle (the longest semi-axis) and its ellipsoid with the quaternion
/// normalised, or no ellipsoid where the three semi-axes are equal (docs/design.md §9: that is
/// the sphere, bit for bit, whatever the rotation).
fn resolve_ellipsoid(e: &EllipsoidRecord) -> (f64, Option<Ellipsoid>) {
    let s = e.semi_axes;
    if s.x == s.y && s.y == s.z {
        return (s.x, None);
    }
    let [w, x, y, z] = e.rotation;
    // Scaled first, so that a quaternion of huge or tiny components normalises without
    // overflow or underflow.
    let q = glam::DVec4::new(x, y, z, w);
    let q = q / q.abs().max_element();
    let ellipsoid = Ellipsoid::new(s, glam::DQuat::from_vec4(q.normalize()));
    (ellipsoid.bounding_radius(), Some(ellipsoid))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Location;
    use crate::scene::{Scene, SceneLoadOptions};

    fn load(text: &str) -> Result<Scene> {
        Scene::from_toml_str(text, Path::new("s.toml"), &SceneLoadOptions::default())
    }

    fn err_text(text: &str) -> String {
        load(text).unwrap_err().to_string()
    }

    fn defaults() -> ResolvedDefaults {
        ResolvedDefaults::new(
            &At::whole(Path::new("d.toml")),
            &crate::scene::file::ParticleDefaults::default(),
        )
        .unwrap()
    }

    #[test]
    fn kappa_is_scaled_by_lambda_but_opacity_is_not() {
        let s = load(
            "[render]\nlambda = 0.5\n[[particles]]\ncenter=[0,0,0]\nradius=2.0\nkappa=3.0\n[[particles]]\ncenter=[5,0,0]\nradius=2.0\nopacity=0.5\n",
        )
        .unwrap();
        assert_eq!(s.particles[0].sigma, 1.5);
        assert!((s.particles[1].sigma - 2f64.ln() / 4.0).abs() < 1e-15);
    }

    #[test]
    fn errors_name_the_table_line_and_field() {
        let e = err_text("[[particles]]\ncenter=[0,0,0]\nradius=1.0\n\n[[particles]]\ncenter=[0,0,0]\nradius=-1.0\n");
        assert!(e.starts_with("s.toml:5:"), "{e}");
        assert!(e.contains("particles[1].radius must be > 0"), "{e}");
        let e = err_text("[[particles]]\ncenter=[0,0,0]\nradius=1.0\nopacity=1.5\n");
        assert!(e.contains("opacity must be in [0, 1]"), "{e}");
        let e = err_text("[[particles]]\ncenter=[0,nan,0]\nradius=1.0\n");
        assert!(e.contains("finite"), "{e}");
        let e = err_text("[[particles]]\ncenter=[0,0,0]\nradius=1.0\nsemi_axes=[1,2,3]\n");
        assert!(
            e.contains("particles[0]: give radius (a sphere) or semi_axes"),
            "{e}"
        );
        let e = err_text("[[particles]]\ncenter=[0,0,0]\nradius=1.0\nrotation=[1,0,0,0]\n");
        assert!(
            e.contains("particles[0].rotation turns an ellipsoid"),
            "{e}"
        );
        let e = err_text("[[particles]]\ncenter=[0,0,0]\n");
        assert!(e.contains("give radius = r (a sphere)"), "{e}");
        let e = err_text("[[particles]]\ncenter=[0,0,0]\nradius=1.0\nkappa=1.0\nopacity=0.5\n");
        assert!(
            e.contains("particles[0]: set opacity or kappa, not both"),
            "{e}"
        );
        let e = err_text(
            "[[particles]]\ncenter=[0,0,0]\nradius=1.0\ndensity=\"gaussian\"\nopacity=1.0\n",
        );
        assert!(
            e.contains("a Gaussian particle's opacity must be < 1"),
            "{e}"
        );
    }

    #[test]
    fn an_ellipsoid_of_equal_axes_is_the_sphere_and_others_are_normalised() {
        let s = load(
            "[[particles]]\ncenter=[0,0,0]\nsemi_axes=[2,2,2]\nrotation=[0,1,0,0]\n[[particles]]\ncenter=[0,0,0]\nsemi_axes=[1,2,3]\nrotation=[2,0,0,0]\n",
        )
        .unwrap();
        assert_eq!(
            (s.particles[0].radius, s.particles[0].ellipsoid),
            (2.0, None)
        );
        let e = s.particles[1].ellipsoid.unwrap();
        assert_eq!(s.particles[1].radius, 3.0);
        assert_eq!(e.shortest_semi_axis(), 1.0);
        // Θmax = 0.5 along the shortest diameter: σ = ln 2 / (2·1).
        assert!((s.particles[1].sigma - 2f64.ln() / 2.0).abs() < 1e-15);
    }

    #[test]
    fn a_records_sigma_is_kept_exactly_and_its_errors_name_its_location() {
        let d = defaults();
        let rec = ParticleRecord {
            center: DVec3::new(1.0, 2.0, 3.0),
            radius: 2.0,
            color: None,
            opacity: Some(0.9),
            sigma: Some(0.123),
            location: Location::Line(7),
            ellipsoid: None,
        };
        let p = record_particle(Path::new("f.csv"), &rec, &d, 0.5, None).unwrap();
        assert_eq!(
            (p.sigma, p.color, p.profile),
            (0.123, DVec3::ONE, Profile::Constant)
        );
        let bad = ParticleRecord {
            radius: -1.0,
            ..rec.clone()
        };
        let e = record_particle(Path::new("f.csv"), &bad, &d, 0.5, None)
            .unwrap_err()
            .to_string();
        assert_eq!(e, "f.csv:7: particle radius must be > 0, got -1");
        // The include's density decides the profile, and a Gaussian of opacity 1 is refused.
        let opaque = ParticleRecord {
            opacity: Some(1.0),
            sigma: None,
            ..rec
        };
        let e = record_particle(
            Path::new("f.csv"),
            &opaque,
            &d,
            0.5,
            Some(Profile::Gaussian),
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("f.csv:7: particle opacity is 1"), "{e}");
    }

    #[test]
    fn given_particles_are_checked_as_tables_after_the_files() {
        let given = [
            ParticleInput {
                center: [0.0, 0.0, 0.0],
                radius: 1.0,
                semi_axes: None,
                rotation: None,
                color: None,
                opacity: None,
                kappa: None,
            },
            ParticleInput {
                center: [0.0, 0.0, 0.0],
                radius: -1.0,
                semi_axes: None,
                rotation: None,
                color: None,
                opacity: None,
                kappa: None,
            },
        ];
        let e = Scene::from_settings_and_particles(
            "[[particles]]\ncenter=[0,0,0]\nradius=1.0\n",
            Path::new("given"),
            &SceneLoadOptions::default(),
            given,
            false,
        )
        .unwrap_err()
        .to_string();
        assert_eq!(e, "given: particles[2].radius must be > 0, got -1");
    }
}
