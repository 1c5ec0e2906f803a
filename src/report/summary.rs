//! The machine-readable summary of a comparison (docs/design.md §5, §7: `--json`), and the one-line
//! verdict for people.

use crate::metrics::gate::GateCheck;
use crate::metrics::{Comparison, DataRangeSource, PerChannel, CHANNELS};
use serde::Serialize;

/// The JSON summary. Infinite values (PSNR of identical channels) are written as `null`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    pub reference: String,
    pub approximation: String,
    pub width: u32,
    pub height: u32,
    pub data_range: f64,
    pub data_range_source: DataRangeSource,
    /// Per channel and mean; `null` when SSIM is undefined (see `ssim_note`).
    pub ssim: Option<PerChannel>,
    pub ssim_note: Option<String>,
    pub rmse: PerChannel,
    pub psnr: PerChannel,
    pub mean_abs: PerChannel,
    pub mean_rel: PerChannel,
    /// Largest absolute error per channel with its pixel, and over all channels.
    pub max_abs: Vec<MaxAbs>,
    pub flip: Option<f64>,
    /// "ldr" or "hdr" (HDR-FLIP) when FLIP was computed.
    pub flip_kind: Option<&'static str>,
    /// HDR-FLIP: [first, last] exposure in stops and their count.
    pub flip_exposures: Option<(f32, f32, usize)>,
    pub flip_note: Option<String>,
    /// Against the reference's own error estimate (its EXR `err` layer), when it has one.
    pub reference_uncertainty: Option<crate::metrics::errors::ReferenceUncertainty>,
    pub gates: Vec<GateCheck>,
    /// `null` without gates.
    pub passed: Option<bool>,
    /// Wall time of the comparison, seconds.
    pub seconds: f64,
}

/// The largest absolute error of one channel.
#[derive(Debug, Clone, Serialize)]
pub struct MaxAbs {
    pub channel: &'static str,
    pub value: f64,
    /// (x, y), x to the right, y down from the top row.
    pub pixel: [u32; 2],
}

impl Summary {
    /// Builds the summary of `cmp` with the gate results `gates`.
    pub fn new(
        reference: &str,
        approximation: &str,
        cmp: &Comparison,
        gates: Vec<GateCheck>,
        seconds: f64,
    ) -> Summary {
        let passed = if gates.is_empty() {
            None
        } else {
            Some(gates.iter().all(|g| g.passed))
        };
        Summary {
            reference: reference.to_string(),
            approximation: approximation.to_string(),
            width: cmp.width,
            height: cmp.height,
            data_range: cmp.data_range,
            data_range_source: cmp.data_range_source,
            ssim: cmp.ssim_values(),
            ssim_note: cmp.ssim.as_ref().err().map(|e| e.to_string()),
            rmse: cmp.error_values(|e| e.rmse),
            psnr: cmp.error_values(|e| e.psnr),
            mean_abs: cmp.error_values(|e| e.mean_abs),
            mean_rel: cmp.error_values(|e| e.mean_rel),
            max_abs: (0..3)
                .map(|c| MaxAbs {
                    channel: CHANNELS[c],
                    value: cmp.errors[c].max_abs,
                    pixel: [cmp.errors[c].max_abs_pixel.0, cmp.errors[c].max_abs_pixel.1],
                })
                .collect(),
            flip: cmp.flip_mean(),
            flip_kind: cmp.flip.as_ref().ok().map(|f| {
                if f.exposures.is_some() {
                    "hdr"
                } else {
                    "ldr"
                }
            }),
            flip_exposures: cmp.flip.as_ref().ok().and_then(|f| f.exposures),
            flip_note: cmp.flip.as_ref().err().cloned(),
            reference_uncertainty: None,
            gates,
            passed,
            seconds,
        }
    }

    /// The worst channel's max abs entry.
    pub fn worst_max_abs(&self) -> &MaxAbs {
        let mut worst = &self.max_abs[0];
        for m in &self.max_abs[1..] {
            if m.value > worst.value {
                worst = m;
            }
        }
        worst
    }

    /// The one-line verdict (docs/design.md §5): PASS/FAIL (naming every failing threshold) or
    /// "compared" without gates, then the headline metrics.
    pub fn verdict(&self) -> String {
        let ssim = match &self.ssim {
            Some(s) => format!(
                "SSIM {:.6} (R {:.6} G {:.6} B {:.6})",
                s.mean, s.r, s.g, s.b
            ),
            None => "SSIM n/a".to_string(),
        };
        let m = self.worst_max_abs();
        let mut metrics = format!(
            "{ssim}, RMSE {:.4e}, PSNR {}, max abs {:.4e} at ({}, {}) {}",
            self.rmse.mean,
            format_db(self.psnr.mean),
            m.value,
            m.pixel[0],
            m.pixel[1],
            m.channel
        );
        if let Some(f) = self.flip {
            let kind = if self.flip_kind == Some("hdr") {
                "HDR-FLIP"
            } else {
                "FLIP"
            };
            metrics += &format!(", {kind} {f:.4}");
        }
        match self.passed {
            None => format!("compared: {metrics}"),
            Some(true) => format!("PASS ({} gates): {metrics}", self.gates.len()),
            Some(false) => {
                let failed: Vec<String> = self
                    .gates
                    .iter()
                    .filter(|g| !g.passed)
                    .map(|g| {
                        format!(
                            "{} = {} (threshold {})",
                            g.name,
                            short(g.value),
                            short(g.threshold)
                        )
                    })
                    .collect();
                format!("FAIL {}: {metrics}", failed.join(", "))
            }
        }
    }
}

/// PSNR for people: "inf dB" for identical images.
pub fn format_db(v: f64) -> String {
    if v.is_infinite() {
        "inf dB".into()
    } else {
        format!("{v:.2} dB")
    }
}

/// A number with enough digits to compare it with a threshold.
pub fn short(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || (1e-3..1e4).contains(&a) {
        format!("{}", (v * 1e6).round() / 1e6)
    } else {
        format!("{v:.4e}")
    }
}
