//! VRML97 (placeholder).
use super::LoadedParticles;
use crate::error::{PgtError, Result};
use std::path::Path;

/// Loads the spheres of a VRML97 file.
pub fn load(path: &Path, _bytes: &[u8]) -> Result<LoadedParticles> {
    Err(PgtError::in_file(path, "VRML is not supported yet"))
}
