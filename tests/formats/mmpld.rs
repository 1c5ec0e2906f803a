//! MMPLD against the real files of `../shared/data/mmpld` (counts from SOURCES.md) and against
//! their bytes, decoded here independently.

use crate::support::*;
use pgt::error::Location;

/// (file, particles in frame 0): SOURCES.md's table.
const COUNTS: &[(&str, usize)] = &[
    ("megamol-tests_xyzr_float_rgba_byte_4lists.mmpld", 19),
    ("part_rnk000000_v103.mmpld", 5344),
    ("test_xyz_double_int_double.mmpld", 19),
    ("test_xyz_double_int_float.mmpld", 19),
    ("test_xyz_double_none.mmpld", 19),
    ("test_xyz_double_rgb_float.mmpld", 19),
    ("test_xyz_double_rgba_byte.mmpld", 19),
    ("test_xyz_double_rgba_float.mmpld", 19),
    ("test_xyz_double_rgba_short.mmpld", 19),
    ("test_xyz_float_int_float.mmpld", 4),
    ("test_xyz_float_none.mmpld", 4),
    ("test_xyz_float_rgb_float.mmpld", 4),
    ("test_xyz_float_rgba_byte.mmpld", 4),
    ("test_xyz_float_rgba_float.mmpld", 4),
    ("test_xyzr_float_int_float.mmpld", 4),
    ("test_xyzr_float_none.mmpld", 4),
    ("test_xyzr_float_rgb_float.mmpld", 4),
    ("test_xyzr_float_rgba_byte.mmpld", 4),
    ("test_xyzr_float_rgba_float.mmpld", 4),
    ("testspheres_old_v100.mmpld", 15),
];

#[test]
fn every_mmpld_file_loads_with_the_right_count() {
    for (name, n) in COUNTS {
        let Some(p) = shared(&format!("mmpld/{name}")) else {
            continue;
        };
        let l = load(&p);
        assert_eq!(l.records.len(), *n, "{name}");
        assert!(
            l.records
                .iter()
                .all(|r| r.radius > 0.0 && r.center.is_finite()),
            "{name}"
        );
        let bug = l.warnings.iter().any(|w| w.contains("timestamp"));
        assert_eq!(bug, name.contains("v103"), "{name}: {:?}", l.warnings);
    }
}

fn f32_at(b: &[u8], at: usize) -> f64 {
    f64::from(f32::from_le_bytes(
        b[at..at + 4].try_into().expect("4 bytes"),
    ))
}

#[test]
fn xyzr_rgba_byte_particles_match_the_bytes() {
    let p = shared_or_skip!("mmpld/test_xyzr_float_rgba_byte.mmpld");
    let b = std::fs::read(&p).expect("read");
    let l = load(&p);
    // Header 60 + seek table 2×8 = 76; timestamp 4, list count 4, types 2, count 8 → data at 94,
    // 20 bytes per particle (xyzr f32 + RGBA u8).
    assert_eq!((b[84], b[85]), (2, 2), "FLOAT_XYZR, UINT8_RGBA");
    for (k, r) in l.records.iter().enumerate() {
        let at = 94 + 20 * k;
        assert_eq!(r.location, Location::Byte(at as u64));
        assert!(close3(
            r.center,
            [f32_at(&b, at), f32_at(&b, at + 4), f32_at(&b, at + 8)],
            0.0
        ));
        assert_eq!(r.radius, f32_at(&b, at + 12));
        let want =
            lin(u32::from(b[at + 16]) << 16 | u32::from(b[at + 17]) << 8 | u32::from(b[at + 18]));
        assert!(close3(r.color.expect("colour"), want, 1e-12), "{k}");
    }
}

#[test]
fn v103_writer_bug_file_uses_global_radius_and_colour() {
    let p = shared_or_skip!("mmpld/part_rnk000000_v103.mmpld");
    let b = std::fs::read(&p).expect("read");
    let l = load(&p);
    // No timestamp: list count at 76, types at 80, global radius at 82, RGBA at 86.
    assert_eq!((b[80], b[81]), (1, 0));
    let radius = f32_at(&b, 82);
    assert_eq!(radius, 1.0);
    assert!(l.records.iter().all(|r| r.radius == radius));
    let g = lin(0xCCCCCC);
    assert_eq!(&b[86..90], &[204, 204, 204, 204]);
    assert!(l
        .records
        .iter()
        .all(|r| close3(r.color.expect("c"), g, 1e-12)));
    // count at 90, bbox 24 bytes → data at 122, 12 bytes each.
    let last = l.records.last().expect("some");
    let at = 122 + 12 * 5343;
    assert_eq!(last.location, Location::Byte(at as u64));
    assert!(close3(
        last.center,
        [f32_at(&b, at), f32_at(&b, at + 4), f32_at(&b, at + 8)],
        0.0
    ));
    assert_eq!(at + 12, b.len());
}

#[test]
fn frames_are_selected() {
    let p = shared_or_skip!("mmpld/testspheres_old_v100.mmpld");
    let a = load(&p);
    let z = load_with(&p, |s| s.frame = Some(99)).expect("frame 99");
    assert_eq!(z.records.len(), 15);
    assert_ne!(a.records[0].center, z.records[0].center);
    let e = load_with(&p, |s| s.frame = Some(100))
        .expect_err("no frame 100")
        .to_string();
    assert!(
        e.contains("testspheres_old_v100.mmpld") && e.contains("100 frame"),
        "{e}"
    );
}

#[test]
fn bad_mmpld_input_is_an_error_with_a_byte_offset() {
    let p = shared_or_skip!("mmpld/test_xyzr_float_rgba_byte.mmpld");
    let good = std::fs::read(&p).expect("read");
    let dir = tempfile::tempdir().expect("tmp");
    let q = dir.path().join("bad.mmpld");
    let check = |bytes: &[u8], want: &str| {
        std::fs::write(&q, bytes).expect("write");
        let e = load_with(&q, |_| {}).expect_err(want).to_string();
        assert!(
            e.contains("bad.mmpld (byte") && e.contains(want),
            "{want}: {e}"
        );
    };
    // Wrong magic.
    let mut b = good.clone();
    b[0] = b'X';
    check(&b, "magic");
    // Truncated: the seek table points past the end.
    check(&good[..good.len() - 5], "outside the file");
    // A frame count larger than the file.
    let mut b = good.clone();
    b[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    check(&b, "frames");
    // A particle count larger than the frame.
    let mut b = good.clone();
    b[86..94].copy_from_slice(&(1u64 << 40).to_le_bytes());
    check(&b, "particles");
    // NaN coordinate.
    let mut b = good.clone();
    b[94..98].copy_from_slice(&f32::NAN.to_le_bytes());
    check(&b, "non-finite");
    // Unknown vertex type.
    let mut b = good.clone();
    b[84] = 9;
    check(&b, "vertex type");
}

#[test]
fn uniform_colour_applies_to_every_format() {
    let p = shared_or_skip!("mmpld/test_xyzr_float_rgba_byte.mmpld");
    let l = load_with(&p, |s| s.color_by = pgt::scene::ColorBy::Uniform).expect("loads");
    assert_eq!(l.records.len(), 4);
    assert!(l.records.iter().all(|r| r.color.is_none()));
}

mod round_trip {
    //! Files written here, independently of pgt, from the layout in SOURCES.md, for every
    //! version, vertex type and colour type; pgt must read back what was written.
    use crate::support::close3;
    use pgt::formats::{load_bytes, Format, IncludeSpec};
    use proptest::prelude::*;

    #[derive(Debug, Clone)]
    struct List {
        vt: u8,
        ct: u8,
        /// Integer-valued so that every vertex type (i16 too) stores them exactly.
        points: Vec<([i16; 3], u8, [u8; 3])>,
    }

    fn decode(c: f64) -> f64 {
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    }

    fn write(version: u16, lists: &[List]) -> Vec<u8> {
        let mut b = b"MMPLD\0".to_vec();
        b.extend_from_slice(&version.to_le_bytes());
        b.extend_from_slice(&1u32.to_le_bytes());
        b.extend_from_slice(&[0u8; 48]);
        b.extend_from_slice(&76u64.to_le_bytes());
        b.extend_from_slice(&0u64.to_le_bytes());
        if version >= 102 {
            b.extend_from_slice(&1.5f32.to_le_bytes());
        }
        b.extend_from_slice(&(lists.len() as i32).to_le_bytes());
        for l in lists {
            b.extend_from_slice(&[l.vt, l.ct]);
            if matches!(l.vt, 1 | 3 | 4) {
                b.extend_from_slice(&0.75f32.to_le_bytes());
            }
            if l.ct == 0 {
                b.extend_from_slice(&[10, 20, 30, 255]);
            }
            if matches!(l.ct, 3 | 7) {
                b.extend_from_slice(&0f32.to_le_bytes());
                b.extend_from_slice(&255f32.to_le_bytes());
            }
            b.extend_from_slice(&(l.points.len() as u64).to_le_bytes());
            if version == 103 {
                b.extend_from_slice(&[0u8; 24]);
            }
            for (p, r, c) in &l.points {
                match l.vt {
                    1 | 2 => {
                        for v in p {
                            b.extend_from_slice(&f32::from(*v).to_le_bytes());
                        }
                        if l.vt == 2 {
                            b.extend_from_slice(&(f32::from(*r) / 8.0 + 0.125).to_le_bytes());
                        }
                    }
                    3 => p.iter().for_each(|v| b.extend_from_slice(&v.to_le_bytes())),
                    _ => p
                        .iter()
                        .for_each(|v| b.extend_from_slice(&f64::from(*v).to_le_bytes())),
                }
                match l.ct {
                    1 => b.extend_from_slice(c),
                    2 => b.extend_from_slice(&[c[0], c[1], c[2], 255]),
                    3 => b.extend_from_slice(&f32::from(c[0]).to_le_bytes()),
                    4 | 5 => {
                        for v in c {
                            b.extend_from_slice(&(f32::from(*v) / 255.0).to_le_bytes());
                        }
                        if l.ct == 5 {
                            b.extend_from_slice(&1f32.to_le_bytes());
                        }
                    }
                    6 => {
                        for v in c {
                            b.extend_from_slice(&(u16::from(*v) * 257).to_le_bytes());
                        }
                        b.extend_from_slice(&u16::MAX.to_le_bytes());
                    }
                    7 => b.extend_from_slice(&f64::from(c[0]).to_le_bytes()),
                    _ => {}
                }
            }
            if version == 101 {
                b.extend_from_slice(&1u32.to_le_bytes());
                b.extend_from_slice(&3u64.to_le_bytes());
                b.extend_from_slice(&[1, 2, 3]);
            }
        }
        let end = b.len() as u64;
        b[68..76].copy_from_slice(&end.to_le_bytes());
        b
    }

    fn list() -> impl Strategy<Value = List> {
        (
            1u8..=4,
            0u8..=7,
            prop::collection::vec((any::<[i16; 3]>(), any::<u8>(), any::<[u8; 3]>()), 0..6),
        )
            .prop_map(|(vt, ct, points)| List { vt, ct, points })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn reads_back_what_was_written(version in 100u16..=103, lists in prop::collection::vec(list(), 0..4)) {
            let bytes = write(version, &lists);
            let spec = IncludeSpec::bare(std::path::Path::new("rt.mmpld"));
            let format = Format::named("mmpld").expect("mmpld");
            let want: Vec<_> = lists.iter().flat_map(|l| l.points.iter().map(move |p| (l, p))).collect();
            if want.is_empty() {
                // Issue 13: a frame without particles is an error, not an empty scene.
                let e = load_bytes(&spec, format, &bytes).expect_err("empty frame").to_string();
                prop_assert!(e.contains("rt.mmpld") && e.contains("holds no particles"), "{}", e);
                return Ok(());
            }
            let got = load_bytes(&spec, format, &bytes).expect("reads");
            prop_assert_eq!(got.records.len(), want.len());
            for (r, (l, (p, rad, c))) in got.records.iter().zip(want) {
                prop_assert!(close3(r.center, p.map(f64::from), 0.0));
                let radius = if l.vt == 2 { f64::from(*rad) / 8.0 + 0.125 } else { 0.75 };
                prop_assert_eq!(r.radius, radius);
                let cf = c.map(|v| f64::from(v) / 255.0);
                let colour = match l.ct {
                    0 => [10.0 / 255.0, 20.0 / 255.0, 30.0 / 255.0].map(decode),
                    3 | 7 => [decode(cf[0]); 3],
                    _ => cf.map(decode),
                };
                prop_assert!(close3(r.color.expect("colour"), colour, 1e-6), "{:?} vs {:?}", r.color, colour);
            }
        }
    }
}
