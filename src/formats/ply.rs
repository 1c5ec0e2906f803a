//! PLY files of 3D Gaussian splatting (3DGS) as ellipsoids (docs/design.md §9, "3D Gaussian
//! splatting PLY").
//!
//! **The file.** A PLY header (`ply`, `format ascii|binary_little_endian|binary_big_endian 1.0`,
//! `comment`/`obj_info` lines, `element NAME COUNT`, `property TYPE NAME`, `end_header`), then
//! the elements' data in header order. The `vertex` element holds the Gaussians, with the
//! properties of the reference implementation (graphdeco-inria `gaussian-splatting`):
//!
//! | property | meaning | pgt |
//! |---|---|---|
//! | `x y z` | centre | the ellipsoid's centre |
//! | `scale_0..2` | natural logs of the standard deviations along the body's axes | semi-axes k·exp(scale_i), k = `extent` (3) |
//! | `rot_0..3` | an unnormalised quaternion (w, x, y, z), body to world | normalised; zero is refused |
//! | `opacity` | a logit: α = 1/(1 + e^(−opacity)) | Θmax = α |
//! | `f_dc_0..2` | the degree-0 SH coefficient per channel | colour 0.5 + C0·f_dc, clamped at 0 |
//! | `f_rest_*` | 0, 9, 24 or 45 higher coefficients (degree 0–3) | `sh = "view"`: the view-dependent colour |
//!
//! Other scalar properties (`nx ny nz`, `transform`, …) are ignored; a list property, an
//! unknown type or a vertex element without the properties above is an error that names them
//! (a mesh PLY is never read as spheres). Elements other than `vertex` are skipped.
//!
//! **pgt's own PLY.** A vertex element with pgt export's properties (`x y z`, `radius` or
//! `sx sy sz qw qx qy qz`, `red green blue opacity sigma`, `crate::scene::export`) is read as
//! the CSV reader reads the same columns: every value as it is, σ bit for bit, so an export
//! reads back as the particles it was written from.
//!
//! **Include options** ([`IncludeSpec`]): `extent` (k, standard deviations per semi-axis, > 0,
//! default [`DEFAULT_EXTENT`]), `sh = "dc" | "view"` (default `"dc"`), `sh_order =
//! "channel-major" | "coefficient-major"` (the order of `f_rest`, default channel-major as the
//! reference implementation writes it; EVER's training code writes coefficient-major).
//!
//! **Why a reader of its own.** The maintained PLY crate (`ply-rs-bw` 4) needs Rust 1.87, above
//! pgt's 1.85; its header model keeps properties in a map by name, so a header with a
//! duplicated property name silently loses one and misreads every later byte; and its payload
//! goes through one call per property and vertex with the property's name as a string. This
//! reader knows the vertex layout after the header: each property's byte offset and type, so a
//! vertex is a fixed-size slice converted with `from_le_bytes` (or `from_be_bytes`). Every
//! count is checked against the bytes that remain before anything is allocated, and every
//! problem is an error that names the header line or the vertex and its byte offset.

use super::{EllipsoidRecord, Format, IncludeSpec, LoadedParticles, ParticleRecord};
use super::{ShColor, ShOrder};
use crate::error::{Location, PgtError, Result};
use glam::DVec3;
use std::path::Path;

/// PLY in the table of formats ([`super::FORMATS`]).
pub const FORMAT: Format = Format {
    name: "ply",
    extensions: &["ply"],
    description: "PLY of 3D Gaussian splatting (ascii or binary)",
    particles: "vertices (Gaussians)",
    read,
    details: Some(details),
    frames: None,
};

/// Standard deviations per semi-axis where the include does not set `extent`: a 3D standard
/// normal holds P(χ²₃ ≤ 9) = 0.9707 of its mass within 3σ, and 3σ is where the reference
/// rasteriser cuts each splat's footprint.
pub const DEFAULT_EXTENT: f64 = 3.0;

/// The real spherical-harmonics constants of the reference rasteriser's `computeColorFromSH`,
/// by degree: C0 = ½√(1/π); C1 = ½√(3/π); C2 = (½√(15/π), −½√(15/π), ¼√(5/π), −½√(15/π),
/// ¼√(15/π)); C3 = (−¼√(35/(2π)), ½√(105/π), −¼√(21/(2π)), ¼√(7/π), −¼√(21/(2π)), ¼√(105/π),
/// −¼√(35/(2π))). The signs are the rasteriser's (its basis with the Condon–Shortley phase).
pub const SH_C0: f64 = 0.282_094_791_773_878_14;
const SH_C1: f64 = 0.488_602_511_902_919_9;
const SH_C2: [f64; 5] = [
    1.092_548_430_592_079_2,
    -1.092_548_430_592_079_2,
    0.315_391_565_252_520_05,
    -1.092_548_430_592_079_2,
    0.546_274_215_296_039_6,
];
const SH_C3: [f64; 7] = [
    -0.590_043_589_926_643_5,
    2.890_611_442_640_554,
    -0.457_045_799_464_465_8,
    0.373_176_332_590_115_4,
    -0.457_045_799_464_465_8,
    1.445_305_721_320_277,
    -0.590_043_589_926_643_5,
];

/// How the data after the header is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

impl Encoding {
    fn name(self) -> &'static str {
        match self {
            Encoding::Ascii => "ascii",
            Encoding::LittleEndian => "binary_little_endian",
            Encoding::BigEndian => "binary_big_endian",
        }
    }
}

/// A PLY scalar type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    /// The type of a header name (both the PLY 1.0 names and the sized ones).
    fn named(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn bytes(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// An ASCII value of this type (a float rounded as the type stores it; an integer in its
    /// range).
    fn parse(self, w: &str) -> Option<f64> {
        let int = |lo: i64, hi: i64| w.parse::<i64>().ok().filter(|v| (lo..=hi).contains(v));
        match self {
            Scalar::F32 => w.parse::<f32>().ok().map(f64::from),
            Scalar::F64 => w.parse::<f64>().ok(),
            Scalar::I8 => int(i8::MIN.into(), i8::MAX.into()).map(|v| v as f64),
            Scalar::U8 => int(0, u8::MAX.into()).map(|v| v as f64),
            Scalar::I16 => int(i16::MIN.into(), i16::MAX.into()).map(|v| v as f64),
            Scalar::U16 => int(0, u16::MAX.into()).map(|v| v as f64),
            Scalar::I32 => int(i32::MIN.into(), i32::MAX.into()).map(|v| v as f64),
            Scalar::U32 => int(0, u32::MAX.into()).map(|v| v as f64),
        }
    }

    /// The value at `at` of a binary record (`at + self.bytes() ≤ b.len()`: the layout puts
    /// every property inside the record).
    #[inline]
    fn read(self, b: &[u8], at: usize, big: bool) -> f64 {
        macro_rules! num {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[at..at + $n]);
                if big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }
            }};
        }
        match self {
            Scalar::I8 => f64::from(num!(i8, 1)),
            Scalar::U8 => f64::from(num!(u8, 1)),
            Scalar::I16 => f64::from(num!(i16, 2)),
            Scalar::U16 => f64::from(num!(u16, 2)),
            Scalar::I32 => f64::from(num!(i32, 4)),
            Scalar::U32 => f64::from(num!(u32, 4)),
            Scalar::F32 => f64::from(num!(f32, 4)),
            Scalar::F64 => num!(f64, 8),
        }
    }
}

/// One scalar property of an element.
#[derive(Debug, Clone)]
struct Property {
    name: String,
    scalar: Scalar,
    /// Byte offset inside a binary record.
    offset: usize,
}

/// One `element` of the header.
#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
    /// The properties' names, for the duplicate check.
    names: std::collections::HashSet<String>,
    /// Header line of the `element` line.
    line: usize,
}

impl Element {
    /// Bytes of one binary record.
    fn stride(&self) -> usize {
        self.properties.iter().map(|p| p.scalar.bytes()).sum()
    }
}

/// The parsed header.
#[derive(Debug, Clone)]
struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the first byte after `end_header`'s line.
    data_start: usize,
    /// Lines of the header (the data of an ASCII file starts on the next one).
    lines: usize,
}

/// What a vertex element holds: 3DGS Gaussians or pgt export's particles.
#[derive(Debug, Clone)]
enum Layout {
    Gaussians(Gaussians),
    Export(Export),
}

/// Where pgt export's properties sit in the vertex element (indices into its properties).
#[derive(Debug, Clone)]
struct Export {
    position: [usize; 3],
    size: Size,
    rgb: [usize; 3],
    opacity: usize,
    sigma: usize,
}

/// The size of pgt export's particles.
#[derive(Debug, Clone)]
enum Size {
    /// `radius`: spheres.
    Radius(usize),
    /// `sx sy sz` and `qw qx qy qz`: ellipsoids.
    Ellipsoid([usize; 3], [usize; 4]),
}

/// Where the 3DGS properties sit in the vertex element (indices into its properties).
#[derive(Debug, Clone)]
struct Gaussians {
    position: [usize; 3],
    dc: [usize; 3],
    opacity: usize,
    scale: [usize; 3],
    rot: [usize; 4],
    /// `f_rest_0..n`, in index order.
    rest: Vec<usize>,
}

/// The names every 3DGS vertex needs, in the reference implementation's order.
const REQUIRED: [&str; 14] = [
    "x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
    "rot_0", "rot_1", "rot_2", "rot_3",
];

/// Headers longer than this are refused (a binary file without a header, read as one; a
/// header of a million properties).
const MAX_HEADER_BYTES: usize = 1 << 20;

fn header_line_err(path: &Path, line: usize, msg: impl Into<String>) -> PgtError {
    PgtError::at_line(path, line, format!("PLY header: {}", msg.into()))
}

/// Parses the header: its lines up to `end_header` (ASCII; a line that is not UTF-8, a
/// keyword the PLY format lacks, a list property or an unknown type is an error naming the line).
fn header(path: &Path, bytes: &[u8]) -> Result<Header> {
    if bytes.is_empty() {
        return Err(PgtError::in_file(
            path,
            "the file is empty (0 bytes), so it holds no particles (a truncated download or a wrong path?)",
        ));
    }
    let mut pos = 0usize;
    let mut line = 0usize;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        line += 1;
        let rest = bytes
            .get(pos..MAX_HEADER_BYTES.min(bytes.len()))
            .unwrap_or_default();
        let Some(n) = rest.iter().position(|&b| b == b'\n') else {
            let msg = if bytes.len() >= MAX_HEADER_BYTES {
                format!(
                    "no `end_header` within the first {MAX_HEADER_BYTES} bytes: not a PLY header"
                )
            } else {
                "the file ends before `end_header`".to_string()
            };
            return Err(header_line_err(path, line, msg));
        };
        let raw = &rest[..n];
        pos += n + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let text = std::str::from_utf8(raw).map_err(|_| {
            header_line_err(path, line, "the line is not text (PLY headers are ASCII)")
        })?;
        let words: Vec<&str> = text.split_whitespace().collect();
        if line == 1 {
            if words != ["ply"] {
                return Err(header_line_err(
                    path,
                    1,
                    format!(
                        "not a PLY file: the first line must be `ply`, found `{}`",
                        short(text)
                    ),
                ));
            }
            continue;
        }
        match words.first().copied() {
            Some("comment") | Some("obj_info") | None => {}
            Some("format") => {
                let e = match words.get(1).copied() {
                    Some("ascii") => Encoding::Ascii,
                    Some("binary_little_endian") => Encoding::LittleEndian,
                    Some("binary_big_endian") => Encoding::BigEndian,
                    _ => {
                        return Err(header_line_err(path, line, format!(
                            "expected `format ascii|binary_little_endian|binary_big_endian 1.0`, found `{}`",
                            short(text)
                        )))
                    }
                };
                if words.len() != 3 || !matches!(words[2], "1.0" | "1") {
                    return Err(header_line_err(path, line, format!(
                        "expected the version 1.0 after the format, found `{}`",
                        short(text)
                    )));
                }
                if encoding.replace(e).is_some() {
                    return Err(header_line_err(path, line, "a second `format` line"));
                }
            }
            Some("element") => elements.push(element_line(path, line, &words, &elements, text)?),
            Some("property") => property_line(path, line, &words, &mut elements, text)?,
            Some("end_header") => break,
            Some(other) => {
                return Err(header_line_err(path, line, format!(
                    "unknown keyword `{}`: expected format, element, property, comment, obj_info or end_header",
                    short(other)
                )))
            }
        }
    }
    let Some(encoding) = encoding else {
        return Err(header_line_err(
            path,
            line,
            "the header has no `format` line",
        ));
    };
    Ok(Header {
        encoding,
        elements,
        data_start: pos,
        lines: line,
    })
}

/// A piece of a header line for a message: at most 60 characters.
fn short(text: &str) -> String {
    let s: String = text.trim().chars().take(60).collect();
    if s.len() < text.trim().len() {
        s + "…"
    } else {
        s
    }
}

/// `element NAME COUNT`.
fn element_line(
    path: &Path,
    line: usize,
    words: &[&str],
    elements: &[Element],
    text: &str,
) -> Result<Element> {
    let (Some(name), Some(count), 3) = (words.get(1), words.get(2), words.len()) else {
        return Err(header_line_err(
            path,
            line,
            format!("expected `element NAME COUNT`, found `{}`", short(text)),
        ));
    };
    let count: u64 = count.parse().map_err(|_| {
        header_line_err(
            path,
            line,
            format!(
                "element {}: the count `{}` is not a non-negative integer",
                short(name),
                short(count)
            ),
        )
    })?;
    if elements.iter().any(|e| e.name == *name) {
        return Err(header_line_err(
            path,
            line,
            format!("a second element `{}`", short(name)),
        ));
    }
    Ok(Element {
        name: name.to_string(),
        count,
        properties: Vec::new(),
        names: std::collections::HashSet::new(),
        line,
    })
}

/// `property TYPE NAME` (a `property list …` is refused).
fn property_line(
    path: &Path,
    line: usize,
    words: &[&str],
    elements: &mut [Element],
    text: &str,
) -> Result<()> {
    let Some(element) = elements.last_mut() else {
        return Err(header_line_err(
            path,
            line,
            "a property before any `element` line",
        ));
    };
    if words.get(1) == Some(&"list") {
        let name = words.last().copied().unwrap_or_default();
        return Err(header_line_err(path, line, format!(
            "element {}: property {} is a list; pgt reads elements of scalar properties only (a 3D Gaussian splatting file has no lists)",
            element.name,
            short(name)
        )));
    }
    let (Some(ty), Some(name), 3) = (words.get(1), words.get(2), words.len()) else {
        return Err(header_line_err(
            path,
            line,
            format!("expected `property TYPE NAME`, found `{}`", short(text)),
        ));
    };
    let Some(scalar) = Scalar::named(ty) else {
        return Err(header_line_err(path, line, format!(
            "element {}: property {} has the unknown type `{}` (expected char, uchar, short, ushort, int, uint, float, double or int8 … float64)",
            element.name,
            short(name),
            short(ty)
        )));
    };
    if !element.names.insert(name.to_string()) {
        return Err(header_line_err(
            path,
            line,
            format!(
                "element {}: a second property `{}`",
                element.name,
                short(name)
            ),
        ));
    }
    let offset = element.stride();
    element.properties.push(Property {
        name: name.to_string(),
        scalar,
        offset,
    });
    Ok(())
}

/// The vertex element and where the 3DGS properties are in it; an error names what is missing.
fn layout(path: &Path, h: &Header) -> Result<(usize, Layout)> {
    let Some(v) = h.elements.iter().position(|e| e.name == "vertex") else {
        let names: Vec<&str> = h.elements.iter().map(|e| e.name.as_str()).collect();
        return Err(PgtError::in_file(path, format!(
            "the PLY file has no `vertex` element (its elements: {names:?}), so it holds no Gaussians"
        )));
    };
    let e = &h.elements[v];
    let find = |n: &str| e.properties.iter().position(|p| p.name == n);
    let missing: Vec<&str> = REQUIRED
        .iter()
        .copied()
        .filter(|n| find(n).is_none())
        .collect();
    if let (false, Some(export)) = (missing.is_empty(), export_layout(e)) {
        return Ok((v, Layout::Export(export)));
    }
    if !missing.is_empty() {
        let has: Vec<&str> = e
            .properties
            .iter()
            .map(|p| p.name.as_str())
            .take(20)
            .collect();
        return Err(PgtError::at_line(path, e.line, format!(
            "element vertex lacks the 3D Gaussian splatting properties {} (it has {}): pgt reads PLY files of 3D Gaussian splatting and those pgt export writes",
            missing.join(", "),
            has.join(", ")
        )));
    }
    let idx = |n: &str| find(n).unwrap_or_default();
    let mut rest: Vec<(usize, usize)> = Vec::new();
    for (i, p) in e.properties.iter().enumerate() {
        if let Some(k) = p.name.strip_prefix("f_rest_") {
            let k: usize = k.parse().map_err(|_| {
                PgtError::at_line(
                    path,
                    e.line,
                    format!(
                        "element vertex: property {} is not f_rest_ followed by a number",
                        p.name
                    ),
                )
            })?;
            rest.push((k, i));
        }
    }
    rest.sort_unstable();
    let n = rest.len();
    if !matches!(n, 0 | 9 | 24 | 45) || rest.iter().enumerate().any(|(j, &(k, _))| j != k) {
        return Err(PgtError::at_line(path, e.line, format!(
            "element vertex has {n} f_rest_* properties; a 3D Gaussian splatting file has f_rest_0 … f_rest_{{n−1}} with n = 0, 9, 24 or 45 (SH degree 0 to 3)"
        )));
    }
    Ok((
        v,
        Layout::Gaussians(Gaussians {
            position: [idx("x"), idx("y"), idx("z")],
            dc: [idx("f_dc_0"), idx("f_dc_1"), idx("f_dc_2")],
            opacity: idx("opacity"),
            scale: [idx("scale_0"), idx("scale_1"), idx("scale_2")],
            rot: [idx("rot_0"), idx("rot_1"), idx("rot_2"), idx("rot_3")],
            rest: rest.into_iter().map(|(_, i)| i).collect(),
        }),
    ))
}

/// pgt export's layout, where the vertex element has all of its properties.
fn export_layout(e: &Element) -> Option<Export> {
    let find = |n: &str| e.properties.iter().position(|p| p.name == n);
    let all = |names: &[&str]| {
        names
            .iter()
            .map(|n| find(n))
            .collect::<Option<Vec<usize>>>()
    };
    let three = |names: [&str; 3]| all(&names).map(|v| [v[0], v[1], v[2]]);
    let size = match (find("radius"), three(["sx", "sy", "sz"])) {
        (Some(r), None) => Size::Radius(r),
        (None, Some(axes)) => {
            let q = all(&["qw", "qx", "qy", "qz"])?;
            Size::Ellipsoid(axes, [q[0], q[1], q[2], q[3]])
        }
        _ => return None,
    };
    Some(Export {
        position: three(["x", "y", "z"])?,
        size,
        rgb: three(["red", "green", "blue"])?,
        opacity: find("opacity")?,
        sigma: find("sigma")?,
    })
}

/// The SH degree of `rest` coefficients per vertex (0, 9, 24, 45 → 0 … 3).
fn sh_degree(rest: usize) -> usize {
    match rest {
        0 => 0,
        9 => 1,
        24 => 2,
        _ => 3,
    }
}

/// Whether `path` is a PLY file in the layout of 3D Gaussian splatting (not pgt's export): a
/// bare file of this layout gets the splatting defaults (docs/design.md §1, "A bare particle
/// file"). Reads the header only; a file that cannot be read or parsed is not one (reading it
/// then reports why).
pub fn is_splatting_file(path: &Path) -> bool {
    use std::io::Read;
    let mut head = Vec::new();
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    if file
        .take(MAX_HEADER_BYTES as u64)
        .read_to_end(&mut head)
        .is_err()
    {
        return false;
    }
    header(path, &head)
        .and_then(|h| layout(path, &h))
        .is_ok_and(|(_, l)| matches!(l, Layout::Gaussians(_)))
}

/// What the reader needs of the include, resolved.
struct Options {
    extent: f64,
    /// The camera position for `sh = "view"`; `None`: the DC colour.
    view_from: Option<DVec3>,
    order: ShOrder,
}

fn options(spec: &IncludeSpec) -> Result<Options> {
    let gaussian = spec.density == Some(crate::formats::Profile::Gaussian);
    if gaussian && spec.extent.is_some() {
        return Err(PgtError::in_file(
            &spec.path,
            "include.extent applies to constant density: a Gaussian's semi-axes are its standard deviations (density = \"gaussian\")",
        ));
    }
    // A Gaussian's semi-axes are the standard deviations themselves (docs/design.md §9).
    let extent = if gaussian {
        1.0
    } else {
        spec.extent.unwrap_or(DEFAULT_EXTENT)
    };
    if !(extent.is_finite() && extent > 0.0) {
        return Err(PgtError::in_file(
            &spec.path,
            format!("include.extent must be finite and > 0, got {extent}"),
        ));
    }
    let view_from = match spec.sh.unwrap_or_default() {
        ShColor::Dc => None,
        ShColor::View => Some(spec.view_from.ok_or_else(|| {
            PgtError::in_file(
                &spec.path,
                "sh = \"view\" needs the camera's position: a scene whose [camera] sets `position` (a fixed camera)",
            )
        })?),
    };
    Ok(Options {
        extent,
        view_from,
        order: spec.sh_order.unwrap_or_default(),
    })
}

/// The [`super::Reader`] of 3DGS PLY: every vertex as an ellipsoid (see the module doc).
pub fn read(spec: &IncludeSpec, bytes: &[u8]) -> Result<LoadedParticles> {
    let path = spec.path.as_path();
    let opts = options(spec)?;
    let h = header(path, bytes)?;
    let (v, layout) = layout(path, &h)?;
    let mut warnings = Vec::new();
    let records = match &layout {
        Layout::Gaussians(l) => {
            let convert = |i, at, values: &[f64]| gaussian(path, i, at, values, l, &opts);
            vertices(path, bytes, &h, v, &convert, &mut warnings)?
        }
        Layout::Export(l) => {
            let convert = |_, at, values: &[f64]| Ok(exported(at, values, l));
            vertices(path, bytes, &h, v, &convert, &mut warnings)?
        }
    };
    Ok(LoadedParticles { records, warnings })
}

/// Turns the values of vertex i (at a line or byte) into a particle.
type Convert<'a> = dyn Fn(usize, Location, &[f64]) -> Result<ParticleRecord> + 'a;

/// Every vertex of element `v`, read as the header's encoding says and converted.
fn vertices(
    path: &Path,
    bytes: &[u8],
    h: &Header,
    v: usize,
    convert: &Convert,
    warnings: &mut Vec<String>,
) -> Result<Vec<ParticleRecord>> {
    match h.encoding {
        Encoding::Ascii => read_ascii(path, bytes, h, v, convert),
        Encoding::LittleEndian | Encoding::BigEndian => {
            read_binary(path, bytes, h, v, convert, warnings)
        }
    }
}

/// A vertex of pgt export's layout: its values as they are (the checks every format shares,
/// `super::check_records`, follow).
fn exported(at: Location, v: &[f64], l: &Export) -> ParticleRecord {
    let three = |i: [usize; 3]| DVec3::new(v[i[0]], v[i[1]], v[i[2]]);
    let (radius, ellipsoid) = match l.size {
        Size::Radius(r) => (v[r], None),
        Size::Ellipsoid(axes, q) => {
            let semi_axes = three(axes);
            let rotation = q.map(|k| v[k]);
            let e = EllipsoidRecord {
                semi_axes,
                rotation,
            };
            (semi_axes.max_element(), Some(e))
        }
    };
    ParticleRecord {
        center: three(l.position),
        radius,
        color: Some(three(l.rgb)),
        opacity: Some(v[l.opacity]),
        sigma: Some(v[l.sigma]),
        location: at,
        ellipsoid,
    }
}

/// Bytes of the binary records of `elements`; `None` on overflow.
fn element_bytes(elements: &[Element]) -> Option<u64> {
    elements.iter().try_fold(0u64, |sum, e| {
        e.count
            .checked_mul(e.stride() as u64)
            .and_then(|b| sum.checked_add(b))
    })
}

fn read_binary(
    path: &Path,
    bytes: &[u8],
    h: &Header,
    v: usize,
    convert: &Convert,
    warnings: &mut Vec<String>,
) -> Result<Vec<ParticleRecord>> {
    let e = &h.elements[v];
    let stride = e.stride();
    let data = bytes.len().saturating_sub(h.data_start) as u64;
    let before = element_bytes(&h.elements[..v]).unwrap_or(u64::MAX);
    let start = (h.data_start as u64).saturating_add(before);
    let need = e.count.saturating_mul(stride as u64);
    let have = (bytes.len() as u64).saturating_sub(start);
    if before > data || need > have {
        let whole = have / stride.max(1) as u64;
        return Err(PgtError::at_byte(path, start.saturating_add(whole * stride as u64), format!(
            "the header announces {} vertices of {stride} bytes ({need} bytes from byte {start}), but the file ends after {} bytes of them: it is cut short in vertex {whole}",
            e.count,
            have.min(need)
        )));
    }
    if let Some(all) = element_bytes(&h.elements) {
        if all < data {
            warnings.push(format!(
                "{}: {} bytes after the last element's data are ignored",
                path.display(),
                data - all
            ));
        }
    }
    let (start, count) = (start as usize, e.count as usize);
    let big = h.encoding == Encoding::BigEndian;
    let region = &bytes[start..start + count * stride];
    let mut records = Vec::with_capacity(count);
    let mut values = vec![0.0f64; e.properties.len()];
    for (i, rec) in region.chunks_exact(stride.max(1)).take(count).enumerate() {
        for (value, p) in values.iter_mut().zip(&e.properties) {
            *value = p.scalar.read(rec, p.offset, big);
        }
        let at = Location::Byte((start + i * stride) as u64);
        records.push(convert(i, at, &values)?);
    }
    Ok(records)
}

fn read_ascii(
    path: &Path,
    bytes: &[u8],
    h: &Header,
    v: usize,
    convert: &Convert,
) -> Result<Vec<ParticleRecord>> {
    let e = &h.elements[v];
    let text = bytes.get(h.data_start..).unwrap_or_default();
    let skip: u64 = h.elements[..v]
        .iter()
        .map(|e| e.count)
        .fold(0, u64::saturating_add);
    // Each vertex is one line of at least two bytes.
    if e.count > text.len() as u64 / 2 {
        return Err(PgtError::at_line(
            path,
            e.line,
            format!(
                "the header announces {} vertices, more than the {} bytes of data can hold",
                e.count,
                text.len()
            ),
        ));
    }
    let mut lines = text
        .split(|&b| b == b'\n')
        .enumerate()
        .map(|(k, l)| (h.lines + 1 + k, l))
        .filter(|(_, l)| !l.iter().all(u8::is_ascii_whitespace));
    for _ in 0..skip {
        if lines.next().is_none() {
            break;
        }
    }
    // Grown as lines are read: the count is only bounded by the file's size here.
    let mut records = Vec::with_capacity((e.count as usize).min(1 << 16));
    let mut values = vec![0.0f64; e.properties.len()];
    for i in 0..e.count as usize {
        let Some((line, raw)) = lines.next() else {
            return Err(PgtError::at_line(
                path,
                e.line,
                format!(
                    "the header announces {} vertices, but the data ends after {i}",
                    e.count
                ),
            ));
        };
        let t = String::from_utf8_lossy(raw);
        let words: Vec<&str> = t.split_whitespace().collect();
        if words.len() != values.len() {
            return Err(PgtError::at_line(
                path,
                line,
                format!(
                    "vertex {i}: expected {} values (the vertex properties), found {}",
                    values.len(),
                    words.len()
                ),
            ));
        }
        for ((value, w), p) in values.iter_mut().zip(&words).zip(&e.properties) {
            *value = p.scalar.parse(w).ok_or_else(|| {
                PgtError::at_line(
                    path,
                    line,
                    format!(
                        "vertex {i}: property {} is not a number of its type: `{}`",
                        p.name,
                        short(w)
                    ),
                )
            })?;
        }
        records.push(convert(i, Location::Line(line), &values)?);
    }
    Ok(records)
}

/// One vertex as an ellipsoid (docs/design.md §9, "3D Gaussian splatting PLY"): semi-axes
/// k·exp(scale_i), the normalised quaternion, Θmax = sigmoid(opacity), the SH colour.
fn gaussian(
    path: &Path,
    i: usize,
    at: Location,
    v: &[f64],
    l: &Gaussians,
    opts: &Options,
) -> Result<ParticleRecord> {
    let err = |msg: String| PgtError::Input {
        path: path.to_path_buf(),
        location: at.clone(),
        message: format!("vertex {i}: {msg}"),
    };
    let center = DVec3::new(v[l.position[0]], v[l.position[1]], v[l.position[2]]);
    if !center.is_finite() {
        return Err(err(format!(
            "the position (x, y, z) = {center} is not finite"
        )));
    }
    let mut semi_axes = [0.0; 3];
    for (k, (&s, a)) in l.scale.iter().zip(&mut semi_axes).enumerate() {
        let log = v[s];
        *a = opts.extent * log.exp();
        if !(a.is_finite() && *a >= f64::MIN_POSITIVE) {
            return Err(err(format!(
                "scale_{k} = {log} gives the semi-axis {}·exp({log}) = {a}, not a finite number > 0 (a scale is the log of a standard deviation)",
                opts.extent
            )));
        }
    }
    let q = l.rot.map(|r| v[r]);
    let norm = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return Err(err(format!(
            "the rotation (rot_0, rot_1, rot_2, rot_3) = {q:?} is not a finite, non-zero quaternion"
        )));
    }
    let logit = v[l.opacity];
    if logit.is_nan() {
        return Err(err("opacity is NaN".to_string()));
    }
    let dc = DVec3::new(v[l.dc[0]], v[l.dc[1]], v[l.dc[2]]);
    if !dc.is_finite() {
        return Err(err(format!("f_dc_0..2 = {dc} is not finite")));
    }
    let color = match opts.view_from {
        None => SH_C0 * dc + 0.5,
        Some(camera) => {
            let rest = sh_rest(v, &l.rest, opts.order);
            if !rest.iter().all(|c| c.is_finite()) {
                return Err(err("an f_rest_* coefficient is not finite".to_string()));
            }
            view_color(dc, &rest, center - camera)
        }
    };
    let semi_axes = DVec3::from(semi_axes);
    Ok(ParticleRecord {
        center,
        radius: semi_axes.max_element(),
        color: Some(color.max(DVec3::ZERO)),
        opacity: Some(sigmoid(logit)),
        sigma: None,
        location: at,
        ellipsoid: Some(EllipsoidRecord {
            semi_axes,
            rotation: q.map(|c| c / norm),
        }),
    })
}

/// α = 1/(1 + e^(−x)) for a logit x (±∞ give 1 and 0).
pub fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// The higher SH coefficients of a vertex as RGB vectors, coefficient 1 first (index 0).
fn sh_rest(v: &[f64], rest: &[usize], order: ShOrder) -> Vec<DVec3> {
    let m = rest.len() / 3;
    (0..m)
        .map(|j| {
            let at = |c: usize| match order {
                ShOrder::ChannelMajor => v[rest[c * m + j]],
                ShOrder::CoefficientMajor => v[rest[3 * j + c]],
            };
            DVec3::new(at(0), at(1), at(2))
        })
        .collect()
}

/// The view-dependent colour of the reference rasteriser's `computeColorFromSH` (before its
/// clamp at 0): 0.5 + Σ C_lm·Y_lm(d)·sh_lm with d the unit direction from the camera to the
/// centre and `rest` the coefficients of degree 1 and up (3, 8 or 15 of them: degree 1, 2, 3).
/// A camera at the centre has no direction: the DC term alone.
pub fn view_color(dc: DVec3, rest: &[DVec3], direction: DVec3) -> DVec3 {
    let mut c = SH_C0 * dc;
    let len = direction.length();
    if rest.len() < 3 || !(len > 0.0 && len.is_finite()) {
        return c + 0.5;
    }
    let d = direction / len;
    let (x, y, z) = (d.x, d.y, d.z);
    c += -SH_C1 * y * rest[0] + SH_C1 * z * rest[1] - SH_C1 * x * rest[2];
    if rest.len() >= 8 {
        let (xx, yy, zz) = (x * x, y * y, z * z);
        let (xy, yz, xz) = (x * y, y * z, x * z);
        c += SH_C2[0] * xy * rest[3]
            + SH_C2[1] * yz * rest[4]
            + SH_C2[2] * (2.0 * zz - xx - yy) * rest[5]
            + SH_C2[3] * xz * rest[6]
            + SH_C2[4] * (xx - yy) * rest[7];
        if rest.len() >= 15 {
            c += SH_C3[0] * y * (3.0 * xx - yy) * rest[8]
                + SH_C3[1] * xy * z * rest[9]
                + SH_C3[2] * y * (4.0 * zz - xx - yy) * rest[10]
                + SH_C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy) * rest[11]
                + SH_C3[4] * x * (4.0 * zz - xx - yy) * rest[12]
                + SH_C3[5] * z * (xx - yy) * rest[13]
                + SH_C3[6] * x * (xx - 3.0 * yy) * rest[14];
        }
    }
    c + 0.5
}

/// The [`super::Details`] of PLY: encoding, layout, extra properties, SH degree and the range
/// of the semi-axes at the default extent.
fn details(path: &Path, bytes: &[u8]) -> Result<serde_json::Map<String, serde_json::Value>> {
    use serde_json::json;
    let h = header(path, bytes)?;
    let (v, layout) = layout(path, &h)?;
    let mut d = serde_json::Map::new();
    d.insert("encoding".into(), json!(h.encoding.name()));
    let l = match layout {
        Layout::Export(_) => {
            d.insert("layout".into(), json!("pgt export"));
            return Ok(d);
        }
        Layout::Gaussians(l) => l,
    };
    let names: Vec<&str> = h.elements[v]
        .properties
        .iter()
        .map(|p| p.name.as_str())
        .collect();
    let rest: Vec<String> = (0..l.rest.len()).map(|k| format!("f_rest_{k}")).collect();
    let known = |n: &str| REQUIRED.contains(&n) || n.starts_with("f_rest_");
    let extra: Vec<&str> = names.iter().copied().filter(|n| !known(n)).collect();
    let standard: Vec<&str> = [
        "x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2",
    ]
    .into_iter()
    .chain(rest.iter().map(String::as_str))
    .chain(REQUIRED[6..].iter().copied())
    .collect();
    let reduced: Vec<&str> = standard
        .iter()
        .copied()
        .filter(|n| !n.starts_with('n'))
        .collect();
    let layout = if names == standard {
        "standard".to_string()
    } else if names == reduced {
        "reduced (no normals)".to_string()
    } else if names.len() > standard.len() && names[..standard.len()] == standard[..] {
        format!("standard with extra properties {}", extra[3..].join(", "))
    } else {
        format!("other (extra properties: {})", extra.join(", "))
    };
    let spec = IncludeSpec::bare(path);
    let loaded = read(&spec, bytes)?;
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for e in loaded.records.iter().filter_map(|r| r.ellipsoid) {
        lo = lo.min(e.semi_axes.min_element());
        hi = hi.max(e.semi_axes.max_element());
    }
    d.insert("layout".into(), json!(layout));
    d.insert("sh_degree".into(), json!(sh_degree(l.rest.len())));
    d.insert(
        "semi_axes".into(),
        json!({ "extent": DEFAULT_EXTENT, "min": lo, "max": hi }),
    );
    Ok(d)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vertex of the tests: position, f_dc, opacity logit, log scales, rot, f_rest.
    #[derive(Clone)]
    struct V {
        p: [f32; 3],
        dc: [f32; 3],
        o: f32,
        s: [f32; 3],
        q: [f32; 4],
        rest: Vec<f32>,
    }

    fn v() -> V {
        V {
            p: [1.0, 2.0, 3.0],
            dc: [0.5, -0.25, -4.0],
            o: 0.7,
            s: [-1.0, 0.0, 0.5],
            q: [2.0, 0.0, 0.0, 0.0],
            rest: Vec::new(),
        }
    }

    fn names(n_rest: usize) -> Vec<String> {
        let mut n: Vec<String> = [
            "x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        n.extend((0..n_rest).map(|k| format!("f_rest_{k}")));
        n.extend(REQUIRED[6..].iter().map(|s| s.to_string()));
        n
    }

    fn values(v: &V) -> Vec<f32> {
        let mut out = v.p.to_vec();
        out.extend([0.0; 3]);
        out.extend(v.dc);
        out.extend(&v.rest);
        out.push(v.o);
        out.extend(v.s);
        out.extend(v.q);
        out
    }

    /// A standard-layout file of `vs` in `format` ("binary_little_endian", …).
    fn file(format: &str, vs: &[V]) -> Vec<u8> {
        let n_rest = vs.first().map_or(0, |v| v.rest.len());
        let mut b = format!(
            "ply\nformat {format} 1.0\ncomment test\nelement vertex {}\n",
            vs.len()
        );
        for n in names(n_rest) {
            b.push_str(&format!("property float {n}\n"));
        }
        b.push_str("end_header\n");
        let mut b = b.into_bytes();
        for v in vs {
            for x in values(v) {
                match format {
                    "ascii" => b.extend(format!("{x:?} ").as_bytes()),
                    "binary_big_endian" => b.extend(x.to_be_bytes()),
                    _ => b.extend(x.to_le_bytes()),
                }
            }
            if format == "ascii" {
                b.push(b'\n');
            }
        }
        b
    }

    fn spec() -> IncludeSpec {
        IncludeSpec::bare(Path::new("t.ply"))
    }

    fn err(bytes: &[u8]) -> String {
        read(&spec(), bytes).expect_err("an error").to_string()
    }

    #[test]
    fn a_vertex_becomes_the_documented_ellipsoid() {
        let l = read(&spec(), &file("binary_little_endian", &[v(), v()])).expect("ok");
        assert_eq!(l.records.len(), 2);
        let r = &l.records[1];
        assert_eq!(r.center, DVec3::new(1.0, 2.0, 3.0));
        let e = r.ellipsoid.expect("an ellipsoid");
        let axes = DVec3::new(3.0 * (-1.0f64).exp(), 3.0, 3.0 * 0.5f64.exp());
        assert_eq!(e.semi_axes, axes);
        assert_eq!(r.radius, axes.z);
        assert_eq!(e.rotation, [1.0, 0.0, 0.0, 0.0]);
        assert_eq!(r.opacity, Some(1.0 / (1.0 + (-f64::from(0.7f32)).exp())));
        let c = r.color.expect("a colour");
        assert_eq!(c.x, 0.5 + SH_C0 * 0.5);
        assert_eq!(c.y, 0.5 - SH_C0 * 0.25);
        assert_eq!(c.z, 0.0, "clamped at 0");
        assert_eq!(
            r.location,
            Location::Byte(
                u64::try_from(file("binary_little_endian", &[]).len()).expect("small") + 17 * 4
            )
        );
    }

    #[test]
    fn ascii_and_big_endian_read_as_little_endian() {
        let mut w = v();
        w.rest = (0..45).map(|k| k as f32 * 0.01 - 0.2).collect();
        let vs = [w.clone(), w];
        let le = read(&spec(), &file("binary_little_endian", &vs)).expect("le");
        for f in ["ascii", "binary_big_endian"] {
            let other = read(&spec(), &file(f, &vs)).expect(f);
            for (a, b) in le.records.iter().zip(&other.records) {
                assert_eq!(
                    (a.center, a.ellipsoid, a.color, a.opacity),
                    (b.center, b.ellipsoid, b.color, b.opacity),
                    "{f}"
                );
            }
        }
    }

    #[test]
    fn extent_scales_the_semi_axes() {
        let mut s = spec();
        s.extent = Some(2.0);
        let l = read(&s, &file("binary_little_endian", &[v()])).expect("ok");
        assert_eq!(l.records[0].ellipsoid.expect("e").semi_axes.y, 2.0);
        s.extent = Some(0.0);
        assert!(read(&s, &file("binary_little_endian", &[v()])).is_err());
    }

    #[test]
    fn gaussian_density_takes_the_standard_deviations_and_refuses_extent() {
        let mut s = spec();
        s.density = Some(crate::formats::Profile::Gaussian);
        let l = read(&s, &file("binary_little_endian", &[v()])).expect("ok");
        let axes = DVec3::new((-1.0f64).exp(), 1.0, 0.5f64.exp());
        assert_eq!(l.records[0].ellipsoid.expect("e").semi_axes, axes);
        s.extent = Some(3.0);
        let e = read(&s, &file("binary_little_endian", &[v()]))
            .expect_err("extent refused")
            .to_string();
        assert!(e.contains("t.ply") && e.contains("extent"), "{e}");
    }

    #[test]
    fn a_file_cut_short_names_the_vertex() {
        let b = file("binary_little_endian", &[v(), v(), v()]);
        let e = err(&b[..b.len() - 10]);
        assert!(
            e.contains("t.ply (byte") && e.contains("vertex 2") && e.contains("3 vertices"),
            "{e}"
        );
        let b = file("ascii", &[v(), v(), v()]);
        let cut = b.len() - 40;
        let e = err(&b[..cut]);
        assert!(e.contains("t.ply:") && e.contains("vertex 2"), "{e}");
    }

    #[test]
    fn header_errors_name_the_line() {
        let good = String::from_utf8(file("binary_little_endian", &[])).expect("text");
        let cases: Vec<(String, &str)> = vec![
            (good.replace("ply\n", "plx\n"), "t.ply:1"),
            (
                good.replace("format binary_little_endian 1.0\n", ""),
                "no `format`",
            ),
            (good.replace("1.0", "2.0"), "version"),
            (good.replace("comment test", "bogus test"), "t.ply:3"),
            (
                good.replace("element vertex 0", "element vertex -1"),
                "count",
            ),
            (
                good.replace("property float nx", "property list uchar int nx"),
                "property nx is a list",
            ),
            (
                good.replace("property float nx", "property half nx"),
                "unknown type `half`",
            ),
            (
                good.replace("property float nx", "property float x"),
                "a second property `x`",
            ),
            (
                good.replace("property float opacity\n", ""),
                "lacks the 3D Gaussian splatting properties opacity",
            ),
            (
                good.replace("property float f_rest_0\n", "")
                    .replace("end_header", "property float f_rest_0\nend_header"),
                "",
            ),
            (good.replace("end_header\n", ""), "ends before `end_header`"),
            (
                good.replace("element vertex", "element face"),
                "no `vertex` element",
            ),
        ];
        for (text, want) in cases {
            let e = err(text.as_bytes());
            assert!(e.contains("t.ply") && e.contains(want), "{want}: {e}");
        }
        let mut b = b"ply\nformat ascii 1.0\ncomment \xff\xfe\n".to_vec();
        b.extend(b"end_header\n");
        let e = err(&b);
        assert!(e.contains("t.ply:3") && e.contains("not text"), "{e}");
        let mesh = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n";
        let e = err(mesh);
        assert!(
            e.contains("f_dc_0") && e.contains("rot_3") && e.contains("has x, y, z"),
            "{e}"
        );
    }

    #[test]
    fn f_rest_must_be_a_whole_degree() {
        let mut w = v();
        w.rest = vec![0.0; 10];
        let e = err(&file("binary_little_endian", &[w]));
        assert!(e.contains("10 f_rest_"), "{e}");
    }

    #[test]
    fn bad_values_name_the_vertex_and_field() {
        type Edit = fn(&mut V);
        let cases: Vec<(Edit, &str)> = vec![
            (|w| w.s[1] = 800.0, "scale_1 = 800"),
            (|w| w.s[2] = -800.0, "scale_2 = -800"),
            (|w| w.s[0] = f32::NAN, "scale_0 = NaN"),
            (|w| w.s[0] = f32::INFINITY, "scale_0 = inf"),
            (|w| w.q = [0.0; 4], "not a finite, non-zero quaternion"),
            (|w| w.q[2] = f32::NAN, "quaternion"),
            (|w| w.p[1] = f32::NAN, "position"),
            (|w| w.o = f32::NAN, "opacity is NaN"),
            (|w| w.dc[0] = f32::INFINITY, "f_dc"),
        ];
        for (edit, want) in cases {
            let mut w = v();
            edit(&mut w);
            let e = err(&file("binary_little_endian", &[v(), w]));
            assert!(
                e.contains("t.ply (byte") && e.contains("vertex 1: ") && e.contains(want),
                "{want}: {e}"
            );
        }
        let mut w = v();
        w.o = f32::INFINITY;
        let l = read(&spec(), &file("binary_little_endian", &[w]))
            .expect("an infinite logit is Θmax = 1");
        assert_eq!(l.records[0].opacity, Some(1.0));
    }

    #[test]
    fn sh_constants_are_their_closed_forms() {
        let pi = std::f64::consts::PI;
        let close =
            |a: f64, b: f64| assert!((a - b).abs() <= 4.0 * f64::EPSILON * b.abs(), "{a} {b}");
        close(SH_C0, 0.5 * (1.0 / pi).sqrt());
        close(SH_C1, 0.5 * (3.0 / pi).sqrt());
        let c2 = [
            0.5 * (15.0 / pi).sqrt(),
            -0.5 * (15.0 / pi).sqrt(),
            0.25 * (5.0 / pi).sqrt(),
            -0.5 * (15.0 / pi).sqrt(),
            0.25 * (15.0 / pi).sqrt(),
        ];
        for (a, b) in SH_C2.iter().zip(c2) {
            close(*a, b);
        }
        let (a, b, c, d) = (
            (35.0 / (2.0 * pi)).sqrt(),
            (105.0 / pi).sqrt(),
            (21.0 / (2.0 * pi)).sqrt(),
            (7.0 / pi).sqrt(),
        );
        let c3 = [
            -0.25 * a,
            0.5 * b,
            -0.25 * c,
            0.25 * d,
            -0.25 * c,
            0.25 * b,
            -0.25 * a,
        ];
        for (x, y) in SH_C3.iter().zip(c3) {
            close(*x, y);
        }
    }

    #[test]
    fn view_colour_follows_the_direction_and_the_order() {
        // Degree 1, only the z coefficient (index 1) set in red: C1·z·sh.
        let mut w = v();
        w.rest = vec![0.0; 9];
        w.rest[1] = 0.5;
        let mut s = spec();
        s.sh = Some(ShColor::View);
        assert!(
            read(&s, &file("binary_little_endian", &[w.clone()])).is_err(),
            "no camera"
        );
        s.view_from = Some(DVec3::new(1.0, 2.0, -7.0));
        let l = read(&s, &file("binary_little_endian", &[w.clone()])).expect("ok");
        let dc = l.records[0].color.expect("c");
        assert_eq!(dc.x, 0.5 + SH_C0 * 0.5 + SH_C1 * 1.0 * 0.5);
        // The same coefficient written coefficient-major: red of coefficient 2 is at index 3.
        w.rest = vec![0.0; 9];
        w.rest[3] = 0.5;
        s.sh_order = Some(ShOrder::CoefficientMajor);
        let l2 = read(&s, &file("binary_little_endian", &[w])).expect("ok");
        assert_eq!(l2.records[0].color, l.records[0].color);
    }

    #[test]
    fn details_report_the_layout() {
        let mut w = v();
        w.rest = vec![0.0; 24];
        let d = details(Path::new("t.ply"), &file("binary_little_endian", &[w])).expect("ok");
        assert_eq!(d["layout"], "standard");
        assert_eq!(d["sh_degree"], 2);
        assert_eq!(d["semi_axes"]["max"], 3.0 * 0.5f64.exp());
    }
}
