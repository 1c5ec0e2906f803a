//! The thesis's integrator (thesis eq. 4.15–4.17, docs/design.md §8): midpoint Riemann sums with a
//! fixed number of samples per interval, kept so the adaptive reference can be compared with it.
//! It has no error estimate.

use glam::DVec3;

/// ∫_{t0}^{t1} e^{−σ(t−t0)}·σ·Q(t) dt ≈ Σ_i e^{−σ(t_i−t0)}·σ·Q(t_i)·Δt with Δt = (t1 − t0)/N and
/// t_i the midpoints (thesis eq. 4.16, with the λκ = σ factor of docs/design.md §8). The
/// transmittance inside the interval is exact; only Q is sampled.
pub fn midpoint_sum(
    t0: f64,
    t1: f64,
    sigma: f64,
    samples: u32,
    mut q: impl FnMut(f64) -> DVec3,
) -> DVec3 {
    let n = samples.max(1);
    let dt = (t1 - t0) / n as f64;
    let mut sum = DVec3::ZERO;
    for i in 0..n {
        let s = (i as f64 + 0.5) * dt;
        sum += (-sigma * s).exp() * q(t0 + s);
    }
    sum * (sigma * dt)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_source_converges_to_the_closed_form() {
        let (sigma, len) = (1.3f64, 2.0);
        let exact = 1.0 - (-sigma * len).exp();
        let coarse = (midpoint_sum(1.0, 3.0, sigma, 10, |_| DVec3::ONE).x - exact).abs();
        let fine = (midpoint_sum(1.0, 3.0, sigma, 1000, |_| DVec3::ONE).x - exact).abs();
        // The midpoint rule is second order: 100× the samples, about 10⁴× less error.
        assert!(fine < coarse * 2e-4 && fine < 1e-6, "{coarse} {fine}");
    }
}
