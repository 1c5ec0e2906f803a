//! The PLY header: `ply`, the `format` line, `element` and `property` lines up to
//! `end_header`, each problem an error naming its line.

use crate::error::{PgtError, Result};
use crate::formats::file::Endian;
use std::path::Path;

/// How the data after the header is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

impl Encoding {
    /// The byte order of a binary encoding (`None`: ASCII).
    pub(super) fn endian(self) -> Option<Endian> {
        match self {
            Encoding::Ascii => None,
            Encoding::LittleEndian => Some(Endian::Little),
            Encoding::BigEndian => Some(Endian::Big),
        }
    }

    pub(super) fn name(self) -> &'static str {
        match self {
            Encoding::Ascii => "ascii",
            Encoding::LittleEndian => "binary_little_endian",
            Encoding::BigEndian => "binary_big_endian",
        }
    }
}

/// A PLY scalar type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    /// The type of a header name (both the PLY 1.0 names and the sized ones).
    pub(super) fn named(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    pub(super) fn bytes(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// An ASCII value of this type (a float rounded as the type stores it; an integer in its
    /// range).
    pub(super) fn parse(self, w: &str) -> Option<f64> {
        let int = |lo: i64, hi: i64| w.parse::<i64>().ok().filter(|v| (lo..=hi).contains(v));
        match self {
            Scalar::F32 => w.parse::<f32>().ok().map(f64::from),
            Scalar::F64 => w.parse::<f64>().ok(),
            Scalar::I8 => int(i8::MIN.into(), i8::MAX.into()).map(|v| v as f64),
            Scalar::U8 => int(0, u8::MAX.into()).map(|v| v as f64),
            Scalar::I16 => int(i16::MIN.into(), i16::MAX.into()).map(|v| v as f64),
            Scalar::U16 => int(0, u16::MAX.into()).map(|v| v as f64),
            Scalar::I32 => int(i32::MIN.into(), i32::MAX.into()).map(|v| v as f64),
            Scalar::U32 => int(0, u32::MAX.into()).map(|v| v as f64),
        }
    }

    /// The value at byte `at` of a binary record, in the file's byte order; `None` where it
    /// does not fit.
    #[inline]
    pub(super) fn read(self, b: &[u8], at: usize, endian: Endian) -> Option<f64> {
        match self {
            Scalar::I8 => endian.read::<i8>(b, at).map(f64::from),
            Scalar::U8 => endian.read::<u8>(b, at).map(f64::from),
            Scalar::I16 => endian.read::<i16>(b, at).map(f64::from),
            Scalar::U16 => endian.read::<u16>(b, at).map(f64::from),
            Scalar::I32 => endian.read::<i32>(b, at).map(f64::from),
            Scalar::U32 => endian.read::<u32>(b, at).map(f64::from),
            Scalar::F32 => endian.read::<f32>(b, at).map(f64::from),
            Scalar::F64 => endian.read::<f64>(b, at),
        }
    }
}

/// One scalar property of an element.
#[derive(Debug, Clone)]
pub(super) struct Property {
    pub(super) name: String,
    pub(super) scalar: Scalar,
    /// Byte offset inside a binary record.
    pub(super) offset: usize,
}

/// One `element` of the header.
#[derive(Debug, Clone)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: u64,
    pub(super) properties: Vec<Property>,
    /// The properties' names, for the duplicate check.
    pub(super) names: std::collections::HashSet<String>,
    /// Header line of the `element` line.
    pub(super) line: usize,
}

impl Element {
    /// Bytes of one binary record.
    pub(super) fn stride(&self) -> usize {
        self.properties.iter().map(|p| p.scalar.bytes()).sum()
    }
}

/// The parsed header.
#[derive(Debug, Clone)]
pub(super) struct Header {
    pub(super) encoding: Encoding,
    pub(super) elements: Vec<Element>,
    /// Byte offset of the first byte after `end_header`'s line.
    pub(super) data_start: usize,
    /// Lines of the header (the data of an ASCII file starts on the next one).
    pub(super) lines: usize,
}

/// Headers longer than this are refused (a binary file without a header, read as one; a
/// header of a million properties).
pub(super) const MAX_HEADER_BYTES: usize = 1 << 20;

pub(super) fn header_line_err(path: &Path, line: usize, msg: impl Into<String>) -> PgtError {
    PgtError::at_line(path, line, format!("PLY header: {}", msg.into()))
}

/// Parses the header: its lines up to `end_header` (ASCII; a line that is not UTF-8, a
/// keyword the PLY format lacks, a list property or an unknown type is an error naming the line).
pub(super) fn header(path: &Path, bytes: &[u8]) -> Result<Header> {
    if bytes.is_empty() {
        return Err(PgtError::in_file(
            path,
            "the file is empty (0 bytes), so it holds no particles (a truncated download or a wrong path?)",
        ));
    }
    let mut pos = 0usize;
    let mut line = 0usize;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        line += 1;
        let rest = bytes
            .get(pos..MAX_HEADER_BYTES.min(bytes.len()))
            .unwrap_or_default();
        let Some(n) = rest.iter().position(|&b| b == b'\n') else {
            let msg = if bytes.len() >= MAX_HEADER_BYTES {
                format!(
                    "no `end_header` within the first {MAX_HEADER_BYTES} bytes: not a PLY header"
                )
            } else {
                "the file ends before `end_header`".to_string()
            };
            return Err(header_line_err(path, line, msg));
        };
        let raw = &rest[..n];
        pos += n + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let text = std::str::from_utf8(raw).map_err(|_| {
            header_line_err(path, line, "the line is not text (PLY headers are ASCII)")
        })?;
        let words: Vec<&str> = text.split_whitespace().collect();
        if line == 1 {
            if words != ["ply"] {
                return Err(header_line_err(
                    path,
                    1,
                    format!(
                        "not a PLY file: the first line must be `ply`, found `{}`",
                        short(text)
                    ),
                ));
            }
            continue;
        }
        match words.first().copied() {
            Some("comment") | Some("obj_info") | None => {}
            Some("format") => {
                let e = match words.get(1).copied() {
                    Some("ascii") => Encoding::Ascii,
                    Some("binary_little_endian") => Encoding::LittleEndian,
                    Some("binary_big_endian") => Encoding::BigEndian,
                    _ => {
                        return Err(header_line_err(path, line, format!(
                            "expected `format ascii|binary_little_endian|binary_big_endian 1.0`, found `{}`",
                            short(text)
                        )))
                    }
                };
                if words.len() != 3 || !matches!(words[2], "1.0" | "1") {
                    return Err(header_line_err(path, line, format!(
                        "expected the version 1.0 after the format, found `{}`",
                        short(text)
                    )));
                }
                if encoding.replace(e).is_some() {
                    return Err(header_line_err(path, line, "a second `format` line"));
                }
            }
            Some("element") => elements.push(element_line(path, line, &words, &elements, text)?),
            Some("property") => property_line(path, line, &words, &mut elements, text)?,
            Some("end_header") => break,
            Some(other) => {
                return Err(header_line_err(path, line, format!(
                    "unknown keyword `{}`: expected format, element, property, comment, obj_info or end_header",
                    short(other)
                )))
            }
        }
    }
    let Some(encoding) = encoding else {
        return Err(header_line_err(
            path,
            line,
            "the header has no `format` line",
        ));
    };
    Ok(Header {
        encoding,
        elements,
        data_start: pos,
        lines: line,
    })
}

/// A piece of a header line for a message: at most 60 characters.
pub(super) fn short(text: &str) -> String {
    let s: String = text.trim().chars().take(60).collect();
    if s.len() < text.trim().len() {
        s + "…"
    } else {
        s
    }
}

/// `element NAME COUNT`.
pub(super) fn element_line(
    path: &Path,
    line: usize,
    words: &[&str],
    elements: &[Element],
    text: &str,
) -> Result<Element> {
    let (Some(name), Some(count), 3) = (words.get(1), words.get(2), words.len()) else {
        return Err(header_line_err(
            path,
            line,
            format!("expected `element NAME COUNT`, found `{}`", short(text)),
        ));
    };
    let count: u64 = count.parse().map_err(|_| {
        header_line_err(
            path,
            line,
            format!(
                "element {}: the count `{}` is not a non-negative integer",
                short(name),
                short(count)
            ),
        )
    })?;
    if elements.iter().any(|e| e.name == *name) {
        return Err(header_line_err(
            path,
            line,
            format!("a second element `{}`", short(name)),
        ));
    }
    Ok(Element {
        name: name.to_string(),
        count,
        properties: Vec::new(),
        names: std::collections::HashSet::new(),
        line,
    })
}

/// `property TYPE NAME` (a `property list …` is refused).
pub(super) fn property_line(
    path: &Path,
    line: usize,
    words: &[&str],
    elements: &mut [Element],
    text: &str,
) -> Result<()> {
    let Some(element) = elements.last_mut() else {
        return Err(header_line_err(
            path,
            line,
            "a property before any `element` line",
        ));
    };
    if words.get(1) == Some(&"list") {
        let name = words.last().copied().unwrap_or_default();
        return Err(header_line_err(path, line, format!(
            "element {}: property {} is a list; pgt reads elements of scalar properties only (a 3D Gaussian splatting file has no lists)",
            element.name,
            short(name)
        )));
    }
    let (Some(ty), Some(name), 3) = (words.get(1), words.get(2), words.len()) else {
        return Err(header_line_err(
            path,
            line,
            format!("expected `property TYPE NAME`, found `{}`", short(text)),
        ));
    };
    let Some(scalar) = Scalar::named(ty) else {
        return Err(header_line_err(path, line, format!(
            "element {}: property {} has the unknown type `{}` (expected char, uchar, short, ushort, int, uint, float, double or int8 … float64)",
            element.name,
            short(name),
            short(ty)
        )));
    };
    if !element.names.insert(name.to_string()) {
        return Err(header_line_err(
            path,
            line,
            format!(
                "element {}: a second property `{}`",
                element.name,
                short(name)
            ),
        ));
    }
    let offset = element.stride();
    element.properties.push(Property {
        name: name.to_string(),
        scalar,
        offset,
    });
    Ok(())
}
