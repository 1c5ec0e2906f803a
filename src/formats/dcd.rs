//! DCD trajectories (CHARMM, NAMD, LAMMPS, OpenMM, X-PLOR): positions in Å, one frame at a time
//! (docs/design.md §10).
//!
//! **Why pgt reads DCD itself.** No crate on crates.io reads DCD on its own: the trajectory
//! toolkits that do (`molar`, `molcrafts-molrs`, `chemfiles`) bring a whole analysis framework,
//! C++ sources or a newer Rust than pgt's, for a format of a few Fortran records. This reader is
//! written from the layout that VMD's `dcdplugin` and MDAnalysis document, and is checked
//! against MDAnalysis on the sample files (`tests/data/trajectory_vectors.json`).
//!
//! **Layout.** Fortran unformatted records: each is a length marker, the payload, the same marker
//! again. Markers are 4 bytes (8 in files of some 64-bit Fortran compilers); the byte order is
//! the one in which the first marker reads 84. Records:
//! 1. 84 bytes: `"CORD"` and 20 `i32` control words: NSET (frames) [0], ISTART [1], NSAVC [2],
//!    NAMNF (fixed atoms) [8], DELTA (the time step in AKMA units: `f32` [9] in CHARMM files,
//!    `f64` [9..11] in X-PLOR files), a unit cell per frame [10] and a fourth dimension [11]
//!    (CHARMM files only), and the CHARMM version [19] (non-zero: a CHARMM file);
//! 2. the titles: `i32` count and 80-byte lines (skipped);
//! 3. 4 bytes: the atom count N;
//! 4. with NAMNF > 0: the 1-based indices of the N − NAMNF free atoms.
//!
//! Then per frame: the unit cell (48 bytes, where flagged; ignored), X, Y and Z records of `f32`
//! (N values in the first frame; only the free atoms' values in later frames when atoms are
//! fixed: the fixed ones keep their first-frame positions) and, where flagged, a fourth-dimension
//! record (ignored). Frames have a fixed size, so frame k is read at its offset directly.
//!
//! **Frame count.** Real files exist whose header NSET disagrees with their length (a run that
//! was stopped, a writer that never updated it): the count comes from the length, with a warning
//! where NSET says otherwise. A last frame cut short counts, and reading it is an error naming
//! the frame; a record marker that does not fit the layout (a corrupt frame) is one too.
//!
//! **Time.** The time step is DELTA · NSAVC · 0.04888821 ps (the AKMA time unit, as MDAnalysis
//! and VMD convert it); frame k is at k times that, from the first frame.

use super::file::fortran::RecordError;
use super::file::{ByteSource, Fortran, Reader};
use super::frame_source::Trajectory;
use super::Format;
use crate::error::{PgtError, Result};
use glam::DVec3;
use std::path::Path;
use std::sync::Mutex;

/// DCD in the table of formats ([`super::FORMATS`]): a trajectory.
pub const FORMAT: Format = Format {
    name: "dcd",
    extensions: &["dcd"],
    description: "CHARMM/NAMD/LAMMPS/OpenMM DCD (Å)",
    trajectory: Some(open),
    ..Format::NOTHING
};

/// Picoseconds per AKMA time unit (CHARMM's internal time unit).
pub const AKMA_PS: f64 = 0.048_888_21;

/// Bytes of the first record's payload.
const HEADER_RECORD: u64 = 84;
/// Bytes of a unit-cell record's payload (six `f64`).
const CELL_RECORD: u64 = 48;

/// An open DCD file.
struct Dcd {
    source: ByteSource,
    records: Fortran,
    atoms: usize,
    /// 0-based indices of the free atoms, where atoms are fixed (NAMNF > 0).
    free: Option<Vec<usize>>,
    has_cell: bool,
    has_4d: bool,
    frames_start: u64,
    first_frame_bytes: u64,
    frame_bytes: u64,
    frames: usize,
    time_step_ps: Option<f64>,
    warnings: Vec<String>,
    /// The first frame's positions, kept for the fixed atoms of later frames.
    fixed: Mutex<Option<Vec<DVec3>>>,
}

/// The byte order and marker size: those in which the first marker reads 84.
fn layout(source: &ByteSource) -> Result<Fortran> {
    let b = source.read_at(0, source.len().min(8), "the first record marker")?;
    Fortran::detect(&b, HEADER_RECORD).ok_or_else(|| {
        PgtError::at_byte(
            source.path(),
            0,
            "not a DCD file: the first record marker is not 84 in either byte order",
        )
    })
}

/// The [`super::OpenTrajectory`] of DCD: the header records, the free-atom list and the
/// frame count from the file's length.
pub fn open(source: ByteSource) -> Result<Box<dyn Trajectory>> {
    let records = layout(&source)?;
    let path = source.path().to_path_buf();
    let (head, at) = records.read(&source, 0, Some(HEADER_RECORD), "the header record")?;
    if head.get(..4) != Some(b"CORD".as_slice()) {
        return Err(PgtError::at_byte(
            &path,
            records.marker,
            format!(
                "not a coordinate DCD file: expected \"CORD\", found {:?}",
                String::from_utf8_lossy(head.get(..4).unwrap_or_default())
            ),
        ));
    }
    let header = payload(&path, &head, records.marker, &source, records);
    let icntrl = |k: usize| header.number_at::<i32>(4 + 4 * k, "a control word of the header");
    let charmm = icntrl(19)? != 0;
    let nset = icntrl(0)?;
    let nsavc = icntrl(2)?.max(1);
    let namnf = icntrl(8)?;
    let delta = if charmm {
        f64::from(header.number_at::<f32>(4 + 4 * 9, "DELTA")?)
    } else {
        header.number_at::<f64>(4 + 4 * 9, "DELTA")?
    };
    let (has_cell, has_4d) = (charmm && icntrl(10)? != 0, charmm && icntrl(11)? != 0);
    let (_, at) = records.read(&source, at, None, "the title record")?;
    let (natom_rec, at) = records.read(&source, at, Some(4), "the atom-count record")?;
    let natom_at = at - 4 - records.marker;
    let atoms = payload(&path, &natom_rec, natom_at, &source, records)
        .number_at::<i32>(0, "the atom count")?;
    if atoms < 1 {
        return Err(PgtError::at_byte(
            &path,
            natom_at,
            format!("the atom count is {atoms}; a DCD trajectory needs at least one atom"),
        ));
    }
    let atoms = atoms as usize;
    if !(0..atoms as i64).contains(&i64::from(namnf)) {
        return Err(PgtError::at_byte(
            &path,
            records.marker + 4 + 4 * 8,
            format!("the header says {namnf} fixed atoms, but there are {atoms} atoms"),
        ));
    }
    let (free, at) = free_atoms(&source, records, at, atoms, namnf as usize)?;
    let m = records.marker;
    let coordinates = |n: usize| 3 * (4 * n as u64 + 2 * m);
    let extra = |n: usize| {
        (if has_cell { CELL_RECORD + 2 * m } else { 0 })
            + (if has_4d { 4 * n as u64 + 2 * m } else { 0 })
    };
    let n_later = free.as_ref().map_or(atoms, Vec::len);
    let first_frame_bytes = coordinates(atoms) + extra(atoms);
    let frame_bytes = coordinates(n_later) + extra(n_later);
    let remaining = source.len() - at;
    let (frames, complete) = if remaining == 0 {
        (0, 0)
    } else if remaining <= first_frame_bytes {
        (1, usize::from(remaining == first_frame_bytes))
    } else {
        let rest = remaining - first_frame_bytes;
        (
            1 + rest.div_ceil(frame_bytes) as usize,
            1 + (rest / frame_bytes) as usize,
        )
    };
    if frames == 0 {
        return Err(PgtError::at_byte(
            &path,
            at,
            "the file has no frames: it ends after the header",
        ));
    }
    let mut warnings = Vec::new();
    if complete < frames {
        warnings.push(format!(
            "{}: the last frame ({}) is truncated: the file ends before its end; reading it is an error",
            path.display(),
            frames - 1
        ));
    }
    if i64::from(nset) != complete as i64 {
        warnings.push(format!(
            "{}: the header says {nset} frames, the file holds {complete} complete frame(s) (counted from its length)",
            path.display()
        ));
    }
    let time_step_ps =
        (delta.is_finite() && delta > 0.0).then(|| delta * f64::from(nsavc) * AKMA_PS);
    Ok(Box::new(Dcd {
        source,
        records,
        atoms,
        free,
        has_cell,
        has_4d,
        frames_start: at,
        first_frame_bytes,
        frame_bytes,
        frames,
        time_step_ps,
        warnings,
        fixed: Mutex::new(None),
    }))
}

/// The free-atom list at `at` (where `fixed` > 0 atoms are fixed): 0-based indices, checked to
/// lie in 1..=N in the file, and the offset after the record.
fn free_atoms(
    source: &ByteSource,
    records: Fortran,
    at: u64,
    atoms: usize,
    fixed: usize,
) -> Result<(Option<Vec<usize>>, u64)> {
    if fixed == 0 {
        return Ok((None, at));
    }
    let n = atoms - fixed;
    let (list, next) = records.read(source, at, Some(4 * n as u64), "the free-atom list")?;
    let list_at = at + records.marker;
    let list = payload(source.path(), &list, list_at, source, records);
    let mut free = Vec::with_capacity(n);
    for k in 0..n {
        let i = list.number_at::<i32>(4 * k, "a free atom's index")?;
        if !(1..=atoms as i64).contains(&i64::from(i)) {
            return Err(PgtError::at_byte(
                source.path(),
                list_at + 4 * k as u64,
                format!("free atom {k} has index {i}, outside 1..={atoms}"),
            ));
        }
        free.push(i as usize - 1);
    }
    Ok((Some(free), next))
}

/// A reader over `bytes`, a record's payload (or a frame) read from file offset `at` of
/// `source`, in the file's byte order.
fn payload<'a>(
    path: &'a Path,
    bytes: &'a [u8],
    at: u64,
    source: &ByteSource,
    records: Fortran,
) -> Reader<'a> {
    Reader::window(path, bytes, at, source.len(), "record", records.endian)
}

impl Dcd {
    /// The file offset of frame `index`.
    fn frame_offset(&self, index: usize) -> u64 {
        if index == 0 {
            self.frames_start
        } else {
            self.frames_start + self.first_frame_bytes + (index as u64 - 1) * self.frame_bytes
        }
    }

    /// The X, Y, Z values of frame `index` (N values in the first frame, the free atoms' in later
    /// frames where atoms are fixed), checked record by record.
    fn coordinates(&self, index: usize) -> Result<Vec<DVec3>> {
        let path = self.source.path();
        let n = if index == 0 {
            self.atoms
        } else {
            self.free.as_ref().map_or(self.atoms, Vec::len)
        };
        let start = self.frame_offset(index);
        let size = if index == 0 {
            self.first_frame_bytes
        } else {
            self.frame_bytes
        };
        if start + size > self.source.len() {
            return Err(PgtError::at_byte(
                path,
                start,
                format!(
                    "frame {index} is truncated: it needs {size} bytes from byte {start}, but the file ends at byte {}",
                    self.source.len()
                ),
            ));
        }
        let bytes = self
            .source
            .read_at(start, size, &format!("frame {index}"))?;
        let records = self.records;
        let mut at = 0usize;
        let mut take = |len: usize, what: &str| -> Result<usize> {
            let payload_at = records.record_in(&bytes, at, len).map_err(|e| match e {
                RecordError::Markers { at: bad_at, opening, closing } => PgtError::at_byte(
                    path,
                    start + bad_at as u64,
                    format!(
                        "frame {index}: the {what} record has length markers {opening} and {closing}, expected {len} (a corrupt frame)"
                    ),
                ),
                RecordError::CutShort { at } => PgtError::at_byte(
                    path,
                    start + at as u64,
                    format!("frame {index}: the {what} record is cut short (a corrupt frame)"),
                ),
            })?;
            at = payload_at + len + records.marker as usize;
            Ok(payload_at)
        };
        if self.has_cell {
            take(CELL_RECORD as usize, "unit-cell")?;
        }
        let axes = [take(4 * n, "X")?, take(4 * n, "Y")?, take(4 * n, "Z")?];
        if self.has_4d {
            take(4 * n, "fourth-dimension")?;
        }
        let frame = payload(path, &bytes, start, &self.source, records);
        let mut out = Vec::with_capacity(n);
        for k in 0..n {
            let mut v = [0f32; 3];
            for (c, x) in v.iter_mut().enumerate() {
                *x = frame.number_at(axes[c] + 4 * k, "a coordinate")?;
            }
            if let Some(c) = v.iter().position(|x| !x.is_finite()) {
                return Err(PgtError::at_byte(
                    path,
                    start + (axes[c] + 4 * k) as u64,
                    format!(
                        "frame {index}: the {} coordinate of atom {} is not finite ({})",
                        ["x", "y", "z"][c],
                        k + 1,
                        v[c]
                    ),
                ));
            }
            out.push(DVec3::new(
                f64::from(v[0]),
                f64::from(v[1]),
                f64::from(v[2]),
            ));
        }
        Ok(out)
    }
}

impl Trajectory for Dcd {
    fn path(&self) -> &Path {
        self.source.path()
    }
    fn atoms(&self) -> usize {
        self.atoms
    }
    fn frames(&self) -> usize {
        self.frames
    }
    fn time_step_ps(&self) -> Option<f64> {
        self.time_step_ps
    }
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }
    fn read_positions(&self, index: usize, out: &mut Vec<DVec3>) -> Result<Option<f64>> {
        if index >= self.frames {
            return Err(super::frame_source::past_the_end(
                self.path(),
                index,
                self.frames,
            ));
        }
        out.clear();
        match (&self.free, index) {
            (Some(free), k) if k > 0 => {
                let moved = self.coordinates(index)?;
                let mut fixed = self.fixed.lock().unwrap_or_else(|e| e.into_inner());
                if fixed.is_none() {
                    *fixed = Some(self.coordinates(0)?);
                }
                out.extend_from_slice(fixed.as_deref().unwrap_or_default());
                for (&i, p) in free.iter().zip(moved) {
                    if let Some(slot) = out.get_mut(i) {
                        *slot = p;
                    }
                }
            }
            _ => out.extend(self.coordinates(index)?),
        }
        Ok(self.time_step_ps.map(|dt| dt * index as f64))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A little-endian CHARMM DCD of `frames` frames of `atoms` atoms (atom k of frame f at
    /// (f, k, −k)), with a unit cell record, NSET = `nset`.
    pub(crate) fn synthetic(frames: usize, atoms: usize, nset: i32) -> Vec<u8> {
        let mut b = Vec::new();
        let rec = |b: &mut Vec<u8>, payload: &[u8]| {
            b.extend_from_slice(&(payload.len() as u32).to_le_bytes());
            b.extend_from_slice(payload);
            b.extend_from_slice(&(payload.len() as u32).to_le_bytes());
        };
        let mut head = b"CORD".to_vec();
        let mut icntrl = [0i32; 20];
        icntrl[0] = nset;
        icntrl[2] = 10;
        icntrl[10] = 1;
        icntrl[19] = 24;
        for (k, v) in icntrl.iter().enumerate() {
            if k == 9 {
                head.extend_from_slice(&2.0f32.to_le_bytes());
            } else {
                head.extend_from_slice(&v.to_le_bytes());
            }
        }
        rec(&mut b, &head);
        let mut titles = 1i32.to_le_bytes().to_vec();
        titles.extend_from_slice(&[b' '; 80]);
        rec(&mut b, &titles);
        rec(&mut b, &(atoms as i32).to_le_bytes());
        for f in 0..frames {
            rec(&mut b, &[0u8; 48]);
            for axis in 0..3 {
                let mut p = Vec::new();
                for k in 0..atoms {
                    let v = [f as f32, k as f32, -(k as f32)][axis];
                    p.extend_from_slice(&v.to_le_bytes());
                }
                rec(&mut b, &p);
            }
        }
        b
    }

    fn open_bytes(b: Vec<u8>) -> Result<Box<dyn Trajectory>> {
        open(ByteSource::from_bytes(Path::new("t.dcd"), b))
    }

    #[test]
    fn reads_frames_and_the_time_step() {
        let t = open_bytes(synthetic(3, 4, 3)).expect("ok");
        assert_eq!((t.atoms(), t.frames()), (4, 3));
        assert!(t.warnings().is_empty(), "{:?}", t.warnings());
        let dt = t.time_step_ps().expect("dt");
        assert!((dt - 2.0 * 10.0 * AKMA_PS).abs() < 1e-12);
        let mut p = Vec::new();
        let time = t.read_positions(2, &mut p).expect("ok");
        assert_eq!(p[3], DVec3::new(2.0, 3.0, -3.0));
        assert!((time.expect("t") - 2.0 * dt).abs() < 1e-12);
    }

    #[test]
    fn header_count_disagreeing_with_the_length_is_a_warning() {
        let t = open_bytes(synthetic(3, 2, 0)).expect("ok");
        assert_eq!(t.frames(), 3);
        assert!(t.warnings().iter().any(|w| w.contains("says 0 frames")));
    }

    #[test]
    fn truncation_and_corruption_name_the_frame() {
        let full = synthetic(3, 2, 3);
        let t = open_bytes(full[..full.len() - 5].to_vec()).expect("opens");
        assert_eq!(t.frames(), 3);
        let mut p = Vec::new();
        assert!(t.read_positions(1, &mut p).is_ok());
        let e = t.read_positions(2, &mut p).unwrap_err().to_string();
        assert!(e.contains("frame 2 is truncated"), "{e}");
        // Frame 1's Y record marker (after its cell and X records).
        let mut bad = full.clone();
        let frame_bytes = 48 + 8 + 3 * (8 + 8);
        let at = full.len() - 2 * frame_bytes + (48 + 8) + (8 + 8);
        bad[at] = 99;
        let t = open_bytes(bad).expect("opens");
        let e = t.read_positions(1, &mut p).unwrap_err().to_string();
        assert!(
            e.contains("frame 1: the Y record") && e.contains(&format!("byte {at}")),
            "{e}"
        );
        for n in 0..150 {
            let _ = open_bytes(full[..n].to_vec()).map(|t| t.read_positions(0, &mut p));
        }
    }
}
