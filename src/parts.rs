//! A reference render cut into parts for a cluster (docs/design.md §7: `pgt render SCENE --part I/N
//! -o PART.exr` and `pgt merge PART... -o OUT`; docs/cluster.md), and their bit-identical merge.
//!
//! **Which pixels a part holds.** Part I of N (I 0-based, as Slurm's `$SLURM_ARRAY_TASK_ID` and
//! Kubernetes' `$JOB_COMPLETION_INDEX` count) holds the image rows y with y mod N = I. Rows are
//! interleaved, not cut in bands, because the cost of a pixel varies a hundredfold between a
//! molecule and the background: every part samples the image's rows evenly, so every part gets
//! the same share of molecule (on the 1UUN lit frame, 8 parts: the slowest within a few per cent
//! of the mean; see README "Rendering on a cluster"). N may be at most the image height.
//!
//! **The part file.** An EXR (written like every pgt image: float32 `R`, `G`, `B`, and `err.R/G/B`
//! where the renderer estimates its error) of the full image width whose rows are the part's rows,
//! top to bottom: the pixels of other parts are not stored at all. Its header carries, as text
//! attributes, what `merge` checks:
//!
//! | attribute | value |
//! |---|---|
//! | `pgtFormat` | `pgt-part/1` (marks the file as a pgt part; the number is the layout version) |
//! | `pgtImageSize` | `WxH` of the whole image |
//! | `pgtPart` | `I/N` |
//! | `pgtRows` | `y mod N = I` (the layout, for a human reading the header) |
//! | `pgtRenderHash` | 128-bit FNV-1a of the loaded scene (camera, render settings with the command-line overrides, lights, particles, bit for bit), the options that change pixels (`--spp`, `--integrator`, `--samples`, `--gpu` with the adapter's name) and pgt's version |
//!
//! Every pixel is a pure function of the scene and those options (docs/design.md §3), and a part goes
//! through the same per-pixel code as a whole render ([`crate::reference::render_pixel`], or on
//! the GPU the same per-ray program, [`crate::reference::gpu::render_rows_on`]), so the merge is
//! bit-identical to a one-machine render on the same device, err layer included.

use crate::error::{PgtError, Result};
use crate::image_io::RgbImage;
use crate::optics::particle::Particle;
use crate::reference::{rows::render_rows, Device, RenderOptions, RenderStats};
use crate::scene::Scene;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// `pgtFormat` of a part file; bump the number when the layout changes.
pub const FORMAT_TAG: &str = "pgt-part/1";

/// Which part of how many (`--part I/N`, I 0-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct PartOf {
    pub index: u32,
    pub count: u32,
}

impl std::fmt::Display for PartOf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// Parses `I/N` with 0 ≤ I < N (the command-line form of [`PartOf`]).
pub fn parse_part(s: &str) -> std::result::Result<PartOf, String> {
    let err = || format!("expected I/N with 0 <= I < N (I counts from 0), got '{s}'");
    let (i, n) = s.split_once('/').ok_or_else(err)?;
    let index: u32 = i.trim().parse().map_err(|_| err())?;
    let count: u32 = n.trim().parse().map_err(|_| err())?;
    if index >= count {
        return Err(err());
    }
    Ok(PartOf { index, count })
}

/// The rows of part `part` of an image `height` rows high: y = I, I + N, I + 2N, …
pub fn rows_of(part: PartOf, height: u32) -> Vec<u32> {
    (part.index..height).step_by(part.count as usize).collect()
}

/// A 128-bit FNV-1a-style hash: text (a scene's `Debug` text, exact: floats print as their
/// shortest round-trip form) is fed a byte at a time through `fmt::Write`, so it is hashed
/// without being held in memory; the particles are fed a 64-bit word at a time (the bits of
/// every number), which is what keeps the hash of a large frame cheap.
struct Fnv128(u128);

const FNV_PRIME: u128 = 0x0000_0000_0100_0000_0000_0000_0000_013B;

impl std::fmt::Write for Fnv128 {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        for &b in s.as_bytes() {
            self.0 = (self.0 ^ b as u128).wrapping_mul(FNV_PRIME);
        }
        Ok(())
    }
}

impl Fnv128 {
    fn word(&mut self, w: u64) {
        self.0 = (self.0 ^ w as u128).wrapping_mul(FNV_PRIME);
    }

    fn f64(&mut self, v: f64) {
        self.word(v.to_bits());
    }

    fn vec3(&mut self, v: glam::DVec3) {
        self.f64(v.x);
        self.f64(v.y);
        self.f64(v.z);
    }

    /// Every field of `p`, as bits. The pattern names every field (no `..`), so a new field
    /// of [`Particle`] does not compile until it is hashed here.
    fn particle(&mut self, p: &Particle) {
        let Particle {
            center,
            radius,
            color,
            sigma,
            albedo,
            ks,
            shininess,
            ellipsoid,
            profile,
        } = *p;
        self.vec3(center);
        self.f64(radius);
        self.vec3(color);
        self.f64(sigma);
        self.vec3(albedo);
        self.f64(ks);
        self.f64(shininess);
        // An ellipsoid is its semi-axes and rotation (the rest of it is computed from them).
        match ellipsoid {
            None => self.word(0),
            Some(e) => {
                self.word(1);
                self.vec3(e.semi_axes());
                let q = e.rotation();
                for v in [q.x, q.y, q.z, q.w] {
                    self.f64(v);
                }
            }
        }
        self.word(profile as u64);
    }
}

/// The header attribute of a part (and of a frame of a sequence) that holds its render hash.
pub const RENDER_HASH_ATTRIBUTE: &str = "pgtRenderHash";

/// The hash that ties parts to one render: the loaded scene (everything but its file name and
/// warnings, so the same scene at another path on another node matches) and the options that
/// change pixels, with pgt's version (another version may compute other bits).
pub fn render_hash(scene: &Scene, options: &RenderOptions) -> String {
    render_hash_on(scene, options, Device::Cpu)
}

/// [`render_hash`] of a render on `device`: a GPU render's hash adds the GPU and its adapter
/// (the GPU's bits differ from the CPU's, and another adapter may compute other bits); the
/// CPU's is [`render_hash`]'s.
pub fn render_hash_on(scene: &Scene, options: &RenderOptions, device: Device) -> String {
    let options_text = format!("spp {} | {:?}", options.spp, options.integrator);
    match device {
        Device::Cpu => hash_with(scene, &options_text),
        Device::Gpu(ctx) => hash_with(
            scene,
            &format!("{options_text} | gpu reference on {}", ctx.adapter.name),
        ),
    }
}

/// The hash of `scene` (as [`render_hash`] sees it) with `what` computes it (the options, or a
/// GPU method and its parameters): "pgt VERSION | what | camera | settings | lights", then
/// every particle's bits.
pub fn hash_with(scene: &Scene, what: &str) -> String {
    let mut h = Fnv128(0x6c62_272e_07bb_0142_62b8_2175_6295_c58d);
    // Every field but the file name, the warnings and the provenance (where settings were
    // chosen changes messages, not pixels; the pattern names every field, so a new one does not
    // compile until it is placed here); the particles follow as bits.
    let Scene {
        source: _,
        camera,
        render,
        lights,
        particles,
        warnings: _,
        provenance: _,
    } = scene;
    // Writing into the hasher cannot fail.
    let _ = write!(
        h,
        "pgt {} | {what} | {camera:?} | {render:?} | {lights:?} | {} particles",
        env!("CARGO_PKG_VERSION"),
        particles.len()
    );
    for p in particles {
        h.particle(p);
    }
    format!("{:032x}", h.0)
}

/// What a part file's header says.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PartHeader {
    /// Size of the whole image.
    pub width: u32,
    pub height: u32,
    /// Which part of how many it is.
    pub part: PartOf,
    /// [`render_hash`] of the render the part belongs to.
    pub hash: String,
}

/// One part: its header and its rows (full width, one image row per row of the part).
#[derive(Debug, Clone)]
pub struct Part {
    pub header: PartHeader,
    pub image: RgbImage,
    /// The rows' error estimate (the `err` layer), where the renderer has one.
    pub error: Option<RgbImage>,
}

/// Renders part `part` of the scene's image on `device`.
pub fn render_part(
    scene: &Scene,
    options: &RenderOptions,
    device: Device,
    part: PartOf,
) -> Result<(Part, RenderStats)> {
    let (width, height) = (scene.camera.width, scene.camera.height);
    if part.count > height {
        return Err(PgtError::Usage(format!(
            "--part {part}: at most {height} parts for an image {height} rows high (a part is a set of rows)"
        )));
    }
    let rows = rows_of(part, height);
    let out = match device {
        Device::Cpu => render_rows(scene, options, &rows)?,
        Device::Gpu(ctx) => crate::reference::gpu::render_rows_on(ctx, scene, options, &rows)?,
    };
    let header = PartHeader {
        width,
        height,
        part,
        hash: render_hash_on(scene, options, device),
    };
    let rendered = Part {
        header,
        image: out.image,
        error: out.error,
    };
    Ok((rendered, out.stats))
}

/// Writes a part file (an EXR; see the module documentation for its header), atomically.
pub fn write_part(path: &Path, part: &Part) -> Result<()> {
    let h = &part.header;
    let header = [
        ("pgtFormat", FORMAT_TAG.to_string()),
        ("pgtImageSize", format!("{}x{}", h.width, h.height)),
        ("pgtPart", h.part.to_string()),
        (
            "pgtRows",
            format!("y mod {} = {}", h.part.count, h.part.index),
        ),
        (RENDER_HASH_ATTRIBUTE, h.hash.clone()),
    ];
    let layers: Vec<(&str, &RgbImage)> = part.error.iter().map(|e| ("err", e)).collect();
    crate::image_io::write_exr_with_header(path, &part.image, &layers, &header)
}

/// Reads and checks one part file; any problem is an error naming the file.
pub fn read_part(path: &Path) -> Result<Part> {
    use exr::prelude::{read_all_flat_layers_from_file, AttributeValue};
    let not_part = |why: String| PgtError::in_file(path, format!("not a pgt part: {why}"));
    let img = read_all_flat_layers_from_file(path)
        .map_err(|e| not_part(format!("cannot read it as an EXR ({e})")))?;
    let [layer] = img.layer_data.as_slice() else {
        return Err(not_part(format!(
            "it has {} EXR layers, a part has one",
            img.layer_data.len()
        )));
    };
    // Custom attributes of a single-part file may be filed under the image or the layer.
    let text: BTreeMap<String, String> = img
        .attributes
        .other
        .iter()
        .chain(layer.attributes.other.iter())
        .filter_map(|(k, v)| match v {
            AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
            _ => None,
        })
        .collect();
    let get = |key: &str| {
        text.get(key).ok_or_else(|| {
            not_part(format!(
                "its header has no '{key}' attribute (`pgt render --part I/N` writes parts)"
            ))
        })
    };
    let format = get("pgtFormat")?;
    if format != FORMAT_TAG {
        return Err(not_part(format!(
            "its format is '{format}', this pgt reads '{FORMAT_TAG}'"
        )));
    }
    let bad = |key: &str, v: &str| not_part(format!("its '{key}' attribute '{v}' is malformed"));
    let size = get("pgtImageSize")?;
    let (width, height) = size
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)))
        .filter(|&(w, h)| w > 0 && h > 0)
        .ok_or_else(|| bad("pgtImageSize", size))?;
    let part_text = get("pgtPart")?;
    let part = parse_part(part_text).map_err(|_| bad("pgtPart", part_text))?;
    let header = PartHeader {
        width,
        height,
        part,
        hash: get(RENDER_HASH_ATTRIBUTE)?.clone(),
    };
    let rows = rows_of(part, height).len();
    if (layer.size.0, layer.size.1) != (width as usize, rows) {
        return Err(not_part(format!(
            "it holds {}x{} pixels, but part {part} of a {width}x{height} image has {width}x{rows}",
            layer.size.0, layer.size.1
        )));
    }
    let channel = |name: &str| -> Option<Vec<f32>> {
        let ch = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name)?;
        Some(ch.sample_data.values_as_f32().collect())
    };
    let plane_image = |prefix: &str| -> Result<Option<RgbImage>> {
        let names = ["R", "G", "B"].map(|c| format!("{prefix}{c}"));
        let planes: Vec<Option<Vec<f32>>> = names.iter().map(|n| channel(n)).collect();
        if planes.iter().all(Option::is_none) {
            return Ok(None);
        }
        let n = width as usize * rows;
        let planes: Vec<Vec<f32>> = planes
            .into_iter()
            .zip(&names)
            .map(|(p, name)| match p {
                Some(p) if p.len() == n => Ok(p),
                _ => Err(not_part(format!(
                    "channel '{name}' is missing or incomplete"
                ))),
            })
            .collect::<Result<_>>()?;
        let pixels = (0..n)
            .map(|i| [planes[0][i], planes[1][i], planes[2][i]])
            .collect();
        Ok(Some(RgbImage {
            width,
            height: rows as u32,
            pixels,
        }))
    };
    let image = plane_image("")?.ok_or_else(|| not_part("it has no R, G, B channels".into()))?;
    let error = plane_image("err.")?;
    Ok(Part {
        header,
        image,
        error,
    })
}

/// Reads the part files and joins them ([`merge`]): the whole image and its `err` layer where
/// the parts have one (`pgt merge`, `pgt.merge`).
pub fn merge_files(paths: &[PathBuf]) -> Result<(RgbImage, Option<RgbImage>)> {
    let mut parts = Vec::with_capacity(paths.len());
    for path in paths {
        parts.push((path.clone(), read_part(path)?));
    }
    merge(&parts)
}

/// The largest and the mean value of an error image over pixels and channels: the figures
/// `pgt render` and `pgt merge` print for the whole image's error estimate.
pub fn error_figures(error: &RgbImage) -> (f64, f64) {
    let (max, sum) = error
        .pixels
        .iter()
        .flatten()
        .fold((0.0f64, 0.0f64), |(m, s), &v| {
            (m.max(v as f64), s + v as f64)
        });
    (max, sum / (3 * error.pixels.len()).max(1) as f64)
}

/// Joins parts into the whole image and its error layer, after checking that they are exactly
/// the N parts of one render: same image size, part count, render hash and layers, each index
/// once, none missing. Every error names the file at fault.
pub fn merge(parts: &[(PathBuf, Part)]) -> Result<(RgbImage, Option<RgbImage>)> {
    let Some((first_path, first)) = parts.first() else {
        return Err(PgtError::Usage("merge needs at least one part".into()));
    };
    let h0 = &first.header;
    let mut by_index: BTreeMap<u32, &PathBuf> = BTreeMap::new();
    for (path, part) in parts {
        let h = &part.header;
        if (h.width, h.height, h.part.count) != (h0.width, h0.height, h0.part.count) {
            return Err(PgtError::in_file(
                path,
                format!(
                    "part {} of a {}x{} image, but {} is part {} of a {}x{} image: they are parts of different renders",
                    h.part, h.width, h.height, first_path.display(), h0.part, h0.width, h0.height
                ),
            ));
        }
        if h.hash != h0.hash {
            return Err(PgtError::in_file(
                path,
                format!(
                    "a part of a different render than {} (the scene or an option that changes pixels differs: render hash {} vs {})",
                    first_path.display(), h.hash, h0.hash
                ),
            ));
        }
        if part.error.is_some() != first.error.is_some() {
            return Err(PgtError::in_file(
                path,
                format!(
                    "has {} err layer, {} has {}: parts of different renders",
                    if part.error.is_some() { "an" } else { "no" },
                    first_path.display(),
                    if first.error.is_some() { "one" } else { "none" }
                ),
            ));
        }
        if let Some(other) = by_index.insert(h.part.index, path) {
            return Err(PgtError::in_file(
                path,
                format!("part {} given twice (also as {})", h.part, other.display()),
            ));
        }
    }
    let missing: Vec<String> = (0..h0.part.count)
        .filter(|i| !by_index.contains_key(i))
        .map(|i| i.to_string())
        .collect();
    if !missing.is_empty() {
        return Err(PgtError::Usage(format!(
            "part(s) {} of {} missing: the parts given (such as {}, part {}) are of a {}x{} image cut into {} parts, and the merge needs all of them",
            missing.join(", "),
            h0.part.count,
            first_path.display(),
            h0.part,
            h0.width,
            h0.height,
            h0.part.count
        )));
    }
    let mut image = RgbImage::new(h0.width, h0.height);
    let mut error = first
        .error
        .as_ref()
        .map(|_| RgbImage::new(h0.width, h0.height));
    let w = h0.width as usize;
    for (_, part) in parts {
        for (k, y) in rows_of(part.header.part, h0.height).into_iter().enumerate() {
            let (dst, src) = (y as usize * w..(y as usize + 1) * w, k * w..(k + 1) * w);
            image.pixels[dst.clone()].copy_from_slice(&part.image.pixels[src.clone()]);
            if let (Some(e), Some(pe)) = (&mut error, &part.error) {
                e.pixels[dst].copy_from_slice(&pe.pixels[src]);
            }
        }
    }
    Ok((image, error))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_parse_and_cover_every_row_once() {
        assert_eq!(parse_part("2/8"), Ok(PartOf { index: 2, count: 8 }));
        for bad in ["8/8", "1", "-1/4", "a/b", "0/0", "1/2/3"] {
            assert!(parse_part(bad).is_err(), "{bad}");
        }
        let mut seen = vec![0u32; 37];
        for i in 0..5 {
            for y in rows_of(PartOf { index: i, count: 5 }, 37) {
                seen[y as usize] += 1;
            }
        }
        assert!(seen.iter().all(|&n| n == 1), "{seen:?}");
    }

    #[test]
    fn the_hash_sees_every_bit_and_option_but_not_the_file_name() {
        let text = "[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n";
        let load =
            |t: &str, p: &str| Scene::from_toml_str(t, Path::new(p), &Default::default()).unwrap();
        let a = load(text, "a.toml");
        let o = RenderOptions::default();
        assert_eq!(
            render_hash(&a, &o),
            render_hash(&load(text, "elsewhere/b.toml"), &o)
        );
        let mut moved = a.clone();
        moved.particles[0].radius = f64::from_bits(1.0f64.to_bits() + 1);
        assert_ne!(render_hash(&a, &o), render_hash(&moved, &o));
        let spp = RenderOptions { spp: 2, ..o };
        assert_ne!(render_hash(&a, &o), render_hash(&a, &spp));
        let riemann = RenderOptions {
            integrator: crate::reference::Integrator::Riemann { samples: 10 },
            ..o
        };
        let riemann11 = RenderOptions {
            integrator: crate::reference::Integrator::Riemann { samples: 11 },
            ..o
        };
        assert_ne!(render_hash(&a, &riemann), render_hash(&a, &riemann11));
        let threads = RenderOptions {
            threads: Some(3),
            progress: true,
            ..o
        };
        assert_eq!(render_hash(&a, &o), render_hash(&a, &threads));
    }
}
