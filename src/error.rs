//! Library error type. Every error that reaches the user names the file, the line (or byte offset)
//! and the problem (docs/design.md §6, §7); the CLI maps all of them to exit code 2.

use std::path::{Path, PathBuf};

/// Where in an input a problem is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Location {
    /// 1-based line in a text file.
    Line(usize),
    /// 0-based byte offset in a binary file.
    Byte(u64),
    /// The whole file (no finer position is meaningful).
    File,
}

#[derive(Debug, thiserror::Error)]
pub enum PgtError {
    /// Bad input: a malformed file, an invalid value, an unsupported feature.
    #[error("{}: {message}", display_location(path, location))]
    Input {
        path: PathBuf,
        location: Location,
        message: String,
    },
    /// A command-line value that makes no sense (no file involved).
    #[error("{0}")]
    Usage(String),
    /// An I/O failure on a named file.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The GPU side failed (no adapter, shader errors, limits).
    #[error("{0}")]
    Gpu(String),
    /// The work was stopped on request before it finished (a reference render whose
    /// `RenderControl` was stopped: Ctrl-C in Python); nothing was produced.
    #[error("interrupted")]
    Interrupted,
    /// An error of one step of a longer job, prefixed with the step (e.g. a sweep's run label).
    #[error("{context}: {source}")]
    Context {
        context: String,
        #[source]
        source: Box<PgtError>,
    },
}

fn display_location(path: &std::path::Path, location: &Location) -> String {
    match location {
        Location::Line(line) => format!("{}:{line}", path.display()),
        Location::Byte(offset) => format!("{} (byte {offset})", path.display()),
        Location::File => path.display().to_string(),
    }
}

impl PgtError {
    /// A problem at a line of a text input.
    pub fn at_line(path: impl Into<PathBuf>, line: usize, message: impl Into<String>) -> Self {
        PgtError::Input {
            path: path.into(),
            location: Location::Line(line),
            message: message.into(),
        }
    }

    /// A problem at a byte offset of a binary input.
    pub fn at_byte(path: impl Into<PathBuf>, offset: u64, message: impl Into<String>) -> Self {
        PgtError::Input {
            path: path.into(),
            location: Location::Byte(offset),
            message: message.into(),
        }
    }

    /// A problem with a file as a whole.
    pub fn in_file(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        PgtError::Input {
            path: path.into(),
            location: Location::File,
            message: message.into(),
        }
    }

    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        PgtError::Io {
            path: path.into(),
            source,
        }
    }

    /// This error prefixed with the step it happened in ("thesis samples=4 n_exact=1: …").
    pub fn context(self, context: impl Into<String>) -> Self {
        PgtError::Context {
            context: context.into(),
            source: Box::new(self),
        }
    }
}

/// The 1-based line of byte offset `offset` in `text` (offsets past the end give the last line).
pub fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// A TOML syntax or type error in the file `path` (whose contents are `text`) as an error that
/// names the file and line (docs/design.md §6 "Bad input"), quoting the offending line, since serde's
/// message alone ("invalid length 2") does not name the field. Errors without a position (rare
/// in toml 0.8) name the file only.
pub fn toml_error(path: &Path, text: &str, e: &toml::de::Error) -> PgtError {
    let message = e.message().trim().to_string();
    let Some(span) = e.span() else {
        return PgtError::in_file(path, message);
    };
    let line = line_of(text, span.start);
    PgtError::at_line(path, line, with_quoted_line(message, text, line))
}

/// `message (in `the text of line`)`, the line trimmed and cut at 100 characters; the message
/// alone where the line is blank.
pub fn with_quoted_line(message: String, text: &str, line: usize) -> String {
    match text
        .lines()
        .nth(line.saturating_sub(1))
        .map(str::trim)
        .filter(|l| !l.is_empty())
    {
        Some(source_line) => {
            let quoted: String = source_line.chars().take(100).collect();
            format!("{message} (in `{quoted}`)")
        }
        None => message,
    }
}

/// A text input being validated (a scene file, an experiment file): its path and text, so that
/// an error names `file:line` and quotes the line. Scene validation and the experiment reader
/// both report through it and the [`At`] it hands out.
#[derive(Debug, Clone, Copy)]
pub struct SourceText<'a> {
    pub path: &'a Path,
    pub text: &'a str,
}

impl<'a> SourceText<'a> {
    /// The 1-based line of a TOML value.
    pub fn line<T>(&self, value: &toml::Spanned<T>) -> usize {
        line_of(self.text, value.span().start)
    }

    /// An error at `line` that quotes the line's text ([`with_quoted_line`]).
    pub fn error(&self, line: usize, message: String) -> PgtError {
        PgtError::at_line(self.path, line, with_quoted_line(message, self.text, line))
    }

    /// The place of the byte range `span` (its first line), for [`At`]'s checks.
    pub fn at(&self, span: std::ops::Range<usize>) -> At<'a> {
        At {
            path: self.path,
            location: Location::Line(line_of(self.text, span.start)),
        }
    }

    /// The file as a whole (for what no line stands for, e.g. a command-line override).
    pub fn whole(&self) -> At<'a> {
        At::whole(self.path)
    }
}

/// A place in an input that errors name (`file:line`, `file (byte N)` or the file), with the
/// checks that validation makes of the values found there; each error names the field.
#[derive(Debug, Clone)]
pub struct At<'a> {
    pub path: &'a Path,
    pub location: Location,
}

impl<'a> At<'a> {
    /// The file as a whole.
    pub fn whole(path: &'a Path) -> At<'a> {
        At {
            path,
            location: Location::File,
        }
    }

    /// An error here.
    pub fn err(&self, message: impl Into<String>) -> PgtError {
        PgtError::Input {
            path: self.path.to_path_buf(),
            location: self.location.clone(),
            message: message.into(),
        }
    }

    /// `v`, if finite.
    pub fn finite(&self, field: &str, v: f64) -> Result<f64> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err(format!("{field} must be a finite number, got {v}")))
        }
    }

    /// Three finite numbers as a vector.
    pub fn vec3(&self, field: &str, v: [f64; 3]) -> Result<glam::DVec3> {
        if v.iter().all(|x| x.is_finite()) {
            Ok(glam::DVec3::from(v))
        } else {
            Err(self.err(format!("{field} must hold three finite numbers, got {v:?}")))
        }
    }

    /// Three finite numbers ≥ 0 (a colour, an irradiance).
    pub fn non_negative3(&self, field: &str, v: [f64; 3]) -> Result<glam::DVec3> {
        let d = self.vec3(field, v)?;
        if d.min_element() < 0.0 {
            return Err(self.err(format!("{field} must be ≥ 0 in every channel, got {v:?}")));
        }
        Ok(d)
    }

    /// A non-zero vector, normalised.
    pub fn direction(&self, field: &str, v: [f64; 3]) -> Result<glam::DVec3> {
        let d = self.vec3(field, v)?;
        let len = d.length();
        if len == 0.0 || !len.is_finite() {
            return Err(self.err(format!("{field} must be a non-zero vector, got {v:?}")));
        }
        Ok(d / len)
    }

    /// A finite `v` in [lo, hi]; `what` says the range in the message ("in [0, 1]").
    pub fn in_range(&self, field: &str, v: f64, lo: f64, hi: f64, what: &str) -> Result<f64> {
        let v = self.finite(field, v)?;
        if v < lo || v > hi {
            return Err(self.err(format!("{field} must be {what}, got {v}")));
        }
        Ok(v)
    }
}

pub type Result<T, E = PgtError> = std::result::Result<T, E>;

/// The one-line message of a failed command: the error and its causes joined by ": ", leaving
/// out a cause whose text the line already ends with. pgt's own errors put their cause into
/// their message *and* report it as `source()` (so that a library user can walk the chain);
/// printing the chain naively would say "stream did not contain valid UTF-8" twice.
pub fn error_message(e: &anyhow::Error) -> String {
    let mut line = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !line.ends_with(&cause) {
            line.push_str(": ");
            line.push_str(&cause);
        }
    }
    line
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_lines_are_one_based() {
        assert_eq!(line_of("a\nb\nc", 0), 1);
        assert_eq!(line_of("a\nb\nc", 2), 2);
        assert_eq!(line_of("a\nb\nc", 99), 3);
    }

    #[test]
    fn toml_errors_name_the_file_line_and_text() {
        #[derive(Debug, serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct T {
            a: u32,
        }
        let text = "a = 1\nb = 2\n";
        let e = toml::from_str::<T>(text).unwrap_err();
        let err = toml_error(Path::new("x.toml"), text, &e).to_string();
        assert!(err.starts_with("x.toml:2: "), "{err}");
        assert!(err.contains("(in `b = 2`)"), "{err}");
    }

    #[test]
    fn context_prefixes_the_message() {
        let e = PgtError::Usage("bad".into()).context("run 1");
        assert_eq!(e.to_string(), "run 1: bad");
    }
}

#[cfg(test)]
mod message_tests {
    use super::*;

    fn utf8_error() -> std::io::Error {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        )
    }

    #[test]
    fn a_cause_already_in_the_message_is_said_once() {
        let e = anyhow::Error::from(PgtError::io("gate.toml", utf8_error()));
        assert_eq!(
            error_message(&e),
            "gate.toml: stream did not contain valid UTF-8"
        );
        let e = anyhow::Error::from(PgtError::io("a.toml", utf8_error()).context("run 3"));
        assert_eq!(
            error_message(&e),
            "run 3: a.toml: stream did not contain valid UTF-8"
        );
    }

    #[test]
    fn a_cause_not_in_the_message_is_kept() {
        let e = anyhow::Error::from(utf8_error()).context("reading the scene");
        assert_eq!(
            error_message(&e),
            "reading the scene: stream did not contain valid UTF-8"
        );
    }
}
