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

/// The fixture of the view-dependent colour tests: one isotropic Gaussian at the origin
/// (standard deviation 0.5, opacity logit 0: α = ½, f_dc = 0) whose degree-1 SH has a strong
/// z term (red +0.75, green −0.5, blue 0; the y term of blue 0.25, which these eyes do not
/// see), and a COLMAP text model of two 9×9 PINHOLE images with the principal point at the
/// image centre: `a.jpg` at (0, 0, −5) looking along +z, `b.jpg` at (0, 0, +5) looking along −z.
/// Returns the scene file: `[camera] from` the model (a sequence of two frames), the emission
/// model on black, the PLY included with `sh = "view"` and Gaussian density.
pub fn sh_two_eyes_scene(dir: &std::path::Path) -> std::path::PathBuf {
    // f_rest channel-major: red 1..3, green 1..3, blue 1..3; coefficient 2 of each (index 1)
    // is the z term.
    let mut row = vec![0.0f32; 6 + 3];
    row.extend([0.0, 0.75, 0.0, 0.0, -0.5, 0.0, 0.25, 0.0, 0.0]);
    row.extend([
        0.0,
        0.5f32.ln(),
        0.5f32.ln(),
        0.5f32.ln(),
        1.0,
        0.0,
        0.0,
        0.0,
    ]);
    std::fs::write(dir.join("g.ply"), splat_file(9, std::iter::once(row))).unwrap();
    let model = dir.join("sparse");
    std::fs::create_dir_all(&model).unwrap();
    std::fs::write(model.join("cameras.txt"), "1 PINHOLE 9 9 12 12 4.5 4.5\n").unwrap();
    // a: R = I, t = (0, 0, 5): eye −Rᵀt = (0, 0, −5). b: qvec (0, 0, 1, 0), R = diag(−1, 1, −1),
    // the same t: eye (0, 0, 5), looking along Rᵀ(0, 0, 1) = −z.
    std::fs::write(
        model.join("images.txt"),
        "1 1 0 0 0 0 0 5 1 a.jpg\n\n2 0 0 1 0 0 0 5 1 b.jpg\n\n",
    )
    .unwrap();
    let scene = dir.join("s.toml");
    std::fs::write(
        &scene,
        "[camera]\nfrom = \"sparse\"\n[render]\nmodel = \"emission\"\nbackground = [0.0, 0.0, 0.0]\ntol = 1e-9\n[[include]]\npath = \"g.ply\"\nsh = \"view\"\ndensity = \"gaussian\"\n",
    )
    .unwrap();
    scene
}

/// The fixture's colour seen from an eye on the z axis, `z_dir` = the z of the unit direction
/// from the eye to the Gaussian (+1 from a.jpg, −1 from b.jpg): 3DGS's `computeColorFromSH`
/// written out, 0.5 + C0·0 + C1·z·(coefficient 2), C1 = ½√(3/π), clamped at 0.
pub fn sh_two_eyes_color(z_dir: f64) -> glam::DVec3 {
    let c1 = 0.5 * (3.0 / std::f64::consts::PI).sqrt();
    (glam::DVec3::splat(0.5) + c1 * z_dir * glam::DVec3::new(0.75, -0.5, 0.0))
        .max(glam::DVec3::ZERO)
}
