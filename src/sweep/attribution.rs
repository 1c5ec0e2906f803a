//! Error attribution (docs/design.md §5): an approximation's error split into its causes by swapping
//! one stage at a time for its exact counterpart, along the chain an experiment's
//! `[[attribution]]` declares (format: the module documentation of [`crate::sweep`]).
//!
//! The chain is I₀ = the run explained, I₁, …, I_k = the exact reference R, each Iⱼ the
//! previous image with one more stage exact. Cause j's **error map** is dⱼ = Iⱼ₋₁ − Iⱼ, and the
//! maps add up exactly: I₀ − R = Σⱼ dⱼ. Two shares per cause, documented on the report page:
//!
//! * **SSIM share**: (SSIM(Iⱼ, R) − SSIM(Iⱼ₋₁, R)) / (1 − SSIM(I₀, R)), the part of the SSIM
//!   loss that removing the cause wins back. These telescope: they add up to exactly 1 (a share
//!   is negative where removing the cause alone makes the image worse).
//! * **MSE share**: ‖dⱼ‖² / ‖I₀ − R‖². These add up to 1 only when the causes' maps are
//!   orthogonal; the rest, 1 − Σ shares = the cross terms 2Σ⟨dᵢ, dⱼ⟩ / ‖I₀ − R‖², is reported
//!   as the **interaction** (negative where causes cancel each other).
//!
//! Both depend on the order of the chain (a cause removed later is measured with the earlier
//! ones gone); the experiment file fixes the order, and the report states it.

use super::experiment::{Attribution, Experiment};
use super::run_result::RunResult;
use crate::error::Result;
use crate::image_io::RgbImage;
use crate::metrics::{compare, maps, CompareOptions};

/// One cause of an attribution.
#[derive(Debug, Clone)]
pub struct CauseResult {
    /// The cause's name (from the experiment file; `residual` for what a chain that stops
    /// before the reference leaves).
    pub cause: String,
    /// The label of the image with the cause (Iⱼ₋₁) and without it (Iⱼ; `reference`).
    pub from: String,
    pub to: String,
    /// RMSE of dⱼ, mean over R, G, B.
    pub rmse: f64,
    /// Mean SSIM of Iⱼ₋₁ against Iⱼ (1 where the cause changes nothing).
    pub ssim: f64,
    /// SSIM share (see the module docs).
    pub ssim_share: f64,
    /// MSE share (see the module docs).
    pub mse_share: f64,
    /// |dⱼ|, mean over channels, per pixel: the cause's error map.
    pub map: Vec<f32>,
}

/// An attribution of one run's error.
#[derive(Debug, Clone)]
pub struct AttributionResult {
    /// The label of the run explained.
    pub label: String,
    /// Its file stem (for the maps' file names).
    pub stem: String,
    /// Its RMSE and mean SSIM against the reference.
    pub rmse: f64,
    pub ssim: f64,
    pub causes: Vec<CauseResult>,
    /// 1 − Σ MSE shares: the cross terms between the causes' maps.
    pub interaction: f64,
}

/// Σ over pixels and channels of d², and the pixel count × 3.
fn sum_sq(a: &RgbImage, b: &RgbImage) -> f64 {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| {
            (0..3)
                .map(|c| (p[c] as f64 - q[c] as f64).powi(2))
                .sum::<f64>()
        })
        .sum()
}

/// Computes one attribution from the images of its chain (`images[i]` is run i's image where
/// it was kept) and the runs' comparisons with the reference.
pub fn attribute(
    exp: &Experiment,
    attribution: &Attribution,
    images: &[Option<RgbImage>],
    runs: &[RunResult],
    reference: &RgbImage,
    options: &CompareOptions,
) -> Result<AttributionResult> {
    let image = |i: usize| images[i].as_ref().unwrap_or(reference);
    let ssim_of = |i: Option<usize>| match i {
        Some(i) => runs[i]
            .comparison
            .ssim_values()
            .map_or(f64::NAN, |s| s.mean),
        None => 1.0,
    };
    let label_of = |i: Option<usize>| i.map_or("reference".to_string(), |i| exp.runs[i].label());
    let first = attribution.run;
    let total_sq = sum_sq(image(first), reference);
    let total_ssim = ssim_of(Some(first));
    let mut chain: Vec<(String, Option<usize>)> = attribution
        .steps
        .iter()
        .map(|s| (s.cause.clone(), s.run))
        .collect();
    if chain.last().is_none_or(|(_, run)| run.is_some()) {
        chain.push(("residual".into(), None));
    }
    let mut causes = Vec::new();
    let mut from = Some(first);
    for (cause, to) in chain {
        let a = from.map_or(reference, image);
        let b = to.map_or(reference, image);
        let cmp = compare(b, a, options)?;
        let sq = sum_sq(a, b);
        causes.push(CauseResult {
            cause,
            from: label_of(from),
            to: label_of(to),
            rmse: cmp.error_values(|e| e.rmse).mean,
            ssim: cmp.ssim_values().map_or(f64::NAN, |s| s.mean),
            ssim_share: (ssim_of(to) - ssim_of(from)) / (1.0 - total_ssim),
            mse_share: sq / total_sq,
            map: maps::channel_mean(&maps::abs_error(b, a)),
        });
        from = to;
    }
    let interaction = 1.0 - causes.iter().map(|c| c.mse_share).sum::<f64>();
    Ok(AttributionResult {
        label: exp.runs[first].label(),
        stem: exp.runs[first].file_stem(),
        rmse: runs[first].comparison.error_values(|e| e.rmse).mean,
        ssim: total_ssim,
        causes,
        interaction,
    })
}
