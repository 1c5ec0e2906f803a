//! Step 1: `[render]` with its defaults, then the command-line overrides (docs/design.md §1:
//! flags override the scene), and where the mode and the model were chosen.

use super::super::file::RenderTable;
use super::super::provenance::{Origin, Provenance};
use super::super::{RenderSettings, SceneLoadOptions};
use crate::error::{At, PgtError, Result, SourceText};
use toml::Spanned;

/// The render settings of `table` (the defaults without one) with `options`' overrides applied;
/// `provenance` learns where the mode and the model came from.
pub(super) fn settings(
    source: &SourceText,
    table: &Option<Spanned<RenderTable>>,
    options: &SceneLoadOptions,
    provenance: &mut Provenance,
) -> Result<RenderSettings> {
    let render = match table {
        Some(r) => {
            let at = source.at(r.span());
            let line = Some(source.line(r));
            let key = |key, set: bool| match set {
                true => Origin::Key {
                    table: "render",
                    key,
                    line,
                },
                false => Origin::Default,
            };
            provenance.mode = key("mode", r.get_ref().mode.is_some());
            provenance.model = key("model", r.get_ref().model.is_some());
            from_table(&at, r.get_ref())?
        }
        None => RenderSettings::default(),
    };
    apply_overrides(render, options, provenance)
}

/// The `[render]` table's settings, each checked, the defaults where absent.
fn from_table(at: &At, t: &RenderTable) -> Result<RenderSettings> {
    let d = RenderSettings::default();
    Ok(RenderSettings {
        mode: t.mode.unwrap_or(d.mode),
        model: t.model.unwrap_or(d.model),
        background: t.background.map_or(Ok(d.background), |v| {
            at.non_negative3("render.background", v)
        })?,
        lambda: t.lambda.map_or(Ok(d.lambda), |v| {
            let v = at.finite("render.lambda", v)?;
            if v > 0.0 && v <= 1.0 {
                Ok(v)
            } else {
                Err(at.err(format!("render.lambda must be in (0, 1], got {v}")))
            }
        })?,
        light_weight: t.light_weight.unwrap_or(d.light_weight),
        emission_weight: t.emission_weight.map_or(Ok(d.emission_weight), |v| {
            at.in_range("render.emission_weight", v, 0.0, 1.0, "in [0, 1]")
        })?,
        ambient: t.ambient.map_or(Ok(d.ambient), |v| {
            at.in_range("render.ambient", v, 0.0, f64::MAX, "≥ 0")
        })?,
        tol: t.tol.map_or(Ok(d.tol), |v| check_tol(at, v))?,
        gaussian_cutoff: t
            .gaussian_cutoff
            .map(|k| at.in_range("render.gaussian_cutoff", k, 0.5, 40.0, "in [0.5, 40]"))
            .transpose()?,
    })
}

fn check_tol(at: &At, v: f64) -> Result<f64> {
    let v = at.finite("render.tol", v)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(at.err(format!("render.tol must be > 0, got {v}")))
    }
}

/// `--mode`, `--model`, `--tol` and `--background` over the scene's settings.
pub(super) fn apply_overrides(
    mut r: RenderSettings,
    o: &SceneLoadOptions,
    provenance: &mut Provenance,
) -> Result<RenderSettings> {
    if let Some(m) = o.mode {
        r.mode = m;
        provenance.mode = Origin::Flag("--mode");
    }
    if let Some(m) = o.model {
        r.model = m;
        provenance.model = Origin::Flag("--model");
    }
    if let Some(t) = o.tol {
        r.tol = checked_tol_override(t)?;
    }
    if let Some(b) = o.background {
        if !b.iter().all(|c| c.is_finite() && *c >= 0.0) {
            return Err(PgtError::Usage(format!(
                "--background must be three finite numbers ≥ 0 (linear RGB), got {b:?}"
            )));
        }
        r.background = glam::DVec3::from(b);
    }
    Ok(r)
}

/// A tolerance given on the command line (`--tol`), or to the Python package's `render`.
pub fn checked_tol_override(t: f64) -> Result<f64> {
    if !(t.is_finite() && t > 0.0) {
        return Err(PgtError::Usage(format!(
            "--tol must be a finite number > 0, got {t}"
        )));
    }
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::models;
    use crate::scene::{RenderMode, Scene};
    use std::path::Path;

    fn load(text: &str, options: &SceneLoadOptions) -> Result<Scene> {
        Scene::from_toml_str(text, Path::new("s.toml"), options)
    }

    #[test]
    fn every_key_is_read_and_the_rest_default() {
        let s = load(
            "[render]\nmode = \"opaque\"\nbackground = [0.5, 0.25, 0.0]\nlambda = 0.5\nlight_weight = \"sum\"\nemission_weight = 0.25\nambient = 0.125\ntol = 1e-3\ngaussian_cutoff = 5.0\n",
            &SceneLoadOptions::default(),
        )
        .unwrap();
        let r = s.render;
        assert_eq!(r.mode, RenderMode::Opaque);
        assert_eq!(r.model, models::LIT);
        assert_eq!(r.background.to_array(), [0.5, 0.25, 0.0]);
        assert_eq!((r.lambda, r.emission_weight, r.ambient), (0.5, 0.25, 0.125));
        assert_eq!(r.light_weight, crate::scene::LightWeight::Sum);
        assert_eq!((r.tol, r.gaussian_cutoff), (1e-3, Some(5.0)));
        let d = load("", &SceneLoadOptions::default()).unwrap().render;
        assert_eq!(d, RenderSettings::default());
    }

    #[test]
    fn bad_values_name_the_table_line_and_key() {
        for (text, words) in [
            (
                "\n[render]\nlambda = 0.0\n",
                "render.lambda must be in (0, 1], got 0",
            ),
            ("\n[render]\ntol = -1.0\n", "render.tol must be > 0, got -1"),
            (
                "\n[render]\ntol = nan\n",
                "render.tol must be a finite number",
            ),
            (
                "\n[render]\nemission_weight = 2.0\n",
                "render.emission_weight must be in [0, 1]",
            ),
            ("\n[render]\nambient = -1.0\n", "render.ambient must be ≥ 0"),
            (
                "\n[render]\nbackground = [0.0, -1.0, 0.0]\n",
                "render.background must be ≥ 0",
            ),
            (
                "\n[render]\ngaussian_cutoff = 0.25\n",
                "render.gaussian_cutoff must be in [0.5, 40]",
            ),
        ] {
            let e = load(text, &SceneLoadOptions::default())
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with("s.toml:2: ") && e.contains(words),
                "{text}: {e}"
            );
        }
    }

    #[test]
    fn overrides_win_and_are_remembered_as_flags() {
        let o = SceneLoadOptions {
            size: Some((7, 3)),
            mode: Some(RenderMode::Opaque),
            model: Some(models::EMISSION),
            tol: Some(1e-3),
            format: None,
            ..SceneLoadOptions::default()
        };
        let s = load(
            "[camera]\nwidth=100\nheight=100\n[render]\nmode = \"volume\"\nmodel = \"lit\"\ntol = 1e-6\n",
            &o,
        )
        .unwrap();
        assert_eq!((s.camera.width, s.camera.height), (7, 3));
        assert_eq!(s.render.mode, RenderMode::Opaque);
        assert_eq!(s.render.model, models::EMISSION);
        assert_eq!(s.render.tol, 1e-3);
        assert_eq!(s.provenance.mode, Origin::Flag("--mode"));
        assert_eq!(s.provenance.model, Origin::Flag("--model"));
    }

    #[test]
    fn a_bad_tol_override_names_the_flag() {
        for t in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = checked_tol_override(t).unwrap_err().to_string();
            assert!(e.starts_with("--tol must be a finite number > 0"), "{e}");
        }
        assert_eq!(checked_tol_override(1e-7).unwrap(), 1e-7);
    }
}
