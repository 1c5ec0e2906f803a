//! PDB (wwPDB format 3.3, fixed columns): `ATOM`/`HETATM` records become spheres with van der
//! Waals radii; `MODEL`/`ENDMDL` separate models. Everything else (`ANISOU`, `HEADER`, `CONECT`,
//! …) is ignored.
//!
//! Columns read (1-based, inclusive): name 13–16, altLoc 17, resName 18–20, chainID 22,
//! resSeq+iCode 23–27, x 31–38, y 39–46, z 47–54, occupancy 55–60 (1.0 if blank), element 77–78.
//! Where the element columns are blank or hold something else (old files put an ID and a line
//! number in 73–80, MD snapshots leave them empty), the element is inferred from the atom name
//! ([`super::atoms::infer_element`]). pdbtbx was not used: pgt needs the file and line of every
//! error and the lenient handling of those old files.

use super::atoms::{atoms_to_particles, infer_element, Atom};
use super::elements::Element;
use super::file::{columns, lines, scan_lines, ByteSource};
use super::frame_source::{finish_frame, Frame, FrameInfo, FrameSource, TextFrames};
use super::{Format, IncludeSpec, LoadedParticles};
use crate::error::{PgtError, Result};
use glam::DVec3;
use std::path::Path;

/// PDB in the table of formats ([`super::FORMATS`]).
pub const FORMAT: Format = Format {
    name: "pdb",
    extensions: &["pdb", "ent"],
    description: "PDB (wwPDB format 3.3, fixed columns)",
    particles: "ATOM or HETATM records",
    read: Some(read),
    details: Some(details),
    frames: Some(open_frames),
    topology: Some(read_atoms),
    ..Format::NOTHING
};

/// The [`super::Reader`] of PDB: every atom record, then the include's selections
/// ([`atoms_to_particles`]).
pub fn read(spec: &IncludeSpec, bytes: &[u8]) -> Result<LoadedParticles> {
    let (atoms, warnings) = read_atoms(&spec.path, bytes)?;
    atoms_to_particles(spec, atoms, warnings)
}

/// The [`super::Details`] of PDB: models and chains ([`super::atoms::details`]).
fn details(path: &Path, bytes: &[u8]) -> Result<serde_json::Map<String, serde_json::Value>> {
    Ok(super::atoms::details(&read_atoms(path, bytes)?.0))
}

/// Reads every atom of every model of a PDB file's text.
pub fn read_atoms(path: &Path, bytes: &[u8]) -> Result<(Vec<Atom>, Vec<String>)> {
    read_atoms_from(path, bytes, 1)
}

/// [`read_atoms`] of a piece of a file whose first line is line `first_line` of the file.
fn read_atoms_from(
    path: &Path,
    bytes: &[u8],
    first_line: usize,
) -> Result<(Vec<Atom>, Vec<String>)> {
    let mut atoms = Vec::new();
    let warnings = Vec::new();
    let mut model = 1i64;
    for (line_no, raw) in lines(bytes, first_line) {
        let record = columns(raw, 1, 6);
        match record.trim_end() {
            "ATOM" | "HETATM" => atoms.push(atom(
                path,
                raw,
                line_no,
                model,
                record.starts_with("HETATM"),
            )?),
            "MODEL" => {
                let rest = String::from_utf8_lossy(raw.get(6..).unwrap_or_default())
                    .trim()
                    .to_string();
                model = rest
                    .split_whitespace()
                    .next()
                    .and_then(|s| s.parse().ok())
                    .ok_or_else(|| {
                        PgtError::at_line(
                            path,
                            line_no,
                            format!("expected a model number after MODEL, found '{rest}'"),
                        )
                    })?;
            }
            _ => {}
        }
    }
    Ok((atoms, warnings))
}

/// The [`super::OpenFrames`] of PDB: one frame per `MODEL` record, found by one scan at open
/// (frame 0 also holds what comes before the first `MODEL`); a file without `MODEL` records is
/// one frame. Each frame's lines are read and parsed when it is asked for, as a file of one
/// model ([`atoms_to_particles`] with the include's other selections).
pub fn open_frames(spec: &IncludeSpec, source: ByteSource) -> Result<Box<dyn FrameSource>> {
    let mut text = TextFrames::default();
    scan_lines(&source, |line, at, raw| {
        if raw.starts_with(b"MODEL") && (raw.len() == 5 || raw.get(5) == Some(&b' ')) {
            if text.starts.is_empty() {
                text.starts.push(0);
                text.lines.push(1);
            } else {
                text.starts.push(at);
                text.lines.push(line);
            }
        }
        Ok(true)
    })?;
    if text.starts.is_empty() {
        text.starts.push(0);
        text.lines.push(1);
    }
    Ok(Box::new(PdbFrames {
        spec: spec.clone(),
        source,
        text,
    }))
}

/// The models of a PDB file as frames ([`open_frames`]).
struct PdbFrames {
    spec: IncludeSpec,
    source: ByteSource,
    text: TextFrames,
}

impl FrameSource for PdbFrames {
    fn path(&self) -> &Path {
        self.source.path()
    }
    fn info(&self) -> FrameInfo {
        self.text.info()
    }
    fn read_frame(&self, index: usize) -> Result<Frame> {
        let path = self.source.path();
        let (bytes, first_line) = self.text.read(&self.source, index)?;
        let (atoms, warnings) = read_atoms_from(path, &bytes, first_line)?;
        let mut spec = self.spec.clone();
        spec.path = path.to_path_buf();
        spec.model = None;
        let loaded = atoms_to_particles(&spec, atoms, warnings)?;
        let particles = finish_frame(&spec, path, index, loaded)?;
        Ok(Frame {
            index,
            time_ps: None,
            particles,
        })
    }
}

fn coordinate(
    path: &Path,
    line: &[u8],
    line_no: usize,
    axis: &str,
    from: usize,
    to: usize,
) -> Result<f64> {
    let text = columns(line, from, to);
    let v: f64 = text.trim().parse().map_err(|_| {
        PgtError::at_line(
            path,
            line_no,
            format!(
                "expected the {axis} coordinate (a number) in columns {from}–{to}, found '{}'",
                text.trim()
            ),
        )
    })?;
    if !v.is_finite() {
        return Err(PgtError::at_line(
            path,
            line_no,
            format!(
                "the {axis} coordinate in columns {from}–{to} is not finite: '{}'",
                text.trim()
            ),
        ));
    }
    Ok(v)
}

fn atom(path: &Path, raw: &[u8], line_no: usize, model: i64, hetatm: bool) -> Result<Atom> {
    let x = coordinate(path, raw, line_no, "x", 31, 38)?;
    let y = coordinate(path, raw, line_no, "y", 39, 46)?;
    let z = coordinate(path, raw, line_no, "z", 47, 54)?;
    let occ_text = columns(raw, 55, 60);
    let occupancy = if occ_text.trim().is_empty() {
        1.0
    } else {
        match occ_text.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => v,
            _ => {
                return Err(PgtError::at_line(
                    path,
                    line_no,
                    format!(
                        "expected the occupancy (a number) in columns 55–60, found '{}'",
                        occ_text.trim()
                    ),
                ))
            }
        }
    };
    let name_field = columns(raw, 13, 16);
    let element_field = columns(raw, 77, 78);
    let element = if element_field
        .trim()
        .chars()
        .all(|c| c.is_ascii_alphabetic())
        && !element_field.trim().is_empty()
    {
        Element::from_symbol(&element_field).or_else(|| infer_element(&name_field, hetatm))
    } else {
        infer_element(&name_field, hetatm)
    };
    let alt = columns(raw, 17, 17);
    let alt = alt.trim();
    Ok(Atom {
        position: DVec3::new(x, y, z),
        element,
        name: name_field.trim().to_string(),
        alt_loc: (!alt.is_empty()).then(|| alt.to_string()),
        occupancy,
        residue_name: columns(raw, 18, 20).trim().to_string(),
        chain: columns(raw, 22, 22).trim().to_string(),
        residue: columns(raw, 23, 27).into_owned(),
        model,
        line: line_no,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const LINE: &str =
        "ATOM      2  CA  ALA A   2      63.914 -67.078 -16.894  1.00 17.23           C  ";

    #[test]
    fn reads_columns() {
        let (atoms, _) = read_atoms(Path::new("t.pdb"), LINE.as_bytes()).expect("parses");
        let a = &atoms[0];
        assert_eq!(a.position, DVec3::new(63.914, -67.078, -16.894));
        assert_eq!(a.element.map(Element::symbol), Some("C"));
        assert_eq!(a.chain, "A");
        assert_eq!(a.name, "CA");
    }

    #[test]
    fn short_line_is_an_error_with_line() {
        let text = format!("HEADER\n{}\n", &LINE[..40]);
        let e = read_atoms(Path::new("t.pdb"), text.as_bytes())
            .expect_err("short")
            .to_string();
        assert!(e.contains("t.pdb:2") && e.contains("y coordinate"), "{e}");
    }

    #[test]
    fn models_are_frames_with_file_lines_also_with_crlf() {
        let text = format!(
            "HEADER x\r\nMODEL        1\r\n{LINE}\r\nENDMDL\r\nMODEL        2\r\n{}\r\nENDMDL\r\n",
            LINE.replace("63.914", "99.000")
        );
        let spec = IncludeSpec::bare(Path::new("m.pdb"));
        let source = ByteSource::from_bytes(Path::new("m.pdb"), text.into_bytes());
        let frames = open_frames(&spec, source).expect("opens");
        assert_eq!(frames.info().count, 2);
        let f = frames.read_frame(1).expect("frame 1");
        assert_eq!(f.particles.records[0].center.x, 99.0);
        assert_eq!(
            f.particles.records[0].location,
            crate::error::Location::Line(6)
        );
        let e = frames.read_frame(2).unwrap_err().to_string();
        assert!(e.contains("frame 2") && e.contains("2 frame"), "{e}");
    }

    #[test]
    fn nan_is_an_error() {
        let text = LINE.replace("63.914", "   NaN");
        let e = read_atoms(Path::new("t.pdb"), text.as_bytes())
            .expect_err("nan")
            .to_string();
        assert!(e.contains("t.pdb:1") && e.contains("not finite"), "{e}");
    }
}
