//! The values behind the sequence player's pixel probe (docs/design.md §10): for every frame,
//! the linear R, G, B of the reference, the approximation and the temporal error e_t, in
//! `frames/p_NNNNNN.js` beside the frame's PNGs. The player loads a frame's file by
//! `<script src>` when it first shows the frame (a page opened from `file://` may load scripts,
//! but neither `fetch` files nor read a canvas drawn from its own images), so a page of many
//! frames holds only the frames looked at.
//!
//! The encoding is chosen for the size of a committed report: the popping example
//! (`reports/examples/popping`, 64 frames of 96², 191 images) would hold 28 MB of probe values
//! as float32 in base64 and 14 MB as float16. Each image's values are therefore IEEE binary16
//! (three significant digits, the single-image viewer's encoding above 512²), little-endian,
//! R, G, B interleaved, row-major from the top, zlib-compressed (RFC 1950, what the browser's
//! `DecompressionStream("deflate")` reads) and written in base64: 2.0 MB for that example, whose
//! black background and near-zero e_t cost little. (Splitting the bytes into a low and a high
//! plane before zlib, as some float codecs do, made it 1 % larger there.)
//!
//! A file is one call, `pgtProbeFrame(FRAME, {"width": W, "height": H, "reference": B64,
//! "approximation": B64, "temporal": B64 or null})`; the first frame has no temporal error.

use super::viewer::{base64, f32_to_f16_bits};
use crate::error::{PgtError, Result};
use crate::image_io::RgbImage;
use std::path::{Path, PathBuf};

/// zlib's highest level: the files are written once and read many times.
const ZLIB_LEVEL: u8 = 9;

/// The probe file of `frame`, relative to the report folder.
pub fn probe_file(frames_dir: &str, frame: usize) -> String {
    format!("{frames_dir}/p_{frame:06}.js")
}

/// One frame's probe values, as [`read_probe_frame`] gives them back.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbeFrame {
    pub frame: usize,
    pub reference: RgbImage,
    pub approximation: RgbImage,
    /// e_t per pixel and channel; `None` for the first frame.
    pub temporal: Option<RgbImage>,
}

/// The values of `image` in the encoding of the module doc (base64 of zlib of little-endian
/// float16).
pub fn encode_values(image: &RgbImage) -> String {
    let halves: Vec<u8> = image
        .pixels
        .iter()
        .flatten()
        .flat_map(|v| f32_to_f16_bits(*v).to_le_bytes())
        .collect();
    base64(&miniz_oxide::deflate::compress_to_vec_zlib(
        &halves, ZLIB_LEVEL,
    ))
}

/// Writes `dir/frames/p_NNNNNN.js` for one frame; returns its path.
pub fn write_probe_frame(
    dir: &Path,
    frames_dir: &str,
    frame: usize,
    reference: &RgbImage,
    approximation: &RgbImage,
    temporal: Option<&RgbImage>,
) -> Result<PathBuf> {
    let data = serde_json::json!({
        "width": reference.width,
        "height": reference.height,
        "reference": encode_values(reference),
        "approximation": encode_values(approximation),
        "temporal": temporal.map(encode_values),
    });
    let path = dir.join(probe_file(frames_dir, frame));
    super::text::write_text(&path, &format!("pgtProbeFrame({frame}, {data});\n"))?;
    Ok(path)
}

/// Reads a file written by [`write_probe_frame`] back (the tests' way of checking what the
/// player shows).
pub fn read_probe_frame(path: &Path) -> Result<ProbeFrame> {
    let bad = |what: &str| PgtError::in_file(path, format!("not a probe file: {what}"));
    let text = std::fs::read_to_string(path).map_err(|e| PgtError::io(path, e))?;
    let body = text
        .trim()
        .strip_prefix("pgtProbeFrame(")
        .and_then(|s| s.strip_suffix(");"))
        .ok_or_else(|| bad("no pgtProbeFrame(…) call"))?;
    let (frame, json) = body.split_once(',').ok_or_else(|| bad("no frame number"))?;
    let frame: usize = frame.trim().parse().map_err(|_| bad("frame number"))?;
    let v: serde_json::Value = serde_json::from_str(json).map_err(|_| bad("JSON"))?;
    let dim = |k: &str| v[k].as_u64().map(|x| x as u32).ok_or_else(|| bad(k));
    let (w, h) = (dim("width")?, dim("height")?);
    let image = |k: &str| -> Result<Option<RgbImage>> {
        let Some(b64) = v[k].as_str() else {
            return Ok(None);
        };
        let zlib = base64_decode(b64).ok_or_else(|| bad("base64"))?;
        let halves =
            miniz_oxide::inflate::decompress_to_vec_zlib(&zlib).map_err(|_| bad("zlib stream"))?;
        if halves.len() != (w * h * 3 * 2) as usize {
            return Err(bad("value count"));
        }
        let mut img = RgbImage::new(w, h);
        for (v, b) in img.pixels.iter_mut().flatten().zip(halves.chunks_exact(2)) {
            *v = f16_bits_to_f32(u16::from_le_bytes([b[0], b[1]]));
        }
        Ok(Some(img))
    };
    Ok(ProbeFrame {
        frame,
        reference: image("reference")?.ok_or_else(|| bad("reference"))?,
        approximation: image("approximation")?.ok_or_else(|| bad("approximation"))?,
        temporal: image("temporal")?,
    })
}

/// The value of IEEE binary16 bits (exact: every half is a float).
pub fn f16_bits_to_f32(h: u16) -> f32 {
    half::f16::from_bits(h).to_f32()
}

/// Standard base64 (with padding) back to bytes; `None` on a character outside the alphabet.
fn base64_decode(s: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let bytes = s.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(bytes.len() * 3 / 4);
    for chunk in bytes.chunks(4) {
        let mut n = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            n |= value(c)? << (18 - 6 * i);
        }
        out.extend_from_slice(&n.to_be_bytes()[1..chunk.len()]);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halves_read_back_as_written() {
        for v in [0.0f32, 1.0, -2.5, 0.333, 6.1e-5, 1e-7, 65504.0] {
            let back = f16_bits_to_f32(f32_to_f16_bits(v));
            assert!(
                (back - v).abs() <= v.abs() * 2f32.powi(-11) + 2f32.powi(-25),
                "{v} → {back}"
            );
        }
        assert!(f16_bits_to_f32(0x7c00).is_infinite());
    }

    #[test]
    fn base64_round_trips() {
        for n in 0..8 {
            let bytes: Vec<u8> = (0..n).map(|i| (i * 37 + 5) as u8).collect();
            assert_eq!(base64_decode(&base64(&bytes)), Some(bytes));
        }
    }

    #[test]
    fn a_probe_file_reads_back_as_the_halves_of_its_images() {
        let dir = tempfile::tempdir().unwrap();
        let mut r = RgbImage::new(5, 3);
        for (i, p) in r.pixels.iter_mut().enumerate() {
            *p = [i as f32 * 0.1, 0.5, 1e-3 * i as f32];
        }
        let mut a = r.clone();
        a.pixels[7] = [2.0, 0.0, 0.25];
        std::fs::create_dir_all(dir.path().join("frames")).unwrap();
        let path = write_probe_frame(dir.path(), "frames", 3, &r, &a, None).unwrap();
        assert!(path.ends_with("frames/p_000003.js"));
        let back = read_probe_frame(&path).unwrap();
        assert_eq!(back.frame, 3);
        assert_eq!(back.temporal, None);
        let halves = |img: &RgbImage| {
            let mut h = img.clone();
            h.pixels.iter_mut().flatten().for_each(|v| {
                *v = f16_bits_to_f32(f32_to_f16_bits(*v));
            });
            h
        };
        assert_eq!(back.reference, halves(&r));
        assert_eq!(back.approximation, halves(&a));
    }
}
