//! MD trajectories with a topology (docs/design.md §10): a DCD or XTC file moves the atoms that a
//! topology file (PDB, mmCIF, GRO or PSF) names. The topology gives each atom its element (van
//! der Waals radius, CPK colour), chain and residue, so `color_by`, `chains`, `skip_water` and
//! `skip_hydrogen` work as for a PDB file; the trajectory gives the positions of every frame.
//!
//! **Formats.** Trajectories and topologies are entries of the one table of formats
//! ([`super::FORMATS`]): a trajectory format has a [`Format::trajectory`] reader, read through
//! the [`Trajectory`] trait (atom count, frame count, time step, and the positions of one frame
//! in Å: GRO and XTC are in nm and are converted, so that radii by element agree); a topology
//! format has a [`Format::topology`] reader that gives the atoms.
//!
//! **Atom counts must agree.** The topology's atoms (of its first model) are the trajectory's
//! atoms in order; a topology with another count is refused, naming both files and both counts.

use super::atoms::{select_atom_indices, Atom};
use super::file::ByteSource;
pub use super::frame_source::Trajectory;
use super::frame_source::{finish_frame, past_the_end, Frame, FrameInfo, FrameSource};
use super::{Format, IncludeSpec, LoadedParticles, ParticleRecord, FORMATS};
use crate::error::{PgtError, Result};
use glam::DVec3;
use std::path::Path;

/// Opens a trajectory file by its extension; another extension is an error listing the known.
pub fn open_trajectory_file(path: &Path) -> Result<Box<dyn Trajectory>> {
    let Some(open) = Format::trajectory_of(path).and_then(|f| f.trajectory) else {
        let known: Vec<String> = FORMATS
            .iter()
            .filter(|f| f.trajectory.is_some())
            .flat_map(|f| f.extensions.iter().map(|e| format!(".{e}")))
            .collect();
        return Err(PgtError::in_file(
            path,
            format!(
                "unsupported trajectory file type: expected {}",
                known.join(", ")
            ),
        ));
    };
    open(ByteSource::open(path)?)
}

/// The atoms of a topology file's first model, read as its extension says (PDB, mmCIF, GRO or
/// PSF).
pub fn topology_atoms(path: &Path) -> Result<(Vec<Atom>, Vec<String>)> {
    let bytes = super::read_input(path)?;
    let Some(read_atoms) = Format::topology_of(path).and_then(|f| f.topology) else {
        return Err(not_a_topology(path));
    };
    let (atoms, warnings) = read_atoms(path, &bytes)?;
    let first = atoms.first().map(|a| a.model);
    let atoms: Vec<Atom> = atoms
        .into_iter()
        .filter(|a| Some(a.model) == first)
        .collect();
    if atoms.is_empty() {
        return Err(PgtError::in_file(path, "the topology holds no atoms"));
    }
    Ok((atoms, warnings))
}

/// The error for a topology of another extension, naming each topology format by its first
/// extension (`a .pdb, .cif, .gro or .psf file`).
fn not_a_topology(path: &Path) -> PgtError {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or_default()
        .to_ascii_lowercase();
    let first: Vec<String> = FORMATS
        .iter()
        .filter(|f| f.topology.is_some())
        .filter_map(|f| f.extensions.first().map(|e| format!(".{e}")))
        .collect();
    let known = match first.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => first.concat(),
    };
    PgtError::in_file(
        path,
        format!(
            "unsupported topology file type '.{ext}': a trajectory's `path` is its topology, a {known} file"
        ),
    )
}

/// A trajectory with its topology as a [`FrameSource`]: the topology's records (radius, colour)
/// with the trajectory's positions of each frame.
struct TopologyTrajectory {
    spec: IncludeSpec,
    trajectory: Box<dyn Trajectory>,
    /// The kept atoms' records (centres replaced per frame).
    records: Vec<ParticleRecord>,
    /// For each record, its atom's index in a frame.
    atom_index: Vec<usize>,
    warnings: Vec<String>,
}

/// Opens `trajectory` with the topology `spec.path` (docs/design.md §10). The include's
/// selections (`chains`, `skip_water`, `skip_hydrogen`) pick atoms of the topology; the atom
/// counts of the topology and the trajectory must agree.
pub fn open_trajectory(spec: &IncludeSpec, trajectory: &Path) -> Result<Box<dyn FrameSource>> {
    let traj = open_trajectory_file(trajectory)?;
    let (atoms, mut warnings) = topology_atoms(&spec.path)?;
    if atoms.len() != traj.atoms() {
        return Err(PgtError::in_file(
            trajectory,
            format!(
                "the trajectory has {} atoms per frame, but its topology {} has {} atoms{}",
                traj.atoms(),
                spec.path.display(),
                atoms.len(),
                if atoms.iter().any(|a| a.model != 1) {
                    " (in its first model)"
                } else {
                    ""
                }
            ),
        ));
    }
    let atom_index = select_atom_indices(spec, &atoms)?;
    let kept: Vec<Atom> = atom_index
        .iter()
        .filter_map(|&i| atoms.get(i).cloned())
        .collect();
    let records = super::atoms::make_records(spec, kept, &mut warnings);
    warnings.extend(traj.warnings());
    Ok(Box::new(TopologyTrajectory {
        spec: spec.clone(),
        trajectory: traj,
        records,
        atom_index,
        warnings,
    }))
}

impl FrameSource for TopologyTrajectory {
    fn path(&self) -> &Path {
        self.trajectory.path()
    }
    fn info(&self) -> FrameInfo {
        FrameInfo {
            count: self.trajectory.frames(),
            atoms_per_frame: Some(self.trajectory.atoms()),
            time_step_ps: self.trajectory.time_step_ps(),
        }
    }
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }
    fn read_frame(&self, index: usize) -> Result<Frame> {
        let path = self.trajectory.path();
        if index >= self.trajectory.frames() {
            return Err(past_the_end(path, index, self.trajectory.frames()));
        }
        let mut positions = Vec::new();
        let time_ps = self.trajectory.read_positions(index, &mut positions)?;
        let mut records = self.records.clone();
        for (r, &i) in records.iter_mut().zip(&self.atom_index) {
            r.center = positions
                .get(i)
                .copied()
                .ok_or_else(|| PgtError::in_file(path, format!("frame {index} has no atom {i}")))?;
        }
        let loaded = LoadedParticles {
            records,
            warnings: Vec::new(),
            sh: None,
        };
        Ok(Frame {
            index,
            time_ps,
            particles: finish_frame(&self.spec, path, index, loaded)?,
        })
    }
}

/// A trajectory alone (`pgt info md.xtc`): its frame facts and the positions of its first frame.
pub fn trajectory_summary(path: &Path) -> Result<(FrameInfo, Vec<DVec3>, Vec<String>)> {
    let traj = open_trajectory_file(path)?;
    let mut first = Vec::new();
    if traj.frames() > 0 {
        traj.read_positions(0, &mut first)?;
    }
    Ok((
        FrameInfo {
            count: traj.frames(),
            atoms_per_frame: Some(traj.atoms()),
            time_step_ps: traj.time_step_ps(),
        },
        first,
        traj.warnings(),
    ))
}
