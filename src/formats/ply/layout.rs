//! What the vertex element of a PLY header holds: the properties of 3D Gaussian splatting
//! (where each sits), or those pgt export writes; anything else is an error naming what is
//! missing.

use super::header::{Element, Header};
use crate::error::{PgtError, Result};
use std::path::Path;

/// What a vertex element holds: 3DGS Gaussians or pgt export's particles.
#[derive(Debug, Clone)]
pub(super) enum Layout {
    Gaussians(Gaussians),
    Export(Export),
}

/// Where pgt export's properties sit in the vertex element (indices into its properties).
#[derive(Debug, Clone)]
pub(super) struct Export {
    pub(super) position: [usize; 3],
    pub(super) size: Size,
    pub(super) rgb: [usize; 3],
    pub(super) opacity: usize,
    pub(super) sigma: usize,
}

/// The size of pgt export's particles.
#[derive(Debug, Clone)]
pub(super) enum Size {
    /// `radius`: spheres.
    Radius(usize),
    /// `sx sy sz` and `qw qx qy qz`: ellipsoids.
    Ellipsoid([usize; 3], [usize; 4]),
}

/// Where the 3DGS properties sit in the vertex element (indices into its properties).
#[derive(Debug, Clone)]
pub(super) struct Gaussians {
    pub(super) position: [usize; 3],
    pub(super) dc: [usize; 3],
    pub(super) opacity: usize,
    pub(super) scale: [usize; 3],
    pub(super) rot: [usize; 4],
    /// `f_rest_0..n`, in index order.
    pub(super) rest: Vec<usize>,
}

/// The names every 3DGS vertex needs, in the reference implementation's order.
pub(super) const REQUIRED: [&str; 14] = [
    "x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
    "rot_0", "rot_1", "rot_2", "rot_3",
];

/// The vertex element and where the 3DGS properties are in it; an error names what is missing.
pub(super) fn layout(path: &Path, h: &Header) -> Result<(usize, Layout)> {
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
pub(super) fn export_layout(e: &Element) -> Option<Export> {
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
pub(super) fn sh_degree(rest: usize) -> usize {
    match rest {
        0 => 0,
        9 => 1,
        24 => 2,
        _ => 3,
    }
}
