//! CHARMM/X-PLOR PSF topologies (the usual topology of a DCD trajectory, docs/design.md §10):
//! the `!NATOM` section only. A PSF has no coordinates, so it is a topology and not a particle
//! file of its own.
//!
//! After the line `N !NATOM` come N atom lines of whitespace-separated fields: atom ID, segment
//! ID, residue ID, residue name, atom name, atom type, charge, mass (and, in some files, more
//! columns, ignored). Whitespace splitting reads the standard, `EXT` and `XPLOR` layouts alike.
//! The segment is the chain (`color_by = "chain"`, `chains = [...]`). The element is the one
//! whose standard atomic mass is within [`MASS_TOLERANCE`] of the atom's mass (as VMD guesses
//! it), else the one the atom name suggests ([`super::atoms::md_element`]): heavy hydrogens
//! (hydrogen mass repartitioning) and lone pairs of mass 0 fall to their names.

use super::atoms::{md_element, Atom};
use super::elements::Element;
use super::file::text_lines;
use super::Format;
use crate::error::{PgtError, Result};
use glam::DVec3;
use std::path::Path;

/// PSF in the table of formats ([`super::FORMATS`]): a topology only.
pub const FORMAT: Format = Format {
    name: "psf",
    extensions: &["psf"],
    description: "CHARMM/X-PLOR PSF (the !NATOM section)",
    topology: Some(read_atoms),
    ..Format::NOTHING
};

/// How far (in u) an atom's mass may be from an element's standard atomic mass to be taken as
/// that element.
pub const MASS_TOLERANCE: f64 = 0.1;

/// Standard atomic masses (u, IUPAC 2021 abridged) of the elements that MD force fields use.
const MASSES: &[(&str, f64)] = &[
    ("H", 1.008),
    ("He", 4.0026),
    ("Li", 6.94),
    ("B", 10.81),
    ("C", 12.011),
    ("N", 14.007),
    ("O", 15.999),
    ("F", 18.998),
    ("Ne", 20.180),
    ("Na", 22.990),
    ("Mg", 24.305),
    ("Al", 26.982),
    ("Si", 28.085),
    ("P", 30.974),
    ("S", 32.06),
    ("Cl", 35.45),
    ("K", 39.098),
    ("Ar", 39.948),
    ("Ca", 40.078),
    ("Mn", 54.938),
    ("Fe", 55.845),
    ("Co", 58.933),
    ("Ni", 58.693),
    ("Cu", 63.546),
    ("Zn", 65.38),
    ("Se", 78.971),
    ("Br", 79.904),
    ("Rb", 85.468),
    ("Cd", 112.41),
    ("I", 126.90),
    ("Cs", 132.91),
    ("Ba", 137.33),
];

/// The element whose standard atomic mass is within [`MASS_TOLERANCE`] of `mass`.
pub fn element_of_mass(mass: f64) -> Option<Element> {
    MASSES
        .iter()
        .filter(|(_, m)| (m - mass).abs() <= MASS_TOLERANCE)
        .min_by(|a, b| (a.1 - mass).abs().total_cmp(&(b.1 - mass).abs()))
        .and_then(|(s, _)| Element::from_symbol(s))
}

/// Reads the atoms of a PSF file's `!NATOM` section (positions 0: a PSF has none).
pub fn read_atoms(path: &Path, bytes: &[u8]) -> Result<(Vec<Atom>, Vec<String>)> {
    let mut lines = text_lines(bytes, 1);
    let (natom_line, n) = loop {
        let Some((no, line)) = lines.next() else {
            return Err(PgtError::in_file(
                path,
                "not a PSF topology: no `!NATOM` section (expected a line `N !NATOM`)",
            ));
        };
        if line.contains("!NATOM") {
            let first = line
                .split_whitespace()
                .next()
                .unwrap_or_default()
                .to_string();
            let n: usize = first.parse().map_err(|_| {
                PgtError::at_line(
                    path,
                    no,
                    format!("expected the atom count before !NATOM, found '{first}'"),
                )
            })?;
            break (no, n);
        }
    };
    if n > bytes.len() / 16 {
        return Err(PgtError::at_line(
            path,
            natom_line,
            format!(
                "the atom count {n} is larger than the file can hold ({} bytes)",
                bytes.len()
            ),
        ));
    }
    let mut atoms = Vec::with_capacity(n);
    for k in 0..n {
        let Some((no, line)) = lines.next().filter(|(_, l)| !l.trim().is_empty()) else {
            return Err(PgtError::at_line(
                path,
                natom_line,
                format!("the !NATOM section announces {n} atoms but ends after {k}"),
            ));
        };
        atoms.push(atom(path, no, &line)?);
    }
    Ok((atoms, Vec::new()))
}

fn atom(path: &Path, no: usize, line: &str) -> Result<Atom> {
    let f: Vec<&str> = line.split_whitespace().collect();
    let [_, segment, residue, residue_name, name, _, _, mass, ..] = f.as_slice() else {
        return Err(PgtError::at_line(
            path,
            no,
            format!(
                "expected an atom line 'ID segment residue resname name type charge mass', found '{}'",
                line.trim()
            ),
        ));
    };
    let mass: f64 = match mass.parse::<f64>() {
        Ok(m) if m.is_finite() => m,
        _ => {
            return Err(PgtError::at_line(
                path,
                no,
                format!("expected the atom's mass (a number) in the 8th field, found '{mass}'"),
            ))
        }
    };
    Ok(Atom {
        position: DVec3::ZERO,
        element: element_of_mass(mass).or_else(|| md_element(name, residue_name)),
        name: (*name).to_string(),
        alt_loc: None,
        occupancy: 1.0,
        residue_name: (*residue_name).to_string(),
        chain: (*segment).to_string(),
        residue: (*residue).to_string(),
        model: 1,
        line: no,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const PSF: &str = "PSF CMAP\n\n       1 !NTITLE\n REMARKS x\n\n       3 !NATOM\n       1 ALA3 1        ALA      N        NH3   -0.300000       14.0070           0\n       2 ALA3 1        ALA      HT1      HC     0.330000        1.0080           0\n       3 WAT  2        TIP3     OH2      OT    -0.834000       15.9994           0\n\n       2 !NBOND: bonds\n";

    #[test]
    fn reads_atoms_elements_by_mass_and_segments_as_chains() {
        let (atoms, _) = read_atoms(Path::new("t.psf"), PSF.as_bytes()).expect("ok");
        let el: Vec<&str> = atoms
            .iter()
            .map(|a| a.element.map_or("?", |e| e.symbol()))
            .collect();
        assert_eq!(el, ["N", "H", "O"]);
        assert_eq!(atoms[2].chain, "WAT");
        assert_eq!(atoms[2].residue_name, "TIP3");
        assert_eq!(atoms[1].line, 8);
    }

    #[test]
    fn masses_and_names() {
        assert_eq!(element_of_mass(12.011).map(Element::symbol), Some("C"));
        assert_eq!(element_of_mass(40.08).map(Element::symbol), Some("Ca"));
        assert_eq!(element_of_mass(3.024), None);
        assert_eq!(element_of_mass(0.0), None);
    }

    #[test]
    fn bad_files_are_errors_with_lines() {
        let e = read_atoms(Path::new("t.psf"), b"PSF\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("!NATOM"), "{e}");
        let cut = &PSF[..PSF.find("       3 WAT").unwrap_or(0)];
        let e = read_atoms(Path::new("t.psf"), cut.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("t.psf:6") && e.contains("ends after 2"),
            "{e}"
        );
        let e = read_atoms(
            Path::new("t.psf"),
            PSF.replace("14.0070", "heavy").as_bytes(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("t.psf:7") && e.contains("mass"), "{e}");
    }
}
