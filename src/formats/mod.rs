//! File formats (docs/design.md §6, §10). Each format turns a file's bytes into what pgt needs
//! of it: [`ParticleRecord`]s with the line (or byte offset) each came from, so that validation
//! can point at it; the atoms of a topology; the frames of a trajectory.
//!
//! **One table of formats.** Every format is one [`Format`] value, declared in its own module
//! (`pdb::FORMAT`, …) and listed once in [`FORMATS`]. A format says what it reads: particles
//! ([`Format::read`], with [`Format::details`] for `pgt info` and [`Format::frames`] where a
//! file holds several), the atoms of a topology ([`Format::topology`]), the frames of an MD
//! trajectory ([`Format::trajectory`]), or several of these (a PDB file is particles and a
//! topology). Extension detection ([`Format::from_path`], [`Format::trajectory_of`],
//! [`Format::topology_of`]), the `format = "…"` of an `[[include]]` ([`Format::named`]), the
//! "unsupported file type" messages and `pgt info` (name and details) all read that table;
//! nobody matches on a format. A new format is a new module with a `pub const FORMAT: Format`
//! (its readers have the signatures [`Reader`], [`ReadAtoms`], [`OpenTrajectory`]), its `mod`
//! line here and its line in [`FORMATS`].
//!
//! **One byte layer.** The readers take their bytes through [`file`]: numbers in either byte
//! order and a cursor whose every read is checked against the bytes present, Fortran records,
//! numbered lines and columns. A reader never sizes an allocation from a header value before
//! that layer has checked it against the file.
//!
//! **One loading path.** [`load_particles`] (a file) and [`load_bytes`] (bytes already read) run
//! the reader and then, for every format alike: `radius_scale`, `color_by = "uniform"`, the
//! refusal of a file that yields no particles (docs/design.md §1), and the check of every record.

pub mod atoms;
pub mod cameras;
pub mod dcd;
pub mod elements;
pub mod export;
pub mod file;
pub mod frame_source;
pub mod frames;
pub mod gro;
pub mod mmcif;
pub mod mmpld;
pub mod pdb;
pub mod ply;
pub mod profile;
pub mod psf;
pub mod random;
pub mod record;
pub mod summary;
pub mod topology;
pub mod trained;
pub mod vrml;
pub mod xtc;
pub mod xyz_csv;

pub use profile::Profile;
pub use record::{
    ColorBy, EllipsoidRecord, IncludeSpec, ParticleRecord, ShCoefficients, ShColor, ShOrder,
};

use crate::error::{PgtError, Result};
use std::path::Path;

/// What a format delivers: the particles and non-fatal warnings (skipped shapes, guesses).
#[derive(Debug, Clone, Default)]
pub struct LoadedParticles {
    /// The particles, in file order, with `radius_scale` applied.
    pub records: Vec<ParticleRecord>,
    /// Remarks for the user, each naming the file.
    pub warnings: Vec<String>,
    /// The SH coefficients of the records, one entry per record, where the include asks for
    /// the view-dependent colour of a 3D Gaussian splatting PLY (`sh = "view"`, degree ≥ 1).
    pub sh: Option<ShCoefficients>,
}

/// The one signature of every particle reader: the include (its `path` names the file in
/// messages; its selections apply where the format has them) and the file's bytes.
/// `radius_scale`, `color_by = "uniform"`, the empty-file refusal and the record checks are
/// left to [`load_bytes`].
pub type Reader = fn(spec: &IncludeSpec, bytes: &[u8]) -> Result<LoadedParticles>;

/// Format-specific facts for `pgt info` (`models`, `chains`, `version`, `frames`, …).
pub type Details =
    fn(path: &Path, bytes: &[u8]) -> Result<serde_json::Map<String, serde_json::Value>>;

/// Opens the frames of a particle file of this format ([`frames::FrameSource`]); `spec` carries
/// the include's selections, `bytes` the file.
pub type OpenFrames =
    fn(spec: &IncludeSpec, bytes: frames::ByteSource) -> Result<Box<dyn frames::FrameSource>>;

/// The atoms of a topology file (every model; `path` names the file in messages), with the
/// reader's remarks.
pub type ReadAtoms = fn(path: &Path, bytes: &[u8]) -> Result<(Vec<atoms::Atom>, Vec<String>)>;

/// Opens a trajectory from its bytes (header read, frames found).
pub type OpenTrajectory = fn(source: file::ByteSource) -> Result<Box<dyn frame_source::Trajectory>>;

/// One file format: an entry of [`FORMATS`], with what it reads.
#[derive(Debug)]
pub struct Format {
    /// The name of `[[include]] format = "…"` and of `pgt info` (`"pdb"`).
    pub name: &'static str,
    /// File name extensions, lower case, without the dot.
    pub extensions: &'static [&'static str],
    /// One line for people (`"PDB (wwPDB 3.3, fixed columns)"`).
    pub description: &'static str,
    /// What a particle is in this format, for the "holds no particles" error
    /// (`"ATOM or HETATM records"`); empty where the format holds no particles.
    pub particles: &'static str,
    /// The particle reader, where a file of this format is a particle file of its own.
    pub read: Option<Reader>,
    /// Extra facts for `pgt info`, where the format has any.
    pub details: Option<Details>,
    /// Its frames, one at a time, where a particle file of this format may hold several.
    pub frames: Option<OpenFrames>,
    /// The atoms a trajectory moves, where a file of this format can be a topology.
    pub topology: Option<ReadAtoms>,
    /// The trajectory reader, where a file of this format is an MD trajectory.
    pub trajectory: Option<OpenTrajectory>,
}

impl Format {
    /// A format that reads nothing: what a table entry leaves out (`..Format::NOTHING`).
    pub const NOTHING: Format = Format {
        name: "",
        extensions: &[],
        description: "",
        particles: "",
        read: None,
        details: None,
        frames: None,
        topology: None,
        trajectory: None,
    };
}

/// Every format pgt reads: the particle formats in the order messages list them, then the
/// topologies and trajectories that are nothing else.
pub static FORMATS: &[&Format] = &[
    &pdb::FORMAT,
    &mmcif::FORMAT,
    &vrml::FORMAT,
    &mmpld::FORMAT,
    &xyz_csv::XYZ,
    &xyz_csv::CSV,
    &gro::FORMAT,
    &ply::FORMAT,
    &psf::FORMAT,
    &dcd::FORMAT,
    &xtc::FORMAT,
];

impl PartialEq for Format {
    fn eq(&self, other: &Format) -> bool {
        self.name == other.name
    }
}

impl Format {
    /// The particle format of this name (`"pdb"`), as `[[include]] format = "…"` writes it.
    pub fn named(name: &str) -> Option<&'static Format> {
        particle_formats().find(|f| f.name == name)
    }

    /// The particle format a file name's extension stands for (case-insensitive).
    pub fn from_path(path: &Path) -> Option<&'static Format> {
        Format::with_extension(path, |f| f.read.is_some())
    }

    /// The trajectory format a file name's extension stands for (case-insensitive).
    pub fn trajectory_of(path: &Path) -> Option<&'static Format> {
        Format::with_extension(path, |f| f.trajectory.is_some())
    }

    /// The topology format a file name's extension stands for (case-insensitive).
    pub fn topology_of(path: &Path) -> Option<&'static Format> {
        Format::with_extension(path, |f| f.topology.is_some())
    }

    /// The first format of [`FORMATS`] for which `reads` holds that has the extension of `path`.
    fn with_extension(path: &Path, reads: impl Fn(&Format) -> bool) -> Option<&'static Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        FORMATS
            .iter()
            .copied()
            .find(|f| reads(f) && f.extensions.contains(&ext.as_str()))
    }
}

/// The formats of [`FORMATS`] that read particle files, in table order.
pub fn particle_formats() -> impl Iterator<Item = &'static Format> {
    FORMATS.iter().copied().filter(|f| f.read.is_some())
}

/// Every extension of the particle formats as a list for messages: `.pdb, .ent, …, .ply`.
pub fn known_extensions() -> String {
    let all: Vec<String> = particle_formats()
        .flat_map(|f| f.extensions.iter().map(|e| format!(".{e}")))
        .collect();
    all.join(", ")
}

/// Every name of the particle formats as a list for messages: `pdb, mmcif, …`.
pub fn known_names() -> String {
    let all: Vec<&str> = particle_formats().map(|f| f.name).collect();
    all.join(", ")
}

/// serde for `[[include]] format = "…"`: a particle format's name; another name is an error that
/// lists them (toml adds the line).
pub(crate) fn deserialize_format<'de, D>(
    d: D,
) -> std::result::Result<Option<&'static Format>, D::Error>
where
    D: serde::Deserializer<'de>,
{
    let name: Option<String> = serde::Deserialize::deserialize(d)?;
    name.map(|n| {
        Format::named(&n).ok_or_else(|| {
            serde::de::Error::custom(format!(
                "unknown format `{n}`, expected one of {}",
                known_names()
            ))
        })
    })
    .transpose()
}

/// Largest particle file pgt reads (bytes); beyond it the file is refused before it is read.
pub const MAX_FILE_BYTES: u64 = 4 << 30;

/// Reads a whole input file, refusing ones larger than [`MAX_FILE_BYTES`].
pub fn read_input(path: &Path) -> Result<Vec<u8>> {
    let meta = std::fs::metadata(path).map_err(|e| PgtError::io(path, e))?;
    if meta.is_dir() {
        return Err(PgtError::in_file(
            path,
            "is a directory, not a particle file",
        ));
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(PgtError::in_file(
            path,
            format!(
                "the file is {} bytes; pgt reads particle files of at most {MAX_FILE_BYTES} bytes",
                meta.len()
            ),
        ));
    }
    std::fs::read(path).map_err(|e| PgtError::io(path, e))
}

/// The format of an include: `spec.format` if set, else the file's extension; an unknown
/// extension is an error that lists the known ones.
pub fn format_of(spec: &IncludeSpec) -> Result<&'static Format> {
    if let Some(f) = spec.format.or_else(|| Format::from_path(&spec.path)) {
        return Ok(f);
    }
    let ext = spec
        .path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or_default();
    Err(PgtError::in_file(
        &spec.path,
        format!(
            "unsupported particle file type '.{ext}': expected {} or .toml, or name the format: `--format NAME` for a file on the command line, `format = \"NAME\"` in a scene's [[include]] (NAME one of {})",
            known_extensions(),
            known_names()
        ),
    ))
}

/// Loads the particles of an `[[include]]` (or a bare particle file): [`format_of`], then
/// [`read_input`], then [`load_bytes`]. An include with a `trajectory`, a `sequence` or a
/// `frames` selection shows one frame of its source ([`frames::load_static_frame`]).
pub fn load_particles(spec: &IncludeSpec) -> Result<LoadedParticles> {
    if frames::uses_frames(spec) {
        return frames::load_static_frame(spec);
    }
    let format = format_of(spec)?;
    let bytes = read_input(&spec.path)?;
    load_bytes(spec, format, &bytes)
}

/// Parses a file's bytes as `format` and applies what every format shares: `radius_scale`,
/// `color_by = "uniform"` (no particle keeps a colour of its own), the refusal of a file with
/// no particles (docs/design.md §1: an error naming the file), and [`check_records`]. `spec.path`
/// names the file in messages.
pub fn load_bytes(spec: &IncludeSpec, format: &Format, bytes: &[u8]) -> Result<LoadedParticles> {
    let Some(read) = format.read else {
        return Err(PgtError::in_file(
            &spec.path,
            format!(
                "a {} file holds no particles of its own ({})",
                format.name, format.description
            ),
        ));
    };
    let mut loaded = read(spec, bytes)?;
    if loaded.records.is_empty() {
        return Err(no_particles(spec, format, bytes.len(), &loaded.warnings));
    }
    apply_include_options(spec, &mut loaded.records);
    if spec.color_by == ColorBy::Uniform {
        // No particle keeps a colour of its own, the view-dependent one included.
        loaded.sh = None;
    }
    check_records(&spec.path, &loaded.records)?;
    Ok(loaded)
}

/// `radius_scale` and `color_by = "uniform"` (no particle keeps a colour of its own).
pub(crate) fn apply_include_options(spec: &IncludeSpec, records: &mut [ParticleRecord]) {
    if spec.radius_scale != 1.0 {
        for r in records.iter_mut() {
            r.radius *= spec.radius_scale;
            if let Some(e) = &mut r.ellipsoid {
                e.semi_axes *= spec.radius_scale;
            }
        }
    }
    if spec.color_by == ColorBy::Uniform {
        for r in records.iter_mut() {
            r.color = None;
        }
    }
}

/// The error for a file that yields no particles: nearly always a truncated download or a wrong
/// path, so it is refused rather than rendered as an empty background. Readers whose selections
/// (model, chains, frame, …) emptied a non-empty file report that themselves, naming the filter.
fn no_particles(spec: &IncludeSpec, format: &Format, len: usize, warnings: &[String]) -> PgtError {
    let mut message = if len == 0 {
        "the file is empty (0 bytes), so it holds no particles (a truncated download or a wrong path?)"
            .to_string()
    } else {
        format!(
            "the file holds no particles: its {len} bytes contain no {}, read as {}",
            format.particles, format.description
        )
    };
    if !warnings.is_empty() {
        message.push_str(&format!("; the reader noted: {}", warnings.join("; ")));
    }
    PgtError::in_file(&spec.path, message)
}

/// Every particle has a finite centre, a finite radius > 0, a colour ≥ 0 and an opacity in
/// [0, 1], and an ellipsoid finite semi-axes > 0 and a finite, non-zero quaternion (also for
/// `pgt info`, which does not build a scene); the error points at the particle's line or byte.
pub(crate) fn check_records(path: &Path, records: &[ParticleRecord]) -> Result<()> {
    for r in records {
        let problem = if let Some(problem) = r
            .ellipsoid
            .and_then(|e| e.problem(["sx", "sy", "sz"], "the rotation qw, qx, qy, qz"))
        {
            Some(format!("the particle's {problem}"))
        } else if !r.center.is_finite() {
            Some(format!("the particle position {} is not finite", r.center))
        } else if !(r.radius.is_finite() && r.radius > 0.0) {
            Some(format!(
                "the particle radius must be finite and > 0, got {}",
                r.radius
            ))
        } else if r
            .color
            .is_some_and(|c| !(c.is_finite() && c.min_element() >= 0.0))
        {
            Some(format!(
                "the particle colour must be finite and ≥ 0, got {:?}",
                r.color
            ))
        } else if r.opacity.is_some_and(|o| !(0.0..=1.0).contains(&o)) {
            Some(format!(
                "the particle opacity must be in [0, 1], got {:?}",
                r.opacity
            ))
        } else if r.sigma.is_some_and(|s| s.is_nan() || s < 0.0) {
            Some(format!(
                "the particle sigma must be ≥ 0 (or inf), got {:?}",
                r.sigma
            ))
        } else {
            None
        };
        if let Some(message) = problem {
            return Err(PgtError::Input {
                path: path.to_path_buf(),
                location: r.location.clone(),
                message,
            });
        }
    }
    Ok(())
}
