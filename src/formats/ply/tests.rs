//! The PLY reader's tests: synthetic files of every encoding and their refusals.

use super::convert::{SH_C0, SH_C1, SH_C2, SH_C3};
use super::details::details;
use super::layout::REQUIRED;
use super::read;
use crate::error::Location;
use crate::formats::{IncludeSpec, ShColor, ShOrder};
use glam::DVec3;
use std::path::Path;

/// A vertex of the tests: position, f_dc, opacity logit, log scales, rot, f_rest.
#[derive(Clone)]
struct V {
    p: [f32; 3],
    dc: [f32; 3],
    o: f32,
    s: [f32; 3],
    q: [f32; 4],
    rest: Vec<f32>,
}

fn v() -> V {
    V {
        p: [1.0, 2.0, 3.0],
        dc: [0.5, -0.25, -4.0],
        o: 0.7,
        s: [-1.0, 0.0, 0.5],
        q: [2.0, 0.0, 0.0, 0.0],
        rest: Vec::new(),
    }
}

fn names(n_rest: usize) -> Vec<String> {
    let mut n: Vec<String> = [
        "x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    n.extend((0..n_rest).map(|k| format!("f_rest_{k}")));
    n.extend(REQUIRED[6..].iter().map(|s| s.to_string()));
    n
}

fn values(v: &V) -> Vec<f32> {
    let mut out = v.p.to_vec();
    out.extend([0.0; 3]);
    out.extend(v.dc);
    out.extend(&v.rest);
    out.push(v.o);
    out.extend(v.s);
    out.extend(v.q);
    out
}

/// A standard-layout file of `vs` in `format` ("binary_little_endian", …).
fn file(format: &str, vs: &[V]) -> Vec<u8> {
    let n_rest = vs.first().map_or(0, |v| v.rest.len());
    let mut b = format!(
        "ply\nformat {format} 1.0\ncomment test\nelement vertex {}\n",
        vs.len()
    );
    for n in names(n_rest) {
        b.push_str(&format!("property float {n}\n"));
    }
    b.push_str("end_header\n");
    let mut b = b.into_bytes();
    for v in vs {
        for x in values(v) {
            match format {
                "ascii" => b.extend(format!("{x:?} ").as_bytes()),
                "binary_big_endian" => b.extend(x.to_be_bytes()),
                _ => b.extend(x.to_le_bytes()),
            }
        }
        if format == "ascii" {
            b.push(b'\n');
        }
    }
    b
}

fn spec() -> IncludeSpec {
    IncludeSpec::bare(Path::new("t.ply"))
}

fn err(bytes: &[u8]) -> String {
    read(&spec(), bytes).expect_err("an error").to_string()
}

#[test]
fn a_vertex_becomes_the_documented_ellipsoid() {
    let l = read(&spec(), &file("binary_little_endian", &[v(), v()])).expect("ok");
    assert_eq!(l.records.len(), 2);
    let r = &l.records[1];
    assert_eq!(r.center, DVec3::new(1.0, 2.0, 3.0));
    let e = r.ellipsoid.expect("an ellipsoid");
    let axes = DVec3::new(3.0 * (-1.0f64).exp(), 3.0, 3.0 * 0.5f64.exp());
    assert_eq!(e.semi_axes, axes);
    assert_eq!(r.radius, axes.z);
    assert_eq!(e.rotation, [1.0, 0.0, 0.0, 0.0]);
    assert_eq!(r.opacity, Some(1.0 / (1.0 + (-f64::from(0.7f32)).exp())));
    let c = r.color.expect("a colour");
    assert_eq!(c.x, 0.5 + SH_C0 * 0.5);
    assert_eq!(c.y, 0.5 - SH_C0 * 0.25);
    assert_eq!(c.z, 0.0, "clamped at 0");
    assert_eq!(
        r.location,
        Location::Byte(
            u64::try_from(file("binary_little_endian", &[]).len()).expect("small") + 17 * 4
        )
    );
}

#[test]
fn ascii_and_big_endian_read_as_little_endian() {
    let mut w = v();
    w.rest = (0..45).map(|k| k as f32 * 0.01 - 0.2).collect();
    let vs = [w.clone(), w];
    let le = read(&spec(), &file("binary_little_endian", &vs)).expect("le");
    for f in ["ascii", "binary_big_endian"] {
        let other = read(&spec(), &file(f, &vs)).expect(f);
        for (a, b) in le.records.iter().zip(&other.records) {
            assert_eq!(
                (a.center, a.ellipsoid, a.color, a.opacity),
                (b.center, b.ellipsoid, b.color, b.opacity),
                "{f}"
            );
        }
    }
}

#[test]
fn extent_scales_the_semi_axes() {
    let mut s = spec();
    s.extent = Some(2.0);
    let l = read(&s, &file("binary_little_endian", &[v()])).expect("ok");
    assert_eq!(l.records[0].ellipsoid.expect("e").semi_axes.y, 2.0);
    s.extent = Some(0.0);
    assert!(read(&s, &file("binary_little_endian", &[v()])).is_err());
}

#[test]
fn gaussian_density_takes_the_standard_deviations_and_refuses_extent() {
    let mut s = spec();
    s.density = Some(crate::formats::Profile::Gaussian);
    let l = read(&s, &file("binary_little_endian", &[v()])).expect("ok");
    let axes = DVec3::new((-1.0f64).exp(), 1.0, 0.5f64.exp());
    assert_eq!(l.records[0].ellipsoid.expect("e").semi_axes, axes);
    s.extent = Some(3.0);
    let e = read(&s, &file("binary_little_endian", &[v()]))
        .expect_err("extent refused")
        .to_string();
    assert!(e.contains("t.ply") && e.contains("extent"), "{e}");
}

#[test]
fn a_file_cut_short_names_the_vertex() {
    let b = file("binary_little_endian", &[v(), v(), v()]);
    let e = err(&b[..b.len() - 10]);
    assert!(
        e.contains("t.ply (byte") && e.contains("vertex 2") && e.contains("3 vertices"),
        "{e}"
    );
    let b = file("ascii", &[v(), v(), v()]);
    let cut = b.len() - 40;
    let e = err(&b[..cut]);
    assert!(e.contains("t.ply:") && e.contains("vertex 2"), "{e}");
}

#[test]
fn header_errors_name_the_line() {
    let good = String::from_utf8(file("binary_little_endian", &[])).expect("text");
    let cases: Vec<(String, &str)> = vec![
        (good.replace("ply\n", "plx\n"), "t.ply:1"),
        (
            good.replace("format binary_little_endian 1.0\n", ""),
            "no `format`",
        ),
        (good.replace("1.0", "2.0"), "version"),
        (good.replace("comment test", "bogus test"), "t.ply:3"),
        (
            good.replace("element vertex 0", "element vertex -1"),
            "count",
        ),
        (
            good.replace("property float nx", "property list uchar int nx"),
            "property nx is a list",
        ),
        (
            good.replace("property float nx", "property half nx"),
            "unknown type `half`",
        ),
        (
            good.replace("property float nx", "property float x"),
            "a second property `x`",
        ),
        (
            good.replace("property float opacity\n", ""),
            "lacks the 3D Gaussian splatting properties opacity",
        ),
        (
            good.replace("property float f_rest_0\n", "")
                .replace("end_header", "property float f_rest_0\nend_header"),
            "",
        ),
        (good.replace("end_header\n", ""), "ends before `end_header`"),
        (
            good.replace("element vertex", "element face"),
            "no `vertex` element",
        ),
    ];
    for (text, want) in cases {
        let e = err(text.as_bytes());
        assert!(e.contains("t.ply") && e.contains(want), "{want}: {e}");
    }
    let mut b = b"ply\nformat ascii 1.0\ncomment \xff\xfe\n".to_vec();
    b.extend(b"end_header\n");
    let e = err(&b);
    assert!(e.contains("t.ply:3") && e.contains("not text"), "{e}");
    let mesh = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n";
    let e = err(mesh);
    assert!(
        e.contains("f_dc_0") && e.contains("rot_3") && e.contains("has x, y, z"),
        "{e}"
    );
}

#[test]
fn f_rest_must_be_a_whole_degree() {
    let mut w = v();
    w.rest = vec![0.0; 10];
    let e = err(&file("binary_little_endian", &[w]));
    assert!(e.contains("10 f_rest_"), "{e}");
}

#[test]
fn bad_values_name_the_vertex_and_field() {
    type Edit = fn(&mut V);
    let cases: Vec<(Edit, &str)> = vec![
        (|w| w.s[1] = 800.0, "scale_1 = 800"),
        (|w| w.s[2] = -800.0, "scale_2 = -800"),
        (|w| w.s[0] = f32::NAN, "scale_0 = NaN"),
        (|w| w.s[0] = f32::INFINITY, "scale_0 = inf"),
        (|w| w.q = [0.0; 4], "not a finite, non-zero quaternion"),
        (|w| w.q[2] = f32::NAN, "quaternion"),
        (|w| w.p[1] = f32::NAN, "position"),
        (|w| w.o = f32::NAN, "opacity is NaN"),
        (|w| w.dc[0] = f32::INFINITY, "f_dc"),
    ];
    for (edit, want) in cases {
        let mut w = v();
        edit(&mut w);
        let e = err(&file("binary_little_endian", &[v(), w]));
        assert!(
            e.contains("t.ply (byte") && e.contains("vertex 1: ") && e.contains(want),
            "{want}: {e}"
        );
    }
    let mut w = v();
    w.o = f32::INFINITY;
    let l =
        read(&spec(), &file("binary_little_endian", &[w])).expect("an infinite logit is Θmax = 1");
    assert_eq!(l.records[0].opacity, Some(1.0));
}

#[test]
fn sh_constants_are_their_closed_forms() {
    let pi = std::f64::consts::PI;
    let close = |a: f64, b: f64| assert!((a - b).abs() <= 4.0 * f64::EPSILON * b.abs(), "{a} {b}");
    close(SH_C0, 0.5 * (1.0 / pi).sqrt());
    close(SH_C1, 0.5 * (3.0 / pi).sqrt());
    let c2 = [
        0.5 * (15.0 / pi).sqrt(),
        -0.5 * (15.0 / pi).sqrt(),
        0.25 * (5.0 / pi).sqrt(),
        -0.5 * (15.0 / pi).sqrt(),
        0.25 * (15.0 / pi).sqrt(),
    ];
    for (a, b) in SH_C2.iter().zip(c2) {
        close(*a, b);
    }
    let (a, b, c, d) = (
        (35.0 / (2.0 * pi)).sqrt(),
        (105.0 / pi).sqrt(),
        (21.0 / (2.0 * pi)).sqrt(),
        (7.0 / pi).sqrt(),
    );
    let c3 = [
        -0.25 * a,
        0.5 * b,
        -0.25 * c,
        0.25 * d,
        -0.25 * c,
        0.25 * b,
        -0.25 * a,
    ];
    for (x, y) in SH_C3.iter().zip(c3) {
        close(*x, y);
    }
}

#[test]
fn view_colour_follows_the_direction_and_the_order() {
    // Degree 1, only the z coefficient (index 1) set in red: C1·z·sh.
    let mut w = v();
    w.rest = vec![0.0; 9];
    w.rest[1] = 0.5;
    let mut s = spec();
    s.sh = Some(ShColor::View);
    // Without an eye: the DC colour, and the coefficients kept for the scene (DC, then the
    // three degree-1 vectors; red's z coefficient is f_rest_1).
    let kept = read(&s, &file("binary_little_endian", &[w.clone()])).expect("ok");
    assert_eq!(kept.records[0].color.expect("c").x, 0.5 + SH_C0 * 0.5);
    let sh = kept.sh.expect("the coefficients");
    assert_eq!(sh.per_particle, 4);
    assert_eq!(sh.values[2], DVec3::new(0.5, 0.0, 0.0));
    assert_eq!(sh.values[0].x, 0.5);
    s.view_from = Some(DVec3::new(1.0, 2.0, -7.0));
    let l = read(&s, &file("binary_little_endian", &[w.clone()])).expect("ok");
    let dc = l.records[0].color.expect("c");
    assert_eq!(dc.x, 0.5 + SH_C0 * 0.5 + SH_C1 * 1.0 * 0.5);
    // The kept coefficients give the reader's colour for the same eye, bit for bit.
    let eye = DVec3::new(1.0, 2.0, -7.0);
    let center = l.records[0].center;
    assert_eq!(l.sh.as_ref().expect("sh").color(0, center, eye), dc);
    // The same coefficient written coefficient-major: red of coefficient 2 is at index 3.
    w.rest = vec![0.0; 9];
    w.rest[3] = 0.5;
    s.sh_order = Some(ShOrder::CoefficientMajor);
    let l2 = read(&s, &file("binary_little_endian", &[w])).expect("ok");
    assert_eq!(l2.records[0].color, l.records[0].color);
}

#[test]
fn details_report_the_layout() {
    let mut w = v();
    w.rest = vec![0.0; 24];
    let d = details(Path::new("t.ply"), &file("binary_little_endian", &[w])).expect("ok");
    assert_eq!(d["layout"], "standard");
    assert_eq!(d["sh_degree"], 2);
    assert_eq!(d["semi_axes"]["max"], 3.0 * 0.5f64.exp());
}
