//! Synthetic Gaussians with the statistics of trained 3D Gaussian splatting scenes
//! (`pgt gen gaussians`, docs/cli.md): a seeded set to measure the reference at the scale of a
//! trained scene, which the three shared splat files are too small to be.
//!
//! The distributions are fitted to the shared files (`scripts/splat_stats.py`; figures in
//! docs/performance.md, "Trained-scene statistics"): `GSHairLoD_donut_fused.ply` (45,624),
//! `fruit_drops_minimal.ply` (4,721) and `lod3_tile_0.ply` (1,971).
//!
//! | quantity | distribution | fitted to |
//! |---|---|---|
//! | centres | [`PER_CLUSTER`] Gaussians a cluster on average, clusters uniform in the cube of side [`SIDE`], each centre a normal offset of standard deviation [`CLUSTER_SPREAD`]·(cluster spacing) | median nearest-neighbour distance 0.35× that of a uniform set (donut 0.34, fruit 0.15, lod3 0.64) |
//! | ln s_max | normal, median ln([`SCALE_OVER_SPACING`]·(V/N)^{1/3}), standard deviation [`LN_SCALE_SD`] | median s_max ≈ 3× the median nearest-neighbour distance (donut 3.0, fruit 4.3, lod3 0.9); spread 0.6–1.1 |
//! | ln(s_max/s_mid), ln(s_mid/s_min) | each Gamma(2, [`GAP_SCALE`]) | donut's ln(s_mid/s_min) quantiles 10/25/50/75/90 % 0.41, 0.78, 1.3, 2.15, 2.72; s_min/s_max median 0.05 (donut 0.063, fruit 0.097) |
//! | degenerate flat ones | a share [`FLAT_SHARE`] with ln(s_mid/s_min) larger by [`FLAT_EXTRA`] | lod3, where half have s_min/s_max ≈ 10⁻⁵ |
//! | opacity logit | half normal(0.6, 2.5) (donut: 8 % below 0.05, 16 % above 0.95), half normal(−2.75, 2) (fruit: 47 % below 0.05) | |
//! | colour | a cluster's colour uniform in [0.1, 0.9]³ plus a normal(0, 0.15) per Gaussian, DC coefficient (c − 0.5)/C0 | |
//! | orientation | uniformly random (a normalised 4D normal) | |
//!
//! Every number comes from SplitMix64 ([`SplitMix64`]) seeded with the seed, in a fixed order, so
//! a seed gives the same file on every machine. The file is a standard 3DGS PLY
//! (`x y z f_dc_0..2 opacity scale_0..2 rot_0..3`, binary little endian), read as Gaussians with
//! `density = "gaussian"` (docs/design.md §9).

use super::random::SplitMix64;
use glam::{DQuat, DVec3};

/// Side of the cube of the cluster centres, scene units.
pub const SIDE: f64 = 10.0;
/// Gaussians per cluster, on average.
pub const PER_CLUSTER: usize = 64;
/// A centre's offset from its cluster's, per axis, in units of the clusters' mean spacing.
pub const CLUSTER_SPREAD: f64 = 0.09;
/// The median largest standard deviation over (V/N)^{1/3}, V the cube's volume.
pub const SCALE_OVER_SPACING: f64 = 0.58;
/// Standard deviation of ln s_max.
pub const LN_SCALE_SD: f64 = 0.8;
/// Scale of the Gamma(2, ·) gaps between the logs of the three standard deviations.
pub const GAP_SCALE: f64 = 0.8;
/// Share of degenerate flat Gaussians.
pub const FLAT_SHARE: f64 = 0.1;
/// What those add to ln(s_mid/s_min).
pub const FLAT_EXTRA: f64 = 10.0;
/// C0 of degree-0 spherical harmonics, ½√(1/π).
const SH_C0: f64 = 0.282_094_791_773_878_14;

/// One generated Gaussian as a 3DGS file stores it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplatRecord {
    /// Centre.
    pub center: DVec3,
    /// ln of the standard deviations along the body's axes (largest first).
    pub log_scale: DVec3,
    /// Body to world, unit.
    pub rotation: DQuat,
    /// The opacity logit (the file's `opacity`).
    pub opacity_logit: f64,
    /// The DC spherical-harmonic coefficients (`f_dc_0..2`).
    pub dc: DVec3,
}

/// A standard normal variate (Box–Muller, one of the pair).
fn normal(rng: &mut SplitMix64) -> f64 {
    let u = 1.0 - rng.next_f64();
    let v = rng.next_f64();
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// A Gamma(2, `scale`) variate: the sum of two exponentials.
fn gamma2(rng: &mut SplitMix64, scale: f64) -> f64 {
    -scale * ((1.0 - rng.next_f64()).ln() + (1.0 - rng.next_f64()).ln())
}

/// `count` Gaussians drawn with `seed` (the table of the module).
pub fn generate(count: usize, seed: u64) -> Vec<SplatRecord> {
    let mut rng = SplitMix64::new(seed);
    let clusters = count.div_ceil(PER_CLUSTER).max(1);
    let spacing = SIDE * (1.0 / clusters as f64).cbrt();
    let spread = CLUSTER_SPREAD * spacing;
    let cluster: Vec<(DVec3, DVec3)> = (0..clusters)
        .map(|_| {
            let u = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            let c = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            ((u - 0.5) * SIDE, 0.1 + 0.8 * c)
        })
        .collect();
    let median_ln = (SCALE_OVER_SPACING * SIDE / (count.max(1) as f64).cbrt()).ln();
    (0..count)
        .map(|_| {
            let (home, color) = cluster[(rng.next_u64() % clusters as u64) as usize];
            let offset = DVec3::new(normal(&mut rng), normal(&mut rng), normal(&mut rng));
            let ln_max = median_ln + LN_SCALE_SD * normal(&mut rng);
            let ln_mid = ln_max - gamma2(&mut rng, GAP_SCALE);
            let flat = if rng.next_f64() < FLAT_SHARE {
                FLAT_EXTRA
            } else {
                0.0
            };
            let ln_min = ln_mid - gamma2(&mut rng, GAP_SCALE) - flat;
            let opacity_logit = if rng.next_f64() < 0.5 {
                0.6 + 2.5 * normal(&mut rng)
            } else {
                -2.75 + 2.0 * normal(&mut rng)
            };
            let tint = DVec3::new(normal(&mut rng), normal(&mut rng), normal(&mut rng));
            let c = (color + 0.15 * tint).max(DVec3::ZERO);
            let q = glam::DVec4::new(
                normal(&mut rng),
                normal(&mut rng),
                normal(&mut rng),
                normal(&mut rng),
            );
            let q = q / q.length();
            SplatRecord {
                center: home + spread * offset,
                log_scale: DVec3::new(ln_max, ln_mid, ln_min),
                rotation: DQuat::from_xyzw(q.y, q.z, q.w, q.x),
                opacity_logit,
                dc: (c - 0.5) / SH_C0,
            }
        })
        .collect()
}

/// The records as a 3DGS PLY file (binary little endian; `rot_0..3` = w, x, y, z), the layout
/// `formats::ply` reads.
pub fn to_ply(records: &[SplatRecord]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\n",
        records.len()
    );
    for p in [
        "x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
        "rot_0", "rot_1", "rot_2", "rot_3",
    ] {
        out.push_str(&format!("property float {p}\n"));
    }
    out.push_str("end_header\n");
    let mut bytes = out.into_bytes();
    bytes.reserve(records.len() * 14 * 4);
    for r in records {
        let q = r.rotation;
        let values = [
            r.center.x,
            r.center.y,
            r.center.z,
            r.dc.x,
            r.dc.y,
            r.dc.z,
            r.opacity_logit,
            r.log_scale.x,
            r.log_scale.y,
            r.log_scale.z,
            q.w,
            q.x,
            q.y,
            q.z,
        ];
        for v in values {
            bytes.extend_from_slice(&(v as f32).to_le_bytes());
        }
    }
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_seed_gives_the_same_set_and_another_seed_another() {
        assert_eq!(generate(500, 7), generate(500, 7));
        assert_ne!(generate(500, 7), generate(500, 8));
    }

    #[test]
    fn the_statistics_are_the_fitted_ones() {
        let set = generate(20_000, 1);
        let median = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let ratio = median(
            set.iter()
                .map(|r| (r.log_scale.z - r.log_scale.x).exp())
                .collect(),
        );
        assert!((0.02..0.1).contains(&ratio), "s_min/s_max median {ratio}");
        let opacities: Vec<f64> = set
            .iter()
            .map(|r| 1.0 / (1.0 + (-r.opacity_logit).exp()))
            .collect();
        let low = opacities.iter().filter(|&&o| o < 0.05).count() as f64 / 20_000.0;
        let high = opacities.iter().filter(|&&o| o > 0.95).count() as f64 / 20_000.0;
        assert!(
            (0.2..0.4).contains(&low) && (0.05..0.15).contains(&high),
            "{low} {high}"
        );
        let flat = set
            .iter()
            .filter(|r| r.log_scale.x - r.log_scale.z > FLAT_EXTRA)
            .count() as f64
            / 20_000.0;
        assert!((0.08..0.13).contains(&flat), "flat share {flat}");
        assert!(set
            .iter()
            .all(|r| (r.rotation.length() - 1.0).abs() < 1e-12
                && r.center.abs().max_element() < SIDE));
    }
}
