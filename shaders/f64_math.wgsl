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
