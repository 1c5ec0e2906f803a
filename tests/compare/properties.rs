//! Properties of the metrics that hold for any input (docs/design.md §5), on random images:
//! SSIM is symmetric and ≤ 1, identical images give exactly 1 and 0, a constant offset c gives
//! RMSE |c| and max abs |c|, and the results do not depend on the thread count.

use pgt::image_io::RgbImage;
use pgt::metrics::{compare, CompareOptions};
use proptest::prelude::*;

fn image(w: u32, h: u32, values: &[f32]) -> RgbImage {
    RgbImage {
        width: w,
        height: h,
        pixels: (0..(w * h) as usize)
            .map(|i| std::array::from_fn(|c| values[(3 * i + c) % values.len()]))
            .collect(),
    }
}

fn options() -> CompareOptions {
    CompareOptions {
        data_range: Some(1.0),
        flip: false,
        ..CompareOptions::default()
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn ssim_symmetric_bounded_and_exact_on_identity(
        w in 11u32..40, h in 11u32..40,
        a in prop::collection::vec(0.0f32..1.0, 64..256),
        b in prop::collection::vec(0.0f32..1.0, 64..256),
    ) {
        let (x, y) = (image(w, h, &a), image(w, h, &b));
        let xy = compare(&x, &y, &options()).unwrap();
        let yx = compare(&y, &x, &options()).unwrap();
        let (s1, s2) = (xy.ssim_values().unwrap(), yx.ssim_values().unwrap());
        prop_assert_eq!(s1, s2);
        prop_assert!(s1.mean <= 1.0 && s1.mean >= -1.0);
        let xx = compare(&x, &x, &options()).unwrap();
        prop_assert_eq!(xx.ssim_values().unwrap().mean, 1.0);
        prop_assert_eq!(xx.error_values(|e| e.rmse).mean, 0.0);
    }

    #[test]
    fn constant_offset_gives_rmse_and_max_abs_of_the_offset(
        w in 1u32..30, h in 1u32..30,
        a in prop::collection::vec(0.0f32..1.0, 16..64),
        offset in -0.5f32..0.5,
    ) {
        let x = image(w, h, &a);
        let y = RgbImage { pixels: x.pixels.iter().map(|p| p.map(|v| v + offset)).collect(), ..x.clone() };
        let cmp = compare(&x, &y, &options()).unwrap();
        for e in &cmp.errors {
            // f32 rounding of v + offset: at most one ulp of values below 1.5.
            prop_assert!((e.rmse - offset.abs() as f64).abs() < 2e-7, "{} vs {}", e.rmse, offset);
            prop_assert!((e.max_abs - offset.abs() as f64).abs() < 2e-7);
        }
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let values: Vec<f32> = (0..997)
        .map(|i| ((i * 7919) % 1000) as f32 / 1000.0)
        .collect();
    let x = image(123, 77, &values);
    let y = image(123, 77, &values[13..]);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| compare(&x, &y, &CompareOptions::default()).unwrap())
    };
    let (one, four) = (run(1), run(4));
    assert_eq!(one.ssim_values(), four.ssim_values());
    assert_eq!(one.errors, four.errors);
    assert_eq!(one.flip_mean(), four.flip_mean());
    assert_eq!(one.flip.unwrap().map, four.flip.unwrap().map);
}
