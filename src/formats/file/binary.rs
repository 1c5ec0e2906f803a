//! Binary numbers in either byte order, read only where they fit: [`Endian::read`] on a slice
//! already in memory, and [`Reader`], a cursor over a window of a file whose every read is
//! checked against the window's end and whose errors name the file and the byte offset in the
//! file.

use crate::error::{PgtError, Result};
use std::path::Path;

/// The byte order of a file's binary numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Endian {
    Little,
    Big,
}

/// A number as binary files store it: [`Number::BYTES`] bytes in either order.
pub trait Number: Copy {
    /// Its size in bytes.
    const BYTES: usize;
    /// The number whose bytes are `bytes` (exactly [`Number::BYTES`] of them; `None` for
    /// another length).
    fn decode(bytes: &[u8], endian: Endian) -> Option<Self>;
}

macro_rules! numbers {
    ($($t:ty),*) => {$(
        impl Number for $t {
            const BYTES: usize = std::mem::size_of::<$t>();
            #[inline]
            fn decode(bytes: &[u8], endian: Endian) -> Option<$t> {
                let a: [u8; std::mem::size_of::<$t>()] = bytes.try_into().ok()?;
                Some(match endian {
                    Endian::Little => <$t>::from_le_bytes(a),
                    Endian::Big => <$t>::from_be_bytes(a),
                })
            }
        }
    )*};
}

numbers!(u8, i8, u16, i16, u32, i32, u64, i64, f32, f64);

impl Endian {
    /// The number at byte `at` of `bytes`; `None` where it does not fit.
    #[inline]
    pub fn read<T: Number>(self, bytes: &[u8], at: usize) -> Option<T> {
        let end = at.checked_add(T::BYTES)?;
        T::decode(bytes.get(at..end)?, self)
    }
}

/// The error for `n` bytes of `what` wanted at file offset `at` where the `region` (`"file"`,
/// `"frame"`) ends at file offset `end`.
pub fn cut_short(path: &Path, at: u64, what: &str, n: u64, region: &str, end: u64) -> PgtError {
    PgtError::at_byte(
        path,
        at,
        format!("expected {what} ({n} bytes), but the {region} ends at byte {end}"),
    )
}

/// A window of a file's bytes read front to back. Every read is checked against the window's
/// end before anything is taken; an error names the file and the byte offset in the file, and
/// the window (`"file"` where it ends with the file, else its name, such as `"frame"`).
#[derive(Debug, Clone)]
pub struct Reader<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    /// File offset of `bytes[0]`.
    base: u64,
    /// Length of the whole file.
    file_len: u64,
    /// What the window is, where it ends before the file does.
    name: &'static str,
    endian: Endian,
    pos: usize,
}

impl<'a> Reader<'a> {
    /// A reader over the whole file `bytes`.
    pub fn whole(path: &'a Path, bytes: &'a [u8], endian: Endian) -> Reader<'a> {
        Reader::window(path, bytes, 0, bytes.len() as u64, "file", endian)
    }

    /// A reader over `bytes`, the piece of a file of `file_len` bytes that starts at file
    /// offset `base`; `name` says what the piece is (`"frame"`).
    pub fn window(
        path: &'a Path,
        bytes: &'a [u8],
        base: u64,
        file_len: u64,
        name: &'static str,
        endian: Endian,
    ) -> Reader<'a> {
        Reader {
            path,
            bytes,
            base,
            file_len,
            name,
            endian,
            pos: 0,
        }
    }

    /// The offset of the next read, in the window.
    pub fn pos(&self) -> usize {
        self.pos
    }

    /// Bytes left in the window.
    pub fn left(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    /// The file offset of window offset `at`.
    pub fn file_offset(&self, at: usize) -> u64 {
        self.base + at as u64
    }

    /// The next `n` bytes; past the window's end it is an error naming `what`.
    pub fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8]> {
        let stop = self.pos.checked_add(n);
        match stop.and_then(|s| self.bytes.get(self.pos..s)) {
            Some(b) => {
                self.pos += n;
                Ok(b)
            }
            None => Err(self.cut_short(self.pos, n, what)),
        }
    }

    /// The error for `n` bytes of `what` wanted at window offset `at`, past the window's end.
    fn cut_short(&self, at: usize, n: usize, what: &str) -> PgtError {
        let end = self.file_offset(self.bytes.len());
        let region = if end == self.file_len {
            "file"
        } else {
            self.name
        };
        cut_short(self.path, self.file_offset(at), what, n as u64, region, end)
    }

    /// The number at window offset `at`, wherever the cursor is (a field of a record whose
    /// bytes were taken whole); past the window's end it is an error naming `what`.
    pub fn number_at<T: Number>(&self, at: usize, what: &str) -> Result<T> {
        self.endian
            .read(self.bytes, at)
            .ok_or_else(|| self.cut_short(at, T::BYTES, what))
    }

    /// The next `N` bytes as an array.
    pub fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N]> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.take(N, what)?);
        Ok(a)
    }

    /// The next number, in the reader's byte order.
    pub fn number<T: Number>(&mut self, what: &str) -> Result<T> {
        let n = self.number_at(self.pos, what)?;
        self.pos += T::BYTES;
        Ok(n)
    }

    /// An error at window offset `at`.
    pub fn err(&self, at: usize, message: impl Into<String>) -> PgtError {
        PgtError::at_byte(self.path, self.file_offset(at), message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_decode_in_either_byte_order() {
        let b = [0x01, 0x02, 0x03, 0x04, 0x05];
        assert_eq!(Endian::Little.read::<u32>(&b, 0), Some(0x0403_0201));
        assert_eq!(Endian::Big.read::<u32>(&b, 1), Some(0x0203_0405));
        assert_eq!(Endian::Big.read::<i16>(&[0xff, 0xfe], 0), Some(-2));
        assert_eq!(Endian::Little.read::<i16>(&[0xff, 0xfe], 0), Some(-257));
        let x = 1.5f64.to_be_bytes();
        assert_eq!(Endian::Big.read::<f64>(&x, 0), Some(1.5));
        assert_ne!(Endian::Little.read::<f64>(&x, 0), Some(1.5));
        // A NaN keeps its payload bits.
        let nan = f32::from_bits(0x7fc0_0123).to_le_bytes();
        let back = Endian::Little.read::<f32>(&nan, 0).expect("fits");
        assert_eq!(back.to_bits(), 0x7fc0_0123);
    }

    #[test]
    fn a_number_past_the_end_is_none_not_zero() {
        let b = [0u8; 7];
        assert_eq!(Endian::Little.read::<u64>(&b, 0), None);
        assert_eq!(Endian::Little.read::<u32>(&b, 3), Some(0));
        assert_eq!(Endian::Little.read::<u32>(&b, 4), None);
        assert_eq!(Endian::Little.read::<u8>(&b, usize::MAX), None);
    }

    #[test]
    fn a_truncated_read_names_the_file_offset_and_the_region() {
        let path = Path::new("t.bin");
        let bytes = [1u8, 0, 0, 0, 9];
        let mut r = Reader::whole(path, &bytes, Endian::Little);
        assert_eq!(r.number::<u32>("a count").expect("fits"), 1);
        let e = r.number::<u32>("the size").unwrap_err().to_string();
        assert_eq!(
            e,
            "t.bin (byte 4): expected the size (4 bytes), but the file ends at byte 5"
        );
        assert_eq!(r.pos(), 4, "a failed read takes nothing");
        // A window of bytes 100..103 of a 200-byte file ends before the file: its name.
        let mut w = Reader::window(path, &bytes[..3], 100, 200, "frame", Endian::Big);
        let e = w.take(4, "the list").unwrap_err().to_string();
        assert_eq!(
            e,
            "t.bin (byte 100): expected the list (4 bytes), but the frame ends at byte 103"
        );
        assert!(w.take(usize::MAX, "all").is_err(), "no overflow");
        assert_eq!(w.number_at::<u16>(1, "a field").expect("fits"), 0x0000);
        let e = w.number_at::<u16>(2, "a field").unwrap_err().to_string();
        assert_eq!(
            e,
            "t.bin (byte 102): expected a field (2 bytes), but the frame ends at byte 103"
        );
        assert_eq!(w.err(2, "bad").to_string(), "t.bin (byte 102): bad");
    }
}
