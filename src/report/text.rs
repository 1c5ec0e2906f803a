//! Text for the reports: HTML escaping, and text files written atomically.

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
