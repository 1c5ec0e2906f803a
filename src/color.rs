//! Colour-space conversions shared by the readers of images (PNG) and of particle files (CPK
//! tables, MMPLD and VRML colours): one sRGB decoder.

/// IEC 61966-2-1 sRGB decoding of one channel, written once and instantiated for `f64` and
/// `f32` so that each keeps its own arithmetic: the `f32` PNG path rounds exactly as it always
/// did (decoding in `f64` and rounding the result would differ in the last bit for most inputs).
macro_rules! srgb_decode {
    ($c:expr) => {{
        let c = $c;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    }};
}

/// sRGB (IEC 61966-2-1) display value in [0, 1] to linear, in `f64` (particle colours).
pub fn srgb_to_linear(c: f64) -> f64 {
    srgb_decode!(c)
}

/// sRGB (IEC 61966-2-1) display value in [0, 1] to linear, in `f32` (PNG pixels); the same
/// formula as [`srgb_to_linear`], computed in `f32`.
pub fn srgb_to_linear_f32(c: f32) -> f32 {
    srgb_decode!(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two decoders pgt had before they were merged, kept as locked oracles.
    fn old_f32(s: f32) -> f32 {
        if s <= 0.040_45 {
            s / 12.92
        } else {
            ((s + 0.055) / 1.055).powf(2.4)
        }
    }
    fn old_f64(c: f64) -> f64 {
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    }

    /// Every value an 8- or 16-bit PNG decodes to (`image`'s `to_rgb32f`: v / max in f32)
    /// gives bit-identical results, and so do the 8-bit values of the CPK tables in f64.
    #[test]
    fn bit_identical_to_the_former_decoders() {
        for v in 0..=u16::MAX {
            let s = f32::from(v) / f32::from(u16::MAX);
            assert_eq!(
                srgb_to_linear_f32(s).to_bits(),
                old_f32(s).to_bits(),
                "{v}/65535"
            );
        }
        for v in 0..=u8::MAX {
            let s = f32::from(v) / f32::from(u8::MAX);
            assert_eq!(
                srgb_to_linear_f32(s).to_bits(),
                old_f32(s).to_bits(),
                "{v}/255"
            );
            let c = f64::from(v) / 255.0;
            assert_eq!(srgb_to_linear(c).to_bits(), old_f64(c).to_bits(), "{v}/255");
        }
    }

    #[test]
    fn end_points_and_the_linear_segment() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-12);
        assert_eq!(srgb_to_linear(0.04045), 0.04045 / 12.92);
        // The two pieces meet at the threshold (continuity to ~1e-8, IEC's rounded constants).
        assert!((srgb_to_linear(0.04045 + 1e-12) - 0.04045 / 12.92).abs() < 1e-7);
    }
}
