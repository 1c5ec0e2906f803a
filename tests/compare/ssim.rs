//! SSIM, MSE, PSNR and the error statistics against scikit-image / numpy vectors
//! (tests/data/compare/ssim_vectors.json, written by scripts/ssim_vectors.py). The budget is
//! 1e-6 absolute per channel and mean (docs/design.md §5); f64 reordering costs ~1e-15, a real
//! mismatch (wrong window, border mode, crop or constants) is ≥ 1e-4.

use pgt::image_io::{read_image, RgbImage};
use pgt::metrics::{compare, CompareOptions, DataRangeSource};
use serde_json::Value;
use std::path::PathBuf;

const TOLERANCE: f64 = 1e-6;

fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/compare")
}

fn vectors() -> Value {
    let text =
        std::fs::read_to_string(data_dir().join("ssim_vectors.json")).expect("vectors present");
    serde_json::from_str(&text).expect("vectors parse")
}

fn image(case: &Value, key: &str) -> RgbImage {
    let (w, h) = (
        case["width"].as_u64().unwrap() as u32,
        case["height"].as_u64().unwrap() as u32,
    );
    let flat: Vec<f32> = case[key]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap() as f32)
        .collect();
    assert_eq!(flat.len(), (w * h * 3) as usize);
    RgbImage {
        width: w,
        height: h,
        pixels: flat.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(),
    }
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

/// `stats_tolerance`: relative budget of the error statistics (1e-9 for the exact float32
/// inputs; 1e-5 for PNGs, whose f32 sRGB decoding differs from numpy's float64 by ~1e-7).
fn check_case(case: &Value, reference: &RgbImage, approximation: &RgbImage, stats_tolerance: f64) {
    let name = case["name"].as_str().unwrap();
    let data_range = f(&case["data_range"]);
    let options = CompareOptions {
        data_range: Some(data_range),
        flip: false,
        ..CompareOptions::default()
    };
    let cmp = compare(reference, approximation, &options).unwrap();
    assert_eq!(cmp.data_range_source, DataRangeSource::Given);
    let expected = &case["ssim"];
    if expected.get("error").is_some() {
        assert!(
            cmp.ssim.is_err(),
            "{name}: scikit-image refuses this size, pgt must too"
        );
    } else {
        let got = cmp
            .ssim_values()
            .unwrap_or_else(|| panic!("{name}: SSIM missing"));
        for c in 0..3 {
            let want = f(&expected["per_channel"][c]);
            assert!(
                (got.get(c) - want).abs() < TOLERANCE,
                "{name} channel {c}: {} vs {want}",
                got.get(c)
            );
            let map = &cmp.ssim.as_ref().unwrap()[c].map;
            let want_map = expected["maps"][c].as_array().unwrap();
            assert_eq!(map.len(), want_map.len());
            let worst = map
                .iter()
                .zip(want_map)
                .map(|(a, b)| (a - f(b)).abs())
                .fold(0.0, f64::max);
            assert!(
                worst < TOLERANCE,
                "{name} channel {c}: SSIM map differs by {worst}"
            );
        }
        let want = f(&expected["mean"]);
        assert!(
            (got.mean - want).abs() < TOLERANCE,
            "{name} mean: {} vs {want}",
            got.mean
        );
    }
    for c in 0..3 {
        let e = &cmp.errors[c];
        let close = |a: f64, b: f64| (a - b).abs() <= stats_tolerance * (1.0 + b.abs());
        assert!(
            close(e.mse, f(&case["mse"][c])),
            "{name} mse {c}: {} vs {}",
            e.mse,
            case["mse"][c]
        );
        assert!(close(e.rmse, f(&case["rmse"][c])), "{name} rmse {c}");
        assert!(
            close(e.mean_abs, f(&case["mean_abs"][c])),
            "{name} mean abs {c}"
        );
        assert!(
            close(e.max_abs, f(&case["max_abs"][c])),
            "{name} max abs {c}"
        );
        let px = &case["max_abs_pixel"][c];
        assert_eq!(
            (e.max_abs_pixel.0 as u64, e.max_abs_pixel.1 as u64),
            (px[0].as_u64().unwrap(), px[1].as_u64().unwrap()),
            "{name} max abs pixel {c}"
        );
        match case["psnr"][c].as_f64() {
            Some(p) => assert!(
                (e.psnr - p).abs() < stats_tolerance * p.abs().max(1.0),
                "{name} psnr {c}: {} vs {p}",
                e.psnr
            ),
            None => assert_eq!(e.psnr, f64::INFINITY, "{name} psnr {c}"),
        }
    }
}

#[test]
fn ssim_and_errors_match_scikit_image_vectors() {
    let doc = vectors();
    let cases = doc["cases"].as_array().unwrap();
    assert!(cases.len() >= 10, "the vector file lost cases");
    let mut checked = 0;
    for case in cases {
        if case.get("files").is_some() {
            continue; // PNG case: see the next test
        }
        check_case(
            case,
            &image(case, "reference"),
            &image(case, "approximation"),
            1e-9,
        );
        checked += 1;
    }
    assert!(checked >= 10);
}

#[test]
fn png16_files_decode_to_the_vectors_linear_values() {
    let doc = vectors();
    let case = doc["cases"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["name"] == "png16")
        .expect("png16 case");
    let files = case["files"].as_array().unwrap();
    let reference = read_image(&data_dir().join(files[0].as_str().unwrap())).unwrap();
    let approximation = read_image(&data_dir().join(files[1].as_str().unwrap())).unwrap();
    // The decoded pixels agree with numpy's float64 sRGB decoding to f32 rounding.
    let want = image(case, "reference");
    let worst = reference
        .pixels
        .iter()
        .zip(&want.pixels)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-6, "16-bit PNG decodes differently: {worst}");
    check_case(case, &reference, &approximation, 1e-5);
}

/// The vectorised SSIM equals SSIM by per-pixel gathers bit for bit, on an LDR and an HDR pair
/// whose height is not a multiple of the 32-row bands and whose sides are odd (reflected borders
/// on every side). benches/compare.rs times the two at 3840×2160.
#[test]
fn vectorised_ssim_equals_per_pixel_gathers() {
    use crate::support::compare_pairs::{pair, ssim_channel_gather};
    for scale in [1.0f32, 8.0] {
        let (r, a) = pair(301, 97, scale);
        let range = f64::from(scale);
        for c in 0..3 {
            let gathered = ssim_channel_gather(&r, &a, c, range);
            let vectorised = pgt::metrics::ssim::ssim_channel(&r, &a, c, range)
                .unwrap()
                .mean;
            assert_eq!(gathered, vectorised, "scale {scale}, channel {c}");
        }
    }
}

#[test]
fn identical_images_give_ssim_one_and_rmse_zero_exactly() {
    let doc = vectors();
    for case in doc["cases"].as_array().unwrap() {
        let img = image(case, "reference");
        let cmp = compare(&img, &img.clone(), &CompareOptions::default()).unwrap();
        for c in 0..3 {
            assert_eq!(cmp.errors[c].rmse, 0.0);
            assert_eq!(cmp.errors[c].max_abs, 0.0);
            assert_eq!(cmp.errors[c].psnr, f64::INFINITY);
        }
        if let Some(s) = cmp.ssim_values() {
            assert_eq!(
                (s.r, s.g, s.b, s.mean),
                (1.0, 1.0, 1.0, 1.0),
                "{}",
                case["name"]
            );
            assert!(cmp
                .ssim
                .as_ref()
                .unwrap()
                .iter()
                .all(|c| c.map.iter().all(|&v| v == 1.0)));
        }
    }
}

#[test]
fn non_finite_input_is_an_error_not_a_pass() {
    let mut a = RgbImage::new(16, 16);
    let b = RgbImage::new(16, 16);
    a.pixels[17][1] = f32::NAN;
    let e = compare(&a, &b, &CompareOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("non-finite") && e.contains("(1, 1)") && e.contains("channel G"),
        "{e}"
    );
    a.pixels[17][1] = f32::INFINITY;
    assert!(compare(&b, &a, &CompareOptions::default()).is_err());
}

#[test]
fn data_range_defaults_to_one_for_ldr_and_is_derived_for_hdr() {
    let doc = vectors();
    let case = doc["cases"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["name"] == "hdr")
        .unwrap();
    let (r, a) = (image(case, "reference"), image(case, "approximation"));
    let cmp = compare(
        &r,
        &a,
        &CompareOptions {
            flip: false,
            ..CompareOptions::default()
        },
    )
    .unwrap();
    assert_eq!(cmp.data_range_source, DataRangeSource::Derived);
    // The vector's range is max(ref) − min(0, min(ref)) computed by numpy.
    assert!((cmp.data_range - f(&case["data_range"])).abs() < 1e-9);
    assert!((cmp.ssim_values().unwrap().mean - f(&case["ssim"]["mean"])).abs() < TOLERANCE);
    let ldr = image(
        doc["cases"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["name"] == "identical")
            .unwrap(),
        "reference",
    );
    let cmp = compare(&ldr, &ldr, &CompareOptions::default()).unwrap();
    assert_eq!(
        (cmp.data_range, cmp.data_range_source),
        (1.0, DataRangeSource::Default)
    );
}
