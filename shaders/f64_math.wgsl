// f64 exp, expm1 and log1p from +, −, ×, ÷, fma and ldexp (docs/design.md §12).
//
// Vulkan's extended instructions define exp and log for 16- and 32-bit floats only; WGSL's
// builtins on f64 compile and return garbage (lavapipe: exp gives 0). The GPU reference calls
// these functions instead, never a transcendental builtin on f64 (tests/gpu/reference.rs scans
// the program for one). Their error in ulps, measured against the CPU's libm over dense and
// random arguments, is src/reference/gpu/math.rs's EXP_ULPS, EXPM1_ULPS and LOG1P_ULPS, which
// the GPU reference's err uses.
//
// Constants are literals (`lf`): naga's constant evaluator refuses math builtins on f64, so no
// constant is computed from another.

// fdlibm's split of ln 2: LN2_HI has 32 trailing zero bits, so k·LN2_HI is exact for |k| < 2^20
// and x − k·LN2_HI is exact near the reduced argument.
const F64_LN2_HI: f64 = 0.6931471803691238lf;
const F64_LN2_LO: f64 = 1.9082149292705877e-10lf;
const F64_INV_LN2: f64 = 1.4426950408889634lf;
const F64_HALF_LN2: f64 = 0.34657359027997264lf;
const F64_SQRT2: f64 = 1.4142135623730951lf;

// 1/n! for the Taylor series of expm1 on |r| ≤ ln2/2: the first term left out, r^15/15!, is
// below 3e-19 of |r|.
const F64_EXP_C2: f64 = 0.5lf;
const F64_EXP_C3: f64 = 0.16666666666666666lf;
const F64_EXP_C4: f64 = 0.041666666666666664lf;
const F64_EXP_C5: f64 = 0.008333333333333333lf;
const F64_EXP_C6: f64 = 0.001388888888888889lf;
const F64_EXP_C7: f64 = 0.0001984126984126984lf;
const F64_EXP_C8: f64 = 2.48015873015873e-05lf;
const F64_EXP_C9: f64 = 2.7557319223985893e-06lf;
const F64_EXP_C10: f64 = 2.755731922398589e-07lf;
const F64_EXP_C11: f64 = 2.505210838544172e-08lf;
const F64_EXP_C12: f64 = 2.08767569878681e-09lf;
const F64_EXP_C13: f64 = 1.6059043836821613e-10lf;
const F64_EXP_C14: f64 = 1.1470745597729725e-11lf;

// 2/(2n+1) for log(1+f) = 2·atanh(s), s = f/(2+f), in z = s² ≤ 0.0295: the first term left
// out, z^13·2/27, is below 1e-19 of the sum.
const F64_LOG_C1: f64 = 0.6666666666666666lf;
const F64_LOG_C2: f64 = 0.4lf;
const F64_LOG_C3: f64 = 0.2857142857142857lf;
const F64_LOG_C4: f64 = 0.2222222222222222lf;
const F64_LOG_C5: f64 = 0.18181818181818182lf;
const F64_LOG_C6: f64 = 0.15384615384615385lf;
const F64_LOG_C7: f64 = 0.13333333333333333lf;
const F64_LOG_C8: f64 = 0.11764705882352941lf;
const F64_LOG_C9: f64 = 0.10526315789473684lf;
const F64_LOG_C10: f64 = 0.09523809523809523lf;
const F64_LOG_C11: f64 = 0.08695652173913043lf;
const F64_LOG_C12: f64 = 0.08lf;

// expm1 on the reduced range |r| ≤ ln2/2 (a little beyond is fine): r + r²·q(r), q the Taylor
// series Σ_{n=2}^{14} r^{n−2}/n! by Horner with fma.
fn f64_expm1_reduced(r: f64) -> f64 {
    var q = F64_EXP_C14;
    q = fma(q, r, F64_EXP_C13);
    q = fma(q, r, F64_EXP_C12);
    q = fma(q, r, F64_EXP_C11);
    q = fma(q, r, F64_EXP_C10);
    q = fma(q, r, F64_EXP_C9);
    q = fma(q, r, F64_EXP_C8);
    q = fma(q, r, F64_EXP_C7);
    q = fma(q, r, F64_EXP_C6);
    q = fma(q, r, F64_EXP_C5);
    q = fma(q, r, F64_EXP_C4);
    q = fma(q, r, F64_EXP_C3);
    q = fma(q, r, F64_EXP_C2);
    return fma(r * r, q, r);
}

// x = k·ln 2 + r with |r| ≤ ln2/2 (fdlibm's Cody–Waite reduction): k and r.
struct F64Reduced {
    k: i32,
    r: f64,
}

fn f64_reduce(x: f64) -> F64Reduced {
    let kf = round(x * F64_INV_LN2);
    let hi = x - kf * F64_LN2_HI;
    let lo = kf * F64_LN2_LO;
    return F64Reduced(i32(kf), hi - lo);
}

// 2^k·m in two steps, so that neither step over- or underflows where the result does not (k up
// to ±1100): exact for a normal result, one rounding for a subnormal one.
fn f64_scale(m: f64, k: i32) -> f64 {
    let k1 = k / 2;
    return ldexp(ldexp(m, k1), k - k1);
}

// e^x. 0 below −745.2 (below half the smallest subnormal), +∞ above 709.79.
fn f64_exp(x: f64) -> f64 {
    if (x < -745.2lf) {
        return 0.0lf;
    }
    if (x > 709.79lf) {
        return x * 1.0e308lf;
    }
    let red = f64_reduce(x);
    return f64_scale(1.0lf + f64_expm1_reduced(red.r), red.k);
}

// e^x − 1 with the digits of small x. −1 below −38 (e^x is then below half an ulp of 1).
fn f64_expm1(x: f64) -> f64 {
    if (abs(x) <= F64_HALF_LN2) {
        return f64_expm1_reduced(x);
    }
    if (x < -38.0lf) {
        return -1.0lf;
    }
    if (x > 709.79lf) {
        return x * 1.0e308lf;
    }
    let red = f64_reduce(x);
    let p = f64_expm1_reduced(red.r);
    if (red.k == 0) {
        return p;
    }
    if (red.k <= -54 || red.k >= 54) {
        // 2^k·(1 + p) − 1: one of the two terms is below an ulp of the other.
        return f64_scale(1.0lf + p, red.k) - 1.0lf;
    }
    // 2^k·(p − (2^−k − 1)): 2^−k − 1 is exact for |k| ≤ 53, and the one subtraction rounds a
    // result of the size of the answer (no cancellation).
    return ldexp(p - (ldexp(1.0lf, -red.k) - 1.0lf), red.k);
}

// log(1 + f) for √2/2 − 1 ≤ f ≤ √2 − 1 (fdlibm's form): with s = f/(2 + f) and hfsq = f²/2,
// log(1 + f) = 2·atanh(s) = f − hfsq + s·(hfsq + R), R = Σ_{n≥1} 2s^{2n}/(2n+1); f enters
// exactly, the rest is a correction a few times smaller.
fn f64_log1p_reduced(f: f64) -> f64 {
    let s = f / (2.0lf + f);
    let z = s * s;
    var r = F64_LOG_C12;
    r = fma(r, z, F64_LOG_C11);
    r = fma(r, z, F64_LOG_C10);
    r = fma(r, z, F64_LOG_C9);
    r = fma(r, z, F64_LOG_C8);
    r = fma(r, z, F64_LOG_C7);
    r = fma(r, z, F64_LOG_C6);
    r = fma(r, z, F64_LOG_C5);
    r = fma(r, z, F64_LOG_C4);
    r = fma(r, z, F64_LOG_C3);
    r = fma(r, z, F64_LOG_C2);
    r = fma(r, z, F64_LOG_C1);
    r = r * z;
    let hfsq = 0.5lf * f * f;
    return f - (hfsq - s * (hfsq + r));
}

// m and k (an integer, as f64) with y = 2^k·m, √2/2 ≤ m < √2, for 2^−63 ≤ y < 2^1024 (by powers of two: exact):
// first 1 ≤ m < 2, the exponent taken off a binary digit at a time.
struct F64Split {
    m: f64,
    k: f64,
}

fn f64_split(y: f64) -> F64Split {
    var m = y;
    var k = 0.0lf;
    if (m >= 1.3407807929942597e+154lf) { m = m * 7.458340731200207e-155lf; k = k + 512.0lf; }
    if (m >= 1.157920892373162e+77lf) { m = m * 8.636168555094445e-78lf; k = k + 256.0lf; }
    if (m >= 3.402823669209385e+38lf) { m = m * 2.938735877055719e-39lf; k = k + 128.0lf; }
    if (m >= 1.8446744073709552e+19lf) { m = m * 5.421010862427522e-20lf; k = k + 64.0lf; }
    if (m >= 4294967296.0lf) { m = m * 2.3283064365386963e-10lf; k = k + 32.0lf; }
    if (m >= 65536.0lf) { m = m * 1.52587890625e-05lf; k = k + 16.0lf; }
    if (m >= 256.0lf) { m = m * 0.00390625lf; k = k + 8.0lf; }
    if (m >= 16.0lf) { m = m * 0.0625lf; k = k + 4.0lf; }
    if (m >= 4.0lf) { m = m * 0.25lf; k = k + 2.0lf; }
    if (m >= 2.0lf) { m = m * 0.5lf; k = k + 1.0lf; }
    if (m < 4.656612873077393e-10lf) { m = m * 4294967296.0lf; k = k - 32.0lf; }
    if (m < 3.0517578125e-05lf) { m = m * 65536.0lf; k = k - 16.0lf; }
    if (m < 0.0078125lf) { m = m * 256.0lf; k = k - 8.0lf; }
    if (m < 0.125lf) { m = m * 16.0lf; k = k - 4.0lf; }
    if (m < 0.5lf) { m = m * 4.0lf; k = k - 2.0lf; }
    if (m < 1.0lf) { m = m * 2.0lf; k = k - 1.0lf; }
    if (m >= F64_SQRT2) { m = m * 0.5lf; k = k + 1.0lf; }
    return F64Split(m, k);
}

// log(1 + x) for x > −1 with the digits of small x. Where 1 + x is not near 1 it is split as
// 2^k·m and log(1 + x) = k·ln 2 + log(m) + c/(1 + x), c the rounding error of 1 + x (exact by
// Fast2Sum).
fn f64_log1p(x: f64) -> f64 {
    if (x > -0.2928932188134524lf && x < 0.41421356237309503lf) {
        return f64_log1p_reduced(x);
    }
    let y = 1.0lf + x;
    var c = x - (y - 1.0lf);
    if (x >= 1.0lf) {
        c = 1.0lf - (y - x);
    }
    let split = f64_split(y);
    let kf = split.k;
    let lo = kf * F64_LN2_LO + c / y;
    return kf * F64_LN2_HI + (f64_log1p_reduced(split.m - 1.0lf) + lo);
}

// erfc in FreeBSD's form (s_erf.c, as the `libm` crate ports it; its coefficients): a rational
// approximation of erf on |x| < 0.84375, of erf(1 + s) − c on [0.84375, 1.25], and of
// log(x·erfc x) + x² − 0.5625 in 1/x² on [1.25, 1/0.35] and [1/0.35, 28]; erfc(−x) = 2 − erfc x.
// The e^{−x²} of the tails as e^{−z² − 0.5625}·e^{(z − x)(z + x) + R/S} with z = x rounded to
// f32, whose square is exact in f64. Its error in ulps is math.rs's ERFC_ULPS.
const F64_ERX: f64 = 8.45062911510467529297e-01lf;
const F64_PP0: f64 = 1.28379167095512558561e-01lf;
const F64_PP1: f64 = -3.25042107247001499370e-01lf;
const F64_PP2: f64 = -2.84817495755985104766e-02lf;
const F64_PP3: f64 = -5.77027029648944159157e-03lf;
const F64_PP4: f64 = -2.37630166566501626084e-05lf;
const F64_QQ1: f64 = 3.97917223959155352819e-01lf;
const F64_QQ2: f64 = 6.50222499887672944485e-02lf;
const F64_QQ3: f64 = 5.08130628187576562776e-03lf;
const F64_QQ4: f64 = 1.32494738004321644526e-04lf;
const F64_QQ5: f64 = -3.96022827877536812320e-06lf;
const F64_PA0: f64 = -2.36211856075265944077e-03lf;
const F64_PA1: f64 = 4.14856118683748331666e-01lf;
const F64_PA2: f64 = -3.72207876035701323847e-01lf;
const F64_PA3: f64 = 3.18346619901161753674e-01lf;
const F64_PA4: f64 = -1.10894694282396677476e-01lf;
const F64_PA5: f64 = 3.54783043256182359371e-02lf;
const F64_PA6: f64 = -2.16637559486879084300e-03lf;
const F64_QA1: f64 = 1.06420880400844228286e-01lf;
const F64_QA2: f64 = 5.40397917702171048937e-01lf;
const F64_QA3: f64 = 7.18286544141962662868e-02lf;
const F64_QA4: f64 = 1.26171219808761642112e-01lf;
const F64_QA5: f64 = 1.36370839120290507362e-02lf;
const F64_QA6: f64 = 1.19844998467991074170e-02lf;
const F64_RA0: f64 = -9.86494403484714822705e-03lf;
const F64_RA1: f64 = -6.93858572707181764372e-01lf;
const F64_RA2: f64 = -1.05586262253232909814e+01lf;
const F64_RA3: f64 = -6.23753324503260060396e+01lf;
const F64_RA4: f64 = -1.62396669462573470355e+02lf;
const F64_RA5: f64 = -1.84605092906711035994e+02lf;
const F64_RA6: f64 = -8.12874355063065934246e+01lf;
const F64_RA7: f64 = -9.81432934416914548592e+00lf;
const F64_SA1: f64 = 1.96512716674392571292e+01lf;
const F64_SA2: f64 = 1.37657754143519042600e+02lf;
const F64_SA3: f64 = 4.34565877475229228821e+02lf;
const F64_SA4: f64 = 6.45387271733267880336e+02lf;
const F64_SA5: f64 = 4.29008140027567833386e+02lf;
const F64_SA6: f64 = 1.08635005541779435134e+02lf;
const F64_SA7: f64 = 6.57024977031928170135e+00lf;
const F64_SA8: f64 = -6.04244152148580987438e-02lf;
const F64_RB0: f64 = -9.86494292470009928597e-03lf;
const F64_RB1: f64 = -7.99283237680523006574e-01lf;
const F64_RB2: f64 = -1.77579549177547519889e+01lf;
const F64_RB3: f64 = -1.60636384855821916062e+02lf;
const F64_RB4: f64 = -6.37566443368389627722e+02lf;
const F64_RB5: f64 = -1.02509513161107724954e+03lf;
const F64_RB6: f64 = -4.83519191608651397019e+02lf;
const F64_SB1: f64 = 3.03380607434824582924e+01lf;
const F64_SB2: f64 = 3.25792512996573918826e+02lf;
const F64_SB3: f64 = 1.53672958608443695994e+03lf;
const F64_SB4: f64 = 3.19985821950859553908e+03lf;
const F64_SB5: f64 = 2.55305040643316442583e+03lf;
const F64_SB6: f64 = 4.74528541206955367215e+02lf;
const F64_SB7: f64 = -2.24409524465858183362e+01lf;

// erfc(|x|) for 0.84375 ≤ |x| < 28.
fn f64_erfc_far(x: f64) -> f64 {
    let a = abs(x);
    if (a < 1.25lf) {
        let s = a - 1.0lf;
        let p = F64_PA0 + s * (F64_PA1 + s * (F64_PA2 + s * (F64_PA3 + s * (F64_PA4 + s * (F64_PA5 + s * F64_PA6)))));
        let q = 1.0lf + s * (F64_QA1 + s * (F64_QA2 + s * (F64_QA3 + s * (F64_QA4 + s * (F64_QA5 + s * F64_QA6)))));
        return 1.0lf - F64_ERX - p / q;
    }
    let s = 1.0lf / (a * a);
    var r: f64;
    var big_s: f64;
    if (a < 2.8571414947509766lf) {
        r = F64_RA0 + s * (F64_RA1 + s * (F64_RA2 + s * (F64_RA3 + s * (F64_RA4 + s * (F64_RA5 + s * (F64_RA6 + s * F64_RA7))))));
        big_s = 1.0lf + s * (F64_SA1 + s * (F64_SA2 + s * (F64_SA3 + s * (F64_SA4 + s * (F64_SA5 + s * (F64_SA6 + s * (F64_SA7 + s * F64_SA8)))))));
    } else {
        r = F64_RB0 + s * (F64_RB1 + s * (F64_RB2 + s * (F64_RB3 + s * (F64_RB4 + s * (F64_RB5 + s * F64_RB6)))));
        big_s = 1.0lf + s * (F64_SB1 + s * (F64_SB2 + s * (F64_SB3 + s * (F64_SB4 + s * (F64_SB5 + s * (F64_SB6 + s * F64_SB7))))));
    }
    let z = f64(f32(a));
    return f64_exp(-z * z - 0.5625lf) * f64_exp((z - a) * (z + a) + r / big_s) / a;
}

// erfc x = 1 − erf x, with the digits of small results for large x: 0 from x ≥ 28 (below
// 2^−1074 from 27.3), 2 from x ≤ −6 (within half an ulp of 2).
fn f64_erfc(x: f64) -> f64 {
    let a = abs(x);
    if (a < 0.84375lf) {
        if (a < 1.3877787807814457e-17lf) {
            return 1.0lf - x;
        }
        let z = x * x;
        let r = F64_PP0 + z * (F64_PP1 + z * (F64_PP2 + z * (F64_PP3 + z * F64_PP4)));
        let s = 1.0lf + z * (F64_QQ1 + z * (F64_QQ2 + z * (F64_QQ3 + z * (F64_QQ4 + z * F64_QQ5))));
        let y = r / s;
        if (x < 0.25lf) {
            return 1.0lf - (x + x * y);
        }
        return 0.5lf - (x - 0.5lf + x * y);
    }
    if (a < 28.0lf) {
        let far = f64_erfc_far(x);
        return select(far, 2.0lf - far, x < 0.0lf);
    }
    return select(0.0lf, 2.0lf, x < 0.0lf);
}
