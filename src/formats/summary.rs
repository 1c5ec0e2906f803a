//! The summary of particles that `pgt info` prints (docs/design.md §7): count, bounds, radius
//! range, the most common colours, the loaders' warnings, the format's details and frames. The
//! summary of a whole file, a particle file or a scene, is `crate::scene::summary::info_of`.

use crate::formats::frames::FrameInfo;
use glam::DVec3;
use std::collections::HashMap;

/// How many of the most common colours the summary lists.
const TOP_COLORS: usize = 8;

/// What `pgt info` reports (also the JSON object it prints).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Info {
    /// The file as given.
    pub file: String,
    /// `scene` or the particle format.
    pub format: String,
    /// Number of particles.
    pub particles: usize,
    /// Axis-aligned bounds of the spheres (centre ± radius); absent when there are none.
    pub bounds: Option<Bounds>,
    /// Radius range and mean; absent when there are no particles.
    pub radius: Option<RadiusRange>,
    /// Colour summary.
    pub colors: ColorSummary,
    /// Warnings of the loaders.
    pub warnings: Vec<String>,
    /// Facts of the format: PDB/mmCIF `models` and `chains` (atom records per chain in the
    /// first model, before alternate locations are resolved); MMPLD `version` and `frames`.
    pub details: serde_json::Map<String, serde_json::Value>,
    /// Frames (docs/design.md §10): their count, the atoms per frame where every frame has as
    /// many and the time step in ps where the file says; absent for a file or scene of one
    /// frame. For a scene, the frames it plays; for a trajectory (`.dcd`, `.xtc`) alone, its
    /// own (the particles are then its atoms at frame 0, as points).
    pub frames: Option<FrameInfo>,
}

/// An axis-aligned box.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Bounds {
    /// Lower corner.
    pub min: [f64; 3],
    /// Upper corner.
    pub max: [f64; 3],
}

/// Smallest, largest and mean radius.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RadiusRange {
    /// Smallest radius.
    pub min: f64,
    /// Largest radius.
    pub max: f64,
    /// Mean radius.
    pub mean: f64,
}

/// The particles' colours.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ColorSummary {
    /// Distinct colours among the particles that have one.
    pub distinct: usize,
    /// Particles without a colour of their own (they take the scene's default).
    pub uncolored: usize,
    /// The most common colours, linear RGB, with their counts.
    pub most_common: Vec<ColorCount>,
}

/// One colour and how many particles have it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ColorCount {
    /// Linear RGB.
    pub rgb: [f64; 3],
    /// Particles with this colour.
    pub count: usize,
}

/// Summarises spheres given as (centre, radius, colour).
pub fn summarize(
    file: String,
    format: String,
    spheres: impl Iterator<Item = (DVec3, f64, Option<DVec3>)>,
    warnings: Vec<String>,
) -> Info {
    let mut n = 0usize;
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let (mut rmin, mut rmax, mut rsum) = (f64::INFINITY, f64::NEG_INFINITY, 0.0);
    let mut uncolored = 0usize;
    let mut counts: HashMap<[u64; 3], usize> = HashMap::new();
    for (c, r, col) in spheres {
        n += 1;
        lo = lo.min(c - DVec3::splat(r));
        hi = hi.max(c + DVec3::splat(r));
        rmin = rmin.min(r);
        rmax = rmax.max(r);
        rsum += r;
        match col {
            Some(c) => {
                *counts
                    .entry([c.x.to_bits(), c.y.to_bits(), c.z.to_bits()])
                    .or_insert(0) += 1
            }
            None => uncolored += 1,
        }
    }
    let mut top: Vec<([u64; 3], usize)> = counts.iter().map(|(k, v)| (*k, *v)).collect();
    top.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    Info {
        file,
        format,
        particles: n,
        bounds: (n > 0).then(|| Bounds {
            min: lo.to_array(),
            max: hi.to_array(),
        }),
        radius: (n > 0).then(|| RadiusRange {
            min: rmin,
            max: rmax,
            mean: rsum / n as f64,
        }),
        colors: ColorSummary {
            distinct: counts.len(),
            uncolored,
            most_common: top
                .into_iter()
                .take(TOP_COLORS)
                .map(|(k, count)| ColorCount {
                    rgb: k.map(f64::from_bits),
                    count,
                })
                .collect(),
        },
        warnings,
        details: serde_json::Map::new(),
        frames: None,
    }
}
