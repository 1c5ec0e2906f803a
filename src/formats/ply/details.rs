//! What `pgt info` says of a PLY file: its encoding, its layout (standard, reduced, with
//! extra properties), its SH degree and the range of its semi-axes at the default extent.

use super::header::header;
use super::layout::{layout, sh_degree, Layout, REQUIRED};
use super::DEFAULT_EXTENT;
use crate::error::Result;
use crate::formats::IncludeSpec;
use std::path::Path;

/// The [`super::Details`] of PLY: encoding, layout, extra properties, SH degree and the range
/// of the semi-axes at the default extent.
pub(super) fn details(
    path: &Path,
    bytes: &[u8],
) -> Result<serde_json::Map<String, serde_json::Value>> {
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
    let loaded = super::read(&spec, bytes)?;
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
