//! What every source of frames shares (docs/design.md §10): the [`FrameSource`] interface and
//! its [`Frame`], the file read in checked pieces ([`ByteSource`]), the line scan of the text
//! formats, the checks every frame passes, and the [`Trajectory`] interface of the MD trajectory
//! formats. The readers (one file per format) implement these; [`super::frames`] opens the
//! source an include names and chooses its frames.

use super::{IncludeSpec, LoadedParticles};
use crate::error::{PgtError, Result};
use glam::DVec3;
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

    /// The frame facts of a text file of these frames (a count only: the text formats give
    /// neither a fixed atom count nor a time step).
    pub fn info(&self) -> FrameInfo {
        FrameInfo {
            count: self.starts.len(),
            atoms_per_frame: None,
            time_step_ps: None,
        }
    }

    /// The bytes of frame `index` of `source` and the line it starts on; a frame past the end
    /// is an error naming the file and the count.
    pub fn read(&self, source: &ByteSource, index: usize) -> Result<(Vec<u8>, usize)> {
        let path = source.path();
        let (start, end, first_line) = self
            .range(index, source.len())
            .ok_or_else(|| past_the_end(path, index, self.starts.len()))?;
        let bytes = source.read_at(start, end - start, &format!("frame {index}"))?;
        Ok((bytes, first_line))
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

/// The error for a frame index past the end of a source.
pub fn past_the_end(path: &Path, index: usize, count: usize) -> PgtError {
    PgtError::in_file(
        path,
        format!("frame {index} requested, but the file has {count} frame(s) (0-based)"),
    )
}

/// A trajectory file: positions per frame, without elements or names.
pub trait Trajectory: Send + Sync {
    /// The file, for messages.
    fn path(&self) -> &Path;
    /// Atoms per frame.
    fn atoms(&self) -> usize;
    /// Number of frames (a truncated last frame counts; reading it is the error).
    fn frames(&self) -> usize;
    /// Time between frames in picoseconds, where the file says.
    fn time_step_ps(&self) -> Option<f64>;
    /// Remarks found at open (a header frame count that disagrees with the file's length).
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
    /// The positions of frame `index` in Å, into `out` (cleared first; [`Trajectory::atoms`]
    /// entries), and the frame's time in ps where the file gives one. A truncated or corrupt
    /// frame is an error that names the file, the frame and the byte.
    fn read_positions(&self, index: usize, out: &mut Vec<DVec3>) -> Result<Option<f64>>;
}

/// Opens a trajectory from its bytes (header read, frames found).
pub type OpenTrajectory = fn(source: ByteSource) -> Result<Box<dyn Trajectory>>;

/// One trajectory format: an entry of [`super::topology::TRAJECTORY_FORMATS`].
#[derive(Debug)]
pub struct TrajectoryFormat {
    /// Its name (`"xtc"`).
    pub name: &'static str,
    /// File name extensions, lower case, without the dot.
    pub extensions: &'static [&'static str],
    /// One line for people.
    pub description: &'static str,
    /// The reader.
    pub open: OpenTrajectory,
}
