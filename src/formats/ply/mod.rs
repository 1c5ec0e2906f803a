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
//! default [`DEFAULT_EXTENT`]), `sh = "dc" | "view"` (default `"dc"`; `"view"` keeps every
//! vertex's coefficients in [`LoadedParticles::sh`], which the scene evaluates for the eye of
//! each frame), `sh_order =
//! "channel-major" | "coefficient-major"` (the order of `f_rest`, default channel-major as the
//! reference implementation writes it; EVER's training code writes coefficient-major).
//!
//! **Why a reader of its own.** The maintained PLY crate (`ply-rs-bw` 4) needs Rust 1.87, above
//! pgt's 1.85; its header model keeps properties in a map by name, so a header with a
//! duplicated property name silently loses one and misreads every later byte; and its payload
//! goes through one call per property and vertex with the property's name as a string. This
//! reader knows the vertex layout after the header: each property's byte offset and type, so a
//! vertex is a fixed-size slice whose values the byte layer decodes ([`super::file`]). Every
//! count is checked against the bytes that remain before anything is allocated, and every
//! problem is an error that names the header line or the vertex and its byte offset.
//!
//! **Files**, one job each: [`header`] parses the header, [`layout`] finds what the vertex
//! element holds (3DGS Gaussians or pgt export's particles), [`data`] reads the vertices
//! (ASCII or binary), [`convert`] turns a vertex into a particle (the equations of
//! docs/design.md §9: semi-axes, Θmax, the SH colour), and [`details`] gives `pgt info` its
//! facts. This file holds the table entry and the reader that runs them.

mod convert;
mod data;
mod details;
mod header;
mod layout;
#[cfg(test)]
mod tests;

pub use convert::{sigmoid, view_color, SH_C0};

use super::{Format, IncludeSpec, LoadedParticles};
use super::{Profile, ShColor, ShOrder};
use crate::error::{PgtError, Result};
use glam::DVec3;
use layout::Layout;

/// PLY in the table of formats ([`super::FORMATS`]).
pub const FORMAT: Format = Format {
    name: "ply",
    extensions: &["ply"],
    description: "PLY of 3D Gaussian splatting (ascii or binary)",
    particles: "vertices (Gaussians)",
    read: Some(read),
    details: Some(details::details),
    ..Format::NOTHING
};

/// Standard deviations per semi-axis where the include does not set `extent`: a 3D standard
/// normal holds P(χ²₃ ≤ 9) = 0.9707 of its mass within 3σ, and 3σ is where the reference
/// rasteriser cuts each splat's footprint.
pub const DEFAULT_EXTENT: f64 = 3.0;

/// Whether `path` is a PLY file in the layout of 3D Gaussian splatting (not pgt's export): a
/// bare file of this layout gets the splatting defaults (docs/design.md §1, "A bare particle
/// file"). Reads the header only; a file that cannot be read or parsed is not one (reading it
/// then reports why).
pub fn is_splatting_file(path: &std::path::Path) -> bool {
    use std::io::Read;
    let mut head = Vec::new();
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    if file
        .take(header::MAX_HEADER_BYTES as u64)
        .read_to_end(&mut head)
        .is_err()
    {
        return false;
    }
    header::header(path, &head)
        .and_then(|h| layout::layout(path, &h))
        .is_ok_and(|(_, l)| matches!(l, Layout::Gaussians(_)))
}

/// What the reader needs of the include, resolved.
struct Options {
    extent: f64,
    /// `sh = "view"`: keep the SH coefficients ([`super::ShCoefficients`]).
    view: bool,
    /// The eye the records' colours are evaluated for (`sh = "view"` with
    /// [`IncludeSpec::view_from`]); `None`: the DC colour.
    view_from: Option<DVec3>,
    order: ShOrder,
}

fn options(spec: &IncludeSpec) -> Result<Options> {
    let gaussian = spec.density == Some(Profile::Gaussian);
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
    let view = spec.sh.unwrap_or_default() == ShColor::View;
    Ok(Options {
        extent,
        view,
        view_from: spec.view_from.filter(|_| view),
        order: spec.sh_order.unwrap_or_default(),
    })
}

/// The [`super::Reader`] of 3DGS PLY: every vertex as an ellipsoid (see the module doc), and
/// with `sh = "view"` the SH coefficients of every vertex (degree ≥ 1).
pub fn read(spec: &IncludeSpec, bytes: &[u8]) -> Result<LoadedParticles> {
    let path = spec.path.as_path();
    let opts = options(spec)?;
    let h = header::header(path, bytes)?;
    let (v, layout) = layout::layout(path, &h)?;
    let mut warnings = Vec::new();
    let mut sh = None;
    let records = match &layout {
        Layout::Gaussians(l) => {
            let keep = opts.view && !l.rest.is_empty();
            let values = std::cell::RefCell::new(Vec::new());
            let convert = |i, at, vertex: &[f64]| {
                let (record, coefficients) =
                    convert::gaussian(path, i, at, vertex, l, &opts, keep)?;
                values.borrow_mut().extend(coefficients);
                Ok(record)
            };
            let records = data::vertices(path, bytes, &h, v, &convert, &mut warnings)?;
            if keep {
                sh = Some(super::ShCoefficients {
                    per_particle: 1 + l.rest.len() / 3,
                    values: values.into_inner(),
                });
            }
            records
        }
        Layout::Export(l) => {
            let convert = |_, at, values: &[f64]| Ok(convert::exported(at, values, l));
            data::vertices(path, bytes, &h, v, &convert, &mut warnings)?
        }
    };
    Ok(LoadedParticles {
        records,
        warnings,
        sh,
    })
}
