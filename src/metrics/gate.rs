//! Pass/fail gates on a comparison (docs/design.md §5, §7: exit 0 pass, 1 fail, 2 error).
//!
//! A gate file is TOML; every key is optional, unknown keys are errors:
//!
//! ```toml
//! # Thresholds on the mean over the channels (docs/design.md §5 "mean").
//! min_ssim = 0.99
//! max_rmse = 0.01
//! min_psnr = 35.0          # dB
//! max_abs = 0.25           # largest absolute error of any pixel
//! max_mean_abs = 0.005
//! max_mean_rel = 0.05
//! max_flip = 0.05          # mean LDR-FLIP
//!
//! # Sequences only (docs/design.md §10): the worst frame's temporal error, mean over channels.
//! max_temporal_p99 = 0.02  # 99th percentile of e_t
//! max_temporal_mean = 0.002
//! max_pops = 0             # pixels above the pop threshold
//!
//! # Per-channel thresholds, [R, G, B].
//! [channels]
//! min_ssim = [0.98, 0.99, 0.99]
//! max_rmse = [0.02, 0.02, 0.02]
//! min_psnr = [30.0, 30.0, 30.0]
//! max_abs = [0.5, 0.5, 0.5]
//!
//! # Percentiles of per-pixel maps (abs and rel: mean over channels; ssim: mean over channels
//! # of the SSIM map; flip: the FLIP map). Nearest rank. `max` for errors, `min` for ssim.
//! [[percentiles]]
//! map = "abs"
//! percentile = 99.0
//! max = 0.05
//!
//! [[percentiles]]
//! map = "ssim"
//! percentile = 1.0
//! min = 0.9
//! ```

use super::maps;
use super::{Comparison, CHANNELS};
use crate::error::{line_of, toml_error, with_quoted_line, PgtError, Result};
use crate::image_io::RgbImage;
use serde::de::IgnoredAny;
use std::collections::BTreeMap;
use std::path::Path;
use toml::Spanned;

/// The gate file (see the module documentation).
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gate {
    pub min_ssim: Option<f64>,
    pub max_rmse: Option<f64>,
    pub min_psnr: Option<f64>,
    pub max_abs: Option<f64>,
    pub max_mean_abs: Option<f64>,
    pub max_mean_rel: Option<f64>,
    pub max_flip: Option<f64>,
    /// Sequences only: the largest mean-over-channels 99th percentile of any frame's temporal
    /// error.
    pub max_temporal_p99: Option<f64>,
    /// Sequences only: the largest mean temporal error of any frame.
    pub max_temporal_mean: Option<f64>,
    /// Sequences only: the most pops of any frame.
    pub max_pops: Option<f64>,
    pub channels: Option<ChannelGate>,
    #[serde(default)]
    pub percentiles: Vec<PercentileGate>,
}

/// Per-channel thresholds, each `[R, G, B]`.
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelGate {
    pub min_ssim: Option<[f64; 3]>,
    pub max_rmse: Option<[f64; 3]>,
    pub min_psnr: Option<[f64; 3]>,
    pub max_abs: Option<[f64; 3]>,
}

/// Which per-pixel map a percentile gate looks at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MapKind {
    Abs,
    Rel,
    Ssim,
    Flip,
}

/// A threshold on a percentile of a per-pixel map.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PercentileGate {
    pub map: MapKind,
    /// In (0, 100].
    pub percentile: f64,
    pub max: Option<f64>,
    pub min: Option<f64>,
}

/// Where a value of a gate file is: a top-level key, a key of `[channels]`, the i-th
/// `[[percentiles]]` table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Field {
    Top(&'static str),
    Channel(&'static str),
    Percentile(usize),
}

/// The positions of a gate file's values: the types above keep none, so the text is read a
/// second time for them (only when a message needs one).
#[derive(serde::Deserialize)]
struct Spans {
    channels: Option<BTreeMap<String, Spanned<IgnoredAny>>>,
    #[serde(default)]
    percentiles: Vec<Spanned<IgnoredAny>>,
}

impl Field {
    /// The 1-based line of the value in `text` (a file that [`Gate`] parsed).
    fn line(self, text: &str) -> Option<usize> {
        let span = match self {
            Field::Top(name) => {
                let top: BTreeMap<String, Spanned<IgnoredAny>> = toml::from_str(text).ok()?;
                top.get(name)?.span()
            }
            Field::Channel(name) => {
                let spans: Spans = toml::from_str(text).ok()?;
                spans.channels?.get(name)?.span()
            }
            Field::Percentile(i) => {
                let spans: Spans = toml::from_str(text).ok()?;
                spans.percentiles.get(i)?.span()
            }
        };
        Some(line_of(text, span.start))
    }
}

/// The outcome of one threshold.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct GateCheck {
    /// What was checked, e.g. `min_ssim`, `channels.max_rmse[G]`, `p99(abs) <= max`.
    pub name: String,
    pub value: f64,
    pub threshold: f64,
    pub passed: bool,
    /// A lower bound (`min_*`: passes when value ≥ threshold), else an upper bound.
    #[serde(skip)]
    pub lower_bound: bool,
}

impl Gate {
    /// Reads and validates a gate file.
    pub fn load(path: &Path) -> Result<Gate> {
        let text = std::fs::read_to_string(path).map_err(|e| PgtError::io(path, e))?;
        Gate::parse(&text, path)
    }

    /// Parses and validates the text of the gate file `path`; errors name the file and the
    /// line of the offending value (docs/design.md §6 "Bad input").
    pub fn parse(text: &str, path: &Path) -> Result<Gate> {
        let gate: Gate = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
        match gate.problem() {
            None => Ok(gate),
            Some((field, message)) => Err(match field.line(text) {
                Some(line) => PgtError::at_line(path, line, with_quoted_line(message, text, line)),
                None => PgtError::in_file(path, message),
            }),
        }
    }

    /// Whether no threshold is set.
    pub fn is_empty(&self) -> bool {
        self.without_channels_is_empty()
            && self
                .channels
                .as_ref()
                .is_none_or(|c| *c == ChannelGate::default())
    }

    fn without_channels_is_empty(&self) -> bool {
        [
            self.min_ssim,
            self.max_rmse,
            self.min_psnr,
            self.max_abs,
            self.max_mean_abs,
            self.max_mean_rel,
            self.max_flip,
            self.max_temporal_p99,
            self.max_temporal_mean,
            self.max_pops,
        ]
        .iter()
        .all(Option::is_none)
            && self.percentiles.is_empty()
    }

    /// Checks the values make sense (finite; percentiles in (0, 100] with exactly one bound).
    pub fn validate(&self) -> std::result::Result<(), String> {
        match self.problem() {
            Some((_, message)) => Err(message),
            None => Ok(()),
        }
    }

    /// The first value that makes no sense, where it is, and why.
    fn problem(&self) -> Option<(Field, String)> {
        let scalars = [
            ("min_ssim", self.min_ssim),
            ("max_rmse", self.max_rmse),
            ("min_psnr", self.min_psnr),
            ("max_abs", self.max_abs),
            ("max_mean_abs", self.max_mean_abs),
            ("max_mean_rel", self.max_mean_rel),
            ("max_flip", self.max_flip),
            ("max_temporal_p99", self.max_temporal_p99),
            ("max_temporal_mean", self.max_temporal_mean),
            ("max_pops", self.max_pops),
        ];
        for (name, v) in scalars {
            if let Some(v) = v {
                if !v.is_finite() {
                    let message = format!("{name} must be a finite number, got {v}");
                    return Some((Field::Top(name), message));
                }
            }
        }
        if let Some(c) = &self.channels {
            for (name, v) in [
                ("min_ssim", c.min_ssim),
                ("max_rmse", c.max_rmse),
                ("min_psnr", c.min_psnr),
                ("max_abs", c.max_abs),
            ] {
                if v.is_some_and(|v| v.iter().any(|x| !x.is_finite())) {
                    let message = format!("channels.{name} must hold finite numbers");
                    return Some((Field::Channel(name), message));
                }
            }
        }
        for (i, p) in self.percentiles.iter().enumerate() {
            if !(p.percentile > 0.0 && p.percentile <= 100.0) {
                let message = format!("percentile must be in (0, 100], got {}", p.percentile);
                return Some((Field::Percentile(i), message));
            }
            match (p.min, p.max) {
                (Some(v), None) | (None, Some(v)) if v.is_finite() => {}
                _ => {
                    let message = format!(
                        "percentile gate on '{:?}' needs exactly one finite 'min' or 'max'",
                        p.map
                    )
                    .to_lowercase();
                    return Some((Field::Percentile(i), message));
                }
            }
        }
        None
    }

    /// The thresholds that only a sequence has (the temporal error), by name, where set.
    pub fn temporal_keys(&self) -> Vec<(&'static str, f64)> {
        [
            ("max_temporal_p99", self.max_temporal_p99),
            ("max_temporal_mean", self.max_temporal_mean),
            ("max_pops", self.max_pops),
        ]
        .into_iter()
        .filter_map(|(n, v)| v.map(|v| (n, v)))
        .collect()
    }

    /// This gate without the temporal thresholds (what each frame of a sequence is held to).
    pub fn per_frame(&self) -> Gate {
        Gate {
            max_temporal_p99: None,
            max_temporal_mean: None,
            max_pops: None,
            ..self.clone()
        }
    }

    /// Evaluates every threshold: the lower bounds (SSIM, PSNR), the upper bounds (errors,
    /// FLIP), then the percentiles, in that order. An error (not a failure) where a gated metric
    /// is undefined: SSIM of an image smaller than the window, FLIP of an HDR pair.
    pub fn evaluate(
        &self,
        cmp: &Comparison,
        reference: &RgbImage,
        approximation: &RgbImage,
    ) -> Result<Vec<GateCheck>> {
        let mut checks = Checks(Vec::new());
        self.lower_bounds(cmp, &mut checks)?;
        self.upper_bounds(cmp, &mut checks)?;
        for p in &self.percentiles {
            let values = per_pixel(p.map, cmp, reference, approximation)?;
            let v = maps::percentile(&values, p.percentile).unwrap_or(f32::NAN) as f64;
            let kind = format!("{:?}", p.map).to_lowercase();
            match (p.min, p.max) {
                (Some(t), _) => checks.at_least(format!("p{}({kind}) >= min", p.percentile), v, t),
                (None, Some(t)) => {
                    checks.at_most(format!("p{}({kind}) <= max", p.percentile), v, t)
                }
                (None, None) => continue, // excluded by validate()
            }
        }
        Ok(checks.0)
    }

    /// The `min_*` thresholds: mean, then per channel.
    fn lower_bounds(&self, cmp: &Comparison, checks: &mut Checks) -> Result<()> {
        if let Some(t) = self.min_ssim {
            checks.at_least("min_ssim".into(), need_ssim(cmp)?.mean, t);
        }
        if let Some(t) = self.min_psnr {
            checks.at_least("min_psnr".into(), cmp.error_values(|e| e.psnr).mean, t);
        }
        let Some(c) = &self.channels else {
            return Ok(());
        };
        if let Some(t) = c.min_ssim {
            let s = need_ssim(cmp)?;
            checks.per_channel("channels.min_ssim", |k| s.get(k), t, Checks::at_least);
        }
        if let Some(t) = c.min_psnr {
            let psnr = |k: usize| cmp.errors[k].psnr;
            checks.per_channel("channels.min_psnr", psnr, t, Checks::at_least);
        }
        Ok(())
    }

    /// The `max_*` thresholds: mean (the worst pixel for `max_abs`), then per channel.
    fn upper_bounds(&self, cmp: &Comparison, checks: &mut Checks) -> Result<()> {
        if let Some(t) = self.max_rmse {
            checks.at_most("max_rmse".into(), cmp.error_values(|e| e.rmse).mean, t);
        }
        if let Some(t) = self.max_abs {
            let worst = cmp.errors.iter().map(|e| e.max_abs).fold(0.0, f64::max);
            checks.at_most("max_abs".into(), worst, t);
        }
        if let Some(t) = self.max_mean_abs {
            let v = cmp.error_values(|e| e.mean_abs).mean;
            checks.at_most("max_mean_abs".into(), v, t);
        }
        if let Some(t) = self.max_mean_rel {
            let v = cmp.error_values(|e| e.mean_rel).mean;
            checks.at_most("max_mean_rel".into(), v, t);
        }
        if let Some(t) = self.max_flip {
            checks.at_most("max_flip".into(), need_flip(cmp)?, t);
        }
        let Some(c) = &self.channels else {
            return Ok(());
        };
        if let Some(t) = c.max_rmse {
            let rmse = |k: usize| cmp.errors[k].rmse;
            checks.per_channel("channels.max_rmse", rmse, t, Checks::at_most);
        }
        if let Some(t) = c.max_abs {
            let max_abs = |k: usize| cmp.errors[k].max_abs;
            checks.per_channel("channels.max_abs", max_abs, t, Checks::at_most);
        }
        Ok(())
    }
}

/// The checks of one evaluation, in order.
struct Checks(Vec<GateCheck>);

impl Checks {
    /// A lower bound: passes when `value >= threshold` (NaN fails).
    fn at_least(&mut self, name: String, value: f64, threshold: f64) {
        let passed = value >= threshold;
        self.push(name, value, threshold, passed, true);
    }

    /// An upper bound: passes when `value <= threshold` (NaN fails).
    fn at_most(&mut self, name: String, value: f64, threshold: f64) {
        let passed = value <= threshold;
        self.push(name, value, threshold, passed, false);
    }

    /// One check per channel, named `name[R]`, `name[G]`, `name[B]`.
    fn per_channel(
        &mut self,
        name: &str,
        value: impl Fn(usize) -> f64,
        thresholds: [f64; 3],
        check: fn(&mut Self, String, f64, f64),
    ) {
        for k in 0..3 {
            check(
                self,
                format!("{name}[{}]", CHANNELS[k]),
                value(k),
                thresholds[k],
            );
        }
    }

    fn push(&mut self, name: String, value: f64, threshold: f64, passed: bool, lower: bool) {
        self.0.push(GateCheck {
            name,
            value,
            threshold,
            passed,
            lower_bound: lower,
        });
    }
}

/// The mean SSIM values, or an error saying why a gate on them cannot be evaluated.
fn need_ssim(cmp: &Comparison) -> Result<super::PerChannel> {
    cmp.ssim_values().ok_or_else(|| {
        PgtError::Usage(format!(
            "an SSIM gate is set but SSIM is undefined: {}",
            ssim_reason(cmp)
        ))
    })
}

/// The mean FLIP, or an error saying why a gate on it cannot be evaluated.
fn need_flip(cmp: &Comparison) -> Result<f64> {
    cmp.flip_mean().ok_or_else(|| {
        PgtError::Usage(format!(
            "a FLIP gate is set but FLIP is undefined: {}",
            flip_reason(cmp)
        ))
    })
}

/// One value per pixel of a map kind (see [`MapKind`]).
pub fn per_pixel(
    kind: MapKind,
    cmp: &Comparison,
    reference: &RgbImage,
    approximation: &RgbImage,
) -> Result<Vec<f32>> {
    Ok(match kind {
        MapKind::Abs => maps::channel_mean(&maps::abs_error(reference, approximation)),
        MapKind::Rel => {
            maps::channel_mean(&maps::rel_error(reference, approximation, cmp.data_range))
        }
        MapKind::Ssim => match &cmp.ssim {
            Ok(s) => maps::channel_mean(&maps::ssim_image(cmp.width, cmp.height, s)),
            Err(e) => {
                return Err(PgtError::Usage(format!(
                    "an SSIM percentile gate is set but SSIM is undefined: {e}"
                )))
            }
        },
        MapKind::Flip => match &cmp.flip {
            Ok(f) => f.map.clone(),
            Err(e) => {
                return Err(PgtError::Usage(format!(
                    "a FLIP percentile gate is set but FLIP is undefined: {e}"
                )))
            }
        },
    })
}

fn ssim_reason(cmp: &Comparison) -> String {
    cmp.ssim
        .as_ref()
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default()
}

fn flip_reason(cmp: &Comparison) -> String {
    cmp.flip.as_ref().err().cloned().unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_lines_are_one_based() {
        let text = "min_ssim = 0.9\nmax_rsme = 0.1\n";
        let e = toml::from_str::<Gate>(text).unwrap_err();
        assert_eq!(crate::error::line_of(text, e.span().unwrap().start), 2);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("gate.toml");
        std::fs::write(&path, text).unwrap();
        let err = Gate::load(&path).unwrap_err().to_string();
        assert!(
            err.contains("gate.toml:2:") && err.contains("max_rsme"),
            "{err}"
        );
    }

    #[test]
    fn unknown_keys_are_rejected() {
        assert!(toml::from_str::<Gate>("min_ssim = 0.9\nmax_rsme = 0.1\n").is_err());
        assert!(toml::from_str::<Gate>("[channels]\nmin_ssim = [0.9, 0.9]\n").is_err());
        let g: Gate = toml::from_str(
            "min_ssim = 0.9\n[[percentiles]]\nmap = \"abs\"\npercentile = 99\nmax = 0.1\n",
        )
        .unwrap();
        assert_eq!(g.min_ssim, Some(0.9));
        assert_eq!(g.percentiles[0].map, MapKind::Abs);
        assert!(g.validate().is_ok());
        let bad: Gate =
            toml::from_str("[[percentiles]]\nmap = \"abs\"\npercentile = 99\n").unwrap();
        assert!(bad.validate().is_err());
        assert!(Gate::default().is_empty());
        assert!(!g.is_empty());
    }

    #[test]
    fn invalid_values_name_their_line() {
        let cases = [
            ("max_rmse = 0.1\nmin_ssim = nan\n", 2, "min_ssim must be a finite number"),
            (
                "min_ssim = 0.9\n\n[channels]\nmax_rmse = [0.1, 0.1, 0.1]\nmax_abs = [1.0, inf, 1.0]\n",
                5,
                "channels.max_abs must hold finite numbers",
            ),
            (
                "[[percentiles]]\nmap = \"abs\"\npercentile = 99\nmax = 0.1\n\n[[percentiles]]\nmap = \"rel\"\npercentile = 0\nmax = 0.1\n",
                6,
                "percentile must be in (0, 100], got 0",
            ),
            (
                "[[percentiles]]\nmap = \"ssim\"\npercentile = 5\nmin = 0.1\nmax = 0.2\n",
                1,
                "needs exactly one finite 'min' or 'max'",
            ),
        ];
        for (text, line, message) in cases {
            let err = Gate::parse(text, Path::new("g.toml"))
                .unwrap_err()
                .to_string();
            assert!(err.starts_with(&format!("g.toml:{line}: ")), "{err}");
            assert!(err.contains(message), "{err}");
        }
    }
}
