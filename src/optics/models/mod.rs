//! The optical models of docs/design.md §2, one file each, and their registry.
//!
//! A new model is one file here implementing [`OpticalModel`](super::model::OpticalModel) (opening with its
//! table, as the others do), its `mod` line and one entry in [`ALL`]. Scene files, `--model`,
//! error messages and the renderer read [`ALL`]; nothing matches on a model's name.

mod emission;
mod lit;
mod single_scatter;

use super::model::Model;

/// docs/design.md §2, emission model.
pub const EMISSION: Model = Model::new(&emission::Emission);
/// docs/design.md §2, lit model (the default).
pub const LIT: Model = Model::new(&lit::Lit);
/// docs/design.md §2, single-scatter model.
pub const SINGLE_SCATTER: Model = Model::new(&single_scatter::SingleScatter);

/// The registry, one entry per model, in the order of `--help` and of error messages.
pub const ALL: &[Model] = &[EMISSION, LIT, SINGLE_SCATTER];

/// The registry's lookups by name: scene files, `--model` and messages go through [`ALL`].
impl Model {
    /// The registered model called `name`, or `None`.
    pub fn from_name(name: &str) -> Option<Model> {
        ALL.iter().copied().find(|m| m.name() == name)
    }

    /// The registered names, for messages: "`emission`, `lit`, `single-scatter`".
    pub fn names() -> String {
        ALL.iter()
            .map(|m| format!("`{}`", m.name()))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The message for a name that is not registered.
    pub fn unknown(name: &str) -> String {
        format!(
            "unknown optical model `{name}`, expected one of {}",
            Self::names()
        )
    }
}

impl std::str::FromStr for Model {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Model::from_name(s).ok_or_else(|| Model::unknown(s))
    }
}

impl<'de> serde::Deserialize<'de> for Model {
    /// By name; toml attaches the line of the value to the error.
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        name.parse().map_err(serde::de::Error::custom)
    }
}

impl serde::Serialize for Model {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// `--model NAME`: the registry is the list of values, each model's summary its help.
impl clap::ValueEnum for Model {
    fn value_variants<'a>() -> &'a [Self] {
        ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()).help(self.summary()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::intervals::Interval;
    use crate::optics::source::{LightSample, SourceParams};
    use glam::DVec3;
    use std::f64::consts::PI;

    fn interval() -> Interval {
        Interval {
            t0: 0.0,
            t1: 1.0,
            sigma: 2.0,
            emission: DVec3::new(0.2, 0.4, 0.8),
            albedo: DVec3::new(0.5, 0.25, 1.0),
        }
    }

    fn samples() -> [LightSample; 2] {
        [
            LightSample {
                radiance: DVec3::X,
                irradiance: DVec3::splat(4.0 * PI),
                transmittance: 0.5,
            },
            LightSample {
                radiance: DVec3::Y,
                irradiance: DVec3::new(0.0, 8.0 * PI, 0.0),
                transmittance: 0.25,
            },
        ]
    }

    #[test]
    fn names_are_unique_and_resolve() {
        for (i, m) in ALL.iter().enumerate() {
            assert_eq!(Model::from_name(m.name()), Some(*m));
            assert!(ALL[..i].iter().all(|o| o.name() != m.name()), "{m} twice");
            assert!(!m.summary().is_empty());
        }
        assert_eq!(Model::from_name("glow"), None);
        assert_eq!(
            Model::unknown("glow"),
            "unknown optical model `glow`, expected one of `emission`, `lit`, `single-scatter`"
        );
        assert_eq!("single-scatter".parse::<Model>(), Ok(SINGLE_SCATTER));
        assert_ne!(LIT, EMISSION);
    }

    #[test]
    fn sources_are_the_equations_of_design_section_2() {
        let p = SourceParams {
            light_weight: 0.5,
            emission_weight: 0.3,
        };
        let (iv, s) = (interval(), samples());
        assert_eq!(EMISSION.source(&p, &iv, &s), iv.emission);
        assert_eq!(LIT.source(&p, &iv, &s), DVec3::new(0.5, 0.5, 0.0));
        // a·E + α·(E_1·T_1 + E_2·T_2)/4π = 0.3·E + α·(2, 3, 2)/4 … with E_l·T_l = (2π, 4π, 2π).
        let expected = 0.3 * iv.emission + iv.albedo * DVec3::new(0.5, 1.0, 0.5);
        let q = SINGLE_SCATTER.source(&p, &iv, &s);
        assert!((q - expected).abs().max_element() < 1e-15, "{q}");
    }

    #[test]
    fn light_parts_are_linear_in_the_shadow_rays_radiance_and_transmittance() {
        // The renderer's shadow-ray cut (`reference::volume`) bounds q_l's error through this:
        // q_l(λ·s₁ + μ·s₂) = λ·q_l(s₁) + μ·q_l(s₂) in (L_l, T_l) at one irradiance E_l
        // (`OpticalModel::light_source`).
        let p = SourceParams {
            light_weight: 0.5,
            emission_weight: 0.3,
        };
        let iv = interval();
        let [s1, s2] = samples();
        let s2 = LightSample {
            irradiance: s1.irradiance,
            ..s2
        };
        for m in ALL {
            let (q1, q2) = (m.light_source(&p, &iv, &s1), m.light_source(&p, &iv, &s2));
            for (lambda, mu) in [(0.0, 0.0), (1e-9, 0.0), (0.5, 0.25), (3.0, 1.0)] {
                let mixed = LightSample {
                    radiance: lambda * s1.radiance + mu * s2.radiance,
                    transmittance: lambda * s1.transmittance + mu * s2.transmittance,
                    irradiance: s1.irradiance,
                };
                let want = lambda * q1 + mu * q2;
                let got = m.light_source(&p, &iv, &mixed);
                assert!(
                    (got - want).abs().max_element() <= 1e-15 * want.abs().max_element(),
                    "{m}, λ = {lambda}, μ = {mu}: {got} against {want}"
                );
            }
        }
    }

    #[test]
    fn source_is_the_constant_part_plus_the_light_parts() {
        let p = SourceParams {
            light_weight: 0.5,
            emission_weight: 0.3,
        };
        let (iv, s) = (interval(), samples());
        for m in ALL {
            let mut split = m.emission_factor(&p) * iv.emission;
            for l in &s {
                split += m.light_source(&p, &iv, l);
            }
            let whole = m.source(&p, &iv, &s);
            assert!(
                (split - whole).abs().max_element() < 1e-15,
                "{m}: {split} vs {whole}"
            );
            assert_eq!(m.opaque_limit(&p, &iv, &s), whole);
            if m.light_need() == crate::optics::model::LightNeed::None {
                assert_eq!(m.source(&p, &iv, &[]), whole, "{m} reads its lights");
            }
            if m.light_need() == crate::optics::model::LightNeed::IrradianceTransmittance {
                // The renderer does not trace the shadow rays' radiance for these models
                // (`VolumeRenderer::shadow_composite`) and passes zero.
                let dark = s.map(|l| LightSample {
                    radiance: DVec3::ZERO,
                    ..l
                });
                assert_eq!(m.source(&p, &iv, &dark), whole, "{m} reads L_l");
                for (l, d) in s.iter().zip(&dark) {
                    assert_eq!(m.light_source(&p, &iv, d), m.light_source(&p, &iv, l));
                }
            }
        }
    }
}
