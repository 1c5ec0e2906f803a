//! XYZ and CSV (placeholder).
use super::LoadedParticles;
use crate::error::{PgtError, Result};
use std::path::Path;

/// Loads an XYZ file.
pub fn load_xyz(path: &Path, _bytes: &[u8]) -> Result<LoadedParticles> {
    Err(PgtError::in_file(path, "XYZ is not supported yet"))
}

/// Loads a CSV file.
pub fn load_csv(path: &Path, _bytes: &[u8]) -> Result<LoadedParticles> {
    Err(PgtError::in_file(path, "CSV is not supported yet"))
}
