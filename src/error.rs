//! Library error type. Every error that reaches the user names the file, the line (or byte offset)
//! and the problem (DESIGN.md §6, §7); the CLI maps all of them to exit code 2.

use std::path::PathBuf;

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
}

pub type Result<T, E = PgtError> = std::result::Result<T, E>;
