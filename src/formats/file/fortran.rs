//! Fortran unformatted sequential records (DCD): each record is a length marker, its payload,
//! and the same marker again. Markers are 4 bytes, or 8 in files of some 64-bit Fortran
//! compilers, in the file's byte order. Both markers are checked before a payload is used: a
//! marker that disagrees is a corrupt (or misread) file.

use super::binary::{cut_short, Endian};
use super::source::ByteSource;
use crate::error::{PgtError, Result};

/// How a file writes its records: the byte order and the marker size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fortran {
    pub endian: Endian,
    /// Bytes of a record marker: 4 or 8.
    pub marker: u64,
}

/// Why a record inside bytes already read does not have the payload length expected
/// ([`Fortran::record_in`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RecordError {
    /// A marker is not the length: the offset of the first one that differs, and both.
    Markers {
        at: usize,
        opening: u64,
        closing: u64,
    },
    /// The bytes end before the record does (at `at`).
    CutShort { at: usize },
}

impl Fortran {
    /// The layout in which a file's first marker reads `first`: 4-byte markers before 8-byte
    /// ones, little-endian before big-endian; `start` is the file's first (up to 8) bytes.
    pub fn detect(start: &[u8], first: u64) -> Option<Fortran> {
        let four = |endian| Fortran { endian, marker: 4 };
        let eight = |endian| Fortran { endian, marker: 8 };
        [
            four(Endian::Little),
            four(Endian::Big),
            eight(Endian::Little),
            eight(Endian::Big),
        ]
        .into_iter()
        .find(|f| f.marker_at(start, 0) == Some(first))
    }

    /// The marker at byte `at` of `bytes`, where it fits.
    pub fn marker_at(self, bytes: &[u8], at: usize) -> Option<u64> {
        if self.marker == 4 {
            self.endian.read::<u32>(bytes, at).map(u64::from)
        } else {
            self.endian.read::<u64>(bytes, at)
        }
    }

    /// The record of `source` whose opening marker is at `at`: its payload and the offset after
    /// it. The opening marker must be `expected` (`None`: any length that fits the file) and
    /// the closing marker the same; an error names the marker's byte and `what`.
    pub fn read(
        self,
        source: &ByteSource,
        at: u64,
        expected: Option<u64>,
        what: &str,
    ) -> Result<(Vec<u8>, u64)> {
        let marker = |at: u64, which: &str| -> Result<u64> {
            let what = format!("the {which} of {what}");
            let m = source.read_at(at, self.marker, &what)?;
            self.marker_at(&m, 0)
                .ok_or_else(|| cut_short(source.path(), at, &what, self.marker, "file", at))
        };
        let len = marker(at, "length marker")?;
        if let Some(e) = expected.filter(|&e| e != len) {
            return Err(PgtError::at_byte(
                source.path(),
                at,
                format!("{what}: the record length marker is {len}, expected {e}"),
            ));
        }
        let payload = source.read_at(at + self.marker, len, what)?;
        let end_at = at + self.marker + len;
        let closing = marker(end_at, "closing marker")?;
        if closing != len {
            return Err(PgtError::at_byte(
                source.path(),
                end_at,
                format!(
                    "{what}: the closing record marker is {closing}, expected {len} (a corrupt file)"
                ),
            ));
        }
        Ok((payload, end_at + self.marker))
    }

    /// The record at byte `at` of `bytes` (a piece of the file already read), whose payload
    /// must be `len` bytes: the payload's offset in `bytes`.
    pub fn record_in(
        self,
        bytes: &[u8],
        at: usize,
        len: usize,
    ) -> std::result::Result<usize, RecordError> {
        let m = self.marker as usize;
        let closing_at = at.saturating_add(m).saturating_add(len);
        let (Some(opening), Some(closing)) =
            (self.marker_at(bytes, at), self.marker_at(bytes, closing_at))
        else {
            return Err(RecordError::CutShort { at });
        };
        if opening != len as u64 || closing != len as u64 {
            let at = if opening != len as u64 {
                at
            } else {
                closing_at
            };
            return Err(RecordError::Markers {
                at,
                opening,
                closing,
            });
        }
        Ok(at + m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// Records of `payloads` with 4-byte little-endian markers.
    fn records(payloads: &[&[u8]]) -> Vec<u8> {
        let mut b = Vec::new();
        for p in payloads {
            b.extend_from_slice(&(p.len() as u32).to_le_bytes());
            b.extend_from_slice(p);
            b.extend_from_slice(&(p.len() as u32).to_le_bytes());
        }
        b
    }

    #[test]
    fn the_first_marker_gives_the_layout() {
        let le4 = 84u32.to_le_bytes();
        let be4 = 84u32.to_be_bytes();
        let be8 = 84u64.to_be_bytes();
        let f = |endian, marker| Some(Fortran { endian, marker });
        assert_eq!(Fortran::detect(&le4, 84), f(Endian::Little, 4));
        assert_eq!(Fortran::detect(&be4, 84), f(Endian::Big, 4));
        assert_eq!(Fortran::detect(&be8, 84), f(Endian::Big, 8));
        assert_eq!(Fortran::detect(&be4, 85), None);
        assert_eq!(
            Fortran::detect(&[84, 0], 84),
            None,
            "too short for a marker"
        );
    }

    #[test]
    fn records_are_read_with_both_markers_checked() {
        let le = Fortran {
            endian: Endian::Little,
            marker: 4,
        };
        let b = records(&[b"abcd", b"xy"]);
        let source = ByteSource::from_bytes(Path::new("t.dcd"), b.clone());
        let (p, next) = le.read(&source, 0, Some(4), "the header").expect("ok");
        assert_eq!((p.as_slice(), next), (b"abcd".as_slice(), 12));
        let (p, next) = le.read(&source, next, None, "the title").expect("ok");
        assert_eq!((p.as_slice(), next), (b"xy".as_slice(), 22));
        let e = le.read(&source, 0, Some(8), "the header").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.dcd (byte 0): the header: the record length marker is 4, expected 8"
        );
        let mut bad = b.clone();
        bad[8] = 5;
        let source = ByteSource::from_bytes(Path::new("t.dcd"), bad);
        let e = le.read(&source, 0, None, "the header").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.dcd (byte 8): the header: the closing record marker is 5, expected 4 (a corrupt file)"
        );
        let cut = ByteSource::from_bytes(Path::new("t.dcd"), b[..6].to_vec());
        let e = le
            .read(&cut, 0, None, "the header")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("t.dcd (byte 4): expected the header (4 bytes)"),
            "{e}"
        );
    }

    #[test]
    fn a_record_in_memory_names_the_marker_that_differs() {
        let le = Fortran {
            endian: Endian::Little,
            marker: 4,
        };
        let b = records(&[b"abcd", b"efgh"]);
        assert_eq!(le.record_in(&b, 12, 4), Ok(16));
        assert_eq!(
            le.record_in(&b, 12, 3),
            Err(RecordError::Markers {
                at: 12,
                opening: 4,
                closing: u64::from(u32::from_le_bytes([b'h', 4, 0, 0]))
            })
        );
        let mut bad = b.clone();
        bad[20] = 7;
        assert_eq!(
            le.record_in(&bad, 12, 4),
            Err(RecordError::Markers {
                at: 20,
                opening: 4,
                closing: 7
            })
        );
        assert_eq!(
            le.record_in(&b[..22], 12, 4),
            Err(RecordError::CutShort { at: 12 })
        );
    }
}
