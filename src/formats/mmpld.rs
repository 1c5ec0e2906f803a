//! MMPLD (placeholder).
use super::LoadedParticles;
use crate::error::{PgtError, Result};
use crate::scene::IncludeSpec;

/// Loads one frame of an MMPLD file.
pub fn load(spec: &IncludeSpec, _bytes: &[u8]) -> Result<LoadedParticles> {
    Err(PgtError::in_file(&spec.path, "MMPLD is not supported yet"))
}
