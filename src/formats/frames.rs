//! Particle sources that hold frames (docs/design.md §10): MMPLD frames, PDB `MODEL`s, mmCIF
//! model numbers, XYZ frames back to back, numbered file sequences and MD trajectories (DCD, XTC)
//! with a topology.
//!
//! **One frame at a time.** A [`FrameSource`] is opened once (it reads headers, seek tables or a
//! scan of frame offsets) and then reads **one frame on demand**, by index, from its file: random
//! access wherever the format allows (MMPLD's seek table, DCD's fixed frame size, the offsets of
//! XTC frames, `MODEL` records and XYZ count lines found by one scan at open). Nothing holds more
//! than one frame's particles, so a 10,000-frame trajectory of 100,000 atoms is never in memory
//! at once. (mmCIF is the exception: its `_atom_site` loop is parsed whole at open, see
//! [`super::mmcif`].) Sources are `Send + Sync`: their file handle sits behind a mutex that is
//! held only while a frame's bytes are read, so workers may read different frames at once.
//!
//! **What an `[[include]]` says about frames** (the keys of [`IncludeSpec`]):
//! * `trajectory = "md.xtc"`: the frames come from a DCD or XTC file, and `path` is its topology
//!   (PDB, mmCIF, GRO or PSF), which gives elements (radii, colours) and chains;
//! * `sequence = "traj/frame_%04d.csv"` or `"traj/frame_*.csv"`: numbered files, one frame each,
//!   in the order of their numbers (instead of `path`);
//! * `frames = "A..B"` (0-based, B excluded; `"A.."` to the end) and `frame_step = S`: which
//!   frames of the source the scene plays: frame i of the scene is frame A + i·S of the source;
//! * `frame = k` (or `model = m` for PDB/mmCIF): the include shows that one frame in every scene
//!   frame (the static selection it always was).

use super::{format_of, Format, IncludeSpec, LoadedParticles};
use crate::error::{PgtError, Result};
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// What `pgt info` and the scene need to know of a source's frames.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct FrameInfo {
    /// Number of frames.
    pub count: usize,
    /// Particles (atoms) per frame where every frame has the same number; `None` where frames
    /// differ or the count is only known by reading every frame.
    pub atoms_per_frame: Option<usize>,
    /// Time between frames in picoseconds, where the file says (XTC, DCD).
    pub time_step_ps: Option<f64>,
}

/// One frame of a source.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Its index in the source (0-based).
    pub index: usize,
    /// Its time in picoseconds, where the file gives one.
    pub time_ps: Option<f64>,
    /// The particles, with the include's `radius_scale`, `color_by = "uniform"` and the record
    /// checks applied ([`finish_frame`]).
    pub particles: LoadedParticles,
}

/// A particle source with frames, read one frame at a time (see the module doc).
pub trait FrameSource: Send + Sync {
    /// The file that messages name (the trajectory, the sequence pattern, the particle file).
    fn path(&self) -> &Path;
    /// Frame count, atoms per frame and time step.
    fn info(&self) -> FrameInfo;
    /// Remarks found when the source was opened (a header that disagrees with the file length).
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
    /// Frame `index` (0-based); an index past the end, a truncated or corrupt frame is an error
    /// that names the file and the frame.
    fn read_frame(&self, index: usize) -> Result<Frame>;
}

/// Opens the frames of an include: a trajectory with its topology, a numbered sequence, or the
/// frames of the particle file itself (its [`Format::frames`]); a format without frames gives a
/// source of one frame.
pub fn open_frames(spec: &IncludeSpec) -> Result<Box<dyn FrameSource>> {
    if let Some(trajectory) = &spec.trajectory {
        return super::topology::open_trajectory(spec, trajectory);
    }
    if let Some(pattern) = &spec.sequence {
        return Ok(Box::new(Sequence::open(spec, pattern)?));
    }
    let format = format_of(spec)?;
    match format.frames {
        Some(open) => open(spec, ByteSource::open(&spec.path)?),
        None => Ok(Box::new(SingleFrame::load(spec, format)?)),
    }
}

/// Whether an include needs the frame machinery for its static (frame 0) particles: a trajectory,
/// a sequence or a frame selection. Every other include keeps the one-file loading path.
pub fn uses_frames(spec: &IncludeSpec) -> bool {
    spec.trajectory.is_some() || spec.sequence.is_some() || spec.frames.is_some()
}

/// The particles an include shows when it is not played: frame `frame = k`, else the first
/// frame of its `frames` selection, else frame 0 (docs/design.md §10).
pub fn load_static_frame(spec: &IncludeSpec) -> Result<LoadedParticles> {
    let source = open_frames(spec)?;
    let selection = FrameSelection::of(spec, source.as_ref())?;
    let index = match spec.frame {
        Some(k) => k,
        None => selection.source_index(0).unwrap_or(0),
    };
    let mut frame = source.read_frame(index)?;
    let mut warnings = source.warnings();
    warnings.append(&mut frame.particles.warnings);
    frame.particles.warnings = warnings;
    Ok(frame.particles)
}

/// Which frames of a source an include plays: `frames = "A..B"` and `frame_step`, checked
/// against the source (an error naming the include's file and the range when it falls outside).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameSelection {
    /// First source frame.
    pub start: usize,
    /// One past the last source frame that may be played.
    pub end: usize,
    /// Source frames between two scene frames (≥ 1).
    pub step: usize,
}

impl FrameSelection {
    /// The selection of `spec` over `source` (all frames, step 1, by default).
    pub fn of(spec: &IncludeSpec, source: &dyn FrameSource) -> Result<FrameSelection> {
        let count = source.info().count;
        let step = spec.frame_step.unwrap_or(1);
        if step == 0 {
            return Err(PgtError::in_file(
                source.path(),
                "`frame_step` must be ≥ 1, got 0",
            ));
        }
        let range = spec.frames.unwrap_or(FrameRange {
            start: 0,
            end: None,
        });
        let end = range.end.unwrap_or(count);
        if range.start >= end || end > count {
            return Err(PgtError::in_file(
                source.path(),
                format!(
                    "`frames = \"{range}\"` is outside the file's frames: it has {count} frame(s), 0..{count}"
                ),
            ));
        }
        if let Some(k) = spec.frame {
            if k >= count {
                return Err(PgtError::in_file(
                    source.path(),
                    format!("frame {k} requested, but the file has {count} frame(s) (0-based)"),
                ));
            }
        }
        Ok(FrameSelection {
            start: range.start,
            end,
            step,
        })
    }

    /// How many frames the selection plays.
    pub fn len(&self) -> usize {
        (self.end - self.start).div_ceil(self.step)
    }

    /// Whether it plays no frame (never, for a selection made by [`FrameSelection::of`]).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The source frame of scene frame `i`, if the selection has one.
    pub fn source_index(&self, i: usize) -> Option<usize> {
        (i < self.len()).then(|| self.start + i * self.step)
    }
}

/// `frames = "A..B"`: a half-open range of 0-based frame indices (`"A.."`: to the end). The same
/// syntax as a frame range on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameRange {
    pub start: usize,
    /// One past the last frame; `None`: the last frame of the source.
    pub end: Option<usize>,
}

impl std::fmt::Display for FrameRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.end {
            Some(e) => write!(f, "{}..{e}", self.start),
            None => write!(f, "{}..", self.start),
        }
    }
}

impl std::str::FromStr for FrameRange {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<FrameRange, String> {
        let bad = || {
            format!("expected a frame range \"A..B\" or \"A..\" (0-based, B excluded), got \"{s}\"")
        };
        let (a, b) = s.trim().split_once("..").ok_or_else(bad)?;
        let start = if a.trim().is_empty() {
            0
        } else {
            a.trim().parse().map_err(|_| bad())?
        };
        let end = if b.trim().is_empty() {
            None
        } else {
            Some(b.trim().parse::<usize>().map_err(|_| bad())?)
        };
        if end.is_some_and(|e| e <= start) {
            return Err(format!(
                "the frame range \"{s}\" is empty: its end must be greater than its start"
            ));
        }
        Ok(FrameRange { start, end })
    }
}

impl<'de> serde::Deserialize<'de> for FrameRange {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

/// Applies what every frame shares with a whole-file load ([`super::load_bytes`]):
/// `radius_scale`, `color_by = "uniform"`, the refusal of an empty frame (naming it) and the
/// record checks.
pub fn finish_frame(
    spec: &IncludeSpec,
    path: &Path,
    index: usize,
    mut loaded: LoadedParticles,
) -> Result<LoadedParticles> {
    if loaded.records.is_empty() {
        return Err(PgtError::in_file(
            path,
            format!("frame {index} holds no particles"),
        ));
    }
    super::apply_include_options(spec, &mut loaded.records);
    super::check_records(path, &loaded.records)?;
    Ok(loaded)
}

/// A seekable byte stream (a file, or bytes in memory for tests and fuzzing).
pub trait ReadSeek: Read + Seek + Send {}
impl<T: Read + Seek + Send> ReadSeek for T {}

/// A file read in pieces: every read names its offset and is checked against the length before
/// anything is allocated. The handle sits behind a mutex so that sources are `Sync`.
pub struct ByteSource {
    path: PathBuf,
    len: u64,
    inner: Mutex<Box<dyn ReadSeek>>,
}

impl std::fmt::Debug for ByteSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ByteSource")
            .field("path", &self.path)
            .field("len", &self.len)
            .finish()
    }
}

impl ByteSource {
    /// Opens a file (a directory is refused).
    pub fn open(path: &Path) -> Result<ByteSource> {
        let file = std::fs::File::open(path).map_err(|e| PgtError::io(path, e))?;
        let meta = file.metadata().map_err(|e| PgtError::io(path, e))?;
        if meta.is_dir() {
            return Err(PgtError::in_file(
                path,
                "is a directory, not a particle file",
            ));
        }
        Ok(ByteSource {
            path: path.to_path_buf(),
            len: meta.len(),
            inner: Mutex::new(Box::new(file)),
        })
    }

    /// Any seekable stream of `len` bytes, named `path` in messages.
    pub fn from_reader(path: &Path, len: u64, reader: Box<dyn ReadSeek>) -> ByteSource {
        ByteSource {
            path: path.to_path_buf(),
            len,
            inner: Mutex::new(reader),
        }
    }

    /// Bytes in memory, named `path` in messages.
    pub fn from_bytes(path: &Path, bytes: Vec<u8>) -> ByteSource {
        ByteSource {
            path: path.to_path_buf(),
            len: bytes.len() as u64,
            inner: Mutex::new(Box::new(std::io::Cursor::new(bytes))),
        }
    }

    /// The file's name for messages.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Length in bytes.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// Whether the file is empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// `len` bytes from `offset`; past the end of the file it is an error naming `what` (and the
    /// caller's context, such as the frame) at that offset.
    pub fn read_at(&self, offset: u64, len: u64, what: &str) -> Result<Vec<u8>> {
        let end = offset.checked_add(len).filter(|&e| e <= self.len);
        let Some(_) = end else {
            return Err(PgtError::at_byte(
                &self.path,
                offset,
                format!(
                    "expected {what} ({len} bytes), but the file ends at byte {}",
                    self.len
                ),
            ));
        };
        let mut buf = vec![0u8; len as usize];
        let mut inner = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        inner
            .seek(SeekFrom::Start(offset))
            .and_then(|_| inner.read_exact(&mut buf))
            .map_err(|e| PgtError::io(&self.path, e))?;
        Ok(buf)
    }

    /// The whole file (for formats parsed whole at open).
    pub fn read_all(&self, what: &str) -> Result<Vec<u8>> {
        if self.len > super::MAX_FILE_BYTES {
            return Err(PgtError::in_file(
                &self.path,
                format!(
                    "the file is {} bytes; pgt reads particle files of at most {} bytes",
                    self.len,
                    super::MAX_FILE_BYTES
                ),
            ));
        }
        self.read_at(0, self.len, what)
    }
}

/// Byte ranges of text frames found by one scan (PDB models, XYZ frames): frame k is the bytes
/// `starts[k]..starts[k+1]` (the last ends at the end of the file), beginning on line
/// `lines[k]`.
#[derive(Debug, Clone, Default)]
pub struct TextFrames {
    pub starts: Vec<u64>,
    pub lines: Vec<usize>,
}

impl TextFrames {
    /// The byte range and first line of frame `index`.
    pub fn range(&self, index: usize, file_len: u64) -> Option<(u64, u64, usize)> {
        let start = *self.starts.get(index)?;
        let end = self.starts.get(index + 1).copied().unwrap_or(file_len);
        Some((start, end, *self.lines.get(index)?))
    }
}

/// Calls `f(line_number, byte_offset, line)` for every line of a file (1-based numbers, the line
/// without its `\n`), reading it in blocks so that a large file is never in memory at once.
/// `f` returns `false` to stop.
pub fn scan_lines(
    source: &ByteSource,
    mut f: impl FnMut(usize, u64, &[u8]) -> Result<bool>,
) -> Result<()> {
    const BLOCK: u64 = 1 << 20;
    let mut carry: Vec<u8> = Vec::new();
    let mut carry_at = 0u64;
    let mut line_no = 1usize;
    let mut offset = 0u64;
    while offset < source.len() {
        let n = BLOCK.min(source.len() - offset);
        let block = source.read_at(offset, n, "text")?;
        offset += n;
        carry.extend_from_slice(&block);
        let mut start = 0usize;
        while let Some(rel) = carry
            .get(start..)
            .and_then(|s| s.iter().position(|&b| b == b'\n'))
        {
            let line = carry.get(start..start + rel).unwrap_or_default();
            if !f(line_no, carry_at + start as u64, line)? {
                return Ok(());
            }
            line_no += 1;
            start += rel + 1;
        }
        carry.drain(..start);
        carry_at += start as u64;
    }
    if !carry.is_empty() {
        f(line_no, carry_at, &carry)?;
    }
    Ok(())
}

/// A format without frames: its one frame, loaded at open.
struct SingleFrame {
    path: PathBuf,
    particles: LoadedParticles,
}

impl SingleFrame {
    fn load(spec: &IncludeSpec, format: &Format) -> Result<SingleFrame> {
        let bytes = super::read_input(&spec.path)?;
        let particles = super::load_bytes(spec, format, &bytes)?;
        Ok(SingleFrame {
            path: spec.path.clone(),
            particles,
        })
    }
}

impl FrameSource for SingleFrame {
    fn path(&self) -> &Path {
        &self.path
    }
    fn info(&self) -> FrameInfo {
        FrameInfo {
            count: 1,
            atoms_per_frame: Some(self.particles.records.len()),
            time_step_ps: None,
        }
    }
    fn read_frame(&self, index: usize) -> Result<Frame> {
        if index != 0 {
            return Err(past_the_end(&self.path, index, 1));
        }
        Ok(Frame {
            index,
            time_ps: None,
            particles: self.particles.clone(),
        })
    }
}

/// The error for a frame index past the end of a source.
pub fn past_the_end(path: &Path, index: usize, count: usize) -> PgtError {
    PgtError::in_file(
        path,
        format!("frame {index} requested, but the file has {count} frame(s) (0-based)"),
    )
}

/// `sequence = "…"`: numbered particle files, one frame each (see [`SequencePattern`]).
struct Sequence {
    pattern: PathBuf,
    files: Vec<PathBuf>,
    spec: IncludeSpec,
}

impl Sequence {
    fn open(spec: &IncludeSpec, pattern: &Path) -> Result<Sequence> {
        let files = SequencePattern::parse(pattern)?.files()?;
        Ok(Sequence {
            pattern: pattern.to_path_buf(),
            files,
            spec: spec.clone(),
        })
    }
}

impl FrameSource for Sequence {
    fn path(&self) -> &Path {
        &self.pattern
    }
    fn info(&self) -> FrameInfo {
        FrameInfo {
            count: self.files.len(),
            atoms_per_frame: None,
            time_step_ps: None,
        }
    }
    fn read_frame(&self, index: usize) -> Result<Frame> {
        let file = self
            .files
            .get(index)
            .ok_or_else(|| past_the_end(&self.pattern, index, self.files.len()))?;
        let mut spec = self.spec.clone();
        spec.path = file.clone();
        spec.sequence = None;
        spec.frames = None;
        spec.frame_step = None;
        let particles = super::load_particles(&spec)?;
        Ok(Frame {
            index,
            time_ps: None,
            particles,
        })
    }
}

/// The file-name pattern of a sequence: one printf conversion `%d`, `%Nd` or `%0Nd` (`%%` is a
/// literal `%`), or one `*`, in the last path component. Its files are those of the folder whose
/// names match with a decimal number in place of the conversion, in the order of their numbers;
/// the numbers must be evenly spaced (0, 1, 2, … or 0, 10, 20, …): a gap is a missing frame and
/// an error naming it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SequencePattern {
    pattern: PathBuf,
    folder: PathBuf,
    prefix: String,
    suffix: String,
    /// The minimum digit count of `%0Nd` (zero-padded), if the pattern pads.
    zero_padded: Option<usize>,
}

impl SequencePattern {
    /// Parses a pattern; one that has no conversion, or more than one, is an error.
    pub fn parse(pattern: &Path) -> Result<SequencePattern> {
        let bad = |m: String| PgtError::in_file(pattern, m);
        let name = pattern
            .file_name()
            .and_then(|n| n.to_str())
            .ok_or_else(|| bad("the sequence pattern has no file name".into()))?;
        let folder = pattern
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."))
            .to_path_buf();
        let expected =
            "expected one `%d`, `%0Nd` or `*` in the file name (`frame_%04d.csv`, `frame_*.csv`)";
        let mut found: Option<(String, usize, Option<usize>)> = None;
        let mut literal = String::new();
        let chars: Vec<char> = name.chars().collect();
        let mut i = 0;
        while let Some(&c) = chars.get(i) {
            if c == '%' && chars.get(i + 1) == Some(&'%') {
                literal.push('%');
                i += 2;
                continue;
            }
            let conversion = if c == '*' {
                Some((1usize, None))
            } else if c == '%' {
                let digits: String = chars[i + 1..]
                    .iter()
                    .take_while(|d| d.is_ascii_digit())
                    .collect();
                if chars.get(i + 1 + digits.len()) != Some(&'d') {
                    return Err(bad(format!(
                        "unsupported conversion in `{name}`: {expected}"
                    )));
                }
                let pad = digits
                    .starts_with('0')
                    .then(|| digits.parse::<usize>().unwrap_or(0));
                Some((digits.len() + 2, pad))
            } else {
                None
            };
            match conversion {
                Some((width, pad)) => {
                    if found.is_some() {
                        return Err(bad(format!(
                            "`{name}` has more than one number: {expected}"
                        )));
                    }
                    found = Some((literal.clone(), literal.len(), pad));
                    literal.clear();
                    i += width;
                }
                None => {
                    literal.push(c);
                    i += 1;
                }
            }
        }
        let Some((prefix, _, zero_padded)) = found else {
            return Err(bad(format!("`{name}` has no number: {expected}")));
        };
        Ok(SequencePattern {
            pattern: pattern.to_path_buf(),
            folder,
            prefix,
            suffix: literal,
            zero_padded,
        })
    }

    /// The number a file name stands for, if it matches.
    pub fn number_of(&self, name: &str) -> Option<u64> {
        let digits = name
            .strip_prefix(&self.prefix)?
            .strip_suffix(&self.suffix)?;
        if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        if let Some(width) = self.zero_padded {
            if digits.len() < width || (digits.len() > width && digits.starts_with('0')) {
                return None;
            }
        }
        digits.parse().ok()
    }

    /// The matching files in the order of their numbers (see the type's doc).
    pub fn files(&self) -> Result<Vec<PathBuf>> {
        let entries = std::fs::read_dir(&self.folder).map_err(|e| PgtError::io(&self.folder, e))?;
        let mut numbered: Vec<(u64, PathBuf)> = Vec::new();
        for entry in entries {
            let entry = entry.map_err(|e| PgtError::io(&self.folder, e))?;
            let name = entry.file_name();
            if let Some(n) = name.to_str().and_then(|s| self.number_of(s)) {
                numbered.push((n, entry.path()));
            }
        }
        numbered.sort();
        if numbered.is_empty() {
            return Err(PgtError::in_file(
                &self.pattern,
                format!(
                    "no file in {} matches the sequence pattern",
                    self.folder.display()
                ),
            ));
        }
        if let Some(w) = numbered.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(PgtError::in_file(
                &self.pattern,
                format!(
                    "{} and {} have the same number {}",
                    w[0].1.display(),
                    w[1].1.display(),
                    w[0].0
                ),
            ));
        }
        check_even_spacing(&self.pattern, &numbered)?;
        Ok(numbered.into_iter().map(|(_, p)| p).collect())
    }
}

/// The numbers of a sequence are evenly spaced; the first gap is an error naming the missing
/// number (frame) and its neighbours.
fn check_even_spacing(pattern: &Path, numbered: &[(u64, PathBuf)]) -> Result<()> {
    let [(first, _), (second, _), ..] = numbered else {
        return Ok(());
    };
    let step = second - first;
    for (k, w) in numbered.windows(2).enumerate() {
        if w[1].0 - w[0].0 != step {
            return Err(PgtError::in_file(
                pattern,
                format!(
                    "the sequence numbers are not evenly spaced: after {} (frame {k}) comes {}, expected number {} (a missing frame?)",
                    w[0].1.display(),
                    w[1].1.display(),
                    w[0].0 + step
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges_parse_and_refuse() {
        assert_eq!(
            "3..10".parse::<FrameRange>(),
            Ok(FrameRange {
                start: 3,
                end: Some(10)
            })
        );
        assert_eq!(
            "5..".parse::<FrameRange>(),
            Ok(FrameRange {
                start: 5,
                end: None
            })
        );
        assert!("..4".parse::<FrameRange>().is_ok());
        assert!("4..4".parse::<FrameRange>().unwrap_err().contains("empty"));
        assert!("a..4".parse::<FrameRange>().is_err());
        assert!("4".parse::<FrameRange>().is_err());
    }

    #[test]
    fn selections_count_and_map() {
        let s = FrameSelection {
            start: 2,
            end: 11,
            step: 3,
        };
        assert_eq!(s.len(), 3);
        assert_eq!(s.source_index(0), Some(2));
        assert_eq!(s.source_index(2), Some(8));
        assert_eq!(s.source_index(3), None);
    }

    #[test]
    fn sequence_patterns() {
        let p = SequencePattern::parse(Path::new("d/frame_%04d.csv")).expect("ok");
        assert_eq!(p.number_of("frame_0012.csv"), Some(12));
        assert_eq!(p.number_of("frame_12.csv"), None);
        assert_eq!(p.number_of("frame_12345.csv"), Some(12345));
        assert_eq!(p.number_of("frame_0012.xyz"), None);
        let p = SequencePattern::parse(Path::new("frame_*.xyz")).expect("ok");
        assert_eq!(p.number_of("frame_7.xyz"), Some(7));
        assert_eq!(p.number_of("frame_x.xyz"), None);
        let p = SequencePattern::parse(Path::new("100%%_%d.csv")).expect("ok");
        assert_eq!(p.number_of("100%_3.csv"), Some(3));
        for bad in ["frame.csv", "f_%d_%d.csv", "f_*_*.csv", "f_%s.csv"] {
            assert!(SequencePattern::parse(Path::new(bad)).is_err(), "{bad}");
        }
    }

    #[test]
    fn byte_source_refuses_reads_past_the_end() {
        let b = ByteSource::from_bytes(Path::new("m.bin"), vec![1, 2, 3, 4]);
        assert_eq!(b.read_at(1, 2, "x").expect("ok"), vec![2, 3]);
        let e = b.read_at(2, u64::MAX, "the data").unwrap_err().to_string();
        assert!(
            e.contains("m.bin (byte 2)") && e.contains("the data"),
            "{e}"
        );
    }

    #[test]
    fn scan_lines_numbers_lines_and_offsets() {
        let b = ByteSource::from_bytes(Path::new("t.txt"), b"ab\ncd\n\nlast".to_vec());
        let mut seen = Vec::new();
        scan_lines(&b, |n, at, l| {
            seen.push((n, at, String::from_utf8_lossy(l).into_owned()));
            Ok(true)
        })
        .expect("ok");
        assert_eq!(
            seen,
            vec![
                (1, 0, "ab".into()),
                (2, 3, "cd".into()),
                (3, 6, String::new()),
                (4, 7, "last".into())
            ]
        );
    }
}
