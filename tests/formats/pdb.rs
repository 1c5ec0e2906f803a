//! PDB and mmCIF against the real files of `../shared/data/pdb` (SOURCES.md). Expected counts
//! come from SOURCES.md or from `grep`/`awk` over the file text (the command is given).

use crate::support::*;
use pgt::error::Location;
use pgt::scene::ColorBy;

/// (file, atoms with default options). Counts: SOURCES.md's ATOM+HETATM column, except 3al1:
/// 312 atoms with a blank altLoc + 179 distinct (chain, resSeq+iCode, name) among those with one
/// = 491 (`grep -E '^(ATOM  |HETATM)' 3al1.pdb | awk '{k=substr($0,22,6) substr($0,13,4);
/// if (substr($0,17,1)==" ") n++; else if (!(k in s)) {s[k]=1; m++}} END {print n+m}'`).
const COUNTS: &[(&str, usize)] = &[
    ("pdb/1uun_opm_oriented.pdb", 11032),
    ("pdb/1tii.pdb", 5684),
    ("pdb/1aon.pdb", 58870),
    ("pdb/1rx1.pdb", 1435),
    ("pdb/1hpv.pdb", 1631),
    ("pdb/3al1.pdb", 491),
    ("pdb/1tca_2050_megamol.pdb", 4622),
    ("pdb/3SN6.cif", 10274),
];

#[test]
fn every_structure_file_loads_with_the_right_count() {
    for (rel, n) in COUNTS {
        let Some(p) = shared(rel) else { continue };
        let l = load(&p);
        assert_eq!(l.records.len(), *n, "{rel}");
        // Every atom has a tabulated element (no fallback radius) in these files.
        assert!(
            !l.warnings
                .iter()
                .any(|w| w.contains("no recognisable element")),
            "{rel}: {:?}",
            l.warnings
        );
        assert!(
            l.records
                .iter()
                .all(|r| r.radius >= 1.2 && r.radius <= 2.31),
            "{rel}"
        );
    }
}

#[test]
fn uun_chains_a_and_b_are_the_thesis_count() {
    let p = shared_or_skip!("pdb/1uun_opm_oriented.pdb");
    let l = load_with(&p, |s| s.chains = Some(vec!["A".into(), "B".into()])).expect("loads");
    assert_eq!(l.records.len(), 2758);
    let e = load_with(&p, |s| s.chains = Some(vec!["Z".into()]))
        .expect_err("no chain Z")
        .to_string();
    assert!(
        e.contains("1uun_opm_oriented.pdb") && e.contains("'Z'"),
        "{e}"
    );
}

#[test]
fn positions_radii_colours_match_the_text() {
    let p = shared_or_skip!("pdb/1aon.pdb");
    let l = load(&p);
    // Line of the first ATOM record and its columns, read here from the text.
    let atoms = lines_where(&p, |l| l.starts_with("ATOM  ") || l.starts_with("HETATM"));
    for (k, (line, text)) in atoms.iter().enumerate().step_by(997) {
        let r = &l.records[k];
        assert_eq!(r.location, Location::Line(*line));
        let col = |a: usize, b: usize| text[a - 1..b].trim().parse::<f64>().expect("number");
        assert!(
            close3(r.center, [col(31, 38), col(39, 46), col(47, 54)], 1e-9),
            "line {line}"
        );
        let (radius, hex) = match text[76..78].trim() {
            "C" => (1.70, 0x909090),
            "N" => (1.55, 0x3050F8),
            "O" => (1.52, 0xFF0D0D),
            "S" => (1.80, 0xFFFF30),
            other => panic!("unexpected element {other} at line {line}"),
        };
        assert_eq!(r.radius, radius, "line {line}");
        assert!(
            close3(r.color.expect("coloured"), lin(hex), 1e-12),
            "line {line}"
        );
    }
}

#[test]
fn calcium_ion_gets_its_own_radius() {
    let p = shared_or_skip!("pdb/1rx1.pdb");
    let l = load(&p);
    let ca = lines_where(&p, |l| {
        l.starts_with("HETATM") && l.get(76..78) == Some("CA")
    });
    assert_eq!(ca.len(), 1);
    let r = l
        .records
        .iter()
        .find(|r| r.location == Location::Line(ca[0].0))
        .expect("Ca kept");
    assert_eq!(r.radius, 2.31);
    assert!(close3(r.color.expect("c"), lin(0x3DFF00), 1e-12));
}

#[test]
fn old_style_and_md_files_infer_elements() {
    // 1hpv: cols 77–78 hold digits; 1tca: blank. Hydrogens in 1tca: 2300 names whose first letter
    // after leading digits is H (`cut -c13-16 | awk '{n=$1; gsub(/^[0-9]+/,"",n); if (substr(n,1,1)=="H") h++}'`).
    if let Some(p) = shared("pdb/1tca_2050_megamol.pdb") {
        let l = load_with(&p, |s| s.skip_hydrogen = true).expect("loads");
        assert_eq!(l.records.len(), 4622 - 2300);
    }
    if let Some(p) = shared("pdb/1hpv.pdb") {
        let l = load(&p);
        // The ligand 478 has a sulphur S1: find its line and check the radius.
        let s1 = lines_where(&p, |l| {
            l.starts_with("HETATM") && l.get(12..16) == Some(" S1 ")
        });
        assert_eq!(s1.len(), 1);
        let r = l
            .records
            .iter()
            .find(|r| r.location == Location::Line(s1[0].0))
            .expect("kept");
        assert_eq!(r.radius, 1.80);
    }
}

#[test]
fn waters_can_be_skipped() {
    let p = shared_or_skip!("pdb/1tii.pdb");
    let l = load_with(&p, |s| s.skip_water = true).expect("loads");
    assert_eq!(l.records.len(), 5684 - 215);
}

#[test]
fn alternate_locations_keep_the_highest_occupancy() {
    let p = shared_or_skip!("pdb/3al1.pdb");
    let l = load(&p);
    let find = |alt: char, name: &str, res: &str| {
        let v = lines_where(&p, |l| {
            (l.starts_with("ATOM  ") || l.starts_with("HETATM"))
                && l.get(12..16) == Some(name)
                && l[16..17].starts_with(alt)
                && l.get(17..26) == Some(res)
        });
        assert_eq!(v.len(), 1, "{alt} {name} {res}");
        v[0].0
    };
    let has = |line: usize| l.records.iter().any(|r| r.location == Location::Line(line));
    // 2HZ LYS A 105: A 0.44, B 0.56 → B.
    assert!(has(find('B', "2HZ ", "LYS A 105")) && !has(find('A', "2HZ ", "LYS A 105")));
    // 2HG LYS B 205: A 0.38, B 0.30, C 0.32 → A.
    assert!(has(find('A', "2HG ", "LYS B 205")));
    assert!(!has(find('B', "2HG ", "LYS B 205")) && !has(find('C', "2HG ", "LYS B 205")));
}

#[test]
fn colour_by_chain_and_uniform() {
    let p = shared_or_skip!("pdb/1uun_opm_oriented.pdb");
    let l = load_with(&p, |s| s.color_by = ColorBy::Chain).expect("loads");
    // 8 chains × 1379 atoms in file order: the colour changes exactly at the chain boundaries.
    let distinct: std::collections::BTreeSet<String> =
        l.records.iter().map(|r| format!("{:?}", r.color)).collect();
    assert_eq!(distinct.len(), 8);
    assert_eq!(l.records[0].color, l.records[1378].color);
    assert_ne!(l.records[1378].color, l.records[1379].color);
    let u = load_with(&p, |s| s.color_by = ColorBy::Uniform).expect("loads");
    assert!(u.records.iter().all(|r| r.color.is_none()));
}

#[test]
fn radius_scale_applies_once() {
    let p = shared_or_skip!("pdb/1rx1.pdb");
    let a = load(&p);
    let b = load_with(&p, |s| s.radius_scale = 0.5).expect("loads");
    assert!(a
        .records
        .iter()
        .zip(&b.records)
        .all(|(x, y)| (x.radius * 0.5 - y.radius).abs() < 1e-12));
}

#[test]
fn mmcif_matches_its_text() {
    let p = shared_or_skip!("pdb/3SN6.cif");
    let l = load(&p);
    let rows = lines_where(&p, |l| l.starts_with("ATOM ") || l.starts_with("HETATM "));
    assert_eq!(rows.len(), l.records.len());
    for (k, (line, text)) in rows.iter().enumerate().step_by(1013) {
        let f: Vec<&str> = text.split_whitespace().collect();
        let r = &l.records[k];
        assert_eq!(r.location, Location::Line(*line));
        let xyz = [f[10], f[11], f[12]].map(|s| s.parse::<f64>().expect("n"));
        assert!(close3(r.center, xyz, 1e-9), "line {line}");
        let want = match f[2] {
            "C" => 1.70,
            "N" => 1.55,
            "O" => 1.52,
            "S" => 1.80,
            other => panic!("element {other}"),
        };
        assert_eq!(r.radius, want);
    }
    // Chains come from auth_asym_id (column 24); chain R only.
    let n_r = rows
        .iter()
        .filter(|(_, t)| t.split_whitespace().nth(23) == Some("R"))
        .count();
    let r = load_with(&p, |s| s.chains = Some(vec!["R".into()])).expect("loads");
    assert_eq!(r.records.len(), n_r);
    assert!(n_r > 0);
}

#[test]
fn models_are_selected() {
    let dir = tempfile::tempdir().expect("tmp");
    let p = dir.path().join("m.pdb");
    let atom = |x: f64| {
        format!("ATOM      1  CA  ALA A   1    {x:8.3}   0.000   0.000  1.00  0.00           C  \n")
    };
    let text = format!(
        "MODEL        1\n{}{}ENDMDL\nMODEL        2\n{}ENDMDL\n",
        atom(1.0),
        atom(2.0),
        atom(3.0)
    );
    std::fs::write(&p, text).expect("write");
    let a = load(&p);
    assert_eq!(a.records.len(), 2);
    assert!(a.warnings.iter().any(|w| w.contains("2 models")));
    let b = load_with(&p, |s| s.model = Some(2)).expect("model 2");
    assert_eq!(b.records.len(), 1);
    assert_eq!(b.records[0].center.x, 3.0);
    assert_eq!(b.records[0].location, Location::Line(6));
    let e = load_with(&p, |s| s.model = Some(3))
        .expect_err("no model 3")
        .to_string();
    assert!(e.contains("m.pdb") && e.contains("model 3"), "{e}");
}
