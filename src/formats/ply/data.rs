//! The vertex data after a PLY header, ASCII or binary: every announced count checked against
//! the bytes present before anything is allocated, each vertex's values handed to a conversion
//! with the line or byte it came from.

use super::header::{short, Element, Header};
use crate::error::{Location, PgtError, Result};
use crate::formats::file::{lines, Endian};
use crate::formats::ParticleRecord;
use std::path::Path;

/// Turns the values of vertex i (at a line or byte) into a particle.
pub(super) type Convert<'a> = dyn Fn(usize, Location, &[f64]) -> Result<ParticleRecord> + 'a;

/// Every vertex of element `v`, read as the header's encoding says and converted.
pub(super) fn vertices(
    path: &Path,
    bytes: &[u8],
    h: &Header,
    v: usize,
    convert: &Convert,
    warnings: &mut Vec<String>,
) -> Result<Vec<ParticleRecord>> {
    match h.encoding.endian() {
        None => read_ascii(path, bytes, h, v, convert),
        Some(endian) => read_binary(path, bytes, h, v, endian, convert, warnings),
    }
}

/// Bytes of the binary records of `elements`; `None` on overflow.
fn element_bytes(elements: &[Element]) -> Option<u64> {
    elements.iter().try_fold(0u64, |sum, e| {
        e.count
            .checked_mul(e.stride() as u64)
            .and_then(|b| sum.checked_add(b))
    })
}

/// The vertices of a binary file, each a record of the element's stride whose values sit at
/// their properties' offsets.
fn read_binary(
    path: &Path,
    bytes: &[u8],
    h: &Header,
    v: usize,
    endian: Endian,
    convert: &Convert,
    warnings: &mut Vec<String>,
) -> Result<Vec<ParticleRecord>> {
    let e = &h.elements[v];
    let stride = e.stride();
    let data = bytes.len().saturating_sub(h.data_start) as u64;
    let before = element_bytes(&h.elements[..v]).unwrap_or(u64::MAX);
    let start = (h.data_start as u64).saturating_add(before);
    let need = e.count.saturating_mul(stride as u64);
    let have = (bytes.len() as u64).saturating_sub(start);
    if before > data || need > have {
        let whole = have / stride.max(1) as u64;
        return Err(PgtError::at_byte(path, start.saturating_add(whole * stride as u64), format!(
            "the header announces {} vertices of {stride} bytes ({need} bytes from byte {start}), but the file ends after {} bytes of them: it is cut short in vertex {whole}",
            e.count,
            have.min(need)
        )));
    }
    if let Some(all) = element_bytes(&h.elements) {
        if all < data {
            warnings.push(format!(
                "{}: {} bytes after the last element's data are ignored",
                path.display(),
                data - all
            ));
        }
    }
    let (start, count) = (start as usize, e.count as usize);
    let mut records = Vec::with_capacity(count);
    let mut values = vec![0.0f64; e.properties.len()];
    for i in 0..count {
        let at = start + i * stride;
        for (value, p) in values.iter_mut().zip(&e.properties) {
            let field = at + p.offset;
            *value = p.scalar.read(bytes, field, endian).ok_or_else(|| {
                PgtError::at_byte(
                    path,
                    field as u64,
                    format!("vertex {i}: property {} is cut short", p.name),
                )
            })?;
        }
        records.push(convert(i, Location::Byte(at as u64), &values)?);
    }
    Ok(records)
}

/// The vertices of an ASCII file, one line each (blank lines skipped), after the lines of the
/// elements before the vertex element.
fn read_ascii(
    path: &Path,
    bytes: &[u8],
    h: &Header,
    v: usize,
    convert: &Convert,
) -> Result<Vec<ParticleRecord>> {
    let e = &h.elements[v];
    let text = bytes.get(h.data_start..).unwrap_or_default();
    let skip: u64 = h.elements[..v]
        .iter()
        .map(|e| e.count)
        .fold(0, u64::saturating_add);
    // Each vertex is one line of at least two bytes.
    if e.count > text.len() as u64 / 2 {
        return Err(PgtError::at_line(
            path,
            e.line,
            format!(
                "the header announces {} vertices, more than the {} bytes of data can hold",
                e.count,
                text.len()
            ),
        ));
    }
    let mut lines =
        lines(text, h.lines + 1).filter(|(_, l)| !l.iter().all(u8::is_ascii_whitespace));
    for _ in 0..skip {
        if lines.next().is_none() {
            break;
        }
    }
    // Grown as lines are read: the count is only bounded by the file's size here.
    let mut records = Vec::with_capacity((e.count as usize).min(1 << 16));
    let mut values = vec![0.0f64; e.properties.len()];
    for i in 0..e.count as usize {
        let Some((line, raw)) = lines.next() else {
            return Err(PgtError::at_line(
                path,
                e.line,
                format!(
                    "the header announces {} vertices, but the data ends after {i}",
                    e.count
                ),
            ));
        };
        let t = String::from_utf8_lossy(raw);
        let words: Vec<&str> = t.split_whitespace().collect();
        if words.len() != values.len() {
            return Err(PgtError::at_line(
                path,
                line,
                format!(
                    "vertex {i}: expected {} values (the vertex properties), found {}",
                    values.len(),
                    words.len()
                ),
            ));
        }
        for ((value, w), p) in values.iter_mut().zip(&words).zip(&e.properties) {
            *value = p.scalar.parse(w).ok_or_else(|| {
                PgtError::at_line(
                    path,
                    line,
                    format!(
                        "vertex {i}: property {} is not a number of its type: `{}`",
                        p.name,
                        short(w)
                    ),
                )
            })?;
        }
        records.push(convert(i, Location::Line(line), &values)?);
    }
    Ok(records)
}
