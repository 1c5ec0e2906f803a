//! Step 2: `[defaults]`, each value checked once, and σ for a particle from its own opacity or
//! κ, else the defaults', else Θmax = 0.5 (docs/design.md §1 "Extinction").

use super::super::file::ParticleDefaults;
use super::super::provenance::Origin;
use crate::error::{At, Result, SourceText};
use crate::optics::extinction::Extinction;
use crate::optics::particle::Profile;
use glam::DVec3;
use toml::Spanned;

/// `[defaults]` with each field checked once.
pub(super) struct ResolvedDefaults {
    pub color: DVec3,
    /// σ source for particles that set neither opacity nor kappa.
    pub opacity: Option<f64>,
    pub kappa: Option<f64>,
    pub albedo: Option<DVec3>,
    pub ks: f64,
    pub shininess: f64,
    pub density: Profile,
    /// Where `density` was chosen: `[defaults]`' key, or the default.
    pub density_origin: Origin,
}

/// Θmax used when neither the particle nor `[defaults]` sets opacity or kappa.
const DEFAULT_OPACITY: f64 = 0.5;
const DEFAULT_SHININESS: f64 = 32.0;

/// The scene file's `[defaults]` table (every default without one), checked.
pub(super) fn resolve(
    source: &SourceText,
    table: &Option<Spanned<ParticleDefaults>>,
) -> Result<ResolvedDefaults> {
    match table {
        Some(t) => {
            let mut d = ResolvedDefaults::new(&source.at(t.span()), t.get_ref())?;
            if t.get_ref().density.is_some() {
                d.density_origin = Origin::Key {
                    table: "defaults",
                    key: "density",
                    line: Some(source.line(t)),
                };
            }
            Ok(d)
        }
        None => ResolvedDefaults::new(&source.whole(), &ParticleDefaults::default()),
    }
}

impl ResolvedDefaults {
    /// `d` checked, errors named at `at`.
    pub fn new(at: &At, d: &ParticleDefaults) -> Result<Self> {
        if d.opacity.is_some() && d.kappa.is_some() {
            return Err(at.err("defaults: set opacity or kappa, not both"));
        }
        Ok(ResolvedDefaults {
            color: d
                .color
                .map_or(Ok(DVec3::ONE), |c| at.non_negative3("defaults.color", c))?,
            opacity: d
                .opacity
                .map(|o| at.in_range("defaults.opacity", o, 0.0, 1.0, "in [0, 1]"))
                .transpose()?,
            kappa: d
                .kappa
                .map(|k| at.in_range("defaults.kappa", k, 0.0, f64::MAX, "≥ 0"))
                .transpose()?,
            albedo: d
                .albedo
                .map(|a| at.non_negative3("defaults.albedo", a))
                .transpose()?,
            ks: d.ks.map_or(Ok(0.0), |v| {
                at.in_range("defaults.ks", v, 0.0, f64::MAX, "≥ 0")
            })?,
            shininess: d.shininess.map_or(Ok(DEFAULT_SHININESS), |v| {
                at.in_range("defaults.shininess", v, 0.0, f64::MAX, "≥ 0")
            })?,
            density: d.density.unwrap_or_default(),
            density_origin: Origin::Default,
        })
    }

    /// σ from the particle's own opacity/kappa, else the defaults, else Θmax =
    /// [`DEFAULT_OPACITY`] (docs/design.md §1); the equation itself is [`Extinction::sigma`],
    /// for a Gaussian [`Extinction::peak_sigma`] (docs/design.md §9). `radius` is the shortest
    /// semi-axis (the shortest standard deviation of a Gaussian).
    pub fn sigma(
        &self,
        opacity: Option<f64>,
        kappa: Option<f64>,
        radius: f64,
        lambda: f64,
        profile: Profile,
    ) -> f64 {
        let extinction = match (opacity, kappa) {
            (Some(o), _) => Extinction::Opacity(o),
            (None, Some(k)) => Extinction::Kappa(k),
            (None, None) => match (self.opacity, self.kappa) {
                (_, Some(k)) => Extinction::Kappa(k),
                (Some(o), None) => Extinction::Opacity(o),
                (None, None) => Extinction::Opacity(DEFAULT_OPACITY),
            },
        };
        match profile {
            Profile::Constant => extinction.sigma(radius, lambda),
            Profile::Gaussian => extinction.peak_sigma(radius, lambda),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Location;
    use std::path::Path;

    fn resolve_text(text: &str) -> Result<ResolvedDefaults> {
        #[derive(serde::Deserialize)]
        struct File {
            defaults: Option<Spanned<ParticleDefaults>>,
        }
        let file: File = toml::from_str(text).unwrap();
        resolve(
            &SourceText {
                path: Path::new("d.toml"),
                text,
            },
            &file.defaults,
        )
    }

    #[test]
    fn absent_values_take_the_documented_defaults() {
        let d = resolve_text("").unwrap();
        assert_eq!(d.color, DVec3::ONE);
        assert_eq!((d.opacity, d.kappa, d.albedo), (None, None, None));
        assert_eq!((d.ks, d.shininess), (0.0, 32.0));
        assert_eq!(
            (d.density, d.density_origin),
            (Profile::Constant, Origin::Default)
        );
        // Θmax = 0.5 over a radius of 2: σ = ln 2 / 4.
        let s = d.sigma(None, None, 2.0, 1.0, Profile::Constant);
        assert!((s - 2f64.ln() / 4.0).abs() < 1e-15, "{s}");
    }

    #[test]
    fn the_particles_own_extinction_comes_first_then_the_defaults() {
        let d = resolve_text("\n[defaults]\nkappa = 3.0\ndensity = \"gaussian\"\n").unwrap();
        assert_eq!(
            d.density_origin,
            Origin::Key {
                table: "defaults",
                key: "density",
                line: Some(2)
            }
        );
        // κ is scaled by λ, whatever the profile.
        assert_eq!(d.sigma(None, None, 1.0, 0.5, Profile::Constant), 1.5);
        assert_eq!(d.sigma(None, Some(2.0), 1.0, 0.5, Profile::Gaussian), 1.0);
        // The particle's opacity wins over the defaults' κ: −ln(1 − 0.5)/(2·1).
        let s = d.sigma(Some(0.5), None, 1.0, 0.5, Profile::Constant);
        assert!((s - 2f64.ln() / 2.0).abs() < 1e-15, "{s}");
    }

    #[test]
    fn bad_defaults_name_the_table_line() {
        for (text, words) in [
            (
                "\n[defaults]\nopacity = 0.5\nkappa = 1.0\n",
                "set opacity or kappa, not both",
            ),
            (
                "\n[defaults]\nopacity = 2.0\n",
                "defaults.opacity must be in [0, 1]",
            ),
            (
                "\n[defaults]\ncolor = [1.0, -1.0, 0.0]\n",
                "defaults.color must be ≥ 0",
            ),
            ("\n[defaults]\nks = -1.0\n", "defaults.ks must be ≥ 0"),
        ] {
            let Err(e) = resolve_text(text) else {
                panic!("{text}: accepted")
            };
            let crate::error::PgtError::Input {
                location, message, ..
            } = &e
            else {
                panic!("{e}")
            };
            assert_eq!(*location, Location::Line(2), "{e}");
            assert!(message.contains(words), "{text}: {e}");
        }
    }
}
