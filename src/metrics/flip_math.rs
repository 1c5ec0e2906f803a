//! The cube root and powers of FLIP's per-pixel finish ([`super::flip_float`]) without libm
//! calls: branch-free f32 code that the compiler vectorises across a row of pixels, where
//! `f32::cbrt` and `f32::powf` are one library call per value and cost more than all of FLIP's
//! filtering together (a profile of a 4K compare).
//!
//! Accuracy (tests below, against the std functions over their whole domain in FLIP): [`cbrt`]
//! within 3 ulp; [`pow`] within 2·10⁻⁷ + 10⁻⁷·|e·log₂ x| relative (the second term is the f32
//! rounding of the exponent e·log₂ x itself), for the exponents FLIP uses (q_c = 0.7 on distances
//! up to a few hundred, 1 − feature ∈ [0, 1] on values in [0, 1]). FLIP's own budgets are 10⁻⁵
//! per pixel against nv-flip and flip-evaluator (tests/compare/flip.rs).

/// 1.5·2²³: adding and subtracting it rounds an f32 of magnitude < 2²² to the nearest integer
/// (without `f32::round`, a library call on x86-64's baseline SSE2).
const ROUNDER: f32 = 12_582_912.0;

/// ∛x for finite x ≥ 0 (x = 0 gives a tiny positive value; FLIP uses the result only above
/// (6/29)³). A first guess from the exponent bits divided by three (Kahan's constant), then
/// two Halley steps y ← y·(y³ + 2x)/(2y³ + x), each cubing the relative error (3·10⁻² → 10⁻⁵ →
/// below f32 rounding).
#[inline(always)]
pub fn cbrt(x: f32) -> f32 {
    // The bits of x as a number, divided by 3, in f32 (exact enough for a guess, and vectorises
    // where u32 division does not).
    let bits = (x.to_bits() as i32 as f32 * (1.0 / 3.0)) as i32;
    let mut y = f32::from_bits((bits + 709_921_077) as u32);
    for _ in 0..2 {
        let y3 = y * y * y;
        y = y * (y3 + 2.0 * x) / (2.0 * y3 + x);
    }
    y
}

/// log₂ x for finite x > 0 (subnormal x count as the smallest normal): x = m·2ᵉ with
/// m ∈ [√½, √2), log₂ m = (2/ln 2)·atanh t, t = (m − 1)/(m + 1), |t| ≤ 0.172, by its series
/// to t⁹ (truncation below 10⁻⁹).
#[inline(always)]
pub fn log2(x: f32) -> f32 {
    let bits = x.max(f32::MIN_POSITIVE).to_bits() as i32;
    // Move m from [1, 2) to [√½, √2): subtract the bits of √½ so that the exponent rounds.
    let shifted = bits - 0x3f35_04f3;
    let e = shifted >> 23;
    let m = f32::from_bits((bits - (e << 23)) as u32);
    let t = (m - 1.0) / (m + 1.0);
    let t2 = t * t;
    let series =
        t * (2.0 + t2 * (2.0 / 3.0 + t2 * (2.0 / 5.0 + t2 * (2.0 / 7.0 + t2 * (2.0 / 9.0)))));
    e as f32 + series * std::f32::consts::LOG2_E
}

/// 2ʸ, flushed to 0 below 2⁻¹²⁶ and capped at 2¹²⁷: y = n + f, f ∈ [−½, ½], 2ᶠ = e^{f·ln 2} by
/// its Taylor series to the 7th power (truncation below 5·10⁻⁹), 2ⁿ from the exponent bits.
#[inline(always)]
pub fn exp2(y: f32) -> f32 {
    let y = y.clamp(-126.0, 127.0);
    let n = (y + ROUNDER) - ROUNDER;
    let f = (y - n) * std::f32::consts::LN_2;
    let p = 1.0
        + f * (1.0
            + f * (1.0 / 2.0
                + f * (1.0 / 6.0
                    + f * (1.0 / 24.0
                        + f * (1.0 / 120.0 + f * (1.0 / 720.0 + f * (1.0 / 5040.0)))))));
    let scale = f32::from_bits(((n as i32 + 127) << 23) as u32);
    // n = −126 and f < 0 would need a subnormal result; FLIP's values never come near it.
    p * scale
}

/// xᵉ for finite x ≥ 0 and e ≥ 0, with `powf`'s values at the edges: 0ᵉ = 0 for e > 0 and
/// x⁰ = 1 (also 0⁰).
#[inline(always)]
pub fn pow(x: f32, e: f32) -> f32 {
    let v = exp2(e * log2(x));
    let v = if x == 0.0 { 0.0 } else { v };
    if e == 0.0 {
        1.0
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values spread over [lo, hi]: a uniform grid plus a geometric one (small values).
    fn samples(lo: f32, hi: f32, n: usize) -> Vec<f32> {
        let mut v: Vec<f32> = (0..=n)
            .map(|i| lo + (hi - lo) * i as f32 / n as f32)
            .collect();
        let mut x = hi;
        while x > lo.max(1e-30) {
            v.push(x);
            x *= 0.937;
        }
        v
    }

    fn ulps(a: f32, b: f32) -> u32 {
        (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs() as u32
    }

    #[test]
    fn cbrt_within_three_ulp_of_std() {
        // FLIP's domain: XYZ/white of clamped RGB, ≤ about 1.1, above (6/29)³; and beyond.
        let worst = samples(1e-6, 300.0, 200_000)
            .into_iter()
            .map(|x| ulps(cbrt(x), x.cbrt()))
            .max()
            .unwrap();
        assert!(worst <= 3, "cbrt off by {worst} ulp");
    }

    #[test]
    fn pow_within_its_bound_of_powf() {
        let mut worst = 0.0f64;
        for x in samples(1e-12, 400.0, 50_000) {
            for e in [0.7f32, 1.0, 0.999, 0.5, 0.25, 1e-3, 0.1] {
                let (got, want) = (pow(x, e) as f64, x.powf(e) as f64);
                let bound = 2e-7 + 1e-7 * (e as f64 * (x as f64).log2()).abs();
                worst = worst.max((got - want).abs() / want / bound);
            }
        }
        assert!(worst < 1.0, "pow off by {worst} of its bound");
    }

    #[test]
    fn pow_edges_match_powf() {
        for (x, e) in [
            (0.0f32, 0.7f32),
            (0.0, 0.0),
            (0.3, 0.0),
            (1.0, 0.7),
            (0.0, 1.0),
        ] {
            assert_eq!(pow(x, e), x.powf(e), "pow({x}, {e})");
        }
    }

    #[test]
    fn exp2_and_log2_are_inverse_at_integers() {
        for n in -125..127 {
            assert_eq!(exp2(n as f32), 2f32.powi(n), "exp2({n})");
            assert_eq!(log2(2f32.powi(n)), n as f32, "log2(2^{n})");
        }
    }
}
