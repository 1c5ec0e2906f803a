//! The interactive part of a report (docs/design.md §5: "Interactive where a browser runs it
//! (synchronised zoom, A/B flip, a pixel probe with values and the reference's error estimate),
//! and complete without it"): a section of the page, hidden until its script runs, with
//! reference, approximation and error panes that zoom and pan together (nearest-neighbour
//! pixels), an A/B flip, an exposure control and a pixel probe.
//!
//! The probe needs the float values, which a PNG does not hold. They travel in `pgt-data.js`
//! beside the page, loaded by `<script src>` (a page opened from `file://` may load scripts
//! but not `fetch` files): the reference, each approximation and the reference's error estimate
//! as interleaved R, G, B little-endian floats, row-major from the top row, in base64. Up to
//! [`F32_MAX_PIXELS`] pixels (512²: about 4 MiB of base64 per image) they are float32, exactly
//! the values of the EXR; up to [`F16_MAX_PIXELS`] (1024²) float16 (three significant digits,
//! about 8 MiB per image); larger images get no probe data and the viewer shows the PNGs (zoom,
//! pan and flip still work; the page says why the probe is off). The script itself is
//! `pgt-viewer.js` (`src/report/viewer.js`), the same file for every report.

use super::text::{escape, write_text};
use crate::error::{PgtError, Result};
use crate::image_io::RgbImage;
use std::fmt::Write as _;
use std::path::Path;

/// Largest image (pixels) whose values are embedded as float32, exactly.
pub const F32_MAX_PIXELS: u64 = 512 * 512;
/// Largest image (pixels) whose values are embedded at all (as float16 above [`F32_MAX_PIXELS`]).
pub const F16_MAX_PIXELS: u64 = 1024 * 1024;
/// The viewer's script, written beside every page as `pgt-viewer.js`.
const VIEWER_JS: &str = include_str!("viewer.js");
/// File names beside the page.
pub const DATA_FILE: &str = "pgt-data.js";
pub const SCRIPT_FILE: &str = "pgt-viewer.js";

/// How the float values are embedded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    F32,
    F16,
    /// Too large: no values, the probe is off.
    None,
}

impl Encoding {
    /// The encoding for an image of `pixels` pixels (see the module doc for the limits).
    pub fn for_pixels(pixels: u64) -> Encoding {
        if pixels <= F32_MAX_PIXELS {
            Encoding::F32
        } else if pixels <= F16_MAX_PIXELS {
            Encoding::F16
        } else {
            Encoding::None
        }
    }

    fn name(self) -> &'static str {
        match self {
            Encoding::F32 => "f32",
            Encoding::F16 => "f16",
            Encoding::None => "none",
        }
    }
}

/// One approximation the viewer can show against the reference.
#[derive(Debug, Clone)]
pub struct ViewerImage<'a> {
    pub label: String,
    /// Its PNG beside the page (shown where no values are embedded).
    pub png: String,
    /// Its |a − r| heatmap PNG beside the page (the error pane).
    pub heatmap: String,
    pub image: &'a RgbImage,
}

/// What the viewer shows.
#[derive(Debug, Clone)]
pub struct Viewer<'a> {
    pub reference: &'a RgbImage,
    /// The reference's PNG beside the page.
    pub reference_png: String,
    /// The reference's per-pixel error estimate (its EXR `err` layer), where it has one.
    pub estimate: Option<&'a RgbImage>,
    /// At least one; the page offers a choice where there are several (a sweep's runs).
    pub approximations: Vec<ViewerImage<'a>>,
    /// Initial exposure of the reference and approximation panes, in stops.
    pub exposure: f32,
    /// What the error pane shows (its colour map and scale), for its title.
    pub error_caption: String,
}

/// Writes `pgt-data.js` and `pgt-viewer.js` into `dir` and returns the page's section for the
/// viewer (hidden until the script shows it) with its two `<script src>` tags.
pub fn write_viewer(dir: &Path, viewer: &Viewer) -> Result<String> {
    let (w, h) = (viewer.reference.width, viewer.reference.height);
    let encoding = Encoding::for_pixels(w as u64 * h as u64);
    let values = |img: &RgbImage| -> Option<String> {
        ((img.width, img.height) == (w, h) && encoding != Encoding::None)
            .then(|| encode(img, encoding))
    };
    let note = match encoding {
        Encoding::None => format!(
            "The probe and the exposure control are off: {w}×{h} pixels is over the {} pixels whose values a report embeds; the panes show the PNGs.",
            F16_MAX_PIXELS
        ),
        Encoding::F16 => "Probe values are float16 (three significant digits): the image is over 512×512 pixels.".into(),
        Encoding::F32 => String::new(),
    };
    let data = serde_json::json!({
        "width": w,
        "height": h,
        "encoding": encoding.name(),
        "exposure": viewer.exposure,
        "note": note,
        "reference": { "png": viewer.reference_png, "data": values(viewer.reference) },
        "estimate": viewer.estimate.and_then(values),
        "approximations": viewer.approximations.iter().map(|a| serde_json::json!({
            "label": a.label,
            "png": a.png,
            "heatmap": a.heatmap,
            "data": values(a.image),
        })).collect::<Vec<_>>(),
    });
    let js = serde_json::to_string(&data)
        .map_err(|e| PgtError::io(dir.join(DATA_FILE), std::io::Error::other(e)))?;
    write_text(
        &dir.join(DATA_FILE),
        &format!("// pgt report data: see src/report/viewer.rs\nwindow.PGT_DATA = {js};\n"),
    )?;
    write_text(&dir.join(SCRIPT_FILE), VIEWER_JS)?;
    Ok(section(viewer))
}

/// The viewer's HTML: controls, three panes, the probe table.
fn section(viewer: &Viewer) -> String {
    let mut s = String::from(
        "<section id=\"pgt-viewer\" hidden>\n<h2>Interactive view</h2>\n<p class=\"help\">Wheel or +/− to zoom, drag to pan (all panes together), <kbd>f</kbd> flips A/B, <kbd>0</kbd> fits; hover a pixel to probe it.</p>\n<div class=\"controls\">\n<button type=\"button\" id=\"pgt-flip\">A/B flip (f)</button>\n<button type=\"button\" id=\"pgt-zoom-in\">zoom + (+)</button>\n<button type=\"button\" id=\"pgt-zoom-out\">zoom − (−)</button>\n<button type=\"button\" id=\"pgt-zoom-fit\">fit (0)</button>\n<span id=\"pgt-zoom-value\"></span>\n<label>exposure <input type=\"range\" id=\"pgt-exposure\" min=\"-16\" max=\"16\" step=\"any\"> <output id=\"pgt-exposure-value\"></output> stops</label>\n",
    );
    if viewer.approximations.len() > 1 {
        s += "<label>run <select id=\"pgt-run\">";
        for (i, a) in viewer.approximations.iter().enumerate() {
            let _ = write!(s, "<option value=\"{i}\">{}</option>", escape(&a.label));
        }
        s += "</select></label>\n";
    }
    s += "</div>\n<div class=\"panes\">\n";
    for (id, title) in [
        ("a", "reference".to_string()),
        ("b", "approximation".to_string()),
        ("e", format!("error: {}", viewer.error_caption)),
    ] {
        let _ = writeln!(
            s,
            "<div class=\"pane\"><div class=\"pane-title\" id=\"pgt-title-{id}\">{}</div><div class=\"viewport\" id=\"pgt-viewport-{id}\"><canvas id=\"pgt-canvas-{id}\"></canvas></div></div>",
            escape(&title)
        );
    }
    s += "</div>\n<table id=\"pgt-probe\"><tr><th id=\"pgt-probe-pixel\">pixel</th><th>R</th><th>G</th><th>B</th></tr>\n";
    for (key, name) in [
        ("reference", "reference"),
        ("approximation", "approximation"),
        ("difference", "|a − r|"),
        ("estimate", "reference error estimate"),
    ] {
        let _ = write!(s, "<tr><td>{name}</td>");
        for c in 0..3 {
            let _ = write!(s, "<td data-probe=\"{key}-{c}\"></td>");
        }
        s += "</tr>\n";
    }
    let _ = write!(
        s,
        "</table>\n<p id=\"pgt-viewer-note\"></p>\n</section>\n<script src=\"{DATA_FILE}\"></script>\n<script src=\"{SCRIPT_FILE}\"></script>\n"
    );
    s
}

/// The image's values as base64 little-endian floats (R, G, B interleaved, row-major).
fn encode(image: &RgbImage, encoding: Encoding) -> String {
    let mut bytes = Vec::with_capacity(image.pixels.len() * 12);
    for p in &image.pixels {
        for &v in p {
            match encoding {
                Encoding::F16 => bytes.extend_from_slice(&f32_to_f16_bits(v).to_le_bytes()),
                _ => bytes.extend_from_slice(&v.to_le_bytes()),
            }
        }
    }
    base64(&bytes)
}

/// Standard base64 (RFC 4648, with padding), as the browser's `atob` reads it.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for (i, shift) in [18, 12, 6, 0].into_iter().enumerate() {
            if i <= chunk.len() {
                out.push(ALPHABET[(n >> shift & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// IEEE 754 binary16 bits of `v`, rounded to nearest, ties to even; overflow gives infinity,
/// tiny values subnormals or zero, NaN stays NaN.
pub fn f32_to_f16_bits(v: f32) -> u16 {
    let x = v.to_bits();
    let sign = ((x >> 16) & 0x8000) as u16;
    let exp = ((x >> 23) & 0xff) as i32;
    let man = x & 0x007f_ffff;
    if exp == 0xff {
        return sign | 0x7c00 | if man != 0 { 0x200 } else { 0 };
    }
    // Unbiased exponent e; half's normal range is e ∈ [−14, 15].
    let e = exp - 127;
    if e > 15 {
        return sign | 0x7c00;
    }
    // The significand with its implicit bit, and how far it must shift right to become half's
    // 10-bit significand (more for subnormals).
    let (full, shift) = if e >= -14 {
        (man | 0x0080_0000, 13)
    } else if e >= -25 {
        (man | 0x0080_0000, 13 + (-14 - e) as u32)
    } else {
        return sign;
    };
    let kept = full >> shift;
    let rest = full & ((1 << shift) - 1);
    let half_way = 1 << (shift - 1);
    let rounded = if rest > half_way || (rest == half_way && kept & 1 == 1) {
        kept + 1
    } else {
        kept
    };
    if e >= -14 {
        // Normal: carry from rounding may bump the exponent (to infinity at the top).
        let bits = (((e + 15) as u32) << 10) + (rounded - 0x400);
        sign | bits.min(0x7c00) as u16
    } else {
        sign | rounded as u16
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc4648_vectors() {
        for (input, expected) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(input.as_bytes()), expected, "{input}");
        }
        assert_eq!(base64(&[0xfb, 0xff, 0xbf]), "+/+/");
    }

    #[test]
    fn f16_bits_are_ieee_binary16() {
        for (v, bits) in [
            (0.0f32, 0x0000u16),
            (-0.0, 0x8000),
            (1.0, 0x3c00),
            (-2.0, 0xc000),
            (0.5, 0x3800),
            (65504.0, 0x7bff),
            (65520.0, 0x7c00), // rounds up past the largest half: infinity
            (1e6, 0x7c00),
            (f32::INFINITY, 0x7c00),
            (6.103_515_6e-5, 0x0400),     // smallest normal
            (5.960_464_5e-8, 0x0001),     // smallest subnormal
            (2.0e-8, 0x0000),             // below half of it: zero
            (1.0 + 1.0 / 2048.0, 0x3c00), // a tie rounds to even
            (1.0 + 3.0 / 2048.0, 0x3c02),
            (0.1, 0x2e66),
        ] {
            assert_eq!(f32_to_f16_bits(v), bits, "{v}");
        }
        assert_eq!(f32_to_f16_bits(f32::NAN) & 0x7c00, 0x7c00);
        assert_ne!(f32_to_f16_bits(f32::NAN) & 0x03ff, 0);
    }

    #[test]
    fn encodings_by_size() {
        assert_eq!(Encoding::for_pixels(512 * 512), Encoding::F32);
        assert_eq!(Encoding::for_pixels(512 * 512 + 1), Encoding::F16);
        assert_eq!(Encoding::for_pixels(1024 * 1024 + 1), Encoding::None);
    }

    #[test]
    fn data_file_holds_the_exact_floats() {
        let dir = tempfile::tempdir().unwrap();
        let mut r = RgbImage::new(2, 1);
        r.pixels = vec![[0.1, 2.5, 1e-7], [0.0, 1.0, 3.25]];
        let viewer = Viewer {
            reference: &r,
            reference_png: "reference.png".into(),
            estimate: None,
            approximations: vec![ViewerImage {
                label: "a".into(),
                png: "a.png".into(),
                heatmap: "h.png".into(),
                image: &r,
            }],
            exposure: -1.0,
            error_caption: "magma".into(),
        };
        let html = write_viewer(dir.path(), &viewer).unwrap();
        assert!(html.contains("<script src=\"pgt-data.js\"></script>"));
        assert!(html.contains("data-probe=\"estimate-2\"") && !html.contains("pgt-run"));
        let js = std::fs::read_to_string(dir.path().join(DATA_FILE)).unwrap();
        let json = js
            .split_once("window.PGT_DATA = ")
            .unwrap()
            .1
            .trim_end()
            .trim_end_matches(';');
        let v: serde_json::Value = serde_json::from_str(json).unwrap();
        assert_eq!(v["encoding"], "f32");
        assert!(v["estimate"].is_null());
        let expected: Vec<u8> = r
            .pixels
            .iter()
            .flatten()
            .flat_map(|f| f.to_le_bytes())
            .collect();
        assert_eq!(v["reference"]["data"], base64(&expected));
        assert_eq!(v["approximations"][0]["heatmap"], "h.png");
        assert!(dir.path().join(SCRIPT_FILE).is_file());
    }
}
