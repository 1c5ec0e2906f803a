//! Particle file formats (DESIGN.md §6). Each format turns a file into [`ParticleRecord`]s with
//! the line (or byte offset) each came from, so that validation can point at it.
//!
//! | format | extensions | module |
//! |---|---|---|
//! | PDB | `.pdb`, `.ent` | [`pdb`] |
//! | mmCIF | `.cif`, `.mmcif` | [`mmcif`] |
//! | VRML97 | `.wrl`, `.vrml` | [`vrml`] |
//! | MegaMol MMPLD | `.mmpld` | [`mmpld`] |
//! | XYZ | `.xyz` | [`xyz_csv`] |
//! | CSV | `.csv` | [`xyz_csv`] |
//!
//! `[[include]] format = "pdb"` forces a format whatever the extension.

pub mod atoms;
pub mod elements;
pub mod mmcif;
pub mod mmpld;
pub mod pdb;
pub mod random;
pub mod vrml;
pub mod xyz_csv;

use crate::error::{PgtError, Result};
use crate::scene::{IncludeSpec, ParticleRecord};
use std::path::Path;

/// What a format delivers: the particles and non-fatal warnings (skipped shapes, guesses).
#[derive(Debug, Clone, Default)]
pub struct LoadedParticles {
    /// The particles, in file order, with `radius_scale` applied.
    pub records: Vec<ParticleRecord>,
    /// Remarks for the user, each naming the file.
    pub warnings: Vec<String>,
}

/// The particle file formats pgt reads.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize, clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum Format {
    /// PDB (fixed columns).
    Pdb,
    /// mmCIF / PDBx.
    Mmcif,
    /// VRML97.
    Vrml,
    /// MegaMol MMPLD.
    Mmpld,
    /// XYZ (element x y z).
    Xyz,
    /// CSV with a header row.
    Csv,
}

impl Format {
    /// The format a file name's extension stands for.
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "pdb" | "ent" => Format::Pdb,
            "cif" | "mmcif" => Format::Mmcif,
            "wrl" | "vrml" => Format::Vrml,
            "mmpld" => Format::Mmpld,
            "xyz" => Format::Xyz,
            "csv" => Format::Csv,
            _ => return None,
        })
    }
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

/// Loads the particles of an `[[include]]` (or a bare particle file), choosing the format by
/// `spec.format` or else the file's extension, and applies `radius_scale` and, for every
/// format, `color_by = "uniform"` (no particle keeps a colour of its own).
pub fn load_particles(spec: &IncludeSpec) -> Result<LoadedParticles> {
    let format = match spec.format.or_else(|| Format::from_path(&spec.path)) {
        Some(f) => f,
        None => {
            let ext = spec
                .path
                .extension()
                .and_then(|e| e.to_str())
                .unwrap_or_default();
            return Err(PgtError::in_file(
                &spec.path,
                format!(
                    "unsupported particle file type '.{ext}': expected .pdb, .ent, .cif, .mmcif, .wrl, .vrml, \
                     .mmpld, .xyz, .csv or .toml (or set `format` in the [[include]])"
                ),
            ));
        }
    };
    let bytes = read_input(&spec.path)?;
    let mut loaded = load_bytes(spec, format, &bytes)?;
    if spec.radius_scale != 1.0 {
        for r in &mut loaded.records {
            r.radius *= spec.radius_scale;
        }
    }
    if spec.color_by == crate::scene::ColorBy::Uniform {
        // Every format: the file's colours give way to the scene's default colour.
        for r in &mut loaded.records {
            r.color = None;
        }
    }
    check_records(&spec.path, &loaded.records)?;
    Ok(loaded)
}

/// Every particle has a finite centre, a finite radius > 0, a colour ≥ 0 and an opacity in
/// [0, 1] (also for `pgt info`, which does not build a scene); the error points at the
/// particle's line or byte.
fn check_records(path: &Path, records: &[ParticleRecord]) -> Result<()> {
    for r in records {
        let problem = if !r.center.is_finite() {
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

/// Parses a file's bytes as `format` (no `radius_scale`); `spec.path` names it in messages.
pub fn load_bytes(spec: &IncludeSpec, format: Format, bytes: &[u8]) -> Result<LoadedParticles> {
    let path = &spec.path;
    match format {
        Format::Pdb => {
            let (atoms, warnings) = pdb::read_atoms(path, bytes)?;
            atoms::atoms_to_particles(spec, atoms, warnings)
        }
        Format::Mmcif => {
            let (atoms, warnings) = mmcif::read_atoms(path, bytes)?;
            atoms::atoms_to_particles(spec, atoms, warnings)
        }
        Format::Vrml => vrml::load(path, bytes),
        Format::Mmpld => mmpld::load(spec, bytes),
        Format::Xyz => xyz_csv::load_xyz(path, bytes, spec.frame.unwrap_or(0)),
        Format::Csv => xyz_csv::load_csv(path, bytes),
    }
}
