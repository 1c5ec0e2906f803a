//! Comparison conventions (`[[conventions]]` of an experiment): the baseline comparisons repeated
//! with both images stored as another renderer stores them before its SSIM is taken, normalised
//! by their maximum and rounded to a bit depth. The thesis stores the intensity at the sensor
//! "und anschließend normiert" (chapter 5) and does not say how, nor at which bit depth its
//! SSIM was taken; `reports/thesis/` measures what each choice is worth.
//!
//! A convention prepares each image on its own, as a renderer that writes its output file does:
//! `normalize = "max"` divides every channel by the image's largest channel value,
//! `"channel-max"` each channel by that channel's largest value (a channel that is 0
//! everywhere stays 0), `"none"` leaves the values; `quantize = b` then clamps to [0, 1] and
//! rounds to the nearest of 2^b − 1 steps (8: an 8-bit file). The comparison itself is the
//! experiment's (`data_range` included).

use crate::image_io::RgbImage;

/// How an image is normalised before a convention's comparison.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Normalize {
    #[default]
    None,
    Max,
    ChannelMax,
}

/// Largest bit depth `quantize` accepts: beyond it f32 holds no more steps.
pub const MAX_QUANTIZE_BITS: u32 = 24;

/// One `[[conventions]]` table.
#[derive(Debug, Clone, PartialEq, Eq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Convention {
    /// The name `sweep.json` files the results under.
    pub name: String,
    #[serde(default)]
    pub normalize: Normalize,
    /// Bits per channel after normalisation; `None`: the values as they are.
    pub quantize: Option<u32>,
}

impl Convention {
    /// The image as this convention stores it.
    pub fn prepare(&self, image: &RgbImage) -> RgbImage {
        let mut scale = [1.0f32; 3];
        match self.normalize {
            Normalize::None => {}
            Normalize::Max => {
                let max = channel_maxima(image).into_iter().fold(0.0f32, f32::max);
                if max > 0.0 {
                    scale = [1.0 / max; 3];
                }
            }
            Normalize::ChannelMax => {
                for (s, max) in scale.iter_mut().zip(channel_maxima(image)) {
                    if max > 0.0 {
                        *s = 1.0 / max;
                    }
                }
            }
        }
        let steps = self.quantize.map(|bits| ((1u64 << bits) - 1) as f32);
        let pixels = image
            .pixels
            .iter()
            .map(|p| {
                std::array::from_fn(|c| {
                    let v = p[c] * scale[c];
                    match steps {
                        Some(n) => (v.clamp(0.0, 1.0) * n).round() / n,
                        None => v,
                    }
                })
            })
            .collect();
        RgbImage {
            width: image.width,
            height: image.height,
            pixels,
        }
    }
}

/// The largest value of each channel (0 for an empty image or one without positive values).
fn channel_maxima(image: &RgbImage) -> [f32; 3] {
    image
        .pixels
        .iter()
        .fold([0.0f32; 3], |m, p| std::array::from_fn(|c| m[c].max(p[c])))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(pixels: Vec<[f32; 3]>) -> RgbImage {
        RgbImage {
            width: pixels.len() as u32,
            height: 1,
            pixels,
        }
    }

    fn convention(normalize: Normalize, quantize: Option<u32>) -> Convention {
        Convention {
            name: "c".into(),
            normalize,
            quantize,
        }
    }

    #[test]
    fn max_divides_every_channel_by_the_largest_value() {
        let img = image(vec![[0.1, 0.2, 0.0], [0.05, 0.4, 0.0]]);
        let out = convention(Normalize::Max, None).prepare(&img);
        assert_eq!(out.pixels, vec![[0.25, 0.5, 0.0], [0.125, 1.0, 0.0]]);
    }

    #[test]
    fn channel_max_scales_each_channel_to_one_and_keeps_a_black_channel_black() {
        let img = image(vec![[0.1, 0.2, 0.0], [0.05, 0.4, 0.0]]);
        let out = convention(Normalize::ChannelMax, None).prepare(&img);
        assert_eq!(out.pixels, vec![[1.0, 0.5, 0.0], [0.5, 1.0, 0.0]]);
    }

    #[test]
    fn quantize_rounds_to_the_nearest_step_and_clamps() {
        let img = image(vec![[0.5, 1.5, -0.2], [0.501, 0.003, 0.002]]);
        let out = convention(Normalize::None, Some(8)).prepare(&img);
        // 0.5·255 = 127.5 rounds away from zero to 128; 0.501·255 = 127.76 → 128;
        // 0.003·255 = 0.765 → 1; 0.002·255 = 0.51 → 1.
        assert_eq!(
            out.pixels,
            vec![
                [128.0 / 255.0, 1.0, 0.0],
                [128.0 / 255.0, 1.0 / 255.0, 1.0 / 255.0]
            ]
        );
        let one_bit = convention(Normalize::None, Some(1)).prepare(&img);
        assert_eq!(one_bit.pixels[1], [1.0, 0.0, 0.0]);
    }

    #[test]
    fn normalization_is_scale_invariant() {
        let img = image(vec![[0.1, 0.2, 0.3], [0.7, 0.05, 0.9]]);
        let scaled = image(img.pixels.iter().map(|p| p.map(|v| v * 4.0)).collect());
        for n in [Normalize::Max, Normalize::ChannelMax] {
            let c = convention(n, Some(8));
            assert_eq!(c.prepare(&img).pixels, c.prepare(&scaled).pixels, "{n:?}");
        }
    }
}
