//! Step 6: the camera of every frame (docs/design.md §1 "Camera convention", §10 "Cameras that
//! move"): the `[camera]` table's fixed camera (framing the particles where it sets no
//! position), an orbit that starts from it ([`super::orbit`]), or keyframes
//! ([`super::keyframes`]); and the image size, the command line's over the table's.

use super::super::file::CameraTable;
use super::super::framing::{default_camera, DEFAULT_FOV_Y, DEFAULT_SIZE};
use super::super::SceneLoadOptions;
use super::{keyframes, orbit};
use crate::error::{At, Result, SourceText};
use crate::geometry::{check_rotation, Camera, CameraPath, Intrinsics, Keyframe, Lens};
use crate::optics::particle::Particle;
use glam::{DMat3, DVec3};
use toml::Spanned;

/// The camera of every frame: the framed default camera without a `[camera]` table, else the
/// table's dataset cameras, fixed camera, orbit or keyframes.
pub(super) fn path(
    source: &SourceText,
    table: &Option<Spanned<CameraTable>>,
    options: &SceneLoadOptions,
    particles: &[Particle],
) -> Result<CameraPath> {
    let Some(table) = table else {
        let (w, h) = options.size.unwrap_or(DEFAULT_SIZE);
        check_size(&source.whole(), w as i64, h as i64)?;
        return Ok(CameraPath::Fixed(default_camera(particles, w, h)));
    };
    let t = table.get_ref();
    let table_at = source.at(table.span());
    if t.from.is_some() {
        return super::dataset_camera::path(source, &table_at, t, options);
    }
    if t.image.is_some() {
        return Err(table_at.err("camera.image names an image of camera.from, which is not set"));
    }
    if t.dataparser.is_some() {
        return Err(table_at.err(
            "camera.dataparser maps the cameras of camera.from (a transforms.json), which is not set",
        ));
    }
    let table_size = check_size(
        &table_at,
        t.width.unwrap_or(DEFAULT_SIZE.0 as i64),
        t.height.unwrap_or(DEFAULT_SIZE.1 as i64),
    )?;
    let (w, h) = match options.size {
        Some((w, h)) => check_size(&source.whole(), w as i64, h as i64)?,
        None => table_size,
    };
    let lens = lens(&table_at, t, table_size, (w, h))?;
    if t.interpolation.is_some() && t.keyframes.is_empty() {
        return Err(table_at
            .err("camera.interpolation applies to [[camera.keyframes]], and there are none"));
    }
    if !t.keyframes.is_empty() {
        return keyframed(source, &table_at, t, lens, (w, h));
    }
    let (camera, look_at) = fixed(&table_at, t, particles, lens, (w, h))?;
    match &t.orbit {
        None => Ok(CameraPath::Fixed(camera)),
        Some(o) => {
            let start = Keyframe {
                frame: 0,
                position: camera.position,
                look_at,
                up: camera.up,
                fov_y: match lens {
                    Lens::FovY(f) => f,
                    Lens::Pinhole(_) => DEFAULT_FOV_Y,
                },
            };
            let intrinsics = camera.intrinsics;
            orbit::path(
                &source.at(o.span()),
                o.get_ref(),
                start,
                (w, h),
                intrinsics,
                particles,
            )
        }
    }
}

/// `[[camera.keyframes]]`, which interpolate position, look_at, up and fov_y: the table may not
/// set a position, look_at, R or intrinsics of its own.
fn keyframed(
    source: &SourceText,
    table_at: &At,
    t: &CameraTable,
    lens: Lens,
    size: (u32, u32),
) -> Result<CameraPath> {
    if t.orbit.is_some() {
        return Err(table_at.err("camera: set [camera.orbit] or [[camera.keyframes]], not both"));
    }
    if let Some(key) = [
        ("position", t.position.is_some()),
        ("look_at", t.look_at.is_some()),
        ("R", t.r.is_some()),
        ("t", t.t.is_some()),
    ]
    .iter()
    .find(|(_, set)| *set)
    {
        return Err(table_at.err(format!(
            "camera.{}: the keyframes set the camera's position and look_at; remove one or the other",
            key.0
        )));
    }
    let Lens::FovY(fov_y) = lens else {
        return Err(table_at.err(
            "camera: keyframes interpolate fov_y; intrinsics (fx, fy, cx, cy) do not apply to [[camera.keyframes]]",
        ));
    };
    keyframes::path(source, table_at, t, fov_y, size)
}
/// The camera of frame 0, with a degenerate one named at the camera table's line.
pub(super) fn first(
    source: &SourceText,
    path: &CameraPath,
    table: &Option<Spanned<CameraTable>>,
) -> Result<Camera> {
    path.camera_at(0).map_err(|m| {
        let at = table
            .as_ref()
            .map_or_else(|| source.whole(), |t| source.at(t.span()));
        at.err(format!("camera: {m}"))
    })
}

/// An image size, checked against the limits (`scene::check_image_size`).
pub(super) fn check_size(at: &At, w: i64, h: i64) -> Result<(u32, u32)> {
    super::super::check_image_size(w, h).map_err(|e| at.err(e))
}

/// The table's lens: `fx, fy, cx, cy` (all four, for the table's own size, scaled to the image
/// size when `--size` differs: [`Intrinsics::scaled`]) or fov_y ([`fov`]).
fn lens(at: &At, t: &CameraTable, table_size: (u32, u32), size: (u32, u32)) -> Result<Lens> {
    let given = [("fx", t.fx), ("fy", t.fy), ("cx", t.cx), ("cy", t.cy)];
    if given.iter().all(|(_, v)| v.is_none()) {
        return Ok(Lens::FovY(fov(at, t)?));
    }
    if t.fov_y.is_some() || t.focal_length.is_some() {
        return Err(at.err("camera: set fov_y (or focal_length) or fx, fy, cx, cy, not both"));
    }
    let missing: Vec<&str> = given
        .iter()
        .filter(|(_, v)| v.is_none())
        .map(|(k, _)| *k)
        .collect();
    if !missing.is_empty() {
        return Err(at.err(format!(
            "camera: intrinsics need fx, fy, cx and cy; {} missing",
            missing.join(", ")
        )));
    }
    let value = |k: &str, v: Option<f64>| at.finite(&format!("camera.{k}"), v.unwrap_or(0.0));
    let k = Intrinsics {
        fx: value("fx", t.fx)?,
        fy: value("fy", t.fy)?,
        cx: value("cx", t.cx)?,
        cy: value("cy", t.cy)?,
    };
    for (name, f) in [("fx", k.fx), ("fy", k.fy)] {
        if f <= 0.0 {
            return Err(at.err(format!("camera.{name} must be > 0 pixels, got {f}")));
        }
    }
    Ok(Lens::Pinhole(k.scaled(table_size, size)))
}

/// `camera.fov_y` or `camera.focal_length` (degrees), [`DEFAULT_FOV_Y`] by default.
fn fov(at: &At, t: &CameraTable) -> Result<f64> {
    Ok(match (t.fov_y, t.focal_length) {
        (Some(_), Some(_)) => return Err(at.err("camera: set fov_y or focal_length, not both")),
        (Some(f), None) => {
            let f = at.finite("camera.fov_y", f)?;
            if !(f > 0.0 && f < 180.0) {
                return Err(at.err(format!("camera.fov_y must be in (0, 180) degrees, got {f}")));
            }
            f
        }
        (None, Some(f)) => {
            let f = at.finite("camera.focal_length", f)?;
            if f <= 0.0 {
                return Err(at.err(format!("camera.focal_length must be > 0, got {f}")));
            }
            Camera::fov_y_from_focal_length(f)
        }
        (None, None) => DEFAULT_FOV_Y,
    })
}

/// The `[camera]` table's own camera (framing the particles where no position is set) and a
/// point on its view axis (its look_at).
fn fixed(
    at: &At,
    t: &CameraTable,
    particles: &[Particle],
    lens: Lens,
    (w, h): (u32, u32),
) -> Result<(Camera, DVec3)> {
    if let Some(rows) = t.r {
        let camera = posed(at, t, rows, lens, (w, h))?;
        return Ok((camera, camera.position + camera.forward));
    }
    if t.t.is_some() {
        return Err(at.err("camera.t is the translation of camera.R, which is not set"));
    }
    let (position, look_at) = match (t.position, t.look_at) {
        (Some(p), Some(l)) => (
            at.vec3("camera.position", p)?,
            at.vec3("camera.look_at", l)?,
        ),
        (None, None) => {
            let framed = default_camera(particles, w, h);
            (framed.position, framed.position + framed.forward)
        }
        _ => {
            return Err(at
                .err("camera: set both position and look_at, or neither (to frame the particles)"))
        }
    };
    let up = at.direction("camera.up", t.up.unwrap_or([0.0, 1.0, 0.0]))?;
    let forward = look_at - position;
    if forward.length() == 0.0 {
        return Err(at.err("camera.look_at must differ from camera.position"));
    }
    if forward.normalize().cross(up).length() < 1e-9 {
        return Err(at.err("camera.up must not be parallel to the viewing direction"));
    }
    let camera = match lens {
        Lens::FovY(fov_y) => Camera::new(position, look_at, up, fov_y, w, h),
        Lens::Pinhole(k) => {
            Camera::new(position, look_at, up, DEFAULT_FOV_Y, w, h).with_intrinsics(k)
        }
    };
    Ok((camera, look_at))
}

/// The camera of `R` (the OpenCV world-to-camera rotation, rows) with `position` or `t`
/// (docs/design.md §1 "Intrinsics"); R is used as written, checked by [`check_rotation`].
fn posed(
    at: &At,
    t: &CameraTable,
    rows: [[f64; 3]; 3],
    lens: Lens,
    (w, h): (u32, u32),
) -> Result<Camera> {
    if t.look_at.is_some() || t.up.is_some() {
        return Err(at.err("camera.R sets the viewing direction and up: remove look_at and up"));
    }
    let rotation = DMat3::from_cols_array_2d(&rows).transpose();
    check_rotation(rotation).map_err(|m| at.err(format!("camera.R {m}")))?;
    let position = match (t.position, t.t) {
        (Some(p), None) => at.vec3("camera.position", p)?,
        (None, Some(tv)) => Camera::eye_of(rotation, at.vec3("camera.t", tv)?),
        _ => return Err(at.err("camera.R needs camera.position or camera.t (one of them)")),
    };
    Ok(Camera::from_rotation(position, rotation, lens, w, h))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Scene, SceneLoadOptions};
    use std::path::Path;

    fn load(text: &str) -> Result<Scene> {
        Scene::from_toml_str(
            &format!("[render]\nmodel = \"emission\"\n{text}"),
            Path::new("s.toml"),
            &SceneLoadOptions::default(),
        )
    }

    fn err_text(text: &str) -> String {
        load(text).unwrap_err().to_string()
    }

    #[test]
    fn a_fixed_camera_takes_the_tables_values() {
        let s = load("[camera]\nposition = [0.0, 0.0, -10.0]\nlook_at = [0.0, 0.0, 0.0]\nfocal_length = 2.0\nwidth = 30\nheight = 20\n").unwrap();
        assert_eq!((s.camera.width, s.camera.height), (30, 20));
        assert_eq!(s.camera.position, DVec3::new(0.0, 0.0, -10.0));
        // fov_y = 2·atan(1/f): tan(fov_y/2) = 1/f.
        assert!(
            (s.camera.tan_half_fov - 0.5).abs() < 1e-12,
            "{}",
            s.camera.tan_half_fov
        );
    }

    #[test]
    fn without_a_position_the_camera_frames_the_particles() {
        let particles = "[[particles]]\ncenter = [1.0, 2.0, 3.0]\nradius = 1.0\n";
        let s = load(&format!("[camera]\nwidth = 8\nheight = 8\n{particles}")).unwrap();
        let framed = default_camera(&s.particles, 8, 8);
        assert_eq!(s.camera.position, framed.position);
        let s = load(particles).unwrap();
        assert_eq!((s.camera.width, s.camera.height), DEFAULT_SIZE);
    }

    #[test]
    fn errors_name_the_camera_table_line_and_field() {
        for (table, words) in [
            ("width = 0", "image size"),
            ("fov_y = 180.0", "camera.fov_y must be in (0, 180) degrees"),
            (
                "fov_y = 40.0\nfocal_length = 2.0",
                "set fov_y or focal_length, not both",
            ),
            ("focal_length = 0.0", "camera.focal_length must be > 0"),
            (
                "position = [0.0, 0.0, 1.0]",
                "set both position and look_at, or neither",
            ),
            (
                "position = [1.0, 1.0, 1.0]\nlook_at = [1.0, 1.0, 1.0]",
                "look_at must differ",
            ),
            (
                "position = [0.0, 0.0, 1.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, 2.0]",
                "up must not be parallel",
            ),
            (
                "up = [0.0, 0.0, 0.0]",
                "camera.up must be a non-zero vector",
            ),
            (
                "interpolation = \"linear\"",
                "camera.interpolation applies to [[camera.keyframes]]",
            ),
        ] {
            let e = err_text(&format!("[camera]\n{table}\n"));
            assert!(
                e.starts_with("s.toml:3: ") && e.contains(words),
                "{table}: {e}"
            );
        }
    }

    #[test]
    fn a_size_override_is_checked_against_the_whole_file() {
        let o = SceneLoadOptions {
            size: Some((0, 4)),
            ..SceneLoadOptions::default()
        };
        let e = Scene::from_toml_str("[camera]\nwidth = 8\n", Path::new("s.toml"), &o)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("s.toml: image size"), "{e}");
    }
}
