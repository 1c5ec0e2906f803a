//! LDR-FLIP against NVIDIA's `flip-evaluator` (pip) on committed 8-bit PNGs
//! (tests/data/compare/flip_vectors.json, written by scripts/ssim_vectors.py). pgt reads the PNGs
//! as linear and re-encodes them to 8-bit sRGB for FLIP, which must give back the same bytes, so
//! the two implementations see identical inputs. Budget: 1e-4 on the mean and 1e-3 per pixel
//! (float32 evaluation in both; the C++ core is the same code, a wrong input encoding shows up as
//! ≥ 1e-2).

use pgt::image_io::read_image;
use pgt::metrics::flip::{flip_ldr, FlipError};
use std::path::PathBuf;

#[test]
fn flip_matches_flip_evaluator() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/compare");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("flip_vectors.json")).unwrap())
            .unwrap();
    let files = doc["files"].as_array().unwrap();
    let r = read_image(&dir.join(files[0].as_str().unwrap())).unwrap();
    let a = read_image(&dir.join(files[1].as_str().unwrap())).unwrap();
    let ppd = doc["ppd"].as_f64().unwrap() as f32;
    let flip = flip_ldr(&r, &a, ppd).unwrap();
    let want = doc["mean"].as_f64().unwrap();
    assert!(want > 0.05, "the vector pair must differ visibly");
    assert!(
        (flip.mean - want).abs() < 1e-4,
        "FLIP mean {} vs flip-evaluator {want}",
        flip.mean
    );
    let map = doc["map"].as_array().unwrap();
    assert_eq!(map.len(), flip.map.len());
    let worst = flip
        .map
        .iter()
        .zip(map)
        .map(|(x, y)| (*x as f64 - y.as_f64().unwrap()).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-3, "FLIP map differs by {worst}");
}

#[test]
fn flip_of_identical_images_is_zero_and_hdr_is_refused() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/compare");
    let r = read_image(&dir.join("flip_ref.png")).unwrap();
    let flip = flip_ldr(&r, &r, 67.0).unwrap();
    assert_eq!(flip.mean, 0.0);
    let mut hdr = r.clone();
    hdr.pixels[3] = [2.0, 0.5, 0.5];
    assert_eq!(flip_ldr(&r, &hdr, 67.0).unwrap_err(), FlipError::Hdr(2.0));
}
