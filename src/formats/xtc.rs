//! GROMACS XTC trajectories: compressed positions in nm, converted to Å, one frame at a time
//! (docs/design.md §10).
//!
//! **Why pgt decodes XTC itself.** The pure-Rust crate for XTC, `molly`, is fast and well kept,
//! but it trusts its input: a corrupt frame makes it panic (`assert_eq!` on the header's two atom
//! counts, `expect("pop beyond buffer bounds")` on a short bit stream, index panics when the
//! small-integer index leaves its table, integer overflow of `max − min`) and it allocates what a
//! header announces before checking it against the file. pgt must refuse a corrupt frame with a
//! message naming the file and the frame. `xdrfile` wraps GROMACS's C library (LGPL, a C build).
//! So this module is a bounds-checked port of the decompression of GROMACS's `libxdrfile`
//! (`xdrfile_decompress_coord_float`); `molly` and MDAnalysis serve as independent oracles in the
//! tests.
//!
//! **Layout** (XDR: big-endian, 4-byte units). Per frame: `i32` magic (1995, or 2023 for files
//! whose compressed block may exceed 2³¹ bytes), `i32` atom count N, `i32` step, `f32` time (ps),
//! `f32[9]` box (nm), N again; then for N ≤ 9 the 3N `f32` positions; else `f32` precision
//! (positions are integers in units of 1/precision nm), `i32[3]` minimum and `i32[3]` maximum
//! integer coordinate, `i32` initial small-integer index, the byte count of the compressed block
//! (`u32`, or `u64` for magic 2023) and the block, padded to 4 bytes.
//!
//! **The compressed block.** Atoms are read in order: one "large" integer triple (each component
//! in [0, max − min], packed into one mixed-radix number of ⌈log₂ Π sizes⌉ bits, or, where a size
//! exceeds 2²⁴, as separate fields of ⌈log₂ size⌉ bits), then a flag bit; when set, a 5-bit run
//! length r (r mod 3 − 1 is the change of the small index, r − r mod 3 three times the number of
//! "small" atoms that follow; the run carries over to the next atom when the flag is clear). Small
//! atoms are triples of offsets from the previous atom, packed with the radix
//! `MAGICINTS[smallidx]`; the first small atom of a run is stored before the large one (water
//! O–H swap). Everything the stream says is checked: the small index stays in the table, runs
//! do not write past N atoms, the bit stream does not end early.
//!
//! **Frames.** XTC has no index: one scan at open reads each frame's header and byte count to
//! find the offsets (a few dozen bytes per frame). A header that is not an XTC header, or whose
//! atom count differs from the first frame's, is an error at open naming the frame and the byte;
//! a last frame cut short counts, and reading it is the error. The time step is the time of frame
//! 1 minus that of frame 0.

use super::file::binary::Number;
use super::file::{ByteSource, Endian, Reader};
use super::frame_source::Trajectory;
use super::gro::ANGSTROM_PER_NM;
use super::Format;
use crate::error::{PgtError, Result};
use glam::DVec3;
use std::path::Path;

/// XTC in the table of formats ([`super::FORMATS`]): a trajectory.
pub const FORMAT: Format = Format {
    name: "xtc",
    extensions: &["xtc"],
    description: "GROMACS XTC (compressed, nm, converted to Å)",
    trajectory: Some(open),
    ..Format::NOTHING
};

/// The magic number of classic XTC frames.
const MAGIC_1995: i32 = 1995;
/// The magic number of frames with a 64-bit byte count.
const MAGIC_2023: i32 = 2023;
/// Bytes of a frame header: magic, N, step, time, box, N.
const HEADER_BYTES: u64 = 56;
/// Bytes after the header before the compressed block's byte count: precision, min, max,
/// small index.
const PRELUDE_BYTES: u64 = 32;
/// Frames of at most this many atoms store their positions uncompressed.
const MAX_UNCOMPRESSED: usize = 9;

/// The radices of small-integer triples (libxdrfile's `magicints`): index i packs three numbers
/// below `MAGICINTS[i]` into i bits.
const MAGICINTS: [u32; 73] = [
    0, 0, 0, 0, 0, 0, 0, 0, 0, 8, 10, 12, 16, 20, 25, 32, 40, 50, 64, 80, 101, 128, 161, 203, 256,
    322, 406, 512, 645, 812, 1024, 1290, 1625, 2048, 2580, 3250, 4096, 5060, 6501, 8192, 10321,
    13003, 16384, 20642, 26007, 32768, 41285, 52015, 65536, 82570, 104031, 131072, 165140, 208063,
    262144, 330280, 416127, 524287, 660561, 832255, 1048576, 1321122, 1664510, 2097152, 2642245,
    3329021, 4194304, 5284491, 6658042, 8388607, 10568983, 13316085, 16777216,
];
/// The smallest valid small-integer index (`MAGICINTS[FIRSTIDX − 1]` is 0).
const FIRSTIDX: usize = 9;

/// The XDR (big-endian) number at byte `at` of a frame's bytes; bytes that end before it are a
/// corrupt frame.
fn xdr<T: Number>(bytes: &[u8], at: usize) -> std::result::Result<T, Corrupt> {
    Endian::Big
        .read(bytes, at)
        .ok_or_else(|| (at as u64, "the frame ends inside its header".to_string()))
}

/// Where one frame is.
#[derive(Debug, Clone, Copy)]
struct FrameAt {
    offset: u64,
    /// Bytes of the whole frame.
    size: u64,
    time: f32,
    magic: i32,
}

/// An open XTC file.
struct Xtc {
    source: ByteSource,
    atoms: usize,
    frames: Vec<FrameAt>,
    warnings: Vec<String>,
}

/// The [`super::OpenTrajectory`] of XTC: one scan of the frame headers.
pub fn open(source: ByteSource) -> Result<Box<dyn Trajectory>> {
    let path = source.path().to_path_buf();
    let len = source.len();
    let mut frames: Vec<FrameAt> = Vec::new();
    let mut atoms = 0usize;
    let mut warnings = Vec::new();
    let mut at = 0u64;
    while at < len {
        let k = frames.len();
        let want = (HEADER_BYTES + PRELUDE_BYTES + 8).min(len - at);
        let head = source.read_at(at, want, &format!("the header of frame {k}"))?;
        if (head.len() as u64) < HEADER_BYTES {
            warnings.push(truncated_warning(&path, k));
            frames.push(FrameAt {
                offset: at,
                size: HEADER_BYTES,
                time: f32::NAN,
                magic: MAGIC_1995,
            });
            break;
        }
        // A frame's header as XDR numbers, errors naming their file offset.
        let header = Reader::window(&path, &head, at, len, "frame header", Endian::Big);
        let magic = header.number_at::<i32>(0, "the magic number")?;
        if magic != MAGIC_1995 && magic != MAGIC_2023 {
            return Err(PgtError::at_byte(
                &path,
                at,
                format!("frame {k}: expected the XTC magic number 1995 or 2023, found {magic} (not an XTC file, or a corrupt frame)"),
            ));
        }
        let n = header.number_at::<i32>(4, "the atom count")?;
        let n2 = header.number_at::<i32>(52, "the atom count")?;
        if n < 1 || n != n2 {
            return Err(PgtError::at_byte(
                &path,
                at + 4,
                format!("frame {k}: the header's atom counts are {n} and {n2}; expected one positive count twice"),
            ));
        }
        let n = n as usize;
        if k == 0 {
            atoms = n;
        } else if n != atoms {
            return Err(PgtError::at_byte(
                &path,
                at + 4,
                format!("frame {k} has {n} atoms, frame 0 has {atoms}: an XTC trajectory keeps its atoms"),
            ));
        }
        let size = if n <= MAX_UNCOMPRESSED {
            HEADER_BYTES + 12 * n as u64
        } else {
            let count_bytes: u64 = if magic == MAGIC_2023 { 8 } else { 4 };
            let count_at = (HEADER_BYTES + PRELUDE_BYTES) as usize;
            if head.len() < count_at + count_bytes as usize {
                HEADER_BYTES + PRELUDE_BYTES + count_bytes
            } else {
                let block = if magic == MAGIC_2023 {
                    header.number_at::<u64>(count_at, "the block's byte count")?
                } else {
                    u64::from(header.number_at::<u32>(count_at, "the block's byte count")?)
                };
                let padded = block.checked_add(3).map(|b| b / 4 * 4).unwrap_or(u64::MAX);
                (HEADER_BYTES + PRELUDE_BYTES + count_bytes).saturating_add(padded)
            }
        };
        frames.push(FrameAt {
            offset: at,
            size,
            time: header.number_at::<f32>(12, "the time")?,
            magic,
        });
        match at.checked_add(size).filter(|&e| e <= len) {
            Some(end) => at = end,
            None => {
                warnings.push(truncated_warning(&path, k));
                break;
            }
        }
    }
    if frames.is_empty() {
        return Err(PgtError::in_file(
            &path,
            "the file is empty: it holds no XTC frame",
        ));
    }
    Ok(Box::new(Xtc {
        source,
        atoms,
        frames,
        warnings,
    }))
}

fn truncated_warning(path: &Path, k: usize) -> String {
    format!(
        "{}: the last frame ({k}) is truncated: the file ends before its end; reading it is an error",
        path.display()
    )
}

impl Trajectory for Xtc {
    fn path(&self) -> &Path {
        self.source.path()
    }
    fn atoms(&self) -> usize {
        self.atoms
    }
    fn frames(&self) -> usize {
        self.frames.len()
    }
    fn time_step_ps(&self) -> Option<f64> {
        match self.frames.as_slice() {
            [a, b, ..] if (b.time - a.time).is_finite() => {
                Some(f64::from(b.time) - f64::from(a.time))
            }
            _ => None,
        }
    }
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }
    fn read_positions(&self, index: usize, out: &mut Vec<DVec3>) -> Result<Option<f64>> {
        let path = self.source.path();
        let f = *self
            .frames
            .get(index)
            .ok_or_else(|| super::frame_source::past_the_end(path, index, self.frames.len()))?;
        if f.offset.saturating_add(f.size) > self.source.len() {
            return Err(PgtError::at_byte(
                path,
                f.offset,
                format!(
                    "frame {index} is truncated: it needs {} bytes from byte {}, but the file ends at byte {}",
                    f.size,
                    f.offset,
                    self.source.len()
                ),
            ));
        }
        let bytes = self
            .source
            .read_at(f.offset, f.size, &format!("frame {index}"))?;
        out.clear();
        decode_frame(&bytes, self.atoms, f.magic, out).map_err(|(at, message)| {
            PgtError::at_byte(path, f.offset + at, format!("frame {index}: {message}"))
        })?;
        Ok(Some(f64::from(f.time)))
    }
}

/// A decoding problem: the byte (from the frame's start) and what is wrong.
type Corrupt = (u64, String);

/// The positions (Å) of one frame's bytes.
fn decode_frame(
    bytes: &[u8],
    atoms: usize,
    magic: i32,
    out: &mut Vec<DVec3>,
) -> std::result::Result<(), Corrupt> {
    let at = HEADER_BYTES as usize;
    let to_angstrom = |v: f32| f64::from(v) * ANGSTROM_PER_NM;
    if atoms <= MAX_UNCOMPRESSED {
        for k in 0..atoms {
            let mut p = [0f32; 3];
            for (c, v) in p.iter_mut().enumerate() {
                *v = xdr(bytes, at + 12 * k + 4 * c)?;
            }
            if !p.iter().all(|v| v.is_finite()) {
                return Err((
                    (at + 12 * k) as u64,
                    format!("the position of atom {} is not finite", k + 1),
                ));
            }
            out.push(DVec3::new(
                to_angstrom(p[0]),
                to_angstrom(p[1]),
                to_angstrom(p[2]),
            ));
        }
        return Ok(());
    }
    let precision: f32 = xdr(bytes, at)?;
    if !(precision.is_finite() && precision > 0.0) {
        return Err((
            at as u64,
            format!("the precision {precision} is not a finite number > 0"),
        ));
    }
    let (mut minint, mut maxint) = ([0i32; 3], [0i32; 3]);
    for c in 0..3 {
        minint[c] = xdr(bytes, at + 4 + 4 * c)?;
        maxint[c] = xdr(bytes, at + 16 + 4 * c)?;
    }
    let smallidx: i32 = xdr(bytes, at + 28)?;
    let count_at = at + PRELUDE_BYTES as usize;
    let (count, block_at) = if magic == MAGIC_2023 {
        (xdr::<u64>(bytes, count_at)?, count_at + 8)
    } else {
        (u64::from(xdr::<u32>(bytes, count_at)?), count_at + 4)
    };
    // The stream ends at the block's byte count: the padding to 4 bytes is no part of it.
    let block_end = usize::try_from(count)
        .ok()
        .and_then(|c| block_at.checked_add(c))
        .unwrap_or(usize::MAX)
        .min(bytes.len());
    let block = bytes.get(block_at..block_end).unwrap_or_default();
    let ints = decompress(block, atoms, minint, maxint, smallidx)
        .map_err(|(k, m)| (block_at as u64 + k, m))?;
    let inv = 1.0f32 / precision;
    out.extend(ints.iter().map(|c| {
        DVec3::new(
            to_angstrom(c[0] as f32 * inv),
            to_angstrom(c[1] as f32 * inv),
            to_angstrom(c[2] as f32 * inv),
        )
    }));
    Ok(())
}

/// Bits read most significant first from a byte stream (libxdrfile's `decodebits` state).
struct Bits<'a> {
    data: &'a [u8],
    next: usize,
    lastbits: u32,
    lastbyte: u32,
}

impl Bits<'_> {
    fn byte(&mut self) -> std::result::Result<u32, Corrupt> {
        let b = self.data.get(self.next).copied().ok_or_else(|| {
            (
                self.next as u64,
                "the compressed block ends before every atom is decoded (a corrupt frame)"
                    .to_string(),
            )
        })?;
        self.next += 1;
        Ok(u32::from(b))
    }

    /// The next `n` bits (n ≤ 32) as an unsigned number.
    fn bits(&mut self, mut n: u32) -> std::result::Result<u32, Corrupt> {
        let mask = if n >= 32 { u32::MAX } else { (1u32 << n) - 1 };
        let mut num = 0u32;
        while n >= 8 {
            self.lastbyte = (self.lastbyte << 8) | self.byte()?;
            num |= (self.lastbyte >> self.lastbits) << (n - 8);
            n -= 8;
        }
        if n > 0 {
            if self.lastbits < n {
                self.lastbits += 8;
                self.lastbyte = (self.lastbyte << 8) | self.byte()?;
            }
            self.lastbits -= n;
            num |= (self.lastbyte >> self.lastbits) & ((1u32 << n) - 1);
        }
        Ok(num & mask)
    }

    /// Three integers packed in `nbits` bits with the radices `sizes` (libxdrfile's
    /// `decodeints`): the bytes form one little-endian number, divided by `sizes[2]` and then
    /// `sizes[1]`; the remainders are the last two integers and the quotient the first.
    fn packed(&mut self, nbits: u32, sizes: [u64; 3]) -> std::result::Result<[i32; 3], Corrupt> {
        let mut bytes = [0u64; 32];
        let mut count = 0usize;
        let mut n = nbits;
        while n > 8 {
            *bytes
                .get_mut(count)
                .ok_or((self.next as u64, "too many bits".to_string()))? = u64::from(self.bits(8)?);
            count += 1;
            n -= 8;
        }
        if n > 0 {
            *bytes
                .get_mut(count)
                .ok_or((self.next as u64, "too many bits".to_string()))? = u64::from(self.bits(n)?);
            count += 1;
        }
        let mut nums = [0i32; 3];
        for i in [2usize, 1] {
            let mut num = 0u64;
            for j in (0..count).rev() {
                num = (num << 8) | bytes[j];
                let p = num / sizes[i];
                bytes[j] = p;
                num -= p * sizes[i];
            }
            nums[i] = num as i32;
        }
        nums[0] = (bytes[0] | (bytes[1] << 8) | (bytes[2] << 16) | (bytes[3] << 24)) as u32 as i32;
        Ok(nums)
    }
}

/// The number of bits of `size` (libxdrfile's `sizeofint`, at most 32).
fn bits_of(size: u64) -> u32 {
    (64 - size.leading_zeros()).min(32)
}

/// The number of values each integer coordinate takes, max − min + 1, refused where the range
/// is negative or exceeds what 32 bits hold.
fn coordinate_sizes(minint: [i32; 3], maxint: [i32; 3]) -> std::result::Result<[u64; 3], Corrupt> {
    let mut sizes = [0u64; 3];
    for c in 0..3 {
        let size = i64::from(maxint[c]) - i64::from(minint[c]) + 1;
        if !(1..=i64::from(u32::MAX)).contains(&size) {
            return Err((
                0,
                "the coordinate range (maximum − minimum) is negative or too large".to_string(),
            ));
        }
        sizes[c] = size as u64;
    }
    Ok(sizes)
}

/// The integer positions of `atoms` atoms from a compressed block (the module doc's algorithm,
/// libxdrfile's `xdrfile_decompress_coord_float` after the prelude). Errors carry the byte
/// offset in the block.
fn decompress(
    block: &[u8],
    atoms: usize,
    minint: [i32; 3],
    maxint: [i32; 3],
    smallidx: i32,
) -> std::result::Result<Vec<[i32; 3]>, Corrupt> {
    let corrupt = |at: usize, m: &str| -> Corrupt { (at as u64, m.to_string()) };
    let sizes = coordinate_sizes(minint, maxint)?;
    let large = sizes.iter().any(|&s| s > 0xff_ffff);
    let field_bits = sizes.map(bits_of);
    let product_bits = 128
        - u128::from(sizes[0] * sizes[1])
            .saturating_mul(u128::from(sizes[2]))
            .leading_zeros();
    let mut smallidx = usize::try_from(smallidx)
        .ok()
        .filter(|&i| i < MAGICINTS.len())
        .ok_or_else(|| {
            corrupt(
                0,
                &format!("the small-integer index {smallidx} is outside 0..=72"),
            )
        })?;
    let magic = |i: usize| u64::from(MAGICINTS[i]);
    let mut smaller = magic(FIRSTIDX.max(smallidx.saturating_sub(1))) / 2;
    let mut smallnum = magic(smallidx) / 2;
    let mut bits = Bits {
        data: block,
        next: 0,
        lastbits: 0,
        lastbyte: 0,
    };
    // Every atom takes at least one bit of the block, so the block bounds the allocation and a
    // header that lies about the atom count ends in an error, not in a huge reservation.
    let mut out: Vec<[i32; 3]> = Vec::with_capacity(atoms.min(block.len().saturating_mul(8)));
    let mut run = 0i32;
    let add = |a: [i32; 3], b: [i32; 3]| std::array::from_fn(|c| a[c].wrapping_add(b[c]));
    while out.len() < atoms {
        let big = if large {
            [
                bits.bits(field_bits[0])?,
                bits.bits(field_bits[1])?,
                bits.bits(field_bits[2])?,
            ]
            .map(|v| v as i32)
        } else {
            bits.packed(product_bits, sizes)?
        };
        let this = add(big, minint);
        let mut prev = this;
        let mut is_smaller = 0i32;
        if bits.bits(1)? == 1 {
            run = bits.bits(5)? as i32;
            is_smaller = run % 3;
            run -= is_smaller;
            is_smaller -= 1;
        }
        if run > 0 {
            if out.len() + 1 + run as usize / 3 > atoms {
                return Err(corrupt(
                    bits.next,
                    "a run of small atoms goes past the frame's atom count",
                ));
            }
            let offset = smallnum as i32;
            let size = magic(smallidx);
            if size == 0 {
                // libxdrfile divides by this radix (or reads an unset byte at index 0): no
                // decoder can unpack small atoms below the first index.
                return Err(corrupt(
                    bits.next,
                    &format!(
                        "a run of small atoms at the small-integer index {smallidx}, below the first usable index {FIRSTIDX}"
                    ),
                ));
            }
            for k in (0..run).step_by(3) {
                let small = bits.packed(smallidx as u32, [size; 3])?;
                let mut current: [i32; 3] =
                    std::array::from_fn(|c| small[c].wrapping_add(prev[c]).wrapping_sub(offset));
                if k == 0 {
                    // The first small atom was stored before the large one (water O–H swap).
                    std::mem::swap(&mut current, &mut prev);
                    out.push(prev);
                } else {
                    prev = current;
                }
                out.push(current);
            }
        } else {
            out.push(this);
        }
        let new_idx = smallidx as i64 + i64::from(is_smaller);
        smallidx = usize::try_from(new_idx)
            .ok()
            .filter(|&i| i < MAGICINTS.len())
            .ok_or_else(|| corrupt(bits.next, "the small-integer index leaves 0..=72"))?;
        if is_smaller < 0 {
            smallnum = smaller;
            smaller = if smallidx > FIRSTIDX {
                magic(smallidx - 1) / 2
            } else {
                0
            };
        } else if is_smaller > 0 {
            smaller = smallnum;
            smallnum = magic(smallidx) / 2;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bit_lengths() {
        assert_eq!(bits_of(1), 1);
        assert_eq!(bits_of(255), 8);
        assert_eq!(bits_of(256), 9);
        assert_eq!(bits_of(u64::from(u32::MAX)), 32);
    }

    #[test]
    fn bits_come_most_significant_first() {
        let mut b = Bits {
            data: &[0b1011_0011, 0b0101_0000],
            next: 0,
            lastbits: 0,
            lastbyte: 0,
        };
        assert_eq!(b.bits(1).expect("ok"), 1);
        assert_eq!(b.bits(3).expect("ok"), 0b011);
        assert_eq!(b.bits(8).expect("ok"), 0b0011_0101);
        assert!(b.bits(8).is_err());
    }

    #[test]
    fn uncompressed_small_frames() {
        let mut f = Vec::new();
        for v in [1995i32, 2, 0] {
            f.extend_from_slice(&v.to_be_bytes());
        }
        f.extend_from_slice(&5.0f32.to_be_bytes());
        f.extend_from_slice(&[0u8; 36]);
        f.extend_from_slice(&2i32.to_be_bytes());
        for v in [0.1f32, 0.2, 0.3, 1.0, 2.0, 3.0] {
            f.extend_from_slice(&v.to_be_bytes());
        }
        let mut two = f.clone();
        two.extend_from_slice(&f);
        two[12..16].copy_from_slice(&5.0f32.to_be_bytes());
        let len = f.len();
        two[len + 12..len + 16].copy_from_slice(&7.5f32.to_be_bytes());
        let t = open(ByteSource::from_bytes(Path::new("s.xtc"), two)).expect("ok");
        assert_eq!((t.atoms(), t.frames()), (2, 2));
        assert_eq!(t.time_step_ps(), Some(2.5));
        let mut p = Vec::new();
        assert_eq!(t.read_positions(1, &mut p).expect("ok"), Some(7.5));
        assert!(
            (p[1] - DVec3::new(10.0, 20.0, 30.0)).length() < 1e-5,
            "{p:?}"
        );
    }

    #[test]
    fn garbage_is_refused_without_panic() {
        let e = open(ByteSource::from_bytes(Path::new("g.xtc"), vec![7u8; 100]))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("frame 0") && e.contains("magic"), "{e}");
        // A valid prelude with a stream of random bits must end in an error or positions, never
        // a panic.
        let mut s = 7u64;
        for _ in 0..200 {
            let block: Vec<u8> = (0..64)
                .map(|_| {
                    s = s.wrapping_mul(6364136223846793005).wrapping_add(1);
                    (s >> 56) as u8
                })
                .collect();
            let _ = decompress(&block, 40, [0, 0, 0], [1000, 1000, 1000], 12);
            let _ = decompress(&block, 40, [-5, 0, 0], [i32::MAX, 10, 10], 72);
        }
    }
}
