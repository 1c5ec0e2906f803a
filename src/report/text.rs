//! Text for the reports: HTML escaping, text files written atomically, and their folders.

use crate::error::Result;
use std::path::Path;

/// HTML-escapes text.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Writes a text file atomically.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    use std::io::Write;
    crate::image_io::write_atomically(path, |w| w.write_all(text.as_bytes()))
}

/// Makes `dir` and the folders above it, under the signal cleanup's hold
/// ([`crate::signals::hold_off`]): a temporary report folder that the cleanup has removed is not
/// made again between the removal and the exit.
pub fn create_folder(dir: &Path) -> Result<()> {
    crate::signals::hold_off(|| std::fs::create_dir_all(dir))
        .map_err(|e| crate::error::PgtError::io(dir, e))
}
