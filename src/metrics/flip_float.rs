//! FLIP (Andersson et al. 2020, "FLIP: A Difference Evaluator for Alternating Images") evaluated
//! in f32 on linear RGB, in Rust, in parallel bands of rows: the colour pipeline (YCxCz, the
//! contrast sensitivity filters, CIELab with the Hunt adjustment, HyAB distance) and the feature
//! pipeline (edges and points from Gaussian derivatives) of the paper, with NVIDIA's constants and
//! separated filters (`separatedConvolutions.pdf` of the FLIP repository).
//!
//! It replaces nv-flip in [`super::flip`] for speed and because nv-flip only accepts 8-bit sRGB:
//! HDR-FLIP here tone-maps each exposure in float and never quantises. Evaluated on the decoded
//! bytes nv-flip would see, it reproduces nv-flip's map to float rounding (tests below and in
//! tests/compare/flip.rs); the filters sum in the same order as NVIDIA's C++ (taps from −r to r,
//! products then sums), and the cube root and powers of the per-pixel finish are
//! [`super::flip_math`]'s vectorisable ones (within 10⁻⁶ of libm's).
//!
//! Structure (a 4K pair in about a second): the image is cut into work items of
//! [`ROWS`] rows by at most [`STRIP`] columns. An item converts each input row it reads (its own,
//! and the filters' [`Filters::reach`] beyond, clamped to the image) to YCxCz through a caller's
//! per-pixel transform (clamping for LDR, tone mapping at one exposure for HDR), filters it along
//! x into a ring of the last 2·reach + 1 rows, and as soon as an output row's rows are in the
//! ring filters them along y and finishes its pixels. The ring of a strip stays in a core's
//! cache. Borders clamp to the edge, as NVIDIA's code does, so the result does not depend on the
//! layout or the thread count. A plainer band-by-band version is kept in the tests as the
//! oracle of this one.

use super::flip_math;
use rayon::prelude::*;

/// FLIP's constants (paper, Table 1; NVIDIA `FLIPConstants`): colour exponent q_c, cut-off p_c,
/// remapped cut-off p_t, feature filter width w (degrees). The feature exponent q_f = 0.5 is
/// applied as a square root.
const GQC: f32 = 0.7;
const GPC: f32 = 0.4;
const GPT: f32 = 0.95;
const GW: f32 = 0.082;
/// π in f32, the value NVIDIA's code holds (its literal 3.14159265358979f rounds to it).
const PI: f32 = std::f32::consts::PI;
/// Contrast sensitivity Gaussians (paper eq. 2) for the Y, Cx and Cz channels: a₁, b₁, a₂, b₂
/// (the second Gaussian is used by Cz only).
const A1: [f32; 3] = [1.0, 1.0, 34.1];
const B1: [f32; 3] = [0.0047, 0.0053, 0.04];
const A2: [f32; 3] = [0.0, 0.0, 13.5];
const B2: [f32; 3] = [1.0e-5, 1.0e-5, 0.025];
/// D65 reference white and its inverse (XYZ), as NVIDIA's code holds them.
const WHITE: [f32; 3] = [0.950_428_55, 1.0, 1.088_900_4];
const INV_WHITE: [f32; 3] = [1.052_156_9, 1.0, 0.918_357_7];

/// Output columns of a work item at most: its ring of x-filtered rows (7 planes, 2 images,
/// 2·reach + 1 rows) is about 600 KB at 512 columns and reach 10, within a core's L2 cache, so
/// the y filters read from cache (the full-width bands before were memory-bound there).
const STRIP: usize = 512;
/// Output rows of a work item: tall, so that the reach rows above and below, which the item
/// above or below converts and x-filters too, cost little (8% at 256 rows and reach 10).
const ROWS: usize = 256;
/// Columns the filters accumulate in registers at a time.
const LANES: usize = 16;

/// Linear RGB → XYZ (D65; NVIDIA's rational coefficients).
#[inline(always)]
fn linear_rgb_to_xyz(c: [f32; 3]) -> [f32; 3] {
    let m = [
        [
            10135552.0f32 / 24577794.0,
            8788810.0 / 24577794.0,
            4435075.0 / 24577794.0,
        ],
        [
            2613072.0 / 12288897.0,
            8788810.0 / 12288897.0,
            887015.0 / 12288897.0,
        ],
        [
            1425312.0 / 73733382.0,
            8788810.0 / 73733382.0,
            70074185.0 / 73733382.0,
        ],
    ];
    m.map(|r| r[0] * c[0] + r[1] * c[1] + r[2] * c[2])
}

/// XYZ → linear RGB (D65).
#[inline(always)]
fn xyz_to_linear_rgb(c: [f32; 3]) -> [f32; 3] {
    let m = [
        [3.241_003_3f32, -1.537_398_9, -0.498_615_87],
        [-0.969_224_33, 1.875_930_1, 0.041_554_224],
        [0.055_639_423, -0.204_011_2, 1.057_148_9],
    ];
    m.map(|r| r[0] * c[0] + r[1] * c[1] + r[2] * c[2])
}

/// XYZ → YCxCz (paper §3.1: the opponent space in which the CSFs act), relative to D65.
#[inline(always)]
fn xyz_to_ycxcz(c: [f32; 3]) -> [f32; 3] {
    let (x, y, z) = (
        c[0] * INV_WHITE[0],
        c[1] * INV_WHITE[1],
        c[2] * INV_WHITE[2],
    );
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// YCxCz → XYZ.
#[inline(always)]
fn ycxcz_to_xyz(c: [f32; 3]) -> [f32; 3] {
    let y = (c[0] + 16.0) / 116.0;
    let cx = c[1] / 500.0;
    let cz = c[2] / 200.0;
    [(y + cx) * WHITE[0], y * WHITE[1], (y - cz) * WHITE[2]]
}

/// CIELab's f(v): ∛v above (6/29)³, linear below, with the cube root `cbrt`. Both sides are
/// computed and one selected, so that a row of pixels vectorises.
#[inline(always)]
fn lab_f(v: f32, cbrt: &impl Fn(f32) -> f32) -> f32 {
    let delta = 6.0f32 / 29.0;
    let delta_sq = delta * delta;
    let factor = 1.0 / (3.0 * delta_sq);
    let (root, linear) = (cbrt(v), factor * v + 4.0f32 / 29.0);
    if v > delta * delta_sq {
        root
    } else {
        linear
    }
}

/// XYZ → CIELab (D65), with the cube root `cbrt` (NVIDIA's is powf(v, 1/3); pgt's finish uses
/// [`flip_math::cbrt`], the kept oracle and the constants `f32::cbrt`).
#[inline(always)]
fn xyz_to_lab(c: [f32; 3], cbrt: impl Fn(f32) -> f32) -> [f32; 3] {
    let (x, y, z) = (
        lab_f(c[0] * INV_WHITE[0], &cbrt),
        lab_f(c[1] * INV_WHITE[1], &cbrt),
        lab_f(c[2] * INV_WHITE[2], &cbrt),
    );
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// Hunt-adjusted CIELab (paper eq. 4): chroma scaled by 0.01·L.
#[inline(always)]
fn hunt(lab: [f32; 3]) -> [f32; 3] {
    [lab[0], 0.01 * lab[0] * lab[1], 0.01 * lab[0] * lab[2]]
}

/// HyAB distance (paper eq. 5): |ΔL| + ‖Δ(a, b)‖.
#[inline(always)]
fn hyab(p: [f32; 3], q: [f32; 3]) -> f32 {
    let (da, db) = (p[1] - q[1], p[2] - q[2]);
    (p[0] - q[0]).abs() + (da * da + db * db).sqrt()
}

/// The largest colour distance, green to blue (paper §3.1), raised to q_c.
fn max_distance() -> f32 {
    let lab = |c| hunt(xyz_to_lab(linear_rgb_to_xyz(c), f32::cbrt));
    hyab(lab([0.0, 1.0, 0.0]), lab([0.0, 0.0, 1.0])).powf(GQC)
}

/// The separated filters at a viewing condition (pixels per degree).
#[derive(Debug, Clone)]
pub struct Filters {
    /// Radius of the CSF filters (pixels).
    pub spatial_radius: usize,
    /// Per tap: the Y and Cx CSF weights (each sums to 1).
    ycx: Vec<[f32; 2]>,
    /// Per tap: the two Cz Gaussians, each the square root of its 2-D filter's separable factor.
    cz: Vec<[f32; 2]>,
    /// Radius of the feature filters (pixels).
    pub feature_radius: usize,
    /// Per tap: Gaussian, its first and its second derivative (normalised as NVIDIA does).
    feature: Vec<[f32; 3]>,
}

/// exp(−π²x²/b)·a·√(π/b): one CSF Gaussian in the paper's form (eq. 2).
fn csf_gaussian(x2: f32, a: f32, b: f32) -> f32 {
    a * (PI / b).sqrt() * (-(PI * PI) * x2 / b).exp()
}

/// The square root of the amplitude, so that the product of an x and a y factor is one term of
/// Cz's sum of two Gaussians.
fn csf_gaussian_sqrt(x2: f32, a: f32, b: f32) -> f32 {
    (a * (PI / b).sqrt()).sqrt() * (-(PI * PI) * x2 / b).exp()
}

impl Filters {
    /// The filters for `ppd` pixels per degree. Radii: ⌈3·√(b_max/(2π²))·ppd⌉ for the CSFs and
    /// ⌈3·σ_f⌉ with σ_f = w·ppd/2 for the features (NVIDIA's choices).
    pub fn new(ppd: f32) -> Filters {
        let max_b = B1.iter().chain(&B2).fold(0.0f32, |m, &b| m.max(b));
        let spatial_radius = (3.0 * (max_b / (2.0 * (PI * PI))).sqrt() * ppd).ceil() as usize;
        let dx = 1.0 / ppd;
        let mut ycx = Vec::new();
        let mut cz = Vec::new();
        let (mut sum_ycx, mut sum_cz) = ([0.0f32; 2], [0.0f32; 2]);
        for i in 0..2 * spatial_radius + 1 {
            let x = (i as f32 - spatial_radius as f32) * dx;
            let x2 = x * x;
            let t = [
                csf_gaussian(x2, A1[0], B1[0]),
                csf_gaussian(x2, A1[1], B1[1]),
            ];
            let z = [
                csf_gaussian_sqrt(x2, A1[2], B1[2]),
                csf_gaussian_sqrt(x2, A2[2], B2[2]),
            ];
            for ((s, v), (sz, vz)) in sum_ycx.iter_mut().zip(t).zip(sum_cz.iter_mut().zip(z)) {
                *s += v;
                *sz += vz;
            }
            ycx.push(t);
            cz.push(z);
        }
        let norm_ycx = [1.0 / sum_ycx[0], 1.0 / sum_ycx[1]];
        let norm_cz = 1.0 / (sum_cz[0] * sum_cz[0] + sum_cz[1] * sum_cz[1]).sqrt();
        for t in &mut ycx {
            *t = [t[0] * norm_ycx[0], t[1] * norm_ycx[1]];
        }
        for z in &mut cz {
            *z = [z[0] * norm_cz, z[1] * norm_cz];
        }

        let sd = 0.5 * GW * ppd;
        let feature_radius = (3.0 * sd).ceil() as usize;
        let mut feature = Vec::new();
        let (mut g_sum, mut dg_pos, mut dg_neg, mut ddg_pos, mut ddg_neg) =
            (0.0f32, 0.0, 0.0, 0.0, 0.0);
        for i in 0..2 * feature_radius + 1 {
            let x = i as f32 - feature_radius as f32;
            let g = (-(x * x) / (2.0 * sd * sd)).exp();
            g_sum += g;
            let dg = -x * g;
            if dg > 0.0 {
                dg_pos += dg;
            } else {
                dg_neg -= dg;
            }
            let ddg = (x * x / (sd * sd) - 1.0) * g;
            if ddg > 0.0 {
                ddg_pos += ddg;
            } else {
                ddg_neg -= ddg;
            }
            feature.push([g, dg, ddg]);
        }
        // Gaussian weights sum to 1; the positive and negative lobes of the derivatives to ±1.
        for f in &mut feature {
            *f = [
                f[0] / g_sum,
                f[1] / if f[1] > 0.0 { dg_pos } else { dg_neg },
                f[2] / if f[2] > 0.0 { ddg_pos } else { ddg_neg },
            ];
        }
        Filters {
            spatial_radius,
            ycx,
            cz,
            feature_radius,
            feature,
        }
    }

    /// Rows above and below a band that its pixels read.
    pub fn reach(&self) -> usize {
        self.spatial_radius.max(self.feature_radius)
    }
}

/// A filtered YCxCz pixel back to linear RGB, clamped to [0, 1], and on to Hunt-adjusted CIELab
/// (paper §3.1). A function, not a closure, so that it inlines into the vectorised row loop.
#[inline(always)]
fn filtered_to_lab(c: [f32; 3], cbrt: impl Fn(f32) -> f32) -> [f32; 3] {
    let rgb = xyz_to_linear_rgb(ycxcz_to_xyz(c)).map(|v| v.clamp(0.0, 1.0));
    hunt(xyz_to_lab(linear_rgb_to_xyz(rgb), cbrt))
}

/// FLIP's per-pixel colour and feature terms → the FLIP value (paper eqs. 5–9).
#[derive(Debug, Clone, Copy)]
struct Finisher {
    cmax: f32,
    pccmax: f32,
}

impl Finisher {
    /// The colour difference ΔE_c in [0, 1] of two filtered YCxCz pixels (paper eq. 6), with
    /// [`flip_math`]'s cube root and power.
    #[inline(always)]
    fn color(&self, r: [f32; 3], t: [f32; 3]) -> f32 {
        self.color_with(r, t, flip_math::cbrt, flip_math::pow)
    }

    /// [`Finisher::color`] with a given cube root and power (the oracle in the tests uses libm's).
    #[inline(always)]
    fn color_with(
        &self,
        r: [f32; 3],
        t: [f32; 3],
        cbrt: impl Fn(f32) -> f32 + Copy,
        pow: impl Fn(f32, f32) -> f32,
    ) -> f32 {
        let d = pow(
            hyab(filtered_to_lab(r, cbrt), filtered_to_lab(t, cbrt)),
            GQC,
        );
        let (low, high) = (
            d * (GPT / self.pccmax),
            GPT + ((d - self.pccmax) / (self.cmax - self.pccmax)) * (1.0 - GPT),
        );
        if d < self.pccmax {
            low
        } else {
            high
        }
    }
}

/// The seven x-filtered planes of one image: CSF-filtered Y, Cx and the two Cz Gaussians, then
/// the feature filters of normalised Y along x: first derivative, second derivative, Gaussian.
const X_PLANES: usize = 7;
/// The eight y-filtered values of a pixel: the four colour planes by their own CSF, then dx·g and
/// ddx·g (the x-derivative planes by the Gaussian) and g·dy, g·ddy (the Gaussian plane by the
/// derivatives).
const Y_VALUES: usize = 8;
/// The x plane that each y value filters.
const Y_SOURCE: [usize; Y_VALUES] = [0, 1, 2, 3, 4, 5, 6, 6];
/// The padded YCxCz row that each x plane filters: 0 Y, 1 Cx, 2 Cz, 3 normalised Y.
const X_SOURCE: [usize; X_PLANES] = [0, 1, 2, 2, 3, 3, 3];

/// The filters' taps in the pipeline's order, with the offsets at which each tap reads.
struct Taps {
    /// Per x plane: the start in the padded row (reach − r + k) of tap k, and the tap weights.
    x: [(Vec<usize>, Vec<f32>); X_PLANES],
    /// Per y value: its taps (its source plane is [`Y_SOURCE`]).
    y: [Vec<f32>; Y_VALUES],
    /// Rows and columns beyond its own that a pixel reads.
    reach: usize,
}

impl Taps {
    fn new(f: &Filters) -> Taps {
        let col2 = |v: &[[f32; 2]], k: usize| v.iter().map(|t| t[k]).collect::<Vec<f32>>();
        let feature = |k: usize| f.feature.iter().map(|t| t[k]).collect::<Vec<f32>>();
        let reach = f.reach();
        let x_taps = |taps: Vec<f32>| {
            let r = taps.len() / 2;
            ((0..taps.len()).map(|k| reach - r + k).collect(), taps)
        };
        Taps {
            x: [
                x_taps(col2(&f.ycx, 0)),
                x_taps(col2(&f.ycx, 1)),
                x_taps(col2(&f.cz, 0)),
                x_taps(col2(&f.cz, 1)),
                x_taps(feature(1)),
                x_taps(feature(2)),
                x_taps(feature(0)),
            ],
            y: [
                col2(&f.ycx, 0),
                col2(&f.ycx, 1),
                col2(&f.cz, 0),
                col2(&f.cz, 1),
                feature(0),
                feature(0),
                feature(1),
                feature(2),
            ],
            reach,
        }
    }
}

/// out[x] = Σₖ taps[k]·src[starts[k] + x], k in order (NVIDIA's: taps from −r to r, products
/// then sums), accumulated in registers [`LANES`] columns at a time. One function for both
/// directions: along x the starts are consecutive columns of a padded row, along y the rows of
/// the ring.
#[inline(always)]
fn correlate(src: &[f32], starts: &[usize], taps: &[f32], out: &mut [f32]) {
    let n = out.len();
    let full = n - n % LANES;
    for x in (0..full).step_by(LANES) {
        let mut acc = [0.0f32; LANES];
        for (&s, &wk) in starts.iter().zip(taps) {
            for (a, &v) in acc.iter_mut().zip(&src[s + x..s + x + LANES]) {
                *a += wk * v;
            }
        }
        out[x..x + LANES].copy_from_slice(&acc);
    }
    for (x, o) in out.iter_mut().enumerate().skip(full) {
        let mut acc = 0.0f32;
        for (&s, &wk) in starts.iter().zip(taps) {
            acc += wk * src[s + x];
        }
        *o = acc;
    }
}

/// One image's working rows in a work item (a strip of `width` columns).
struct ImageWork {
    /// Y, Cx, Cz and normalised Y of one input row over the strip and `reach` columns beyond.
    pad: [Vec<f32>; 4],
    /// The x-filtered planes of the last 2·reach + 1 input rows, input row y at slot y mod that.
    ring: [Vec<f32>; X_PLANES],
    /// The y-filtered values of the current output row.
    y: [Vec<f32>; Y_VALUES],
    width: usize,
}

impl ImageWork {
    fn new(width: usize, reach: usize) -> ImageWork {
        ImageWork {
            pad: std::array::from_fn(|_| vec![0.0; width + 2 * reach]),
            ring: std::array::from_fn(|_| vec![0.0; width * (2 * reach + 1)]),
            y: std::array::from_fn(|_| vec![0.0; width]),
            width,
        }
    }

    /// YCxCz of input row `row` through `transform`, over the strip's columns from `x0` and
    /// `reach` columns on either side (clamped to the image, as NVIDIA's borders are), then the
    /// seven x filters into ring slot `slot`.
    #[inline(always)]
    fn x_row<F: Fn([f32; 3]) -> [f32; 3]>(
        &mut self,
        row: &[[f32; 3]],
        x0: usize,
        transform: &F,
        taps: &Taps,
        slot: usize,
    ) {
        let (w, sw, reach) = (row.len(), self.width, taps.reach);
        let first = x0.saturating_sub(reach);
        let end = (x0 + sw + reach).min(w);
        let off = first + reach - x0;
        let len = end - first;
        let [py, pcx, pcz, pg] = &mut self.pad;
        let pixels = row[first..end].iter();
        let dst = py[off..off + len]
            .iter_mut()
            .zip(&mut pcx[off..off + len])
            .zip(&mut pcz[off..off + len])
            .zip(&mut pg[off..off + len]);
        for (p, (((y, cx), cz), g)) in pixels.zip(dst) {
            let c = xyz_to_ycxcz(linear_rgb_to_xyz(transform(*p)));
            (*y, *cx, *cz) = (c[0], c[1], c[2]);
            *g = c[0] * (1.0 / 116.0) + 16.0 / 116.0;
        }
        for plane in &mut self.pad {
            let (left, right) = (plane[off], plane[off + len - 1]);
            plane[..off].fill(left);
            plane[off + len..].fill(right);
        }
        for (p, (starts, weights)) in taps.x.iter().enumerate() {
            let out = &mut self.ring[p][slot * sw..(slot + 1) * sw];
            correlate(&self.pad[X_SOURCE[p]], starts, weights, out);
        }
    }

    /// The eight y filters of the current output row; `starts[k]` is where in a ring plane the
    /// row y − reach + k (clamped to the image) begins.
    #[inline(always)]
    fn y_row(&mut self, taps: &Taps, starts: &[usize]) {
        for (v, weights) in taps.y.iter().enumerate() {
            let r = weights.len() / 2;
            let rows = &starts[taps.reach - r..taps.reach + r + 1];
            correlate(&self.ring[Y_SOURCE[v]], rows, weights, &mut self.y[v]);
        }
    }
}

/// FLIP of one output row from the y-filtered values of reference and test, maxed into `out`
/// (paper eqs. 5–9: colour difference, edge and point feature differences, ΔE_c^{1−ΔE_f}).
#[inline(always)]
fn finish_row(
    reference: &[Vec<f32>; Y_VALUES],
    test: &[Vec<f32>; Y_VALUES],
    finisher: Finisher,
    out: &mut [f32],
) {
    let n = out.len();
    let r: [&[f32]; Y_VALUES] = std::array::from_fn(|k| &reference[k][..n]);
    let t: [&[f32]; Y_VALUES] = std::array::from_fn(|k| &test[k][..n]);
    let inv_sqrt2 = 1.0 / 2.0f32.sqrt();
    for (x, d) in out.iter_mut().enumerate() {
        let color = finisher.color(filtered_ycxcz(&r, x), filtered_ycxcz(&t, x));
        let de = (edge(&r, x) - edge(&t, x)).abs();
        let dp = (point(&r, x) - point(&t, x)).abs();
        let feature = (inv_sqrt2 * de.max(dp)).sqrt();
        let flip = flip_math::pow(color, 1.0 - feature);
        *d = d.max(flip);
    }
}

/// The filtered YCxCz of pixel x (Cz is the sum of its two Gaussians). Functions rather than
/// closures here so that they inline into the AVX2 build.
#[inline(always)]
fn filtered_ycxcz(v: &[&[f32]; Y_VALUES], x: usize) -> [f32; 3] {
    [v[0][x], v[1][x], v[2][x] + v[3][x]]
}

/// Edge strength at pixel x: ‖(dx·g, g·dy)‖ (paper eq. 8).
#[inline(always)]
fn edge(v: &[&[f32]; Y_VALUES], x: usize) -> f32 {
    (v[4][x] * v[4][x] + v[6][x] * v[6][x]).sqrt()
}

/// Point strength at pixel x: ‖(ddx·g, g·ddy)‖ (paper eq. 8).
#[inline(always)]
fn point(v: &[&[f32]; Y_VALUES], x: usize) -> f32 {
    (v[5][x] * v[5][x] + v[7][x] * v[7][x]).sqrt()
}

/// The FLIP map of one work item (columns x0..x1, rows y0..y1), maxed over `transforms`. Input
/// rows are x-filtered once each into a ring as the output rows need them, so the rows the y
/// filters read stay in cache.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn work_item<F: Fn([f32; 3]) -> [f32; 3]>(
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    (w, h): (usize, usize),
    (x0, x1): (usize, usize),
    (y0, y1): (usize, usize),
    transforms: &[F],
    taps: &Taps,
    finisher: Finisher,
) -> Vec<f32> {
    let (sw, reach) = (x1 - x0, taps.reach);
    let slots = 2 * reach + 1;
    let mut out = vec![0.0f32; sw * (y1 - y0)];
    let mut work = [ImageWork::new(sw, reach), ImageWork::new(sw, reach)];
    let mut starts = vec![0usize; slots];
    for transform in transforms {
        let mut next = y0.saturating_sub(reach);
        for (y, out_row) in (y0..y1).zip(out.chunks_exact_mut(sw)) {
            while next <= (y + reach).min(h - 1) {
                let row = next * w..(next + 1) * w;
                work[0].x_row(&reference[row.clone()], x0, transform, taps, next % slots);
                work[1].x_row(&test[row], x0, transform, taps, next % slots);
                next += 1;
            }
            for (k, s) in starts.iter_mut().enumerate() {
                let yy = (y + k).saturating_sub(reach).min(h - 1);
                *s = (yy % slots) * sw;
            }
            for image in &mut work {
                image.y_row(taps, &starts);
            }
            finish_row(&work[0].y, &work[1].y, finisher, out_row);
        }
    }
    out
}

/// [`work_item`] compiled for AVX2 when the CPU has it (checked at run time; pgt's build targets
/// baseline x86-64): the same operations in the same order on 8 lanes instead of SSE2's 4, so
/// the map is the same bit for bit (Rust never fuses a multiply and an add by itself; tested
/// below). About twice the throughput of the filters and the finish.
#[allow(clippy::too_many_arguments)]
fn work_item_fastest<F: Fn([f32; 3]) -> [f32; 3]>(
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    size: (usize, usize),
    xs: (usize, usize),
    ys: (usize, usize),
    transforms: &[F],
    taps: &Taps,
    finisher: Finisher,
) -> Vec<f32> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above), the one condition for calling a
        // function compiled with `target_feature(enable = "avx2")`.
        return unsafe {
            work_item_avx2(reference, test, size, xs, ys, transforms, taps, finisher)
        };
    }
    work_item(reference, test, size, xs, ys, transforms, taps, finisher)
}

/// [`work_item`], inlined into a function compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
unsafe fn work_item_avx2<F: Fn([f32; 3]) -> [f32; 3]>(
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    size: (usize, usize),
    xs: (usize, usize),
    ys: (usize, usize),
    transforms: &[F],
    taps: &Taps,
    finisher: Finisher,
) -> Vec<f32> {
    work_item(reference, test, size, xs, ys, transforms, taps, finisher)
}

/// The per-pixel maximum over `transforms` of the FLIP map of `reference` against `test`
/// (row-major linear RGB, `w`×`h`), each transform mapping an input pixel to linear RGB in
/// [0, 1] before FLIP (clamping for LDR-FLIP, exposure and tone mapping for HDR-FLIP, whose
/// map is exactly this maximum over exposures). Parallel over work items of [`ROWS`] rows by at
/// most [`STRIP`] columns; the result does not depend on the thread count or the layout.
pub fn flip_max_map<F>(
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    width: u32,
    height: u32,
    pixels_per_degree: f32,
    transforms: &[F],
) -> Vec<f32>
where
    F: Fn([f32; 3]) -> [f32; 3] + Sync,
{
    let (w, h) = (width as usize, height as usize);
    let taps = Taps::new(&Filters::new(pixels_per_degree));
    let cmax = max_distance();
    let finisher = Finisher {
        cmax,
        pccmax: GPC * cmax,
    };
    let strips = w.div_ceil(STRIP);
    let items: Vec<((usize, usize), (usize, usize))> = (0..h)
        .step_by(ROWS)
        .flat_map(|y0| {
            (0..strips).map(move |s| {
                (
                    (s * w / strips, (s + 1) * w / strips),
                    (y0, (y0 + ROWS).min(h)),
                )
            })
        })
        .collect();
    let parts: Vec<Vec<f32>> = items
        .par_iter()
        .map(|&(xs, ys)| {
            work_item_fastest(reference, test, (w, h), xs, ys, transforms, &taps, finisher)
        })
        .collect();
    let mut map = vec![0.0f32; w * h];
    for (&((x0, x1), (y0, _)), part) in items.iter().zip(&parts) {
        for (y, src) in (y0..).zip(part.chunks_exact(x1 - x0)) {
            map[y * w + x0..y * w + x1].copy_from_slice(src);
        }
    }
    map
}

/// sRGB decoding as NVIDIA's code does it (f32, `powf`), for feeding 8-bit sRGB data.
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// The former implementation, band by band over whole rows with libm's cube root and powers:
/// plainer than the one above and kept as its oracle (the filters agree bit for bit, the finish
/// to the accuracy of [`flip_math`]).
#[cfg(test)]
mod simple {
    use super::*;

    /// Output rows per parallel work item.
    const BAND: usize = 64;

    /// Convolves each row of `src` (rows of `w`) with `weights` along x, borders clamped to the
    /// edge; `out` receives the rows. Taps are summed from −r to r, as NVIDIA's code does.
    fn filter_x(src: &[f32], w: usize, weights: &[f32], out: &mut [f32], padded: &mut Vec<f32>) {
        let r = weights.len() / 2;
        for (row, dst) in src.chunks_exact(w).zip(out.chunks_exact_mut(w)) {
            padded.clear();
            padded.extend(std::iter::repeat_n(row[0], r));
            padded.extend_from_slice(row);
            padded.extend(std::iter::repeat_n(row[w - 1], r));
            dst.fill(0.0);
            for (k, &wk) in weights.iter().enumerate() {
                for (d, &s) in dst.iter_mut().zip(&padded[k..k + w]) {
                    *d += wk * s;
                }
            }
        }
    }

    /// Convolves `plane` (rows `lo..` of the image, `w` wide) along y at image row `y`, rows clamped
    /// to 0..h, into `out` (one row).
    #[allow(clippy::too_many_arguments)]
    fn filter_y(
        plane: &[f32],
        w: usize,
        lo: usize,
        h: usize,
        y: usize,
        weights: &[f32],
        out: &mut [f32],
    ) {
        let r = weights.len() as isize / 2;
        out.fill(0.0);
        for (k, &wk) in weights.iter().enumerate() {
            let yy = (y as isize + k as isize - r).clamp(0, h as isize - 1) as usize - lo;
            for (d, &s) in out.iter_mut().zip(&plane[yy * w..(yy + 1) * w]) {
                *d += wk * s;
            }
        }
    }

    /// The x-filtered planes of one image over a band's rows (with halo).
    struct Planes {
        /// CSF-filtered Y, Cx and the two Cz terms.
        color: [Vec<f32>; 4],
        /// Feature filters along x of normalised Y: first derivative, second derivative, Gaussian.
        feature: [Vec<f32>; 3],
    }

    /// YCxCz of rows lo..hi through `transform`, then the x passes.
    fn x_passes(
        image: &[[f32; 3]],
        w: usize,
        rows: std::ops::Range<usize>,
        transform: &(impl Fn([f32; 3]) -> [f32; 3] + ?Sized),
        filters: &Filters,
    ) -> Planes {
        let n = (rows.end - rows.start) * w;
        let mut ycxcz: [Vec<f32>; 3] = std::array::from_fn(|_| Vec::with_capacity(n));
        for p in &image[rows.start * w..rows.end * w] {
            let c = xyz_to_ycxcz(linear_rgb_to_xyz(transform(*p)));
            for (plane, v) in ycxcz.iter_mut().zip(c) {
                plane.push(v);
            }
        }
        let gray: Vec<f32> = ycxcz[0]
            .iter()
            .map(|&y| y * (1.0 / 116.0) + 16.0 / 116.0)
            .collect();
        let mut padded = Vec::new();
        let mut run = |src: &[f32], weights: Vec<f32>| {
            let mut out = vec![0.0f32; n];
            filter_x(src, w, &weights, &mut out, &mut padded);
            out
        };
        let col = |v: &[[f32; 2]], k: usize| v.iter().map(|t| t[k]).collect::<Vec<f32>>();
        let fcol = |k: usize| filters.feature.iter().map(|t| t[k]).collect::<Vec<f32>>();
        Planes {
            color: [
                run(&ycxcz[0], col(&filters.ycx, 0)),
                run(&ycxcz[1], col(&filters.ycx, 1)),
                run(&ycxcz[2], col(&filters.cz, 0)),
                run(&ycxcz[2], col(&filters.cz, 1)),
            ],
            feature: [
                run(&gray, fcol(1)),
                run(&gray, fcol(2)),
                run(&gray, fcol(0)),
            ],
        }
    }

    /// One image's y-filtered values at a row.
    struct RowValues {
        color: [Vec<f32>; 4],
        feature: [Vec<f32>; 4],
    }

    fn y_passes(
        planes: &Planes,
        w: usize,
        lo: usize,
        h: usize,
        y: usize,
        f: &Filters,
    ) -> RowValues {
        let row = |plane: &[f32], weights: Vec<f32>| {
            let mut out = vec![0.0f32; w];
            filter_y(plane, w, lo, h, y, &weights, &mut out);
            out
        };
        let col = |v: &[[f32; 2]], k: usize| v.iter().map(|t| t[k]).collect::<Vec<f32>>();
        let fcol = |k: usize| f.feature.iter().map(|t| t[k]).collect::<Vec<f32>>();
        RowValues {
            color: [
                row(&planes.color[0], col(&f.ycx, 0)),
                row(&planes.color[1], col(&f.ycx, 1)),
                row(&planes.color[2], col(&f.cz, 0)),
                row(&planes.color[3], col(&f.cz, 1)),
            ],
            // dx·g, ddx·g, g·dy, g·ddy (x-filtered planes: dx, ddx, g).
            feature: [
                row(&planes.feature[0], fcol(0)),
                row(&planes.feature[1], fcol(0)),
                row(&planes.feature[2], fcol(1)),
                row(&planes.feature[2], fcol(2)),
            ],
        }
    }

    /// FLIP map of one band for one transform, maxed into `out` (rows y0..y1).
    #[allow(clippy::too_many_arguments)]
    fn band(
        reference: &[[f32; 3]],
        test: &[[f32; 3]],
        (w, h): (usize, usize),
        (y0, y1): (usize, usize),
        transform: &(impl Fn([f32; 3]) -> [f32; 3] + ?Sized),
        filters: &Filters,
        finisher: Finisher,
        out: &mut [f32],
    ) {
        let halo = filters.reach();
        let (lo, hi) = (y0.saturating_sub(halo), (y1 + halo).min(h));
        let pr = x_passes(reference, w, lo..hi, transform, filters);
        let pt = x_passes(test, w, lo..hi, transform, filters);
        let inv_sqrt2 = 1.0 / 2.0f32.sqrt();
        for y in y0..y1 {
            let r = y_passes(&pr, w, lo, h, y, filters);
            let t = y_passes(&pt, w, lo, h, y, filters);
            let dst = &mut out[(y - y0) * w..(y - y0 + 1) * w];
            for (x, d) in dst.iter_mut().enumerate() {
                let ycxcz =
                    |v: &RowValues| [v.color[0][x], v.color[1][x], v.color[2][x] + v.color[3][x]];
                let color = finisher.color_with(ycxcz(&r), ycxcz(&t), f32::cbrt, f32::powf);
                let edge = |v: &RowValues| {
                    let (dx, dy) = (v.feature[0][x], v.feature[2][x]);
                    (dx * dx + dy * dy).sqrt()
                };
                let point = |v: &RowValues| {
                    let (ddx, ddy) = (v.feature[1][x], v.feature[3][x]);
                    (ddx * ddx + ddy * ddy).sqrt()
                };
                let de = (edge(&r) - edge(&t)).abs();
                let dp = (point(&r) - point(&t)).abs();
                let feature = (inv_sqrt2 * de.max(dp)).sqrt();
                let flip = color.powf(1.0 - feature);
                *d = d.max(flip);
            }
        }
    }

    /// The per-pixel maximum over `transforms` of the FLIP map of `reference` against `test`
    /// (row-major linear RGB, `w`×`h`), each transform mapping an input pixel to linear RGB in
    /// [0, 1] before FLIP (clamping for LDR-FLIP, exposure and tone mapping for HDR-FLIP, whose
    /// map is exactly this maximum over exposures). Parallel over bands of rows; the result does
    /// not depend on the thread count.
    pub fn flip_max_map_simple<F>(
        reference: &[[f32; 3]],
        test: &[[f32; 3]],
        width: u32,
        height: u32,
        pixels_per_degree: f32,
        transforms: &[F],
    ) -> Vec<f32>
    where
        F: Fn([f32; 3]) -> [f32; 3] + Sync,
    {
        let (w, h) = (width as usize, height as usize);
        let filters = Filters::new(pixels_per_degree);
        let cmax = max_distance();
        let finisher = Finisher {
            cmax,
            pccmax: GPC * cmax,
        };
        let mut map = vec![0.0f32; w * h];
        map.par_chunks_mut(BAND * w)
            .enumerate()
            .for_each(|(i, out)| {
                let y0 = i * BAND;
                let y1 = (y0 + BAND).min(h);
                for transform in transforms {
                    band(
                        reference,
                        test,
                        (w, h),
                        (y0, y1),
                        transform,
                        &filters,
                        finisher,
                        out,
                    );
                }
            });
        map
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn noise_pair(w: u32, h: u32) -> (Vec<u8>, Vec<u8>) {
        let mut state = 11u32;
        let mut noise = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 24) as u8
        };
        let r: Vec<u8> = (0..w * h * 3).map(|_| noise()).collect();
        let a: Vec<u8> = r.iter().map(|&v| v.saturating_add(noise() / 6)).collect();
        (r, a)
    }

    /// On the bytes nv-flip sees, the float implementation gives nv-flip's map: budget 1e-5 per
    /// pixel (f32 rounding, e.g. powf vs the C library); a wrong filter or constant is ≥ 1e-3.
    #[test]
    fn equals_nv_flip_on_8_bit_input() {
        let (w, h) = (83u32, 150u32);
        let (r, a) = noise_pair(w, h);
        let decode = |b: &[u8]| -> Vec<[f32; 3]> {
            b.chunks(3)
                .map(|c| [c[0], c[1], c[2]].map(|v| v as f32 / 255.0))
                .collect()
        };
        let (rf, af) = (decode(&r), decode(&a));
        for ppd in [20.0f32, 67.02, 120.0] {
            let want = super::super::flip::flip_srgb8_whole(w, h, &r, &a, ppd);
            let got = flip_max_map(&rf, &af, w, h, ppd, &[|p: [f32; 3]| p.map(srgb_to_linear)]);
            let worst = got
                .iter()
                .zip(&want)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0f32, f32::max);
            let same = got.iter().zip(&want).filter(|(x, y)| x == y).count();
            eprintln!(
                "ppd {ppd}: worst {worst:e}, {same} of {} bit-identical",
                want.len()
            );
            assert!(worst < 1e-5, "ppd {ppd}: worst difference {worst}");
        }
    }

    /// The work-item pipeline against the band-by-band oracle, on sizes that cut strips, work
    /// items and the ring in odd places, with two transforms (HDR-FLIP's maximum): the filters
    /// agree bit for bit, so the maps differ only by [`flip_math`]'s finish: budget 1e-5 per
    /// pixel, the one against nv-flip, as CIELab's a = 500·(∛x − ∛y) turns an ulp of a cube root
    /// into ~1e-5 of a small colour distance (measured: 5e-6); a wrong ring slot, border or
    /// strip edge is ≥ 1e-3.
    #[test]
    fn equals_the_simple_oracle() {
        for (w, h, ppd) in [
            (83u32, 150u32, 67.02f32),
            (1100, 300, 67.02),
            (600, 40, 20.0),
            (30, 700, 120.0),
        ] {
            let (r, a) = noise_pair(w, h);
            let decode = |b: &[u8]| -> Vec<[f32; 3]> {
                b.chunks(3)
                    .map(|c| [c[0], c[1], c[2]].map(|v| v as f32 / 90.0))
                    .collect()
            };
            let (rf, af) = (decode(&r), decode(&a));
            let transforms: Vec<_> = [1.0f32, 0.3]
                .into_iter()
                .map(|m| move |p: [f32; 3]| p.map(|v| (v * m).clamp(0.0, 1.0)))
                .collect();
            let got = flip_max_map(&rf, &af, w, h, ppd, &transforms);
            let want = simple::flip_max_map_simple(&rf, &af, w, h, ppd, &transforms);
            assert_eq!(got.len(), want.len());
            let worst = got
                .iter()
                .zip(&want)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0f32, f32::max);
            eprintln!("{w}x{h}, ppd {ppd}: worst {worst:e}");
            assert!(worst < 1e-5, "{w}x{h}, ppd {ppd}: worst difference {worst}");
        }
    }

    /// The AVX2 build of a work item gives the baseline's map bit for bit (same operations,
    /// wider registers, no fused multiply-adds).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_equals_baseline_bit_for_bit() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2 on this CPU: nothing to compare");
            return;
        }
        let (w, h) = (301usize, 90usize);
        let (r, a) = noise_pair(w as u32, h as u32);
        let decode = |b: &[u8]| -> Vec<[f32; 3]> {
            b.chunks(3)
                .map(|c| [c[0], c[1], c[2]].map(|v| v as f32 / 200.0))
                .collect()
        };
        let (rf, af) = (decode(&r), decode(&a));
        let taps = Taps::new(&Filters::new(67.02));
        let cmax = max_distance();
        let finisher = Finisher {
            cmax,
            pccmax: GPC * cmax,
        };
        let transforms = [|p: [f32; 3]| p.map(|v| v.clamp(0.0, 1.0))];
        let (xs, ys) = ((13, 290), (7, 80));
        let base = work_item(&rf, &af, (w, h), xs, ys, &transforms, &taps, finisher);
        // SAFETY: AVX2 is present (checked above).
        let wide =
            unsafe { work_item_avx2(&rf, &af, (w, h), xs, ys, &transforms, &taps, finisher) };
        assert!(base.iter().any(|&v| v > 0.0));
        assert!(base
            .iter()
            .zip(&wide)
            .all(|(x, y)| x.to_bits() == y.to_bits()));
    }

    #[test]
    fn radii_match_nvidias_choices() {
        let f = Filters::new(67.02);
        assert_eq!((f.spatial_radius, f.feature_radius), (10, 9));
    }
}
