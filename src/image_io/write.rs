use super::RgbImage;
use crate::error::{PgtError, Result};
use std::io::{BufWriter, Write};
use std::path::Path;

/// Output format, from the extension of `-o`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageFormat {
    Exr,
    Png,
}

impl ImageFormat {
    /// The format named by a path's extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<ImageFormat> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("exr") => Ok(ImageFormat::Exr),
            Some("png") => Ok(ImageFormat::Png),
            _ => Err(PgtError::Usage(format!(
                "{}: output must end in .exr or .png",
                path.display()
            ))),
        }
    }
}

/// sRGB encoding (IEC 61966-2-1) of a linear value scaled by 2^exposure, clamped to [0, 1],
/// rounded to 8 bits.
pub fn linear_to_srgb8(v: f32, exposure_scale: f32) -> u8 {
    let v = (v * exposure_scale).clamp(0.0, 1.0);
    let v = if v.is_nan() { 0.0 } else { v };
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

/// Writes `image` (and, for EXR, the extra layers, each written as `NAME.R/G/B`) to `path`,
/// atomically. PNG ignores the extra layers and applies `exposure` in stops. A NaN or infinite
/// value in any layer is refused before anything is written (docs/design.md §6
/// "Bad input": nothing non-finite is ever written; it would be a bug, and must not pass a
/// user's CI silently).
pub fn write_image(
    path: &Path,
    image: &RgbImage,
    layers: &[(&str, &RgbImage)],
    exposure: f32,
) -> Result<()> {
    let format = ImageFormat::from_path(path)?;
    check_finite(path, image, layers)?;
    write_atomically(path, |w| match format {
        ImageFormat::Png => write_png(w, image, exposure),
        ImageFormat::Exr => write_exr(w, image, layers, &[]),
    })
}

/// Writes an EXR like [`write_image`] and adds `header` as custom text attributes of its header
/// (name, value): the metadata of a part of a cluster render (`crate::parts`).
pub fn write_exr_with_header(
    path: &Path,
    image: &RgbImage,
    layers: &[(&str, &RgbImage)],
    header: &[(&str, String)],
) -> Result<()> {
    if ImageFormat::from_path(path)? != ImageFormat::Exr {
        return Err(PgtError::Usage(format!(
            "{}: this output must be an .exr file",
            path.display()
        )));
    }
    check_finite(path, image, layers)?;
    write_atomically(path, |w| write_exr(w, image, layers, header))
}

/// The first NaN or infinite value of the image or its layers, as an error naming the output,
/// the pixel (x, y from the top left), the layer and the channel.
fn check_finite(path: &Path, image: &RgbImage, layers: &[(&str, &RgbImage)]) -> Result<()> {
    for (layer, img) in std::iter::once(("", image)).chain(layers.iter().copied()) {
        let Some(i) = img
            .pixels
            .iter()
            .position(|p| p.iter().any(|v| !v.is_finite()))
        else {
            continue;
        };
        let c = img.pixels[i]
            .iter()
            .position(|v| !v.is_finite())
            .unwrap_or(0);
        let (x, y) = (i % img.width.max(1) as usize, i / img.width.max(1) as usize);
        let channel = ["R", "G", "B"][c];
        let what = if layer.is_empty() {
            format!("channel {channel} of the image")
        } else {
            format!("channel {layer}.{channel} of layer '{layer}'")
        };
        return Err(PgtError::in_file(
            path,
            format!(
                "refusing to write a non-finite value ({}) at pixel ({x}, {y}), {what}; nothing was written (this is a bug in pgt: please report it with the command line)",
                img.pixels[i][c]
            ),
        ));
    }
    Ok(())
}

/// Writes a file atomically (docs/design.md §7: never a half-written output): `write` fills a
/// temporary file in the target folder, which is flushed, synced and renamed to `path` only when
/// it succeeded; on any error the temporary file is removed. Missing folders on the way are
/// made (as `--report` makes its folder). The result is readable by anyone (0644), as a plain
/// file would be, not 0600 as temporary files are.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<&std::fs::File>) -> std::io::Result<()>,
) -> Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    // Registered for removal on SIGINT/SIGTERM (crate::signals) from its creation on, and
    // renamed with the signal cleanup held off, so an interrupt leaves neither it nor half a file.
    // The folder is made under the same hold: once the cleanup has removed a temporary report
    // folder, no write may make it again before the process exits.
    let (tmp, guard) = crate::signals::track(
        || {
            std::fs::create_dir_all(dir)?;
            tempfile::Builder::new()
                .prefix(".pgt-partial-")
                .tempfile_in(dir)
        },
        |t| t.path().to_path_buf(),
    )
    .map_err(|e| PgtError::io(dir, e))?;
    {
        let mut w = BufWriter::new(tmp.as_file());
        write(&mut w).map_err(|e| PgtError::io(path, e))?;
        w.flush().map_err(|e| PgtError::io(path, e))?;
    }
    tmp.as_file()
        .sync_all()
        .map_err(|e| PgtError::io(path, e))?;
    guard
        .finish(|| tmp.persist(path))
        .map_err(|e| PgtError::io(path, e.error))?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        // Best effort: the file is complete either way.
        let _ = std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o644));
    }
    Ok(())
}

fn write_png(
    w: &mut BufWriter<&std::fs::File>,
    image: &RgbImage,
    exposure: f32,
) -> std::io::Result<()> {
    let scale = 2f32.powf(exposure);
    let bytes: Vec<u8> = image
        .pixels
        .iter()
        .flat_map(|p| p.map(|v| linear_to_srgb8(v, scale)))
        .collect();
    image::codecs::png::PngEncoder::new(w)
        .write_image(
            &bytes,
            image.width,
            image.height,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(std::io::Error::other)
}

use image::ImageEncoder;

/// Float32 channels `R`, `G`, `B` and `NAME.R/G/B` per layer. Run-length compression: lossless,
/// nearly as fast as none, small where values are exactly 0 (ZIP took 30 s on 4K error maps).
fn write_exr(
    w: &mut BufWriter<&std::fs::File>,
    image: &RgbImage,
    layers: &[(&str, &RgbImage)],
    header: &[(&str, String)],
) -> std::io::Result<()> {
    use exr::prelude::*;
    let size = (image.width as usize, image.height as usize);
    let mut channels: Vec<AnyChannel<FlatSamples>> = Vec::new();
    for (prefix, img) in std::iter::once(("", image)).chain(layers.iter().copied()) {
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            let full = if prefix.is_empty() {
                name.to_string()
            } else {
                format!("{prefix}.{name}")
            };
            let samples: Vec<f32> = img.pixels.iter().map(|p| p[c]).collect();
            channels.push(AnyChannel::new(full.as_str(), FlatSamples::F32(samples)));
        }
    }
    let channels = AnyChannels::sort(channels.into_iter().collect());
    let mut attributes = LayerAttributes::default();
    let text = |s: &str| {
        Text::new_or_none(s)
            .ok_or_else(|| std::io::Error::other(format!("EXR header text '{s}' is not Latin-1")))
    };
    for (name, value) in header {
        attributes
            .other
            .insert(text(name)?, AttributeValue::Text(text(value)?));
    }
    // Blocks in increasing order: the compressor threads finish them in any order, and with
    // the default (unspecified) order the file's bytes then differed from run to run although
    // every value was the same.
    let encoding = Encoding {
        line_order: LineOrder::Increasing,
        ..Encoding::FAST_LOSSLESS
    };
    let layer = Layer::new(size, attributes, encoding, channels);
    Image::from_layer(layer)
        .write()
        .to_buffered(&mut *w)
        .map_err(std::io::Error::other)?;
    if header.len() > 1 {
        sort_header_in_file(w)?;
    }
    Ok(())
}

/// Most bytes of a file read to find the end of its EXR header (pgt's headers take well under
/// a kilobyte).
const HEADER_READ: u64 = 1 << 20;

/// Sorts the header attributes of the EXR just written through `w` ([`sort_header_attributes`]),
/// rewriting them in place.
fn sort_header_in_file(w: &mut BufWriter<&std::fs::File>) -> std::io::Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    w.flush()?;
    let mut file: &std::fs::File = w.get_ref();
    let len = file.seek(SeekFrom::End(0))?;
    let mut prefix = vec![0u8; len.min(HEADER_READ) as usize];
    file.seek(SeekFrom::Start(0))?;
    file.read_exact(&mut prefix)?;
    let end = sort_header_attributes(&mut prefix)?;
    file.seek(SeekFrom::Start(0))?;
    file.write_all(&prefix[..end])?;
    file.seek(SeekFrom::End(0))?;
    Ok(())
}

/// Puts the attributes of a single-part EXR header (`bytes` holds at least the whole header) in
/// the order of their names, in place; returns the header's length. The exr crate writes
/// custom attributes (a part's `pgt…` metadata) in the order of a `HashMap`, which changes from
/// run to run, so the same part would be a different file each time. Sorting keeps every
/// attribute and the header's length, so the offset table after it stays valid.
///
/// The layout (OpenEXR file layout: magic number, version field, then attributes, each a
/// null-terminated name, a null-terminated type name, a little-endian i32 size and the value,
/// ended by an empty name) is checked as it is walked: anything else is an error, not a guess.
fn sort_header_attributes(bytes: &mut [u8]) -> std::io::Result<usize> {
    const MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
    const MULTIPART: u32 = 0x1000;
    let bad = |what: &str| std::io::Error::other(format!("EXR header: {what}"));
    if bytes.len() < 8 || bytes[..4] != MAGIC {
        return Err(bad("no magic number"));
    }
    if u32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]) & MULTIPART != 0 {
        return Err(bad("a multi-part file (pgt writes single-part files)"));
    }
    let zero_from = |from: usize| {
        bytes
            .get(from..)
            .and_then(|rest| rest.iter().position(|&b| b == 0))
            .map(|i| from + i)
            .ok_or_else(|| bad("it does not end within the bytes read"))
    };
    // (name, whole attribute) byte ranges, in file order.
    let mut attributes = Vec::new();
    let mut at = 8;
    loop {
        let name_end = zero_from(at)?;
        if name_end == at {
            break;
        }
        let type_end = zero_from(name_end + 1)?;
        let size_bytes = bytes
            .get(type_end + 1..type_end + 5)
            .ok_or_else(|| bad("an attribute size is cut off"))?;
        let size = i32::from_le_bytes([size_bytes[0], size_bytes[1], size_bytes[2], size_bytes[3]]);
        let size = usize::try_from(size).map_err(|_| bad("a negative attribute size"))?;
        let end = type_end + 5 + size;
        if end > bytes.len() {
            return Err(bad("an attribute value is cut off"));
        }
        attributes.push((at..name_end, at..end));
        at = end;
    }
    let mut sorted = attributes.clone();
    sorted.sort_by(|a, b| bytes[a.0.clone()].cmp(&bytes[b.0.clone()]));
    let body: Vec<u8> = sorted
        .iter()
        .flat_map(|(_, whole)| bytes[whole.clone()].iter().copied())
        .collect();
    bytes[8..at].copy_from_slice(&body);
    Ok(at + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image_with(value: f32, at: usize, channel: usize) -> RgbImage {
        let mut img = RgbImage::new(5, 4);
        img.pixels[at][channel] = value;
        img
    }

    /// Writes and expects a refusal mentioning every needle, with nothing left in the folder.
    fn refused(name: &str, image: &RgbImage, layers: &[(&str, &RgbImage)], needles: &[&str]) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(name);
        let e = write_image(&path, image, layers, 0.0)
            .unwrap_err()
            .to_string();
        for n in needles {
            assert!(e.contains(n), "'{n}' not in: {e}");
        }
        assert!(
            std::fs::read_dir(dir.path()).unwrap().next().is_none(),
            "{e}"
        );
    }

    /// The same image gives the same file, byte for byte, however the compressor threads
    /// finish (many blocks, written several times).
    #[test]
    fn an_exr_is_the_same_bytes_every_time() {
        let mut img = RgbImage::new(512, 384);
        for (k, p) in img.pixels.iter_mut().enumerate() {
            *p = [(k % 997) as f32 * 0.37, (k % 13) as f32, (k as f32).sqrt()];
        }
        let err = img.clone();
        let dir = tempfile::tempdir().unwrap();
        let bytes: Vec<Vec<u8>> = (0..6)
            .map(|n| {
                let path = dir.path().join(format!("{n}.exr"));
                write_image(&path, &img, &[("err", &err)], 0.0).unwrap();
                std::fs::read(path).unwrap()
            })
            .collect();
        assert!(bytes.windows(2).all(|w| w[0] == w[1]));
    }

    /// A part's custom header attributes come out in name order, whatever order the exr
    /// crate's map gives them: the same part is the same bytes on every run.
    #[test]
    fn custom_header_attributes_are_written_in_name_order() {
        let img = RgbImage::new(7, 3);
        let dir = tempfile::tempdir().unwrap();
        let header: Vec<(&str, String)> = ["pgtE", "pgtB", "pgtD", "pgtA", "pgtC"]
            .iter()
            .map(|&k| (k, format!("value of {k}")))
            .collect();
        let files: Vec<Vec<u8>> = (0..4)
            .map(|n| {
                let path = dir.path().join(format!("{n}.exr"));
                write_exr_with_header(&path, &img, &[("err", &img)], &header).unwrap();
                std::fs::read(path).unwrap()
            })
            .collect();
        assert!(files.windows(2).all(|w| w[0] == w[1]));
        let text = String::from_utf8_lossy(&files[0]);
        let at: Vec<usize> = ["pgtA", "pgtB", "pgtC", "pgtD", "pgtE"]
            .iter()
            .map(|k| text.find(k).unwrap())
            .collect();
        assert!(at.windows(2).all(|w| w[0] < w[1]), "{at:?}");
        // Still a valid EXR with every attribute.
        let read = exr::prelude::read_all_flat_layers_from_file(dir.path().join("0.exr")).unwrap();
        let layer = &read.layer_data[0];
        let n = layer
            .attributes
            .other
            .keys()
            .chain(read.attributes.other.keys())
            .filter(|k| k.to_string().starts_with("pgt"))
            .count();
        assert_eq!(n, 5);
    }

    #[test]
    fn a_header_that_is_not_an_exr_header_is_an_error() {
        assert!(sort_header_attributes(&mut [0u8; 16]).is_err());
        let mut cut = vec![0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0];
        cut.extend_from_slice(b"name\0text\0");
        assert!(sort_header_attributes(&mut cut).is_err());
    }

    #[test]
    fn non_finite_values_are_refused_in_every_layer_and_format() {
        let fine = RgbImage::new(5, 4);
        let nan = image_with(f32::NAN, 5 + 2, 1);
        let inf = image_with(f32::NEG_INFINITY, 19, 2);
        let main = ["out.exr", "pixel (2, 1)", "channel G of the image", "NaN"];
        refused("out.exr", &nan, &[], &main);
        refused(
            "out.exr",
            &fine,
            &[("err", &inf)],
            &["pixel (4, 3)", "err.B", "layer 'err'", "-inf"],
        );
        refused("out.png", &nan, &[], &["out.png", "pixel (2, 1)"]);
        refused(
            "out.png",
            &inf,
            &[("err", &fine)],
            &["pixel (4, 3)", "channel B"],
        );
        // Every layer given is checked, even for a PNG that does not store them: a non-finite
        // value anywhere is a bug.
        let dir = tempfile::tempdir().unwrap();
        write_image(&dir.path().join("ok.png"), &fine, &[("err", &inf)], 0.0)
            .expect_err("every layer given is checked");
        let with_header = write_exr_with_header(
            &dir.path().join("part.exr"),
            &fine,
            &[("err", &nan)],
            &[("pgtFormat", "x".into())],
        );
        assert!(with_header.unwrap_err().to_string().contains("layer 'err'"));
        assert!(std::fs::read_dir(dir.path()).unwrap().next().is_none());
        write_image(&dir.path().join("ok.exr"), &fine, &[("err", &fine)], 0.0).unwrap();
    }
}
