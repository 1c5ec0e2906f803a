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

pub use super::file::{scan_lines, ByteSource, ReadSeek};
pub use super::frame_source::{
    finish_frame, past_the_end, Frame, FrameInfo, FrameSource, TextFrames,
};
use super::{format_of, Format, IncludeSpec, LoadedParticles};
use crate::error::{PgtError, Result};
use std::path::{Path, PathBuf};

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
    /// Why the pattern cannot name a file to write (`*`, or space padding `%Nd`), if it
    /// cannot.
    not_for_output: Option<&'static str>,
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
        let mut not_for_output = None;
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
                not_for_output = Some(
                    "a `*` matches files to read; a pattern of files to write needs %d or %0Nd",
                );
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
                if !digits.is_empty() && pad.is_none() {
                    not_for_output =
                        Some("%Nd pads with spaces; a pattern of files to write takes %d or %0Nd");
                }
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
            not_for_output,
        })
    }

    /// The file of number `n` (a pattern of files to write: `%d` or `%0Nd`), or why the
    /// pattern cannot name one.
    pub fn path_for(&self, n: usize) -> std::result::Result<PathBuf, String> {
        if let Some(why) = self.not_for_output {
            return Err(format!("{}: {why}", self.pattern.display()));
        }
        let width = self.zero_padded.unwrap_or(0);
        Ok(self
            .folder_as_written()
            .join(format!("{}{n:0width$}{}", self.prefix, self.suffix)))
    }

    /// The folder as the pattern writes it (empty for a bare file name).
    fn folder_as_written(&self) -> PathBuf {
        self.pattern
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default()
    }

    /// The matching files with their numbers, sorted; two files of one number are an error.
    pub fn numbered_files(&self) -> Result<Vec<(u64, PathBuf)>> {
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
        Ok(numbered)
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

    /// The matching files in the order of their numbers, evenly spaced (see the type's doc).
    pub fn files(&self) -> Result<Vec<PathBuf>> {
        let numbered = self.numbered_files()?;
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
