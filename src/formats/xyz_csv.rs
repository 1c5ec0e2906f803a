//! XYZ and CSV particle lists.
//!
//! **XYZ** (the chemistry format): a line with the atom count N, a comment line, then N lines
//! `Element x y z` (further columns ignored). Elements give van der Waals radii and CPK colours
//! ([`super::elements`]); an unknown symbol gets the fallback radius, with a warning. Several
//! frames may follow one another; the first is read (`frame = k` picks frame k, 0-based).
//!
//! **CSV**: comma-separated, a header row naming the columns (case-insensitive, blanks trimmed,
//! any order, unknown columns ignored with a warning): `x`, `y`, `z` (required); `radius` (or
//! `r`); colour `red`, `green`, `blue` (or `r`, `g`, `b`: where `g` and `b` are present, an `r`
//! is red, and a second `r`, or `radius`, is the radius), linear RGB ≥ 0; `opacity` (Θmax in
//! [0, 1]); `sigma` (extinction σ in 1/length, ≥ 0, `inf` for a perfectly absorbing ball).
//! Without a radius column every particle has radius 1 (with a warning). Blank lines and lines
//! starting with `#` are skipped.
//!
//! **Ellipsoids** (docs/design.md §9): columns `sx`, `sy`, `sz` (the semi-axes along the body's
//! axes, in place of `radius`, all three or none) and optionally `qw`, `qx`, `qy`, `qz` (the
//! orientation, body to world, a quaternion that need not have unit length; without them the
//! body's axes are the scene's). Every row of such a file is an ellipsoid; one with three equal
//! semi-axes is the sphere of that radius. `opacity` is then Θmax along the shortest axis. `pgt export`'s CSV is such a file and reads back without a
//! warning, σ bit for bit.
//!
//! **σ and opacity.** A particle's σ, where the file gives one, is its σ exactly (no λ, no
//! `radius_scale` applies to it), ahead of its `opacity` and of the scene's `[defaults]`
//! opacity or kappa. Where a row gives both, they must agree as docs/design.md §1 ties them,
//! Θmax = 1 − e^{−2rσ} with the row's radius, to [`SIGMA_OPACITY_AGREEMENT`]; a row where they
//! disagree is refused, naming its line (one of the two was edited without the other).

use super::elements::{element_color, element_radius, Element};
use super::file::text::finite_number;
use super::file::{scan_lines, text_lines, ByteSource};
use super::frame_source::{finish_frame, Frame, FrameInfo, FrameSource, TextFrames};
use super::{EllipsoidRecord, Format, IncludeSpec, LoadedParticles, ParticleRecord};
use crate::error::{Location, PgtError, Result};
use glam::DVec3;
use std::path::Path;

/// XYZ in the table of formats ([`super::FORMATS`]).
pub const XYZ: Format = Format {
    name: "xyz",
    extensions: &["xyz"],
    description: "XYZ (lines of element x y z)",
    particles: "atoms in the frame",
    read: Some(read_xyz),
    frames: Some(open_xyz_frames),
    ..Format::NOTHING
};

/// CSV in the table of formats ([`super::FORMATS`]).
pub const CSV: Format = Format {
    name: "csv",
    extensions: &["csv"],
    description: "CSV with a header row",
    particles: "data rows after the header",
    read: Some(read_csv),
    ..Format::NOTHING
};

/// A field that must be a finite number (blanks around it trimmed); the error names the line.
fn number(path: &Path, line: usize, what: &str, s: &str) -> Result<f64> {
    finite_number(s.trim(), what).map_err(|m| PgtError::at_line(path, line, m))
}

/// The [`super::Reader`] of XYZ: frame `spec.frame` (0-based, default 0).
pub fn read_xyz(spec: &IncludeSpec, bytes: &[u8]) -> Result<LoadedParticles> {
    read_xyz_from(spec, bytes, 1)
}

/// [`read_xyz`] of a piece of a file whose first line is line `first_line` of the file.
fn read_xyz_from(spec: &IncludeSpec, bytes: &[u8], first_line: usize) -> Result<LoadedParticles> {
    let path = spec.path.as_path();
    let frame = spec.frame.unwrap_or(0);
    let mut it = text_lines(bytes, first_line).peekable();
    let mut records = Vec::new();
    let mut warnings = Vec::new();
    let mut unknown = 0usize;
    let mut current = 0usize;
    loop {
        // Skip blank lines between frames.
        while it.peek().is_some_and(|(_, l)| l.trim().is_empty()) {
            it.next();
        }
        let Some((line, count_text)) = it.next() else {
            if current == 0 {
                return Err(PgtError::in_file(
                    path,
                    "empty XYZ file: expected an atom count on the first line",
                ));
            }
            return Err(PgtError::in_file(
                path,
                format!("frame {frame} requested but the file has {current} frame(s)"),
            ));
        };
        let n: usize = count_text.trim().parse().map_err(|_| {
            PgtError::at_line(
                path,
                line,
                format!(
                    "expected the atom count (an integer), found '{}'",
                    count_text.trim()
                ),
            )
        })?;
        if n > bytes.len() / 4 {
            return Err(PgtError::at_line(
                path,
                line,
                format!(
                    "the atom count {n} is larger than the file can hold ({} bytes)",
                    bytes.len()
                ),
            ));
        }
        if it.next().is_none() {
            return Err(PgtError::at_line(
                path,
                line,
                "expected a comment line after the atom count",
            ));
        }
        let keep = current == frame;
        if keep {
            records.reserve(n);
        }
        for k in 0..n {
            let Some((l, text)) = it.next().filter(|(_, t)| !t.trim().is_empty()) else {
                return Err(PgtError::at_line(
                    path,
                    line,
                    format!("the frame announces {n} atoms but the file ends after {k}"),
                ));
            };
            if !keep {
                continue;
            }
            let f: Vec<&str> = text.split_whitespace().collect();
            if f.len() < 4 {
                return Err(PgtError::at_line(
                    path,
                    l,
                    format!("expected 'Element x y z', found '{}'", text.trim()),
                ));
            }
            let el = f.first().and_then(|s| Element::from_symbol(s));
            if el.is_none() {
                unknown += 1;
            }
            let c = |i: usize, w: &str| number(path, l, w, f.get(i).copied().unwrap_or_default());
            records.push(ParticleRecord {
                ellipsoid: None,
                center: DVec3::new(c(1, "x")?, c(2, "y")?, c(3, "z")?),
                radius: element_radius(el),
                color: Some(element_color(el)),
                opacity: None,
                sigma: None,
                location: Location::Line(l),
            });
        }
        if keep {
            break;
        }
        current += 1;
    }
    if records.is_empty() && spec.frame.is_some() {
        // The selection emptied the include: name it (docs/design.md §6 "Bad input").
        return Err(PgtError::in_file(
            path,
            format!("`frame = {frame}` holds no particles (its atom count is 0)"),
        ));
    }
    if unknown > 0 {
        warnings.push(format!(
            "{}: {unknown} atoms have an unknown element symbol; they get radius {} Å",
            path.display(),
            super::elements::FALLBACK_RADIUS
        ));
    }
    Ok(LoadedParticles {
        records,
        warnings,
        sh: None,
    })
}

/// How far a row's `opacity` may be from the opacity its `sigma` gives, 1 − e^{−2rσ}: both
/// written with a few digits agree this well; an edit of one of them does not.
pub const SIGMA_OPACITY_AGREEMENT: f64 = 1e-6;

/// Where the scan of an XYZ file is: before a count line, or with lines of a frame to skip.
enum XyzScan {
    Count,
    Skip(usize),
}

/// The [`super::OpenFrames`] of XYZ: one scan at open finds the count line of every frame
/// (blank lines between frames are skipped); a frame's lines are parsed when it is asked for. A
/// count line that is not an integer is an error at open, naming its line; a last frame cut
/// short is found when it is read.
pub fn open_xyz_frames(spec: &IncludeSpec, source: ByteSource) -> Result<Box<dyn FrameSource>> {
    let mut text = TextFrames::default();
    let mut state = XyzScan::Count;
    let path = source.path().to_path_buf();
    let max_atoms = source.len() / 4;
    scan_lines(&source, |line, at, raw| {
        match state {
            XyzScan::Skip(n) => {
                state = if n <= 1 {
                    XyzScan::Count
                } else {
                    XyzScan::Skip(n - 1)
                }
            }
            XyzScan::Count => {
                let t = String::from_utf8_lossy(raw);
                if t.trim().is_empty() {
                    return Ok(true);
                }
                let n: u64 = t.trim().parse().map_err(|_| {
                    PgtError::at_line(
                        &path,
                        line,
                        format!(
                            "frame {}: expected the atom count (an integer), found '{}'",
                            text.starts.len(),
                            t.trim()
                        ),
                    )
                })?;
                if n > max_atoms {
                    return Err(PgtError::at_line(
                        &path,
                        line,
                        format!(
                            "the atom count {n} is larger than the file can hold ({} bytes)",
                            source.len()
                        ),
                    ));
                }
                text.starts.push(at);
                text.lines.push(line);
                state = XyzScan::Skip(n as usize + 1);
            }
        }
        Ok(true)
    })?;
    if text.starts.is_empty() {
        return Err(PgtError::in_file(
            &path,
            "empty XYZ file: expected an atom count on the first line",
        ));
    }
    Ok(Box::new(XyzFrames {
        spec: spec.clone(),
        source,
        text,
    }))
}

/// The frames of an XYZ file ([`open_xyz_frames`]).
struct XyzFrames {
    spec: IncludeSpec,
    source: ByteSource,
    text: TextFrames,
}

impl FrameSource for XyzFrames {
    fn path(&self) -> &Path {
        self.source.path()
    }
    fn info(&self) -> FrameInfo {
        self.text.info()
    }
    fn read_frame(&self, index: usize) -> Result<Frame> {
        let path = self.source.path();
        let (bytes, first_line) = self.text.read(&self.source, index)?;
        let mut spec = self.spec.clone();
        spec.path = path.to_path_buf();
        spec.frame = None;
        let loaded = read_xyz_from(&spec, &bytes, first_line)
            .map_err(|e| e.context(format!("frame {index}")))?;
        let particles = finish_frame(&spec, path, index, loaded)?;
        Ok(Frame {
            index,
            time_ps: None,
            particles,
        })
    }
}

/// The columns a CSV header names.
#[derive(Debug, Default)]
struct Columns {
    xyz: [usize; 3],
    radius: Option<usize>,
    rgb: Option<[usize; 3]>,
    opacity: Option<usize>,
    sigma: Option<usize>,
    /// `sx, sy, sz`.
    semi_axes: Option<[usize; 3]>,
    /// `qw, qx, qy, qz`.
    rotation: Option<[usize; 4]>,
}

fn columns(path: &Path, line: usize, header: &str, warnings: &mut Vec<String>) -> Result<Columns> {
    let names: Vec<String> = header
        .split(',')
        .map(|s| s.trim().to_ascii_lowercase())
        .collect();
    let find = |n: &str| names.iter().position(|c| c == n);
    let expected =
        "expected a header row naming the columns: x,y,z[,radius][,red,green,blue][,opacity][,sigma]";
    let (Some(x), Some(y), Some(z)) = (find("x"), find("y"), find("z")) else {
        return Err(PgtError::at_line(
            path,
            line,
            format!("{expected}; found '{}'", header.trim()),
        ));
    };
    let rs: Vec<usize> = names
        .iter()
        .enumerate()
        .filter(|(_, c)| *c == "r")
        .map(|(i, _)| i)
        .collect();
    let (g, b) = (find("g"), find("b"));
    let mut cols = Columns {
        xyz: [x, y, z],
        ..Columns::default()
    };
    let mut used = vec![x, y, z];
    if let (Some(r), Some(g), Some(b)) = (find("red"), find("green"), find("blue")) {
        cols.rgb = Some([r, g, b]);
        cols.radius = find("radius").or(rs.first().copied());
    } else if let (Some(g), Some(b)) = (g, b) {
        // r,g,b colour: the r nearest before g is red; another r (or `radius`) is the radius.
        let red = rs
            .iter()
            .rev()
            .find(|&&r| r < g)
            .or(rs.last())
            .copied()
            .ok_or_else(|| {
                PgtError::at_line(
                    path,
                    line,
                    "the header has columns g and b but no r for red",
                )
            })?;
        cols.rgb = Some([red, g, b]);
        cols.radius = find("radius").or(rs.iter().copied().find(|&r| r != red));
    } else {
        cols.radius = find("radius").or(rs.first().copied());
    }
    cols.opacity = find("opacity");
    cols.sigma = find("sigma");
    let all = |names: &[&str]| -> Result<Option<Vec<usize>>> {
        let found: Vec<Option<usize>> = names.iter().map(|n| find(n)).collect();
        if found.iter().all(Option::is_none) {
            return Ok(None);
        }
        if let Some(k) = found.iter().position(Option::is_none) {
            return Err(PgtError::at_line(
                path,
                line,
                format!(
                    "the header names some of the columns {} but not {}: give all of them or none",
                    names.join(", "),
                    names[k]
                ),
            ));
        }
        Ok(Some(found.into_iter().flatten().collect()))
    };
    cols.semi_axes = all(&["sx", "sy", "sz"])?.map(|v| [v[0], v[1], v[2]]);
    cols.rotation = all(&["qw", "qx", "qy", "qz"])?.map(|v| [v[0], v[1], v[2], v[3]]);
    if cols.semi_axes.is_some() && find("radius").is_some() {
        return Err(PgtError::at_line(
            path,
            line,
            "the header names both radius and the semi-axes sx, sy, sz: a row is a sphere (radius) or an ellipsoid (sx, sy, sz), give one of them",
        ));
    }
    if cols.semi_axes.is_some() {
        // An `r` column is red, never a radius, where the semi-axes give the size.
        cols.radius = None;
    } else if cols.rotation.is_some() {
        return Err(PgtError::at_line(
            path,
            line,
            "the header names the rotation qw, qx, qy, qz but not the semi-axes sx, sy, sz it turns",
        ));
    }
    used.extend(cols.semi_axes.iter().flatten());
    used.extend(cols.rotation.iter().flatten());
    used.extend(cols.radius);
    used.extend(cols.rgb.iter().flatten());
    used.extend(cols.opacity);
    used.extend(cols.sigma);
    let unused: Vec<&String> = names
        .iter()
        .enumerate()
        .filter(|(i, _)| !used.contains(i))
        .map(|(_, n)| n)
        .collect();
    if !unused.is_empty() {
        warnings.push(format!(
            "{}: ignored CSV columns {:?}",
            path.display(),
            unused
        ));
    }
    if cols.radius.is_none() && cols.semi_axes.is_none() {
        warnings.push(format!(
            "{}: no radius column; every particle has radius 1",
            path.display()
        ));
    }
    Ok(cols)
}

/// A `sigma` cell: a number ≥ 0, or `inf` (Θmax = 1).
fn sigma(path: &Path, line: usize, s: &str) -> Result<f64> {
    match s.trim().parse::<f64>() {
        Ok(v) if v >= 0.0 => Ok(v),
        Ok(v) => Err(PgtError::at_line(
            path,
            line,
            format!("sigma must be ≥ 0 (or inf), found {v}"),
        )),
        Err(_) => Err(PgtError::at_line(
            path,
            line,
            format!("expected a number for sigma, found '{}'", s.trim()),
        )),
    }
}

/// A row's `opacity` and `sigma` must say the same (see the module docs).
/// For a Gaussian (`density = "gaussian"` on the include) the opacity is that through the centre
/// along the shortest axis, 1 − e^(−√(2π)·s·sigma) (docs/design.md §9).
fn check_agreement(
    path: &Path,
    line: usize,
    radius: f64,
    (opacity, sigma): (f64, f64),
    gaussian: bool,
) -> Result<()> {
    let (profile, rule) = if gaussian {
        (
            super::Profile::Gaussian,
            "1 − e^(−√(2π)·s·sigma) (a Gaussian)",
        )
    } else {
        (super::Profile::Constant, "1 − e^(−2·r·sigma)")
    };
    let depth = profile.centre_depth(radius, sigma);
    let from_sigma = if sigma == f64::INFINITY {
        1.0
    } else {
        -(-depth).exp_m1()
    };
    if (from_sigma - opacity).abs() <= SIGMA_OPACITY_AGREEMENT {
        return Ok(());
    }
    Err(PgtError::at_line(
        path,
        line,
        format!(
            "opacity {opacity} and sigma {sigma} disagree: with radius {radius}, sigma gives opacity {rule} = {from_sigma}; give one of them, or both consistent (sigma is used where both are given)"
        ),
    ))
}

/// The [`super::Reader`] of CSV: a file with a header row.
pub fn read_csv(spec: &IncludeSpec, bytes: &[u8]) -> Result<LoadedParticles> {
    let path = spec.path.as_path();
    let mut warnings = Vec::new();
    let mut cols: Option<Columns> = None;
    let mut width = 0usize;
    let mut records = Vec::new();
    for (line, text) in text_lines(bytes, 1) {
        let t = text.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let Some(c) = &cols else {
            width = t.split(',').count();
            cols = Some(columns(path, line, t, &mut warnings)?);
            continue;
        };
        let f: Vec<&str> = t.split(',').collect();
        if f.len() != width {
            return Err(PgtError::at_line(
                path,
                line,
                format!(
                    "expected {width} comma-separated values (as in the header), found {}",
                    f.len()
                ),
            ));
        }
        let get =
            |i: usize, what: &str| number(path, line, what, f.get(i).copied().unwrap_or_default());
        let [xi, yi, zi] = c.xyz;
        let ellipsoid = c
            .semi_axes
            .map(|[sx, sy, sz]| {
                let semi_axes = DVec3::new(get(sx, "sx")?, get(sy, "sy")?, get(sz, "sz")?);
                let rotation = match c.rotation {
                    Some([w, x, y, z]) => {
                        [get(w, "qw")?, get(x, "qx")?, get(y, "qy")?, get(z, "qz")?]
                    }
                    None => [1.0, 0.0, 0.0, 0.0],
                };
                Ok::<_, PgtError>(EllipsoidRecord {
                    semi_axes,
                    rotation,
                })
            })
            .transpose()?;
        let radius = match &ellipsoid {
            Some(e) => e.semi_axes.max_element(),
            None => c.radius.map_or(Ok(1.0), |i| get(i, "radius"))?,
        };
        let opacity = c.opacity.map(|i| get(i, "opacity")).transpose()?;
        let sigma = c
            .sigma
            .map(|i| sigma(path, line, f.get(i).copied().unwrap_or_default()))
            .transpose()?;
        if let (Some(o), Some(s)) = (opacity, sigma) {
            // Θmax is the opacity along the shortest diameter (docs/design.md §9).
            let r = ellipsoid.map_or(radius, |e| e.semi_axes.min_element());
            let gaussian = spec.density == Some(super::Profile::Gaussian);
            check_agreement(path, line, r, (o, s), gaussian)?;
        }
        records.push(ParticleRecord {
            ellipsoid,
            center: DVec3::new(get(xi, "x")?, get(yi, "y")?, get(zi, "z")?),
            radius,
            color: c
                .rgb
                .map(|[r, g, b]| {
                    Ok::<_, PgtError>(DVec3::new(
                        get(r, "red")?,
                        get(g, "green")?,
                        get(b, "blue")?,
                    ))
                })
                .transpose()?,
            opacity,
            sigma,
            location: Location::Line(line),
        });
    }
    if cols.is_none() {
        warnings.push(format!(
            "{}: empty CSV file (no header, no particles)",
            path.display()
        ));
    }
    Ok(LoadedParticles {
        records,
        warnings,
        sh: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn xyz_frame(frame: usize) -> IncludeSpec {
        let mut spec = IncludeSpec::bare(Path::new("t.xyz"));
        spec.frame = Some(frame);
        spec
    }

    #[test]
    fn csv_with_r_g_b_and_radius() {
        let text = "x, y, z, radius, r, g, b\n1,2,3,0.5,1,0,0\n\n# c\n4,5,6,1.5,0,1,0\n";
        let l = read_csv(&IncludeSpec::bare(Path::new("t.csv")), text.as_bytes()).expect("ok");
        assert_eq!(l.records.len(), 2);
        assert_eq!(l.records[1].center, DVec3::new(4.0, 5.0, 6.0));
        assert_eq!(l.records[1].radius, 1.5);
        assert_eq!(l.records[1].color, Some(DVec3::new(0.0, 1.0, 0.0)));
        assert_eq!(l.records[1].location, Location::Line(5));
    }

    #[test]
    fn csv_double_r() {
        let text = "x,y,z,r,r,g,b\n1,2,3,0.5,1,0.2,0.3\n";
        let l = read_csv(&IncludeSpec::bare(Path::new("t.csv")), text.as_bytes()).expect("ok");
        assert_eq!(l.records[0].radius, 0.5);
        assert_eq!(l.records[0].color, Some(DVec3::new(1.0, 0.2, 0.3)));
    }

    #[test]
    fn csv_errors() {
        let e = read_csv(&IncludeSpec::bare(Path::new("t.csv")), b"1,2,3\n")
            .expect_err("no header")
            .to_string();
        assert!(e.contains("t.csv:1") && e.contains("header"), "{e}");
        let e = read_csv(&IncludeSpec::bare(Path::new("t.csv")), b"x,y,z\n1,2\n")
            .expect_err("short")
            .to_string();
        assert!(e.contains("t.csv:2") && e.contains("expected 3"), "{e}");
        let e = read_csv(&IncludeSpec::bare(Path::new("t.csv")), b"x,y,z\n1,nan,2\n")
            .expect_err("nan")
            .to_string();
        assert!(e.contains("t.csv:2") && e.contains("not finite"), "{e}");
    }

    #[test]
    fn csv_sigma_is_read_and_checked_against_opacity() {
        let spec = IncludeSpec::bare(Path::new("t.csv"));
        let o = -(-2.0f64 * 0.5 * 0.3).exp_m1();
        let text = format!("x,y,z,radius,opacity,sigma\n0,0,0,0.5,{o:?},0.3\n1,0,0,2,1.0,inf\n");
        let l = read_csv(&spec, text.as_bytes()).expect("ok");
        assert!(l.warnings.is_empty(), "{:?}", l.warnings);
        assert_eq!(l.records[0].sigma, Some(0.3));
        assert_eq!(l.records[1].sigma, Some(f64::INFINITY));
        let e = read_csv(&spec, b"x,y,z,radius,opacity,sigma\n0,0,0,0.5,0.7,0.3\n")
            .expect_err("disagree")
            .to_string();
        assert!(e.contains("t.csv:2") && e.contains("disagree"), "{e}");
        for bad in ["-1", "nan", "-inf", "x"] {
            let text = format!("x,y,z,sigma\n0,0,0,{bad}\n");
            let e = read_csv(&spec, text.as_bytes()).expect_err(bad).to_string();
            assert!(e.contains("t.csv:2") && e.contains("sigma"), "{bad}: {e}");
        }
    }

    #[test]
    fn xyz_frames() {
        let text = "2\nwater\nO 0 0 0\nH 1 0 0\n1\nsecond\nC 5 5 5\n";
        let l = read_xyz(&xyz_frame(0), text.as_bytes()).expect("ok");
        assert_eq!(l.records.len(), 2);
        assert_eq!(l.records[0].radius, 1.52);
        let l = read_xyz(&xyz_frame(1), text.as_bytes()).expect("ok");
        assert_eq!(l.records[0].center, DVec3::splat(5.0));
        assert_eq!(l.records[0].location, Location::Line(7));
        let e = read_xyz(&xyz_frame(2), text.as_bytes())
            .expect_err("no frame 2")
            .to_string();
        assert!(e.contains("2 frame"), "{e}");
        let e = read_xyz(&xyz_frame(0), b"3\nc\nO 0 0 0\n")
            .expect_err("short")
            .to_string();
        assert!(e.contains("t.xyz:1") && e.contains("ends after 1"), "{e}");
    }
}
