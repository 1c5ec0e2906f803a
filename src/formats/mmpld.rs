//! MegaMol particle lists (MMPLD), versions 1.0–1.3, little-endian.
//!
//! Layout (from UniStuttgart-VISUS/mmpld and MegaMol's `MMPLDDataSource.cpp`; docs/design.md
//! §6, "MMPLD"): a 60-byte header (`"MMPLD\0"`, `u16` version = 100·major+minor,
//! `u32` frames, two `f32[6]` boxes), a seek table of `frames + 1` `u64` offsets (the last is the
//! end of the data; a table of only `frames` entries, as the mmpld library writes, is accepted
//! too), then per frame: `f32` timestamp (version ≥ 1.2), `i32` list count, and per list:
//! `u8` vertex type, `u8` colour type, `f32` global radius (vertex types 1, 3, 4), `u8[4]` global
//! RGBA (colour type 0), `f32[2]` intensity range (colour types 3, 7), `u64` count, `f32[6]` list
//! box (version 1.3), the interleaved particles, and cluster info (version 1.1).
//!
//! Vertex types: 0 none (the list holds no particles), 1 `f32` xyz, 2 `f32` xyzr, 3 `i16` xyz,
//! 4 `f64` xyz. Colour types: 0 none (global RGBA), 1 `u8` RGB, 2 `u8` RGBA, 3 `f32` intensity,
//! 4 `f32` RGB, 5 `f32` RGBA, 6 `u16` RGBA, 7 `f64` intensity.
//!
//! **Colours.** MegaMol shows stored colours as they are, so pgt treats them as sRGB display
//! values in [0, 1] (integers divided by 255 or 65535) and decodes them to linear RGB; negative
//! values become 0. Alpha is ignored (the scene's `opacity` applies). Intensities go through the
//! list's [min, max] range to t ∈ [0, 1] (clamped; t = 0 if max ≤ min) and then a **grey ramp**:
//! sRGB grey t, decoded to linear.
//!
//! **The version-1.3 writer bug.** Writers before MegaMol commit fc4e784 wrote version 103 files
//! without the frame timestamp. For version 103, pgt parses the frame with the timestamp; if that
//! does not end exactly at the next seek-table offset, it parses it again without, and keeps that
//! reading (with a warning) if it ends there.
//!
//! Every count is checked against the bytes that remain before anything is allocated.

use super::file::{ByteSource, Endian, Reader};
use super::{Format, IncludeSpec, LoadedParticles, ParticleRecord};
use crate::color::srgb_to_linear;
use crate::error::{Location, PgtError, Result};
use glam::DVec3;
use std::path::Path;

/// MMPLD in the table of formats ([`super::FORMATS`]).
pub const FORMAT: Format = Format {
    name: "mmpld",
    extensions: &["mmpld"],
    description: "MegaMol MMPLD 1.0–1.3",
    particles: "particles in the frame",
    read: Some(read),
    details: Some(details),
    frames: Some(open_frames),
    ..Format::NOTHING
};

const MAGIC: &[u8; 6] = b"MMPLD\0";
const HEADER_BYTES: u64 = 60;

/// sRGB display value (any range) to linear, negatives clamped to 0.
fn display_to_linear(c: DVec3) -> DVec3 {
    DVec3::new(
        srgb_to_linear(c.x.max(0.0)),
        srgb_to_linear(c.y.max(0.0)),
        srgb_to_linear(c.z.max(0.0)),
    )
}

/// The grey-ramp colour map for intensities.
fn intensity_color(i: f64, min: f64, max: f64) -> DVec3 {
    let t = if max > min {
        ((i - min) / (max - min)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let t = if t.is_finite() { t } else { 0.0 };
    DVec3::splat(srgb_to_linear(t))
}

/// Header facts other tools (`pgt info`) may want.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Header {
    /// 100·major + minor.
    pub version: u16,
    /// Number of frames.
    pub frames: u32,
}

/// Reads the header and seek table: version, frame count and the frame offsets (frames + 1,
/// the last being the end of the data).
fn header_and_table(path: &Path, bytes: &[u8]) -> Result<(Header, Vec<u64>)> {
    header_and_table_of(path, bytes, bytes.len() as u64)
}

/// [`header_and_table`] from the file's first bytes `bytes` (at least the header and the seek
/// table, where the file has them) and the file's length.
fn header_and_table_of(path: &Path, bytes: &[u8], file_len: u64) -> Result<(Header, Vec<u64>)> {
    let mut c = Reader::whole(path, bytes, Endian::Little);
    let magic = c.array::<6>("the magic \"MMPLD\\0\"")?;
    if &magic != MAGIC {
        return Err(c.err(
            0,
            format!("not an MMPLD file: expected the magic \"MMPLD\\0\", found {magic:?}"),
        ));
    }
    let version = c.number::<u16>("the version")?;
    if !(100..=103).contains(&version) {
        return Err(c.err(
            6,
            format!("unsupported MMPLD version {version} (expected 100–103, i.e. 1.0–1.3)"),
        ));
    }
    let frames = c.number::<u32>("the frame count")?;
    c.take(48, "the bounding and clip boxes")?;
    let room = file_len.saturating_sub(HEADER_BYTES) / 8;
    if u64::from(frames) >= room {
        return Err(c.err(
            10,
            format!(
                "the header announces {frames} frames, but the file ({} bytes) has room for a seek table of at most {} entries",
                file_len,
                room
            ),
        ));
    }
    let n = frames as usize + 1;
    let mut table = Vec::with_capacity(n);
    for _ in 0..n {
        table.push(c.number::<u64>("a seek-table offset")?);
    }
    // A table of only `frames` entries (the mmpld library): then the first offset points
    // at the (frames+1)-th entry's bytes, and the data end is the file end.
    let full = HEADER_BYTES + 8 * n as u64;
    if table.first() == Some(&(full - 8)) {
        table.pop();
        table.push(file_len);
    }
    for (k, w) in table.windows(2).enumerate() {
        if let [a, b] = *w {
            if a > b || b > file_len || a < HEADER_BYTES {
                return Err(c.err(
                    60 + 8 * k,
                    format!(
                        "the seek table gives frame {k} the bytes {a}..{b}, outside the file ({} bytes) or backwards",
                        file_len
                    ),
                ));
            }
        }
    }
    Ok((Header { version, frames }, table))
}

/// Reads the header of an MMPLD file.
pub fn header(path: &Path, bytes: &[u8]) -> Result<Header> {
    header_and_table(path, bytes).map(|(h, _)| h)
}

/// The [`super::Details`] of MMPLD: `version` ("1.2") and `frames`.
fn details(path: &Path, bytes: &[u8]) -> Result<serde_json::Map<String, serde_json::Value>> {
    use serde_json::json;
    let h = header(path, bytes)?;
    let mut d = serde_json::Map::new();
    d.insert(
        "version".into(),
        json!(format!("{}.{}", h.version / 100, h.version % 100)),
    );
    d.insert("frames".into(), json!(h.frames));
    Ok(d)
}

/// The [`super::Reader`] of MMPLD: frame `spec.frame` (0-based, default 0). A file without
/// frames, or a selected frame without particles, is an error (docs/design.md §6 "Bad input").
pub fn read(spec: &IncludeSpec, bytes: &[u8]) -> Result<LoadedParticles> {
    let path = spec.path.as_path();
    let (h, table) = header_and_table(path, bytes)?;
    let mut warnings = Vec::new();
    let frame = spec.frame.unwrap_or(0);
    if h.frames == 0 {
        return Err(PgtError::at_byte(
            path,
            10,
            "the file has no frames, so it holds no particles",
        ));
    }
    if frame >= h.frames as usize {
        return Err(PgtError::at_byte(
            path,
            10,
            format!(
                "frame {frame} requested, but the file has {} frame(s) (0-based)",
                h.frames
            ),
        ));
    }
    let (start, end) = match (table.get(frame), table.get(frame + 1)) {
        (Some(&a), Some(&b)) => (a as usize, b as usize),
        _ => return Err(PgtError::at_byte(path, 60, "the seek table is too short")),
    };
    let window = bytes.get(start..end).unwrap_or_default();
    let records = frame_records(
        path,
        window,
        start,
        bytes.len(),
        h.version,
        frame,
        &mut warnings,
    )?;
    if records.is_empty() {
        let which = if spec.frame.is_some() {
            format!("`frame = {frame}`")
        } else {
            format!("frame {frame}")
        };
        return Err(PgtError::at_byte(
            path,
            start as u64,
            format!(
                "{which} holds no particles (the file has {} frame(s))",
                h.frames
            ),
        ));
    }
    Ok(LoadedParticles {
        records,
        warnings,
        sh: None,
    })
}

/// The particles of frame `frame`, whose bytes `window` start at file offset `base`. Version 1.3
/// frames are read with their timestamp and, where that does not end at the frame's end,
/// without (the writer bug of the module doc, with a warning).
fn frame_records(
    path: &Path,
    window: &[u8],
    base: usize,
    file_len: usize,
    version: u16,
    frame: usize,
    warnings: &mut Vec<String>,
) -> Result<Vec<ParticleRecord>> {
    let parse = |timestamp: bool| {
        let mut c = Reader::window(
            path,
            window,
            base as u64,
            file_len as u64,
            "frame",
            Endian::Little,
        );
        parse_frame_lists(&mut c, version, timestamp)
    };
    match parse(version >= 102) {
        Ok(r) => Ok(r),
        Err(e) if version == 103 => match parse(false) {
            Ok(r) => {
                warnings.push(format!(
                    "{}: frame {frame} of this version-1.3 file has no timestamp (a known MegaMol writer bug); read it without",
                    path.display()
                ));
                Ok(r)
            }
            Err(_) => Err(e),
        },
        Err(e) => Err(e),
    }
}

/// The [`super::OpenFrames`] of MMPLD: the header and seek table are read at open, each frame's
/// bytes when it is asked for.
pub fn open_frames(
    spec: &IncludeSpec,
    source: ByteSource,
) -> Result<Box<dyn super::frame_source::FrameSource>> {
    let path = source.path().to_path_buf();
    let head = source.read_at(0, source.len().min(HEADER_BYTES), "the header")?;
    // A header cut short is refused by `header_and_table_of`, which reads it again.
    let frames = Endian::Little.read::<u32>(&head, 8).unwrap_or(0);
    let table_len = 8 * (u64::from(frames) + 1);
    let prefix = source.read_at(
        0,
        source.len().min(HEADER_BYTES + table_len),
        "the seek table",
    )?;
    let (header, table) = header_and_table_of(&path, &prefix, source.len())?;
    if header.frames == 0 {
        return Err(PgtError::at_byte(
            &path,
            10,
            "the file has no frames, so it holds no particles",
        ));
    }
    Ok(Box::new(MmpldFrames {
        spec: spec.clone(),
        source,
        header,
        table,
    }))
}

/// The frames of an MMPLD file ([`open_frames`]).
struct MmpldFrames {
    spec: IncludeSpec,
    source: ByteSource,
    header: Header,
    table: Vec<u64>,
}

impl super::frame_source::FrameSource for MmpldFrames {
    fn path(&self) -> &Path {
        self.source.path()
    }
    fn info(&self) -> super::frame_source::FrameInfo {
        super::frame_source::FrameInfo {
            count: self.header.frames as usize,
            atoms_per_frame: None,
            time_step_ps: None,
        }
    }
    fn read_frame(&self, index: usize) -> Result<super::frame_source::Frame> {
        let path = self.source.path();
        let count = self.header.frames as usize;
        let (Some(&start), Some(&end)) = (self.table.get(index), self.table.get(index + 1)) else {
            return Err(super::frame_source::past_the_end(path, index, count));
        };
        if index >= count {
            return Err(super::frame_source::past_the_end(path, index, count));
        }
        let window = self
            .source
            .read_at(start, end - start, &format!("frame {index}"))?;
        let mut warnings = Vec::new();
        let records = frame_records(
            path,
            &window,
            start as usize,
            self.source.len() as usize,
            self.header.version,
            index,
            &mut warnings,
        )?;
        let particles = super::frame_source::finish_frame(
            &self.spec,
            path,
            index,
            LoadedParticles {
                records,
                warnings,
                sh: None,
            },
        )?;
        Ok(super::frame_source::Frame {
            index,
            time_ps: None,
            particles,
        })
    }
}

/// The header of one particle list: how its particles are laid out and coloured.
struct ListHeader {
    vertex_type: u8,
    colour_type: u8,
    /// Bytes of a particle's position (and radius), by vertex type.
    vertex_bytes: usize,
    /// Bytes of a particle's colour, by colour type.
    colour_bytes: usize,
    /// The list's radius (vertex types 1, 3, 4); 1 otherwise.
    global_radius: f64,
    /// The list's colour, linear (colour type 0); white otherwise.
    global_color: DVec3,
    /// The intensity range of colour types 3 and 7.
    intensity_range: (f64, f64),
    /// The announced number of particles, and its byte offset (for errors).
    count: u64,
    count_at: usize,
}

impl ListHeader {
    /// Bytes per particle (0 for vertex type 0, whose list holds none).
    fn stride(&self) -> usize {
        if self.vertex_type == 0 {
            0
        } else {
            self.vertex_bytes + self.colour_bytes
        }
    }
}

/// Reads a list header up to and including the list box of version 1.3.
fn list_header(c: &mut Reader<'_>, version: u16) -> Result<ListHeader> {
    let vt_at = c.pos();
    let vertex_type = c.number::<u8>("a vertex type")?;
    let colour_type = c.number::<u8>("a colour type")?;
    let vertex_bytes = match vertex_type {
        0 => 0usize,
        1 => 12,
        2 => 16,
        3 => 6,
        4 => 24,
        vt => return Err(c.err(vt_at, format!("unknown vertex type {vt} (expected 0–4)"))),
    };
    let colour_bytes = match colour_type {
        0 => 0usize,
        1 => 3,
        2 | 3 => 4,
        4 => 12,
        5 => 16,
        6 | 7 => 8,
        ct => {
            return Err(c.err(
                vt_at + 1,
                format!("unknown colour type {ct} (expected 0–7)"),
            ))
        }
    };
    let global_radius = if matches!(vertex_type, 1 | 3 | 4) {
        f64::from(c.number::<f32>("the global radius")?)
    } else {
        1.0
    };
    let global_color = if colour_type == 0 {
        let rgba = c.array::<4>("the global RGBA colour")?;
        display_to_linear(
            DVec3::new(f64::from(rgba[0]), f64::from(rgba[1]), f64::from(rgba[2])) / 255.0,
        )
    } else {
        DVec3::ONE
    };
    let intensity_range = if matches!(colour_type, 3 | 7) {
        (
            f64::from(c.number::<f32>("the intensity minimum")?),
            f64::from(c.number::<f32>("the intensity maximum")?),
        )
    } else {
        (0.0, 1.0)
    };
    let count_at = c.pos();
    let count = c.number::<u64>("the particle count")?;
    if version == 103 {
        c.take(24, "the list bounding box")?;
    }
    Ok(ListHeader {
        vertex_type,
        colour_type,
        vertex_bytes,
        colour_bytes,
        global_radius,
        global_color,
        intensity_range,
        count,
        count_at,
    })
}

/// Centre and radius of the particle at offset `p` of the list's data `d` (vertex types 1–4).
fn particle_position(d: &Reader<'_>, p: usize, h: &ListHeader) -> Result<(DVec3, f64)> {
    let f32_at =
        |o: usize| Ok::<_, PgtError>(f64::from(d.number_at::<f32>(p + o, "a coordinate")?));
    let i16_at =
        |o: usize| Ok::<_, PgtError>(f64::from(d.number_at::<i16>(p + o, "a coordinate")?));
    let f64_at = |o: usize| d.number_at::<f64>(p + o, "a coordinate");
    Ok(match h.vertex_type {
        1 => (
            DVec3::new(f32_at(0)?, f32_at(4)?, f32_at(8)?),
            h.global_radius,
        ),
        2 => (DVec3::new(f32_at(0)?, f32_at(4)?, f32_at(8)?), f32_at(12)?),
        3 => (
            DVec3::new(i16_at(0)?, i16_at(2)?, i16_at(4)?),
            h.global_radius,
        ),
        _ => (
            DVec3::new(f64_at(0)?, f64_at(8)?, f64_at(16)?),
            h.global_radius,
        ),
    })
}

/// Linear colour of the particle at offset `p` of the list's data `d` (the colour follows the
/// position).
fn particle_color(d: &Reader<'_>, p: usize, h: &ListHeader) -> Result<DVec3> {
    let o = p + h.vertex_bytes;
    let (imin, imax) = h.intensity_range;
    let u8_at = |k: usize| Ok::<_, PgtError>(f64::from(d.number_at::<u8>(o + k, "a colour")?));
    let u16_at = |k: usize| Ok::<_, PgtError>(f64::from(d.number_at::<u16>(o + k, "a colour")?));
    let f32_at = |k: usize| Ok::<_, PgtError>(f64::from(d.number_at::<f32>(o + k, "a colour")?));
    Ok(match h.colour_type {
        0 => h.global_color,
        1 | 2 => display_to_linear(DVec3::new(u8_at(0)?, u8_at(1)?, u8_at(2)?) / 255.0),
        3 => intensity_color(f32_at(0)?, imin, imax),
        4 | 5 => display_to_linear(DVec3::new(f32_at(0)?, f32_at(4)?, f32_at(8)?)),
        6 => display_to_linear(DVec3::new(u16_at(0)?, u16_at(2)?, u16_at(4)?) / 65535.0),
        _ => intensity_color(d.number_at::<f64>(o, "a colour")?, imin, imax),
    })
}

/// Reads the particles of a list whose header is `h`, after checking that the announced count
/// fits in the bytes left in the frame (before anything is allocated).
fn read_list_particles(
    c: &mut Reader<'_>,
    h: &ListHeader,
    out: &mut Vec<ParticleRecord>,
) -> Result<()> {
    let stride = h.stride();
    let left = c.left();
    let Some(data_bytes) = (stride as u64)
        .checked_mul(h.count)
        .filter(|&n| n <= left as u64)
    else {
        return Err(c.err(
            h.count_at,
            format!(
                "the list announces {} particles of {stride} bytes, more than the {left} bytes left in the frame",
                h.count
            ),
        ));
    };
    let data_at = c.pos();
    c.take(data_bytes as usize, "the particle data")?;
    if h.vertex_type == 0 {
        return Ok(());
    }
    out.reserve(h.count as usize);
    for k in 0..h.count as usize {
        let at = data_at + k * stride;
        let (center, radius) = particle_position(c, at, h)?;
        let color = particle_color(c, at, h)?;
        if !center.is_finite() || !color.is_finite() {
            return Err(c.err(
                at,
                format!("particle {k} of the list has a non-finite position or colour"),
            ));
        }
        out.push(ParticleRecord {
            ellipsoid: None,
            center,
            radius,
            color: Some(color),
            opacity: None,
            sigma: None,
            location: Location::Byte(c.file_offset(at)),
        });
    }
    Ok(())
}

/// Skips the cluster info that follows each list in version 1.1.
fn skip_cluster_info(c: &mut Reader<'_>) -> Result<()> {
    c.number::<u32>("the cluster count")?;
    let size_at = c.pos();
    let size = c.number::<u64>("the cluster data size")?;
    let size = usize::try_from(size)
        .ok()
        .filter(|&s| s <= c.left())
        .ok_or_else(|| {
            c.err(
                size_at,
                format!("cluster data of {size} bytes does not fit in the frame"),
            )
        })?;
    c.take(size, "the cluster data")?;
    Ok(())
}

/// Parses the frame under the cursor (from its position to the end of its window): its lists,
/// which must end exactly there.
fn parse_frame_lists(
    c: &mut Reader<'_>,
    version: u16,
    timestamp: bool,
) -> Result<Vec<ParticleRecord>> {
    let end = c.pos() + c.left();
    if timestamp {
        c.number::<f32>("the frame timestamp")?;
    }
    let lists_at = c.pos();
    let lists = c.number::<i32>("the list count")?;
    if lists < 0 {
        return Err(c.err(lists_at, format!("negative list count {lists}")));
    }
    let mut out = Vec::new();
    for _ in 0..lists {
        let h = list_header(c, version)?;
        read_list_particles(c, &h, &mut out)?;
        if version == 101 {
            skip_cluster_info(c)?;
        }
    }
    if c.left() != 0 {
        return Err(c.err(
            c.pos(),
            format!(
                "the frame's lists end at byte {} but the seek table says the frame ends at byte {}",
                c.file_offset(c.pos()),
                c.file_offset(end)
            ),
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A version-`v` file with one frame of one FLOAT_XYZR/none list of `n` particles.
    pub(crate) fn one_list(v: u16, timestamp: bool, n: u64, announced: u64) -> Vec<u8> {
        let mut b = Vec::new();
        b.extend_from_slice(MAGIC);
        b.extend_from_slice(&v.to_le_bytes());
        b.extend_from_slice(&1u32.to_le_bytes());
        b.extend_from_slice(&[0u8; 48]);
        let table_at = b.len();
        b.extend_from_slice(&[0u8; 16]);
        let start = b.len() as u64;
        if timestamp {
            b.extend_from_slice(&0f32.to_le_bytes());
        }
        b.extend_from_slice(&1i32.to_le_bytes());
        b.extend_from_slice(&[2, 0]);
        b.extend_from_slice(&[255, 0, 0, 255]);
        b.extend_from_slice(&announced.to_le_bytes());
        if v == 103 {
            b.extend_from_slice(&[0u8; 24]);
        }
        for k in 0..n {
            for x in [k as f32, 0.0, 0.0, 0.5] {
                b.extend_from_slice(&x.to_le_bytes());
            }
        }
        if v == 101 {
            b.extend_from_slice(&2u32.to_le_bytes());
            b.extend_from_slice(&4u64.to_le_bytes());
            b.extend_from_slice(&[9u8; 4]);
        }
        let end = b.len() as u64;
        b[table_at..table_at + 8].copy_from_slice(&start.to_le_bytes());
        b[table_at + 8..table_at + 16].copy_from_slice(&end.to_le_bytes());
        b
    }

    fn spec() -> IncludeSpec {
        IncludeSpec::bare(Path::new("t.mmpld"))
    }

    #[test]
    fn reads_a_synthetic_file() {
        let l = read(&spec(), &one_list(102, true, 3, 3)).expect("ok");
        assert_eq!(l.records.len(), 3);
        assert_eq!(l.records[2].center.x, 2.0);
        assert_eq!(l.records[2].radius, 0.5);
        assert_eq!(l.records[0].color, Some(DVec3::new(1.0, 0.0, 0.0)));
    }

    #[test]
    fn every_version() {
        for (v, ts) in [(100, false), (101, false), (102, true), (103, true)] {
            let l = read(&spec(), &one_list(v, ts, 2, 2)).expect("ok");
            assert_eq!(l.records.len(), 2, "{v}");
            assert_eq!(l.records[1].center.x, 1.0, "{v}");
        }
    }

    #[test]
    fn short_xyz_and_u8_rgb() {
        // One list: SHORT_XYZ (3), UINT8_RGB (1), global radius 0.25, one particle (-2, 3, 7)
        // coloured (255, 0, 0).
        let mut b = Vec::new();
        b.extend_from_slice(MAGIC);
        b.extend_from_slice(&102u16.to_le_bytes());
        b.extend_from_slice(&1u32.to_le_bytes());
        b.extend_from_slice(&[0u8; 48]);
        b.extend_from_slice(&76u64.to_le_bytes());
        let end_at = b.len();
        b.extend_from_slice(&0u64.to_le_bytes());
        b.extend_from_slice(&0f32.to_le_bytes());
        b.extend_from_slice(&1i32.to_le_bytes());
        b.extend_from_slice(&[3, 1]);
        b.extend_from_slice(&0.25f32.to_le_bytes());
        b.extend_from_slice(&1u64.to_le_bytes());
        for v in [-2i16, 3, 7] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&[255, 0, 0]);
        let end = b.len() as u64;
        b[end_at..end_at + 8].copy_from_slice(&end.to_le_bytes());
        let l = read(&spec(), &b).expect("ok");
        assert_eq!(l.records[0].center, DVec3::new(-2.0, 3.0, 7.0));
        assert_eq!(l.records[0].radius, 0.25);
        assert_eq!(l.records[0].color, Some(DVec3::X));
    }

    #[test]
    fn v103_without_timestamp_is_recovered() {
        let l = read(&spec(), &one_list(103, false, 2, 2)).expect("ok");
        assert_eq!(l.records.len(), 2);
        assert!(l.warnings.iter().any(|w| w.contains("timestamp")));
        let l = read(&spec(), &one_list(103, true, 2, 2)).expect("ok");
        assert!(l.warnings.is_empty());
    }

    #[test]
    fn lying_count_is_an_error_not_an_allocation() {
        let e = read(&spec(), &one_list(102, true, 2, u64::MAX / 2))
            .expect_err("lie")
            .to_string();
        assert!(
            e.contains("t.mmpld (byte") && e.contains("particles"),
            "{e}"
        );
    }

    #[test]
    fn every_truncation_is_an_error() {
        let full = one_list(102, true, 3, 3);
        for n in 0..full.len() {
            assert!(read(&spec(), &full[..n]).is_err(), "{n}");
        }
    }
}
