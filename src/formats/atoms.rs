//! What PDB and mmCIF share once their syntax is read: a list of atoms, and the selection and
//! colouring of docs/design.md §1 / §6 (model, alternate locations, chains, waters, hydrogens,
//! `color_by`).

use super::elements::{element_color, element_radius, srgb8_hex_to_linear, Element};
use super::LoadedParticles;
use super::{ColorBy, IncludeSpec, ParticleRecord};
use crate::error::{Location, PgtError, Result};
use glam::DVec3;
use std::collections::{BTreeSet, HashMap};

/// One atom record as read from a structure file.
#[derive(Debug, Clone)]
pub struct Atom {
    /// Position in Å.
    pub position: DVec3,
    /// The element, if the file names one or it can be inferred from the atom name.
    pub element: Option<Element>,
    /// Atom name (`CA`, `1HB`), trimmed.
    pub name: String,
    /// Alternate location indicator (`None` for blank, `.` or `?`).
    pub alt_loc: Option<String>,
    /// Occupancy (1 where the file leaves it blank).
    pub occupancy: f64,
    /// Residue name (`ALA`, `HOH`).
    pub residue_name: String,
    /// Chain identifier, trimmed (may be empty).
    pub chain: String,
    /// Residue number with insertion code, as written (identifies the residue within the chain).
    pub residue: String,
    /// Model number as written (1 where the file has no models).
    pub model: i64,
    /// 1-based line of the record.
    pub line: usize,
}

/// Residue names of water (PDB, Amber, CHARMM, GROMACS spellings).
const WATER_NAMES: &[&str] = &[
    "HOH", "WAT", "H2O", "DOD", "D2O", "TIP", "TIP3", "TIP4", "SPC", "SOL",
];

/// Chain colours, 8-bit sRGB: the Okabe–Ito colour-blind-safe set followed by Tableau 10;
/// chain i (in order of first appearance) gets entry i mod the length.
const CHAIN_PALETTE_SRGB8: &[u32] = &[
    0xE69F00, 0x56B4E9, 0x009E73, 0xF0E442, 0x0072B2, 0xD55E00, 0xCC79A7, 0x999999, 0x4E79A7,
    0xF28E2B, 0xE15759, 0x76B7B2, 0x59A14F, 0xEDC948, 0xB07AA1, 0xFF9DA7, 0x9C755F, 0xBAB0AC,
];

/// Whether a residue name is water.
pub fn is_water(residue_name: &str) -> bool {
    WATER_NAMES
        .iter()
        .any(|w| w.eq_ignore_ascii_case(residue_name.trim()))
}

/// Infers the element from a PDB-style atom name (four characters, element right-justified in the
/// first two) when the file has no element column: leading digits and blanks are skipped
/// (`1HB ` → H); a two-letter element is taken only for HETATM records whose name starts in the
/// first column (` FE ` would be right-justified, `FE  ` is iron, `CA  ` in a HETATM is calcium),
/// otherwise the first letter (`CA` in an ATOM record is the α carbon, `HD21` is hydrogen).
pub fn infer_element(name: &str, hetatm: bool) -> Option<Element> {
    let chars: Vec<char> = name.chars().collect();
    let first_is_letter = chars.first().is_some_and(|c| c.is_ascii_alphabetic());
    // A full-width name starting with H (`HG21`, `HO2A`) is a hydrogen, not mercury or holmium;
    // after a two-letter element only digits or blanks may follow (`FE1`, `CL2`).
    let full_width_h =
        chars.len() >= 4 && chars.iter().all(|c| !c.is_whitespace()) && chars.first() == Some(&'H');
    let rest_plain = chars
        .iter()
        .skip(2)
        .all(|c| c.is_ascii_digit() || c.is_whitespace());
    if hetatm
        && first_is_letter
        && !full_width_h
        && rest_plain
        && chars.get(1).is_some_and(|c| c.is_ascii_alphabetic())
    {
        let two: String = chars.iter().take(2).collect();
        if let Some(e) = Element::from_symbol(&two) {
            return Some(e);
        }
    }
    let first = chars.iter().find(|c| c.is_ascii_alphabetic())?;
    Element::from_symbol(&first.to_string())
}

/// Residue names of single-atom ions in CHARMM and GROMACS force fields, with their element.
const ION_RESIDUES: &[(&str, &str)] = &[
    ("SOD", "Na"),
    ("NA+", "Na"),
    ("CLA", "Cl"),
    ("CL-", "Cl"),
    ("POT", "K"),
    ("K+", "K"),
    ("CAL", "Ca"),
    ("CA2+", "Ca"),
    ("MG2+", "Mg"),
    ("ZN2", "Zn"),
    ("ZN2+", "Zn"),
    ("LIT", "Li"),
    ("CES", "Cs"),
    ("RUB", "Rb"),
    ("BAR", "Ba"),
    ("CD2", "Cd"),
];

/// The element of an atom of an MD topology (GRO, PSF), which names atoms without an element
/// column: a single-atom ion residue ([`ION_RESIDUES`], or an atom named like its residue with a
/// two-letter element symbol: `NA`/`NA`, `CL`/`CL`), else the atom name as a PDB ATOM record's
/// ([`infer_element`]: `CA` is the α carbon, `OW` oxygen, `HW1` hydrogen).
pub fn md_element(atom_name: &str, residue_name: &str) -> Option<Element> {
    let res = residue_name.trim();
    let name = atom_name.trim();
    if let Some((_, e)) = ION_RESIDUES
        .iter()
        .find(|(r, _)| r.eq_ignore_ascii_case(res))
    {
        return Element::from_symbol(e);
    }
    if name.eq_ignore_ascii_case(res) && name.len() == 2 {
        if let Some(e) = Element::from_symbol(name) {
            return Some(e);
        }
    }
    infer_element(name, false)
}

/// Applies the selections of `spec` to `atoms` (all models, all alternate locations) and makes
/// particles with van der Waals radii; `radius_scale` is applied later by
/// [`super::load_bytes`]. A file without atoms gives no records (the caller refuses it); a
/// selection that leaves none is an error naming the selection.
pub fn atoms_to_particles(
    spec: &IncludeSpec,
    atoms: Vec<Atom>,
    mut warnings: Vec<String>,
) -> Result<LoadedParticles> {
    if atoms.is_empty() {
        return Ok(LoadedParticles {
            records: Vec::new(),
            warnings,
            sh: None,
        });
    }
    let model = select_model(spec, &atoms, &mut warnings)?;
    check_chains_present(spec, &atoms, model)?;
    let kept = resolve_alternate_locations(&spec.path, atoms, model, &mut warnings);
    let kept = apply_filters(spec, kept, model)?;
    let records = make_records(spec, kept, &mut warnings);
    Ok(LoadedParticles {
        records,
        warnings,
        sh: None,
    })
}

/// The model numbers in order of first appearance.
fn models_of(atoms: &[Atom]) -> Vec<i64> {
    let mut seen = Vec::new();
    for a in atoms {
        if !seen.contains(&a.model) {
            seen.push(a.model);
        }
    }
    seen
}

/// `model = N`: the requested model (an error if the file lacks it), or the first that appears
/// (with a warning where there are several).
fn select_model(spec: &IncludeSpec, atoms: &[Atom], warnings: &mut Vec<String>) -> Result<i64> {
    let path = &spec.path;
    let models = models_of(atoms);
    let model = match spec.model {
        Some(m) => {
            let m = i64::try_from(m).unwrap_or(i64::MAX);
            if !models.contains(&m) {
                return Err(PgtError::in_file(
                    path,
                    format!(
                        "model {m} is not in the file (it has model{} {})",
                        if models.len() == 1 { "" } else { "s" },
                        list(models.iter())
                    ),
                ));
            }
            m
        }
        None => models.first().copied().unwrap_or(1),
    };
    if spec.model.is_none() && models.len() > 1 {
        warnings.push(format!(
            "{}: the file has {} models; using model {model} (set `model = N` to choose)",
            path.display(),
            models.len()
        ));
    }
    Ok(model)
}

/// `chains = [...]`: every chain asked for must exist in the model (a typo is an error, not an
/// empty selection).
fn check_chains_present(spec: &IncludeSpec, atoms: &[Atom], model: i64) -> Result<()> {
    let Some(chains) = &spec.chains else {
        return Ok(());
    };
    let present: BTreeSet<&str> = atoms
        .iter()
        .filter(|a| a.model == model)
        .map(|a| a.chain.as_str())
        .collect();
    let missing: Vec<&String> = chains
        .iter()
        .filter(|c| !present.contains(c.as_str()))
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    Err(PgtError::in_file(
        &spec.path,
        format!(
            "chain{} {} not in model {model} (it has chains {})",
            if missing.len() == 1 { " is" } else { "s are" },
            list(missing.iter()),
            list(present.iter())
        ),
    ))
}

/// The atoms of `model` with alternate locations resolved: per (chain, residue, atom name), the
/// highest occupancy wins; ties go to altLoc 'A', then to the first in the file. The kept atom
/// takes the place of the first.
fn resolve_alternate_locations(
    path: &std::path::Path,
    atoms: Vec<Atom>,
    model: i64,
    warnings: &mut Vec<String>,
) -> Vec<Atom> {
    let mut kept: Vec<Atom> = Vec::new();
    let mut group: HashMap<(String, String, String), usize> = HashMap::new();
    let mut alt_groups = 0usize;
    for a in atoms.into_iter().filter(|a| a.model == model) {
        if a.alt_loc.is_none() {
            kept.push(a);
            continue;
        }
        let key = (a.chain.clone(), a.residue.clone(), a.name.clone());
        match group.get(&key) {
            None => {
                group.insert(key, kept.len());
                alt_groups += 1;
                kept.push(a);
            }
            Some(&i) => {
                if let Some(k) = kept.get_mut(i) {
                    let better = a.occupancy > k.occupancy
                        || (a.occupancy == k.occupancy
                            && a.alt_loc.as_deref() == Some("A")
                            && k.alt_loc.as_deref() != Some("A"));
                    if better {
                        *k = a;
                    }
                }
            }
        }
    }
    if alt_groups > 0 {
        warnings.push(format!(
            "{}: {alt_groups} atoms have alternate locations; kept the one with the highest occupancy of each",
            path.display()
        ));
    }
    kept
}

/// The include's filters in order (`chains`, `skip_water`, `skip_hydrogen`). One that removes
/// every atom still left is an error naming it (an include that yields nothing is nearly
/// always a mistake), with the count each earlier filter kept.
fn apply_filters(spec: &IncludeSpec, mut atoms: Vec<Atom>, model: i64) -> Result<Vec<Atom>> {
    let atom_s = |n: usize| if n == 1 { "atom" } else { "atoms" };
    let mut story = format!("model {model} has {} {}", atoms.len(), atom_s(atoms.len()));
    let mut stage = |atoms: &mut Vec<Atom>, filter: String, keep: &dyn Fn(&Atom) -> bool| {
        atoms.retain(|a| keep(a));
        if atoms.is_empty() {
            return Err(PgtError::in_file(
                &spec.path,
                format!(
                    "the include holds no particles: {story}, and `{filter}` removes all of them"
                ),
            ));
        }
        story.push_str(&format!(", `{filter}` keeps {}", atoms.len()));
        Ok(())
    };
    if let Some(chains) = &spec.chains {
        stage(&mut atoms, format!("chains = {chains:?}"), &|a| {
            chains.contains(&a.chain)
        })?;
    }
    if spec.skip_water {
        stage(&mut atoms, "skip_water = true".into(), &|a| {
            !is_water(&a.residue_name)
        })?;
    }
    if spec.skip_hydrogen {
        stage(&mut atoms, "skip_hydrogen = true".into(), &|a| {
            !a.element.is_some_and(Element::is_hydrogen)
        })?;
    }
    Ok(atoms)
}

/// The indices (in `atoms`) of the atoms a trajectory include keeps: every atom (a topology has
/// one model and no alternate locations to resolve), less those the include's `chains`,
/// `skip_water` and `skip_hydrogen` remove. A chain asked for that is absent, or filters that
/// remove every atom, are errors naming the selection (as for a PDB include).
pub fn select_atom_indices(spec: &IncludeSpec, atoms: &[Atom]) -> Result<Vec<usize>> {
    let model = atoms.first().map_or(1, |a| a.model);
    check_chains_present(spec, atoms, model)?;
    let keep = |a: &Atom| {
        spec.chains.as_ref().is_none_or(|c| c.contains(&a.chain))
            && !(spec.skip_water && is_water(&a.residue_name))
            && !(spec.skip_hydrogen && a.element.is_some_and(Element::is_hydrogen))
    };
    let kept: Vec<usize> = atoms
        .iter()
        .enumerate()
        .filter(|(_, a)| keep(a))
        .map(|(i, _)| i)
        .collect();
    if kept.is_empty() {
        return Err(PgtError::in_file(
            &spec.path,
            format!(
                "the include holds no particles: the topology has {} atoms, and its selections (chains, skip_water, skip_hydrogen) remove all of them",
                atoms.len()
            ),
        ));
    }
    Ok(kept)
}

/// Spheres of the selected atoms: van der Waals radius of the element, colour by `color_by`
/// (chain colours in order of first appearance), with warnings for unknown elements and
/// elements without a tabulated radius.
pub(crate) fn make_records(
    spec: &IncludeSpec,
    atoms: Vec<Atom>,
    warnings: &mut Vec<String>,
) -> Vec<ParticleRecord> {
    let mut chain_index: HashMap<String, usize> = HashMap::new();
    let mut fallback_radius: BTreeSet<String> = BTreeSet::new();
    let mut unknown_element = 0usize;
    let mut records = Vec::with_capacity(atoms.len());
    for a in atoms {
        match a.element {
            None => unknown_element += 1,
            Some(e) if e.vdw_radius().is_none() => {
                fallback_radius.insert(e.symbol().to_string());
            }
            Some(_) => {}
        }
        let next = chain_index.len();
        let ci = *chain_index.entry(a.chain.clone()).or_insert(next);
        let color = match spec.color_by {
            ColorBy::Element => Some(element_color(a.element)),
            ColorBy::Chain => Some(srgb8_hex_to_linear(
                CHAIN_PALETTE_SRGB8
                    .get(ci % CHAIN_PALETTE_SRGB8.len())
                    .copied()
                    .unwrap_or(0xFFFFFF),
            )),
            ColorBy::Uniform => None,
        };
        records.push(ParticleRecord {
            ellipsoid: None,
            center: a.position,
            radius: element_radius(a.element),
            color,
            opacity: None,
            sigma: None,
            location: Location::Line(a.line),
        });
    }
    let path = spec.path.display();
    if unknown_element > 0 {
        warnings.push(format!(
            "{path}: {unknown_element} atoms have no recognisable element; they get radius {} Å",
            super::elements::FALLBACK_RADIUS
        ));
    }
    if !fallback_radius.is_empty() {
        warnings.push(format!(
            "{path}: no tabulated van der Waals radius for {}; used {} Å",
            list(fallback_radius.iter()),
            super::elements::FALLBACK_RADIUS
        ));
    }
    records
}

/// `pgt info` facts of PDB and mmCIF ([`super::Details`]): the model numbers, and the atom
/// records per chain in the first model (before alternate locations are resolved).
pub fn details(atoms: &[Atom]) -> serde_json::Map<String, serde_json::Value> {
    use serde_json::json;
    let models = models_of(atoms);
    let mut chains = serde_json::Map::new();
    for a in atoms.iter().filter(|a| Some(&a.model) == models.first()) {
        let n = chains.get(&a.chain).and_then(|v| v.as_u64()).unwrap_or(0);
        chains.insert(a.chain.clone(), json!(n + 1));
    }
    let mut d = serde_json::Map::new();
    d.insert("models".into(), json!(models));
    d.insert("chains".into(), serde_json::Value::Object(chains));
    d
}

fn list<T: std::fmt::Display>(items: impl Iterator<Item = T>) -> String {
    let v: Vec<String> = items.map(|c| format!("'{c}'")).collect();
    if v.is_empty() {
        "none".to_string()
    } else {
        v.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sym(name: &str, het: bool) -> Option<&'static str> {
        infer_element(name, het).map(Element::symbol)
    }

    #[test]
    fn infers_elements_from_names() {
        assert_eq!(sym(" CA ", false), Some("C"));
        assert_eq!(sym("CA  ", false), Some("C"));
        assert_eq!(sym("CA  ", true), Some("Ca"));
        assert_eq!(sym("FE  ", true), Some("Fe"));
        assert_eq!(sym("1HB ", false), Some("H"));
        assert_eq!(sym("HD21", false), Some("H"));
        assert_eq!(sym(" N  ", true), Some("N"));
        assert_eq!(sym("    ", true), None);
        assert_eq!(sym("1234", true), None);
        assert_eq!(sym("HO2A", true), Some("H"));
        assert_eq!(sym("CL1 ", true), Some("Cl"));
    }

    #[test]
    fn waters() {
        assert!(is_water("HOH"));
        assert!(is_water("wat"));
        assert!(!is_water("HOX"));
    }
}
