//! Particle file formats (DESIGN.md §6). Each format turns a file into [`ParticleRecord`]s with
//! the line (or byte offset) each came from, so that validation can point at it.

use crate::error::{PgtError, Result};
use crate::scene::{IncludeSpec, ParticleRecord};

/// What a format delivers: the particles and non-fatal warnings (skipped shapes, guesses).
#[derive(Debug, Clone, Default)]
pub struct LoadedParticles {
    pub records: Vec<ParticleRecord>,
    pub warnings: Vec<String>,
}

/// Loads the particles of an `[[include]]` (or a bare particle file), choosing the format by the
/// file's extension.
pub fn load_particles(spec: &IncludeSpec) -> Result<LoadedParticles> {
    let ext = spec
        .path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    Err(PgtError::in_file(
        &spec.path,
        format!("unsupported particle file type '.{ext}'"),
    ))
}
