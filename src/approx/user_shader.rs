//! Users' own methods (docs/design.md §4, docs/user-shaders.md): a WGSL file that defines
//! `fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32>` and may use everything the prelude
//! `shaders/common.wgsl` declares. Errors point at the user's file and line
//! ([`super::shader::ShaderProgram::position`] maps the concatenated source back).

use super::shader::ShaderPart;
use crate::error::{PgtError, Result};
use std::borrow::Cow;
use std::path::Path;

/// Reads a user's method file; checks that it defines `shade` (naga would otherwise report the
/// missing function at the entry point's line, in pgt's file, which helps nobody).
pub fn load(path: &Path) -> Result<ShaderPart> {
    let text = std::fs::read_to_string(path).map_err(|e| PgtError::io(path, e))?;
    if !defines_shade(&text) {
        return Err(PgtError::in_file(
            path,
            "a pgt shader must define `fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32>` (see docs/user-shaders.md)",
        ));
    }
    Ok(ShaderPart {
        name: path.display().to_string(),
        text: Cow::Owned(text),
    })
}

/// Whether the text has a `fn shade(` outside comments (a cheap check; naga does the rest).
fn defines_shade(text: &str) -> bool {
    text.lines().any(|line| {
        let code = line.split("//").next().unwrap_or("");
        let mut words = code.split_whitespace();
        while let Some(w) = words.next() {
            if w == "fn" {
                if let Some(next) = words.next() {
                    if next == "shade" || next.starts_with("shade(") {
                        return true;
                    }
                }
            }
        }
        false
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_shade_but_not_in_comments() {
        assert!(defines_shade(
            "fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {}"
        ));
        assert!(defines_shade("  fn   shade (ray: Ray"));
        assert!(!defines_shade("// fn shade(ray: Ray)"));
        assert!(!defines_shade("fn shader(ray: Ray)"));
    }
}
