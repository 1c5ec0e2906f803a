//! Pass/fail gates on a comparison (DESIGN.md §5, §7: exit 0 pass, 1 fail, 2 error).
//!
//! A gate file is TOML; every key is optional, unknown keys are errors:
//!
//! ```toml
//! # Thresholds on the mean over the channels (DESIGN.md §5 "mean").
//! min_ssim = 0.99
//! max_rmse = 0.01
//! min_psnr = 35.0          # dB
//! max_abs = 0.25           # largest absolute error of any pixel
//! max_mean_abs = 0.005
//! max_mean_rel = 0.05
//! max_flip = 0.05          # mean LDR-FLIP
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
use crate::error::{PgtError, Result};
use crate::image_io::RgbImage;
use std::path::Path;

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

/// The outcome of one threshold.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct GateCheck {
    /// What was checked, e.g. `min_ssim`, `channels.max_rmse[G]`, `p99(abs) <= max`.
    pub name: String,
    pub value: f64,
    pub threshold: f64,
    pub passed: bool,
}

impl Gate {
    /// Reads and validates a gate file.
    pub fn load(path: &Path) -> Result<Gate> {
        let text = std::fs::read_to_string(path).map_err(|e| PgtError::io(path, e))?;
        let gate: Gate = toml::from_str(&text).map_err(|e| {
            let line = e
                .span()
                .map(|s| crate::metrics::gate::line_of(&text, s.start));
            match line {
                Some(l) => PgtError::at_line(path, l, e.message().to_string()),
                None => PgtError::in_file(path, e.message().to_string()),
            }
        })?;
        gate.validate().map_err(|m| PgtError::in_file(path, m))?;
        Ok(gate)
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
        ]
        .iter()
        .all(Option::is_none)
            && self.percentiles.is_empty()
    }

    /// Checks the values make sense (finite; percentiles in (0, 100] with exactly one bound).
    pub fn validate(&self) -> std::result::Result<(), String> {
        let scalars = [
            ("min_ssim", self.min_ssim),
            ("max_rmse", self.max_rmse),
            ("min_psnr", self.min_psnr),
            ("max_abs", self.max_abs),
            ("max_mean_abs", self.max_mean_abs),
            ("max_mean_rel", self.max_mean_rel),
            ("max_flip", self.max_flip),
        ];
        for (name, v) in scalars {
            if let Some(v) = v {
                if !v.is_finite() {
                    return Err(format!("{name} must be a finite number, got {v}"));
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
                    return Err(format!("channels.{name} must hold finite numbers"));
                }
            }
        }
        for p in &self.percentiles {
            if !(p.percentile > 0.0 && p.percentile <= 100.0) {
                return Err(format!(
                    "percentile must be in (0, 100], got {}",
                    p.percentile
                ));
            }
            match (p.min, p.max) {
                (Some(v), None) | (None, Some(v)) if v.is_finite() => {}
                _ => {
                    return Err(format!(
                        "percentile gate on '{:?}' needs exactly one finite 'min' or 'max'",
                        p.map
                    )
                    .to_lowercase())
                }
            }
        }
        Ok(())
    }

    /// Evaluates every threshold. An error (not a failure) where a gated metric is undefined:
    /// SSIM of an image smaller than the window, FLIP of an HDR pair.
    pub fn evaluate(
        &self,
        cmp: &Comparison,
        reference: &RgbImage,
        approximation: &RgbImage,
    ) -> Result<Vec<GateCheck>> {
        let mut checks = Vec::new();
        let need_ssim = || {
            cmp.ssim_values().ok_or_else(|| {
                PgtError::Usage(format!(
                    "an SSIM gate is set but SSIM is undefined: {}",
                    ssim_reason(cmp)
                ))
            })
        };
        let need_flip = || {
            cmp.flip_mean().ok_or_else(|| {
                PgtError::Usage(format!(
                    "a FLIP gate is set but FLIP is undefined: {}",
                    flip_reason(cmp)
                ))
            })
        };
        let mut at_least = |name: String, value: f64, threshold: f64| {
            checks.push(GateCheck {
                name,
                value,
                threshold,
                passed: value >= threshold,
            })
        };
        if let Some(t) = self.min_ssim {
            at_least("min_ssim".into(), need_ssim()?.mean, t);
        }
        if let Some(t) = self.min_psnr {
            at_least("min_psnr".into(), cmp.error_values(|e| e.psnr).mean, t);
        }
        if let Some(c) = &self.channels {
            if let Some(t) = c.min_ssim {
                let s = need_ssim()?;
                for k in 0..3 {
                    at_least(
                        format!("channels.min_ssim[{}]", CHANNELS[k]),
                        s.get(k),
                        t[k],
                    );
                }
            }
            if let Some(t) = c.min_psnr {
                for k in 0..3 {
                    at_least(
                        format!("channels.min_psnr[{}]", CHANNELS[k]),
                        cmp.errors[k].psnr,
                        t[k],
                    );
                }
            }
        }
        let mut at_most = |name: String, value: f64, threshold: f64| {
            checks.push(GateCheck {
                name,
                value,
                threshold,
                passed: value <= threshold,
            })
        };
        if let Some(t) = self.max_rmse {
            at_most("max_rmse".into(), cmp.error_values(|e| e.rmse).mean, t);
        }
        if let Some(t) = self.max_abs {
            let worst = cmp.errors.iter().map(|e| e.max_abs).fold(0.0, f64::max);
            at_most("max_abs".into(), worst, t);
        }
        if let Some(t) = self.max_mean_abs {
            at_most(
                "max_mean_abs".into(),
                cmp.error_values(|e| e.mean_abs).mean,
                t,
            );
        }
        if let Some(t) = self.max_mean_rel {
            at_most(
                "max_mean_rel".into(),
                cmp.error_values(|e| e.mean_rel).mean,
                t,
            );
        }
        if let Some(t) = self.max_flip {
            at_most("max_flip".into(), need_flip()?, t);
        }
        if let Some(c) = &self.channels {
            if let Some(t) = c.max_rmse {
                for k in 0..3 {
                    at_most(
                        format!("channels.max_rmse[{}]", CHANNELS[k]),
                        cmp.errors[k].rmse,
                        t[k],
                    );
                }
            }
            if let Some(t) = c.max_abs {
                for k in 0..3 {
                    at_most(
                        format!("channels.max_abs[{}]", CHANNELS[k]),
                        cmp.errors[k].max_abs,
                        t[k],
                    );
                }
            }
        }
        for p in &self.percentiles {
            let values = per_pixel(p.map, cmp, reference, approximation)?;
            let v = maps::percentile(&values, p.percentile).unwrap_or(f32::NAN) as f64;
            let kind = format!("{:?}", p.map).to_lowercase();
            let (name, threshold, passed) = match (p.min, p.max) {
                (Some(t), _) => (format!("p{}({kind}) >= min", p.percentile), t, v >= t),
                (None, Some(t)) => (format!("p{}({kind}) <= max", p.percentile), t, v <= t),
                (None, None) => continue, // excluded by validate()
            };
            checks.push(GateCheck {
                name,
                value: v,
                threshold,
                passed,
            });
        }
        Ok(checks)
    }
}

/// The 1-based line of byte offset `offset` in `text` (for errors that name file:line).
pub fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
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
        assert_eq!(line_of("a\nb\nc", 0), 1);
        assert_eq!(line_of("a\nb\nc", 2), 2);
        assert_eq!(line_of("a\nb\nc", 99), 3);
        let text = "min_ssim = 0.9\nmax_rsme = 0.1\n";
        let e = toml::from_str::<Gate>(text).unwrap_err();
        assert_eq!(line_of(text, e.span().unwrap().start), 2);
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
}
