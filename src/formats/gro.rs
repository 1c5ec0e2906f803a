//! GROMACS GRO files (a structure in nm): a title line, the atom count, one fixed-column line per
//! atom and the box line. A particle file of its own and the usual topology of an XTC
//! trajectory (docs/design.md §10).
//!
//! Atom lines (0-based columns): residue number 0–4, residue name 5–9, atom name 10–14, atom
//! number 15–19, then x, y, z in fields of width w from column 20 (w = 8, `%8.3f`; files written
//! with more decimals have wider fields, and w is the distance between the first two decimal
//! points, as GROMACS reads it), then optional velocities (ignored). Positions are converted
//! from nm to Å (× 10), so that van der Waals radii by element fit. Elements come from atom and
//! residue names ([`super::atoms::md_element`]); GRO has no chains (every atom is in chain "").
//! A GRO file holding several frames back to back is read for its first. The box line (3 or 9
//! numbers) must be present: a file cut short is refused.

use super::atoms::{atoms_to_particles, md_element, Atom};
use super::file::lines;
use super::{Format, IncludeSpec, LoadedParticles};
use crate::error::{PgtError, Result};
use glam::DVec3;
use std::path::Path;

/// Å per nm: GRO and XTC store nm, pgt's molecular units are Å.
pub const ANGSTROM_PER_NM: f64 = 10.0;

/// GRO in the table of formats ([`super::FORMATS`]).
pub const FORMAT: Format = Format {
    name: "gro",
    extensions: &["gro"],
    description: "GROMACS GRO (fixed columns, nm)",
    particles: "atom lines",
    read: Some(read),
    topology: Some(read_atoms),
    ..Format::NOTHING
};

/// The [`super::Reader`] of GRO: every atom, then the include's selections (`chains` do not
/// apply: GRO has none).
pub fn read(spec: &IncludeSpec, bytes: &[u8]) -> Result<LoadedParticles> {
    let (atoms, warnings) = read_atoms(&spec.path, bytes)?;
    atoms_to_particles(spec, atoms, warnings)
}

/// The width of a coordinate field: the distance between the first two decimal points after
/// column 20, or 8.
fn field_width(line: &[u8]) -> usize {
    let dots: Vec<usize> = line
        .iter()
        .enumerate()
        .skip(20)
        .filter(|(_, &b)| b == b'.')
        .map(|(i, _)| i)
        .take(2)
        .collect();
    match dots.as_slice() {
        [a, b] if (4..=20).contains(&(b - a)) => b - a,
        _ => 8,
    }
}

/// Columns `from..to` of a line (0-based, end excluded, as the module doc numbers them),
/// trimmed.
fn columns(line: &[u8], from: usize, to: usize) -> String {
    super::file::columns(line, from + 1, to).trim().to_string()
}

/// Reads the atoms of the first frame of a GRO file, positions in Å.
pub fn read_atoms(path: &Path, bytes: &[u8]) -> Result<(Vec<Atom>, Vec<String>)> {
    let mut lines = lines(bytes, 1);
    if lines.next().is_none() || bytes.is_empty() {
        return Err(PgtError::in_file(
            path,
            "empty GRO file: expected a title line",
        ));
    }
    let Some((count_line, count_text)) = lines.next() else {
        return Err(PgtError::at_line(
            path,
            1,
            "expected the atom count on line 2, found the end of the file",
        ));
    };
    let count_text = String::from_utf8_lossy(count_text).trim().to_string();
    let n: usize = count_text.parse().map_err(|_| {
        PgtError::at_line(
            path,
            count_line,
            format!("expected the atom count (an integer), found '{count_text}'"),
        )
    })?;
    if n > bytes.len() / 20 {
        return Err(PgtError::at_line(
            path,
            count_line,
            format!(
                "the atom count {n} is larger than the file can hold ({} bytes)",
                bytes.len()
            ),
        ));
    }
    let mut atoms = Vec::with_capacity(n);
    let mut width = 8;
    for k in 0..n {
        let atom_line = lines
            .next()
            .filter(|(_, l)| !l.iter().all(u8::is_ascii_whitespace));
        let Some((line_no, line)) = atom_line else {
            return Err(PgtError::at_line(
                path,
                count_line,
                format!("the file announces {n} atoms but ends after {k}"),
            ));
        };
        if k == 0 {
            width = field_width(line);
        }
        atoms.push(atom(path, line_no, line, width)?);
    }
    let box_line = lines
        .next()
        .filter(|(_, l)| !l.iter().all(u8::is_ascii_whitespace));
    let Some((box_no, box_text)) = box_line else {
        return Err(PgtError::in_file(
            path,
            format!("expected the box line after the {n} atoms, found the end of the file (a truncated file?)"),
        ));
    };
    let numbers = String::from_utf8_lossy(box_text)
        .split_whitespace()
        .filter(|w| w.parse::<f64>().is_ok())
        .count();
    if numbers < 3 {
        return Err(PgtError::at_line(
            path,
            box_no,
            format!(
                "expected the box line (3 or 9 numbers) after the {n} atoms, found '{}'",
                String::from_utf8_lossy(box_text).trim()
            ),
        ));
    }
    Ok((atoms, Vec::new()))
}

fn atom(path: &Path, line_no: usize, line: &[u8], width: usize) -> Result<Atom> {
    let mut xyz = [0.0f64; 3];
    for (axis, v) in xyz.iter_mut().enumerate() {
        let from = 20 + axis * width;
        let text = columns(line, from, from + width);
        let value: f64 = text.parse().map_err(|_| {
            PgtError::at_line(
                path,
                line_no,
                format!(
                    "expected the {} coordinate (a number, nm) in columns {}–{}, found '{text}'",
                    ["x", "y", "z"][axis],
                    from + 1,
                    from + width
                ),
            )
        })?;
        if !value.is_finite() {
            return Err(PgtError::at_line(
                path,
                line_no,
                format!(
                    "the {} coordinate is not finite: '{text}'",
                    ["x", "y", "z"][axis]
                ),
            ));
        }
        *v = value * ANGSTROM_PER_NM;
    }
    let residue_name = columns(line, 5, 10);
    let name = columns(line, 10, 15);
    Ok(Atom {
        position: DVec3::from(xyz),
        element: md_element(&name, &residue_name),
        name,
        alt_loc: None,
        occupancy: 1.0,
        residue_name,
        chain: String::new(),
        residue: columns(line, 0, 5),
        model: 1,
        line: line_no,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const GRO: &str = "water\n    3\n    1SOL     OW    1   0.126   1.624   1.679\n    1SOL    HW1    2   0.190   1.661   1.747\n    2NA      NA    3   1.000   2.000   3.000\n   1.86206   1.86206   1.86206\n";

    #[test]
    fn reads_atoms_in_angstrom_with_elements() {
        let (atoms, _) = read_atoms(Path::new("w.gro"), GRO.as_bytes()).expect("ok");
        assert_eq!(atoms.len(), 3);
        assert!((atoms[0].position - DVec3::new(1.26, 16.24, 16.79)).length() < 1e-12);
        let el: Vec<&str> = atoms
            .iter()
            .map(|a| a.element.map_or("?", |e| e.symbol()))
            .collect();
        assert_eq!(el, ["O", "H", "Na"]);
        assert_eq!(atoms[2].line, 5);
    }

    #[test]
    fn wide_fields_follow_the_decimal_points() {
        let text = "t\n1\n    1SOL     OW    1   0.12600   1.62400   1.67900\n1 1 1\n";
        let (atoms, _) = read_atoms(Path::new("w.gro"), text.as_bytes()).expect("ok");
        assert!((atoms[0].position - DVec3::new(1.26, 16.24, 16.79)).length() < 1e-12);
    }

    #[test]
    fn truncated_and_bad_files_are_errors_with_lines() {
        let cut = &GRO[..GRO.find("   1.86206").unwrap_or(0)];
        let e = read_atoms(Path::new("w.gro"), cut.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(e.contains("box line"), "{e}");
        let e = read_atoms(Path::new("w.gro"), GRO.replace("1.661", "x.xxx").as_bytes())
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("w.gro:4") && e.contains("y coordinate"),
            "{e}"
        );
        let e = read_atoms(Path::new("w.gro"), b"t\n99999999\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("larger than the file"), "{e}");
    }
}
