//! XYZ and CSV files, and the random set round-trip through CSV.

use crate::support::*;
use pgt::error::Location;
use pgt::formats::random::{generate, to_csv, RandomSpec};

#[test]
fn random_set_round_trips_through_csv() {
    let spec = RandomSpec {
        count: 500,
        seed: 7,
        ..RandomSpec::default()
    };
    let set = generate(&spec);
    let dir = tempfile::tempdir().expect("tmp");
    let p = dir.path().join("r.csv");
    std::fs::write(&p, to_csv(&set)).expect("write");
    let l = load(&p);
    assert_eq!(l.records.len(), 500);
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    for (a, b) in set.iter().zip(&l.records) {
        assert!((a.center - b.center).abs().max_element() <= 5e-7);
        assert!((a.radius - b.radius).abs() <= 5e-7);
        assert!((a.color - b.color.expect("c")).abs().max_element() <= 5e-7);
    }
    assert_eq!(l.records[3].location, Location::Line(5));
}

#[test]
fn xyz_file_loads() {
    let dir = tempfile::tempdir().expect("tmp");
    let p = dir.path().join("w.xyz");
    std::fs::write(
        &p,
        "3\nwater\nO 0.0 0.0 0.0\nH 0.757 0.586 0.0\nH -0.757 0.586 0.0\n",
    )
    .expect("w");
    let l = load(&p);
    assert_eq!(l.records.len(), 3);
    assert_eq!(l.records[1].radius, 1.20);
    assert_eq!(l.records[2].center.x, -0.757);
    assert!(close3(l.records[0].color.expect("c"), lin(0xFF0D0D), 1e-12));
}
