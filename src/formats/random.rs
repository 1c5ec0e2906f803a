//! The synthetic random set (docs/design.md §6, §7: `pgt gen random`). The thesis evaluates a
//! "randomly generated data set of 73,642 particles" (§6) without saying how it was drawn; pgt
//! draws centres uniformly in an axis-aligned box, radii uniformly in [r_min, r_max] and colours
//! uniformly in [0, 1]³ (linear RGB), in that order per particle, from SplitMix64 (Steele, Lea &
//! Flood, "Fast splittable pseudorandom number generators", OOPSLA 2014) seeded with `seed`. The
//! generator is written out here so the set never changes with a crate version.

use glam::DVec3;

/// The thesis's particle count.
pub const THESIS_COUNT: usize = 73_642;

/// What to generate.
#[derive(Debug, Clone, PartialEq)]
pub struct RandomSpec {
    /// Number of particles.
    pub count: usize,
    /// SplitMix64 seed.
    pub seed: u64,
    /// Lower corner of the box of centres.
    pub box_min: DVec3,
    /// Upper corner of the box of centres.
    pub box_max: DVec3,
    /// Radius range, 0 < min ≤ max.
    pub radius: (f64, f64),
}

impl Default for RandomSpec {
    /// The thesis-like set: 73,642 particles in [−100, 100]³, radii in [0.5, 2], seed 1.
    fn default() -> Self {
        RandomSpec {
            count: THESIS_COUNT,
            seed: 1,
            box_min: DVec3::splat(-100.0),
            box_max: DVec3::splat(100.0),
            radius: (0.5, 2.0),
        }
    }
}

/// One generated particle: centre, radius, linear RGB colour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RandomParticle {
    /// Centre.
    pub center: DVec3,
    /// Radius.
    pub radius: f64,
    /// Linear RGB colour.
    pub color: DVec3,
}

/// SplitMix64: a 64-bit state advanced by the golden-ratio increment, then mixed.
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator whose state starts at `seed`.
    pub fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// The set as an iterator, one particle at a time (deterministic for a given spec).
pub fn particles(spec: &RandomSpec) -> impl Iterator<Item = RandomParticle> + '_ {
    let mut rng = SplitMix64::new(spec.seed);
    let extent = spec.box_max - spec.box_min;
    (0..spec.count).map(move |_| {
        let u = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
        let center = spec.box_min + u * extent;
        let radius = spec.radius.0 + rng.next_f64() * (spec.radius.1 - spec.radius.0);
        let color = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
        RandomParticle {
            center,
            radius,
            color,
        }
    })
}

/// Generates the whole set in memory.
pub fn generate(spec: &RandomSpec) -> Vec<RandomParticle> {
    particles(spec).collect()
}

/// Writes particles as CSV with the header `x,y,z,radius,red,green,blue` (six decimals), the
/// format [`super::xyz_csv::read_csv`] reads.
pub fn write_csv(
    out: &mut impl std::io::Write,
    particles: impl IntoIterator<Item = RandomParticle>,
) -> std::io::Result<()> {
    writeln!(out, "x,y,z,radius,red,green,blue")?;
    for p in particles {
        writeln!(
            out,
            "{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6}",
            p.center.x, p.center.y, p.center.z, p.radius, p.color.x, p.color.y, p.color.z
        )?;
    }
    Ok(())
}

/// The set as CSV text ([`write_csv`] into a string).
pub fn to_csv(particles: &[RandomParticle]) -> String {
    let mut v = Vec::with_capacity(particles.len() * 80 + 32);
    // Writing into a Vec cannot fail.
    let _ = write_csv(&mut v, particles.iter().copied());
    String::from_utf8_lossy(&v).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix_reference_values() {
        // First outputs for seed 1234567 from the reference C code (Vigna, prng.di.unimi.it).
        let mut r = SplitMix64::new(1234567);
        assert_eq!(r.next_u64(), 6457827717110365317);
        assert_eq!(r.next_u64(), 3203168211198807973);
    }

    #[test]
    fn first_particle_matches_an_independent_computation() {
        // Computed with a separate Python SplitMix64 (seed 3): x = −100 + 200·(u₀ >> 11)/2⁵³, …,
        // radius = 0.5 + 1.5·u₃, colour = u₄..u₆; printed with six decimals.
        let p = generate(&RandomSpec {
            count: 1,
            seed: 3,
            ..RandomSpec::default()
        });
        let csv = to_csv(&p);
        assert_eq!(
            csv.lines().nth(1),
            Some("-77.309932,40.058703,22.594937,0.609300,0.216439,0.636222,0.135146")
        );
    }

    #[test]
    fn in_range_and_deterministic() {
        let spec = RandomSpec {
            count: 1000,
            ..RandomSpec::default()
        };
        let a = generate(&spec);
        assert_eq!(a, generate(&spec));
        assert!(a.iter().all(|p| p.center.cmpge(spec.box_min).all()
            && p.center.cmplt(spec.box_max).all()
            && p.radius >= 0.5
            && p.radius < 2.0));
        let b = generate(&RandomSpec { seed: 2, ..spec });
        assert_ne!(a, b);
    }
}
