//! What every source of frames shares (docs/design.md §10): the [`FrameSource`] interface and
//! its [`Frame`], the frames of text files found by one scan ([`TextFrames`]), the checks every
//! frame passes, and the [`Trajectory`] interface of the MD trajectory formats. They read their
//! files through the byte layer ([`super::file`]). The readers (one file per format) implement
//! these; [`super::frames`] opens the source an include names and chooses its frames.

use super::file::ByteSource;
use super::{IncludeSpec, LoadedParticles};
use crate::error::{PgtError, Result};
use glam::DVec3;
use std::path::Path;

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
    if spec.color_by == super::ColorBy::Uniform {
        loaded.sh = None;
    }
    super::check_records(path, &loaded.records)?;
    Ok(loaded)
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
