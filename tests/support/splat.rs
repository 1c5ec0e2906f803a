//! 3D Gaussian splatting PLY files written byte by byte, for the PLY tests and the load bench.

/// The standard layout's property names with `n_rest` f_rest coefficients.
pub fn standard_names(n_rest: usize) -> Vec<String> {
    let mut n: Vec<String> = [
        "x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    n.extend((0..n_rest).map(|k| format!("f_rest_{k}")));
    for s in [
        "opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3",
    ] {
        n.push(s.to_string());
    }
    n
}

/// A binary little-endian 3DGS PLY with the standard layout: `rows` holds each vertex's values
/// in [`standard_names`] order.
pub fn splat_file(n_rest: usize, rows: impl ExactSizeIterator<Item = Vec<f32>>) -> Vec<u8> {
    let mut head = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\n",
        rows.len()
    );
    for n in standard_names(n_rest) {
        head.push_str(&format!("property float {n}\n"));
    }
    head.push_str("end_header\n");
    let mut b = head.into_bytes();
    for row in rows {
        for x in row {
            b.extend(x.to_le_bytes());
        }
    }
    b
}
