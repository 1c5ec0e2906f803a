//! VRML97 against the real files of `../shared/data/vrml` (counts from SOURCES.md) and, for the
//! files PyMOL and Jmol wrote from 1rx1.pdb, against the PDB atoms themselves.

use crate::support::*;
use glam::DVec3;
use pgt::error::Location;

/// (file, spheres): SOURCES.md (jmol: 1435 atom balls, drawn as recognised mesh spheres).
const COUNTS: &[(&str, usize)] = &[
    ("vrml/castle_proto_nodes.wrl", 6),
    ("vrml/castle_proto_ultra_simple.wrl", 6),
    ("vrml/drawxtl_be4oteo6.wrl", 104),
    ("vrml/jmol_1rx1_spacefill.wrl", 1435),
    ("vrml/pymol_1rx1_spheres.wrl", 1435),
    ("vrml/pymol_1uun_spheres.wrl", 11032),
];

#[test]
fn every_vrml_file_loads_with_the_right_count() {
    for (rel, n) in COUNTS {
        let Some(p) = shared(rel) else { continue };
        let l = load(&p);
        assert_eq!(l.records.len(), *n, "{rel}: {:?}", l.warnings);
    }
}

#[test]
fn castle_proto_nodes_six_unit_spheres() {
    let p = shared_or_skip!("vrml/castle_proto_nodes.wrl");
    let l = load(&p);
    let xs: Vec<f64> = l.records.iter().map(|r| r.center.x).collect();
    assert_eq!(xs, vec![5.0, 10.0, 15.0, 20.0, 25.0, 30.0]);
    assert!(l
        .records
        .iter()
        .all(|r| r.radius == 1.0 && r.center.y == 0.0));
    // Colours per the file's comments: yellow, unlit (scene default), yellow (instance DEF),
    // red (PROTO default), blue (instance), yellow (default with USE YellowMat).
    let c: Vec<Option<DVec3>> = l.records.iter().map(|r| r.color).collect();
    let (y, r, b) = (DVec3::new(1.0, 1.0, 0.0), DVec3::X, DVec3::Z);
    assert_eq!(c, vec![Some(y), None, Some(y), Some(r), Some(b), Some(y)]);
    assert!(
        l.warnings.iter().any(|w| w.contains("6 Text")),
        "{:?}",
        l.warnings
    );
}

#[test]
fn castle_proto_redefinition_and_radii() {
    let p = shared_or_skip!("vrml/castle_proto_ultra_simple.wrl");
    let l = load(&p);
    let got: Vec<(f64, f64)> = l.records.iter().map(|r| (r.center.x, r.radius)).collect();
    assert_eq!(
        got,
        vec![
            (0.0, 5.0),
            (10.0, 4.0),
            (20.0, 3.0),
            (30.0, 2.0),
            (40.0, 1.0),
            (50.0, 0.5)
        ]
    );
    // The redefined MySphere is green; RedMaterial (a PROTO'd Material) is red.
    assert_eq!(l.records[2].color, Some(DVec3::Y));
    assert_eq!(l.records[4].color, Some(DVec3::X));
}

#[test]
fn drawxtl_radii_and_rotated_frame() {
    let p = shared_or_skip!("vrml/drawxtl_be4oteo6.wrl");
    let l = load(&p);
    let mut radii: Vec<f64> = l.records.iter().map(|r| r.radius).collect();
    radii.sort_by(f64::total_cmp);
    radii.dedup();
    // SOURCES.md: radii 0.23 / 0.30 / 0.45 — the rotations are rigid, so radii are kept.
    for r in &radii {
        assert!(
            [0.23, 0.30, 0.45].iter().any(|x| (x - r).abs() < 1e-9),
            "{r}"
        );
    }
    let colors: std::collections::BTreeSet<String> =
        l.records.iter().map(|r| format!("{:?}", r.color)).collect();
    assert_eq!(colors.len(), 2);
}

/// PDB atoms of 1rx1.pdb (position, element), in file order.
fn rx1_atoms(p: &std::path::Path) -> Vec<(DVec3, String)> {
    lines_where(p, |l| l.starts_with("ATOM  ") || l.starts_with("HETATM"))
        .into_iter()
        .map(|(_, t)| {
            let c = |a: usize, b: usize| t[a - 1..b].trim().parse::<f64>().expect("n");
            (
                DVec3::new(c(31, 38), c(39, 46), c(47, 54)),
                t[76..78].trim().to_string(),
            )
        })
        .collect()
}

#[test]
fn pymol_spheres_are_the_pdb_atoms() {
    let p = shared_or_skip!("vrml/pymol_1rx1_spheres.wrl");
    let atoms = rx1_atoms(&shared_or_skip!("pdb/1rx1.pdb"));
    let l = load(&p);
    assert_eq!(l.records.len(), atoms.len());
    // SOURCES.md: translation = PDB xyz − (27.400, 44.000, 13.301); vdW C 1.70 N 1.55 O 1.52 S 1.80.
    let view = DVec3::new(27.4, 44.0, 13.301);
    for (r, (x, el)) in l.records.iter().zip(&atoms) {
        assert!(
            (r.center + view - *x).abs().max_element() < 2e-3,
            "{} vs {x}",
            r.center + view
        );
        let want = match el.as_str() {
            "C" => Some(1.70),
            "N" => Some(1.55),
            "O" => Some(1.52),
            "S" => Some(1.80),
            _ => None,
        };
        if let Some(w) = want {
            assert!((r.radius - w).abs() < 1e-6, "{el}: {}", r.radius);
        }
    }
    // Locations point at Sphere lines.
    let text = std::fs::read_to_string(&p).expect("read");
    let Location::Line(n) = l.records[0].location else {
        panic!("line")
    };
    assert!(text.lines().nth(n - 1).expect("line").contains("Sphere"));
}

#[test]
fn jmol_mesh_spheres_are_the_pdb_atoms() {
    let p = shared_or_skip!("vrml/jmol_1rx1_spacefill.wrl");
    let atoms = rx1_atoms(&shared_or_skip!("pdb/1rx1.pdb"));
    let l = load(&p);
    assert_eq!(l.records.len(), atoms.len());
    // Transform{scale 10 10 10 children[Transform{translation -26.926 -44.427498 -12.8755 …
    let centre = DVec3::new(26.926, 44.427498, 12.8755);
    for (r, (x, _)) in l.records.iter().zip(&atoms) {
        assert!(
            (r.center / 10.0 + centre - *x).abs().max_element() < 2e-3,
            "{r:?} vs {x}"
        );
    }
    // First atom: `scale 1.85 1.85 1.85` on the unit geodesic, ×10.
    assert!(
        (l.records[0].radius - 18.5).abs() < 0.1,
        "{}",
        l.records[0].radius
    );
    assert!(l.warnings.iter().any(|w| w.contains("1435 IndexedFaceSet")));
}

fn vrml_err(body: &str) -> String {
    let dir = tempfile::tempdir().expect("tmp");
    let p = dir.path().join("bad.wrl");
    std::fs::write(&p, format!("#VRML V2.0 utf8\n{body}")).expect("write");
    load_with(&p, |_| {}).expect_err(body).to_string()
}

fn vrml_ok(body: &str) -> pgt::formats::LoadedParticles {
    let dir = tempfile::tempdir().expect("tmp");
    let p = dir.path().join("ok.wrl");
    std::fs::write(&p, format!("#VRML V2.0 utf8\n{body}")).expect("write");
    load(&p)
}

#[test]
fn bad_vrml_names_file_line_and_expectation() {
    let cases: &[(&str, &str, &str)] = &[
        (
            "Transform { children [ Shape { geometry Sphere { } } ]\n",
            "bad.wrl:",
            "expected '}'",
        ),
        (
            "Transform { children [ Shape { geometry Sphere { } }\n}\n",
            "bad.wrl:",
            "']'",
        ),
        (
            "\n\nFooBar { }\n",
            "bad.wrl:4",
            "unknown node type 'FooBar'",
        ),
        (
            "Group { children USE Nope }\n",
            "bad.wrl:2",
            "undefined name 'Nope'",
        ),
        (
            "PROTO Me [] { Me { } }\nMe { }\n",
            "bad.wrl:2",
            "instantiates itself",
        ),
        (
            "Shape { geometry Sphere { radius nan } }\n",
            "bad.wrl:2",
            "expected a field value",
        ),
        (
            "Shape { geometry Sphere { radius 1e999 } }\n",
            "bad.wrl:2",
            "not finite",
        ),
        (
            "Transform { translation 1 2 } \n",
            "bad.wrl:2",
            "expected 3 numbers",
        ),
        (
            "PROTO P [ field SFFloat r 1 ] { Shape { geometry Sphere { radius IS q } } }\nP { }\n",
            "bad.wrl:",
            "not a field",
        ),
        (
            "PROTO P [ ] { Group { } }\nP { r 2 }\n",
            "bad.wrl:3",
            "no field 'r'",
        ),
        (
            "Shape { geometry Sphere { radius \"1 } }\n",
            "bad.wrl:2",
            "unterminated string",
        ),
        ("}\n", "bad.wrl:2", "expected a node"),
    ];
    for (body, at, what) in cases {
        let e = vrml_err(body);
        assert!(e.contains(at) && e.contains(what), "{body:?} → {e}");
    }
    let dir = tempfile::tempdir().expect("tmp");
    let p = dir.path().join("v1.wrl");
    std::fs::write(&p, "#VRML V1.0 ascii\nSeparator { }\n").expect("w");
    let e = load_with(&p, |_| {}).expect_err("v1").to_string();
    assert!(e.contains("v1.wrl:1") && e.contains("#VRML V2.0"), "{e}");
}

#[test]
fn deep_nesting_is_an_error_not_a_stack_overflow() {
    let body = format!(
        "{}{}",
        "Group { children [ ".repeat(5000),
        "] } ".repeat(5000)
    );
    assert!(vrml_err(&body).contains("deeper than"));
}

#[test]
fn exponential_use_is_bounded() {
    // Each level USEs the previous one 10 times: 10^12 spheres if expanded.
    let mut s = String::from("DEF L0 Shape { geometry Sphere { } }\n");
    for k in 1..=12 {
        s += &format!(
            "DEF L{k} Group {{ children [ {} ] }}\n",
            vec![format!("USE L{}", k - 1); 10].join(" ")
        );
    }
    assert!(vrml_err(&s).contains("expands to more than"));
}

#[test]
fn transforms_compose() {
    // Parent translates by (1,0,0) and rotates 90° about z; the child is at (1,0,0) with scale 2:
    // world = T(1,0,0)·Rz(90°)·(1,0,0) = (1,1,0), radius 2·0.5.
    let l = vrml_ok(
        "Transform { translation 1 0 0 rotation 0 0 1 1.5707963267948966 children\n\
         Transform { translation 1 0 0 scale 2 2 2 children [ Shape { geometry Sphere { radius 0.5 } } ] } }\n",
    );
    assert_eq!(l.records.len(), 1);
    assert!((l.records[0].center - DVec3::new(1.0, 1.0, 0.0)).length() < 1e-12);
    assert!((l.records[0].radius - 1.0).abs() < 1e-12);
    // center: rotation about (0,1,0) by π maps the origin to (0,2,0)... about center (0,1,0) in
    // the xy plane: Rz(π) about (0,1,0) takes (0,0,0) to (0,2,0).
    let l = vrml_ok("Transform { center 0 1 0 rotation 0 0 1 3.141592653589793 children Shape { geometry Sphere { } } }\n");
    assert!((l.records[0].center - DVec3::new(0.0, 2.0, 0.0)).length() < 1e-12);
    // Non-uniform scale: the equal-volume sphere, with a warning.
    let l = vrml_ok("Transform { scale 1 2 4 children Shape { geometry Sphere { } } }\n");
    assert!((l.records[0].radius - 2.0).abs() < 1e-12);
    assert!(l.warnings.iter().any(|w| w.contains("non-uniform")));
}

#[test]
fn switch_def_use_material_and_transparency() {
    let l = vrml_ok(
        "Switch { whichChoice 1 choice [ Shape { geometry Sphere { radius 9 } }\n\
         DEF S Shape { appearance Appearance { material Material { diffuseColor 0 0 0 emissiveColor 1 0 0 transparency 0.25 } } geometry Sphere { radius 2 } } ] }\n\
         Transform { translation 5 0 0 children USE S }\n\
         Switch { choice Shape { geometry Sphere { } } }\n",
    );
    assert_eq!(l.records.len(), 2);
    assert!(l
        .records
        .iter()
        .all(|r| r.radius == 2.0 && r.color == Some(DVec3::X) && r.opacity == Some(0.75)));
    assert_eq!(l.records[1].center, DVec3::new(5.0, 0.0, 0.0));
}

#[test]
fn proto_fields_pass_through_is_and_defaults() {
    let l = vrml_ok(
        "PROTO P [ field SFFloat r 1 field SFColor c 0 0 1 ] {\n\
           Shape { appearance Appearance { material Material { diffuseColor IS c } } geometry Sphere { radius IS r } } }\n\
         PROTO Q [ field SFFloat s 3 ] { Transform { translation 7 0 0 children P { r IS s } } }\n\
         P { r 2 } P { } Q { s 4 } Q { }\n\
         EXTERNPROTO E [ field SFFloat r ] \"e.wrl#E\"\n\
         E { r 5 }\n\
         ROUTE A.b TO C.d\n",
    );
    let got: Vec<(f64, f64)> = l.records.iter().map(|r| (r.center.x, r.radius)).collect();
    assert_eq!(got, vec![(0.0, 2.0), (0.0, 1.0), (7.0, 4.0), (7.0, 3.0)]);
    assert!(l.records.iter().all(|r| r.color == Some(DVec3::Z)));
    assert!(
        l.warnings.iter().any(|w| w.contains("1 EXTERNPROTO")),
        "{:?}",
        l.warnings
    );
}

#[test]
fn format_can_be_forced() {
    let dir = tempfile::tempdir().expect("tmp");
    let p = dir.path().join("spheres.txt");
    std::fs::write(
        &p,
        "#VRML V2.0 utf8\nShape { geometry Sphere { radius 3 } }\n",
    )
    .expect("w");
    assert!(load_with(&p, |_| {})
        .expect_err("unknown extension")
        .to_string()
        .contains("unsupported"));
    let l = load_with(&p, |s| s.format = pgt::formats::Format::named("vrml")).expect("forced");
    assert_eq!(l.records[0].radius, 3.0);
}

#[test]
fn deep_use_chains_are_an_error_not_a_stack_overflow() {
    // Each DEF nests the previous one by one level through USE: parse depth stays 2, evaluation
    // depth grows to 600.
    let mut s = String::from("DEF A0 Shape { geometry Sphere { } }\n");
    for k in 1..600 {
        s += &format!(
            "DEF A{k} Transform {{ translation 1 0 0 children USE A{} }}\n",
            k - 1
        );
    }
    assert!(vrml_err(&s).contains("deeper than"));
    // 100 levels are fine: the sphere ends up at x = 99 (A99 is the last statement).
    let mut s = String::from("DEF A0 Shape { geometry Sphere { } }\n");
    for k in 1..100 {
        s += &format!(
            "DEF A{k} Transform {{ translation 1 0 0 children USE A{} }}\n",
            k - 1
        );
    }
    let l = vrml_ok(&s);
    assert_eq!(l.records.len(), 100);
    assert_eq!(l.records.last().map(|r| r.center.x), Some(99.0));
}

#[test]
fn pymol_colours_are_the_decoded_diffuse_colours_of_the_text() {
    let p = shared_or_skip!("vrml/pymol_1rx1_spheres.wrl");
    let l = load(&p);
    // Every `diffuseColor r g b` of the file, in order, one per sphere.
    let colours: Vec<[f64; 3]> = lines_where(&p, |t| t.contains("diffuseColor"))
        .iter()
        .map(|(_, t)| {
            let f: Vec<f64> = t
                .split_whitespace()
                .skip_while(|w| *w != "diffuseColor")
                .skip(1)
                .take(3)
                .map(|w| w.parse().expect("number"))
                .collect();
            [f[0], f[1], f[2]]
        })
        .collect();
    assert_eq!(colours.len(), l.records.len());
    let decode = |c: f64| {
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    for (r, c) in l.records.iter().zip(&colours) {
        assert!(close3(r.color.expect("coloured"), c.map(decode), 1e-12));
        assert_eq!(r.opacity, None, "PyMOL writes no transparency");
    }
}
