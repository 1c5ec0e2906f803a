//! Step 5: `[[lights]]` (docs/design.md §1 "Lights"), each checked for its type's fields, and the
//! warning of a scene whose mode or model takes its light from lights it does not have.

use super::super::file::{LightKind, LightTable};
use super::super::framing::thesis_lights;
use super::super::{RenderMode, RenderSettings};
use crate::error::{At, Result, SourceText};
use crate::optics::light::{Falloff, Light};
use crate::optics::model::LightNeed;
use crate::optics::source::SourceParams;
use std::path::Path;
use toml::Spanned;

/// The scene file's lights; with `default_lights`, none becomes the thesis's two (as for a bare
/// particle file).
pub(super) fn lights(
    source: &SourceText,
    tables: &[Spanned<LightTable>],
    default_lights: bool,
) -> Result<Vec<Light>> {
    let lights = tables
        .iter()
        .enumerate()
        .map(|(i, l)| light(&source.at(l.span()), i, l.get_ref()))
        .collect::<Result<Vec<_>>>()?;
    Ok(if lights.is_empty() && default_lights {
        thesis_lights()
    } else {
        lights
    })
}

/// The `i`-th `[[lights]]` table: the fields its type requires, none of the other type's.
fn light(at: &At, i: usize, l: &LightTable) -> Result<Light> {
    let field = |f: &str| format!("lights[{i}].{f}");
    let required = |f: &str, v: Option<[f64; 3]>| {
        v.ok_or_else(|| {
            at.err(format!("{} is required for a {:?} light", field(f), l.kind).to_lowercase())
        })
    };
    let forbidden = |f: &str, present: bool| {
        if present {
            Err(at
                .err(format!("{} does not apply to a {:?} light", field(f), l.kind).to_lowercase()))
        } else {
            Ok(())
        }
    };
    match l.kind {
        LightKind::Directional => {
            forbidden("position", l.position.is_some())?;
            forbidden("intensity", l.intensity.is_some())?;
            forbidden("falloff", l.falloff.is_some())?;
            Ok(Light::Directional {
                direction: at
                    .direction(&field("direction"), required("direction", l.direction)?)?,
                irradiance: at
                    .non_negative3(&field("irradiance"), required("irradiance", l.irradiance)?)?,
            })
        }
        LightKind::Point => {
            forbidden("direction", l.direction.is_some())?;
            forbidden("irradiance", l.irradiance.is_some())?;
            Ok(Light::Point {
                position: at.vec3(&field("position"), required("position", l.position)?)?,
                intensity: at
                    .non_negative3(&field("intensity"), required("intensity", l.intensity)?)?,
                falloff: l.falloff.unwrap_or(Falloff::InverseSquare),
            })
        }
    }
}

/// The warning of a scene without lights whose mode or model takes its light from them
/// (docs/design.md §1 "Lights"): the opaque mode, and every model with a per-light part (lit,
/// single-scatter). It says what the particles show instead (black, where nothing else lights
/// them) and how to light them. `None` where there are lights or none are needed.
pub(super) fn unlit_warning(
    path: &Path,
    render: &RenderSettings,
    lights: &[Light],
) -> Option<String> {
    if !lights.is_empty() {
        return None;
    }
    let (what, shown) = match render.mode {
        RenderMode::Opaque if render.ambient == 0.0 => (
            "the opaque mode".to_string(),
            "with ambient = 0 the particles render black (they only hide the background)"
                .to_string(),
        ),
        RenderMode::Opaque => (
            "the opaque mode".to_string(),
            format!(
                "the particles show ambient·colour only ({}·C)",
                render.ambient
            ),
        ),
        RenderMode::Volume => {
            let model = render.model.model();
            if model.light_need() == LightNeed::None {
                return None;
            }
            let params = SourceParams::new(render.light_weight, 0, render.emission_weight);
            let what = format!("the {} model", model.name());
            let k = model.emission_factor(&params);
            let shown = if k == 0.0 {
                "the particles render black (they only dim the background)".to_string()
            } else {
                format!("only its emission part {k}·C shows")
            };
            (what, shown)
        }
    };
    Some(format!(
        "{}: the scene has no [[lights]], and {what} takes its light from them: {shown}; add [[lights]] (a bare particle file gets the thesis's two, docs/design.md §1) or render with model = \"emission\"",
        path.display()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::models;
    use crate::scene::{Scene, SceneLoadOptions};
    use glam::DVec3;

    fn load(text: &str) -> Result<Scene> {
        Scene::from_toml_str(text, Path::new("s.toml"), &SceneLoadOptions::default())
    }

    const PARTICLE: &str = "[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n";

    #[test]
    fn lights_are_read_with_their_defaults() {
        let s = load(&format!(
            "[[lights]]\ntype = \"directional\"\ndirection = [0.0, -2.0, 0.0]\nirradiance = [1.0, 0.5, 0.0]\n[[lights]]\ntype = \"point\"\nposition = [1.0, 2.0, 3.0]\nintensity = [4.0, 4.0, 4.0]\n{PARTICLE}"
        ))
        .unwrap();
        assert_eq!(
            s.lights,
            vec![
                Light::Directional {
                    direction: DVec3::NEG_Y,
                    irradiance: DVec3::new(1.0, 0.5, 0.0)
                },
                Light::Point {
                    position: DVec3::new(1.0, 2.0, 3.0),
                    intensity: DVec3::splat(4.0),
                    falloff: Falloff::InverseSquare
                }
            ]
        );
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    }

    #[test]
    fn a_lights_errors_name_its_table_line_and_field() {
        for (table, words) in [
            (
                "type=\"directional\"\ndirection=[0,0,0]\nirradiance=[1,1,1]",
                "lights[0].direction must be a non-zero vector",
            ),
            (
                "type=\"directional\"\nirradiance=[1,1,1]",
                "lights[0].direction is required for a directional light",
            ),
            (
                "type=\"directional\"\ndirection=[0,1,0]\nirradiance=[1,1,1]\nfalloff=\"none\"",
                "lights[0].falloff does not apply to a directional light",
            ),
            (
                "type=\"point\"\nposition=[0,1,0]\nintensity=[1,-1,1]",
                "lights[0].intensity must be ≥ 0",
            ),
            (
                "type=\"point\"\nposition=[0,1,0]\nintensity=[1,1,1]\ndirection=[0,1,0]",
                "lights[0].direction does not apply to a point light",
            ),
        ] {
            let e = load(&format!("\n[[lights]]\n{table}\n"))
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with("s.toml:2: ") && e.contains(words),
                "{table}: {e}"
            );
        }
    }

    #[test]
    fn a_scene_that_needs_lights_and_has_none_is_warned_about() {
        // The lit model, the default: black.
        let s = load(PARTICLE).unwrap();
        assert!(s.lights.is_empty());
        assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
        let w = &s.warnings[0];
        assert!(
            w.starts_with("s.toml: the scene has no [[lights]], and the lit model takes its light from them: the particles render black"),
            "{w}"
        );
        // Single-scatter keeps its emission part a·C.
        let s = load(&format!(
            "[render]\nmodel = \"single-scatter\"\nemission_weight = 0.5\n{PARTICLE}"
        ))
        .unwrap();
        assert!(
            s.warnings[0].contains("only its emission part 0.5·C shows"),
            "{:?}",
            s.warnings
        );
        let s = load(&format!(
            "[render]\nmodel = \"single-scatter\"\nemission_weight = 0.0\n{PARTICLE}"
        ))
        .unwrap();
        assert!(s.warnings[0].contains("render black"), "{:?}", s.warnings);
        // The opaque mode: black without ambient.
        let s = load(&format!("[render]\nmode = \"opaque\"\n{PARTICLE}")).unwrap();
        assert!(s.warnings[0].contains("the opaque mode takes its light from them: with ambient = 0 the particles render black"), "{:?}", s.warnings);
        let s = load(&format!(
            "[render]\nmode = \"opaque\"\nambient = 0.25\n{PARTICLE}"
        ))
        .unwrap();
        assert!(
            s.warnings[0].contains("ambient·colour only (0.25·C)"),
            "{:?}",
            s.warnings
        );
    }

    #[test]
    fn the_emission_model_lights_and_program_defaults_need_no_warning() {
        let s = load(&format!("[render]\nmodel = \"emission\"\n{PARTICLE}")).unwrap();
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        // --model emission over a lit scene file without lights.
        let o = SceneLoadOptions {
            model: Some(models::EMISSION),
            ..SceneLoadOptions::default()
        };
        let s = Scene::from_toml_str(PARTICLE, Path::new("s.toml"), &o).unwrap();
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        // A program's settings that ask for the default lights get the thesis's two.
        let s = Scene::from_settings_and_particles(
            PARTICLE,
            Path::new("p"),
            &SceneLoadOptions::default(),
            std::iter::empty(),
            true,
        )
        .unwrap();
        assert_eq!(s.lights, thesis_lights());
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    }
}
