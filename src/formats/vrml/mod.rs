//! VRML97 (`.wrl`): a tokenizer ([`lexer`]), a parser to a node tree ([`parser`]) and an
//! evaluation that composes transforms and expands PROTOs into spheres ([`eval`], where what
//! becomes a particle, and how colours and opacity are read, is documented).

pub mod eval;
pub mod lexer;
pub mod parser;

use super::{Format, IncludeSpec, LoadedParticles};
use crate::error::{PgtError, Result};

/// VRML97 in the table of formats ([`super::FORMATS`]).
pub const FORMAT: Format = Format {
    name: "vrml",
    extensions: &["wrl", "vrml"],
    description: "VRML97",
    particles: "Sphere shapes",
    read: Some(read),
    ..Format::NOTHING
};

/// The [`super::Reader`] of VRML97: the spheres of the file. The file must start with
/// `#VRML V2.0` (VRML 1.0 is a different language and is refused).
pub fn read(spec: &IncludeSpec, bytes: &[u8]) -> Result<LoadedParticles> {
    let path = spec.path.as_path();
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    if !bytes.starts_with(b"#VRML V2.0") {
        let first: String =
            String::from_utf8_lossy(bytes.get(..bytes.len().min(40)).unwrap_or_default())
                .lines()
                .next()
                .unwrap_or_default()
                .to_string();
        return Err(PgtError::at_line(
            path,
            1,
            format!("expected the VRML97 header '#VRML V2.0 utf8', found '{first}'"),
        ));
    }
    let tokens = lexer::tokenize(path, bytes)?;
    let roots = parser::parse(path, &tokens)?;
    let ev = eval::evaluate(path, &roots)?;
    Ok(LoadedParticles {
        records: ev.records,
        warnings: ev.warnings,
        sh: None,
    })
}
