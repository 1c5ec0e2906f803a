//! `pgt.Scene`: a loaded, validated scene (docs/design.md §1), from a file
//! ([`load_scene`], as `pgt render SCENE` loads it) or from arrays ([`Scene::from_arrays`]),
//! with its particles as `pgt export` writes them and its camera as `pgt camera` prints it.

use crate::arrays::{floats, vec_to_array, Floats, Size};
use crate::errors::{input_error, warn, IntoPy};
use crate::settings;
use numpy::ndarray::{Ix1, Ix2};
use numpy::{PyUntypedArray, PyUntypedArrayMethods};
use pgt::geometry::projection::GraphicsApi;
use pgt::scene::Light;
use pgt::scene::{Model, ParticleInput, RenderMode, SceneLoadOptions};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The name a scene built from arrays has in messages.
const FROM_ARRAYS: &str = "Scene.from_arrays";

/// A scene: particles, lights, camera and render settings, validated and resolved (defaults
/// applied, σ computed). Immutable; build one with `pgt.load_scene` or `Scene.from_arrays`.
#[pyclass(frozen, module = "pgt")]
pub struct Scene {
    pub inner: Arc<pgt::Scene>,
}

/// `mode` and `model` strings as the library's values, with the scene file's messages.
fn parse_mode(py: Python<'_>, s: &str) -> PyResult<RenderMode> {
    use serde::Deserialize;
    let d = serde::de::value::StrDeserializer::<serde::de::value::Error>::new(s);
    RenderMode::deserialize(d).map_err(|e| input_error(py, format!("mode: {e}")))
}

fn parse_model(py: Python<'_>, s: &str) -> PyResult<Model> {
    s.parse::<Model>()
        .map_err(|e| input_error(py, format!("model: {e}")))
}

fn mode_name(m: RenderMode) -> &'static str {
    match m {
        RenderMode::Opaque => "opaque",
        RenderMode::Volume => "volume",
    }
}

/// A `size=(width, height)` argument (any sequence of two integers), checked as `--size` is.
fn parse_size(py: Python<'_>, size: Option<&Bound<'_, PyAny>>) -> PyResult<Option<(u32, u32)>> {
    let Some(size) = size.filter(|s| !s.is_none()) else {
        return Ok(None);
    };
    let bad = || input_error(py, format!("size: expected (width, height), got {size}"));
    let wh: Vec<i64> = size.extract().map_err(|_| bad())?;
    let [w, h] = wh[..] else {
        return Err(bad());
    };
    pgt::scene::check_image_size(w, h)
        .map(Some)
        .map_err(|e| input_error(py, format!("size: {e}")))
}

/// Issues the scene's warnings as `pgt.PgtWarning`s.
pub fn warn_all(py: Python<'_>, scene: &pgt::Scene, stacklevel: i32) -> PyResult<()> {
    for w in &scene.warnings {
        warn(py, w, stacklevel)?;
    }
    Ok(())
}

/// A `format=` argument: the name of a particle format, as `--format` takes it.
fn parse_format(py: Python<'_>, name: &str) -> PyResult<&'static pgt::formats::Format> {
    pgt::formats::Format::named(name).ok_or_else(|| {
        let names: Vec<&str> = pgt::formats::particle_formats().map(|f| f.name).collect();
        input_error(
            py,
            format!(
                "format: unknown format '{name}'; expected one of {}",
                names.join(", ")
            ),
        )
    })
}

/// The overrides of `pgt render`'s `--size`, `--mode`, `--model`, `--tol` and `--format`.
pub fn scene_load_options(
    py: Python<'_>,
    size: Option<&Bound<'_, PyAny>>,
    mode: Option<&str>,
    model: Option<&str>,
    tol: Option<f64>,
    format: Option<&str>,
) -> PyResult<SceneLoadOptions> {
    Ok(SceneLoadOptions {
        size: parse_size(py, size)?,
        mode: mode.map(|m| parse_mode(py, m)).transpose()?,
        model: model.map(|m| parse_model(py, m)).transpose()?,
        tol,
        format: format.map(|f| parse_format(py, f)).transpose()?,
        ..SceneLoadOptions::default()
    })
}

/// Loads a scene file (.toml) or a bare particle file with the overrides of `pgt render`'s
/// `--size`, `--mode`, `--model`, `--tol` and `--format`.
#[pyfunction]
#[pyo3(signature = (path, *, size=None, mode=None, model=None, tol=None, format=None))]
pub fn load_scene(
    py: Python<'_>,
    path: PathBuf,
    size: Option<&Bound<'_, PyAny>>,
    mode: Option<&str>,
    model: Option<&str>,
    tol: Option<f64>,
    format: Option<&str>,
) -> PyResult<Scene> {
    let options = scene_load_options(py, size, mode, model, tol, format)?;
    let scene = py.detach(|| pgt::Scene::load(&path, &options)).py_err(py)?;
    warn_all(py, &scene, 2)?;
    Ok(Scene {
        inner: Arc::new(scene),
    })
}

/// Per-particle values of `Scene.from_arrays`: an array of n values, or one value for all.
enum PerParticle<'py> {
    None,
    All(f64),
    Each(Floats<'py, Ix1>),
}

impl PerParticle<'_> {
    fn get(&self, i: usize) -> Option<f64> {
        match self {
            PerParticle::None => None,
            PerParticle::All(v) => Some(*v),
            PerParticle::Each(a) => Some(a.get(i)),
        }
    }
}

fn per_particle<'py>(
    name: &'static str,
    obj: Option<&Bound<'py, PyAny>>,
    n: usize,
) -> PyResult<PerParticle<'py>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(PerParticle::None);
    };
    let scalar = match obj.cast::<PyUntypedArray>() {
        Ok(a) => a.ndim() == 0,
        Err(_) => obj.extract::<f64>().is_ok(),
    };
    if scalar {
        let v: f64 = obj.extract()?;
        if !v.is_finite() {
            return Err(input_error(
                obj.py(),
                format!("{name}: non-finite value ({v}); NaN and infinity are refused"),
            ));
        }
        return Ok(PerParticle::All(v));
    }
    Ok(PerParticle::Each(floats(name, obj, &[Size::Is(n)])?))
}

/// Adds `value` under `key` to `table` unless it is `None`.
fn put(table: &mut toml::Table, key: &str, value: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
    if let Some(v) = value {
        if let Some(v) = settings::to_toml(v, key)? {
            table.insert(key.to_string(), v);
        }
    }
    Ok(())
}

/// The particles' shape among `from_arrays`' arguments (which were given): radii for
/// spheres or semi-axes for ellipsoids, rotations only with semi-axes.
fn shape_arguments(py: Python<'_>, radii: bool, semi_axes: bool, rotations: bool) -> PyResult<()> {
    match (radii, semi_axes) {
        (true, true) => {
            return Err(input_error(
                py,
                format!("{FROM_ARRAYS}: give radii (spheres) or semi_axes (ellipsoids), not both"),
            ))
        }
        (false, false) => {
            return Err(input_error(
                py,
                format!("{FROM_ARRAYS}: give radii (spheres) or semi_axes (ellipsoids)"),
            ))
        }
        _ => {}
    }
    if rotations && !semi_axes {
        return Err(input_error(
            py,
            format!("{FROM_ARRAYS}: rotations turn ellipsoids; give semi_axes with them"),
        ));
    }
    Ok(())
}

#[pymethods]
impl Scene {
    /// A scene from particle arrays, with the defaults of `pgt render PARTICLES` (a bare
    /// particle file): the camera frames the particles' bounding sphere from -z with
    /// fov_y 40°, the thesis's two directional lights (green from above, blue from below),
    /// black background, volume mode, lit model, 512x512, tol 1e-5.
    ///
    /// Particles (float32 or float64 arrays; lists are converted):
    ///   centers   (n, 3) centres in metres.
    ///   radii     (n,) radii in metres, > 0; None with semi_axes.
    ///   colors    (n, 3) linear RGB >= 0 [white].
    ///   opacity   (n,) or one value: Theta_max in [0, 1], the opacity along a diameter
    ///             (an ellipsoid's shortest one).
    ///   kappa     (n,) or one value: extinction coefficient >= 0 (sigma = lambda*kappa);
    ///             give opacity or kappa, not both [opacity 0.5].
    ///
    /// Ellipsoids (keyword arguments, docs/design.md §9), instead of radii:
    ///   semi_axes (n, 3) semi-axes in metres along the body's x, y, z, > 0.
    ///   rotations (n, 4) orientations as quaternions (w, x, y, z), normalised [none].
    ///
    /// Scene (keyword arguments; the fields of a scene file, docs/design.md §1):
    ///   lights           list of dicts, e.g. pgt.directional_light(direction, irradiance),
    ///                    pgt.point_light(position, intensity); [] for none [the thesis's two].
    ///   camera           dict with position, look_at, up, fov_y or focal_length [framing].
    ///   size             (width, height) in pixels [(512, 512)].
    ///   mode             "volume" or "opaque" ["volume"].
    ///   model            "emission", "lit" or "single-scatter" ["lit"].
    ///   background       linear RGB [(0, 0, 0)].
    ///   tol              absolute radiance tolerance of the reference per pixel and channel
    ///                    [1e-5].
    ///   lambda_          lambda in (0, 1] [1].
    ///   light_weight     "mean" or "sum" (lit model) ["mean"].
    ///   emission_weight  a in [0, 1] (single-scatter) [1].
    ///   ambient          opaque-mode ambient term [0].
    ///   defaults         dict of the scene file's [defaults] (albedo, ks, shininess, ...);
    ///                    {"density": "gaussian"} makes the particles Gaussians whose radii
    ///                    or semi-axes are standard deviations (docs/design.md §9).
    ///
    /// Raises pgt.InputError (a ValueError) naming the argument for arrays of the wrong
    /// shape or dtype, NaN or infinity, and values out of range.
    #[staticmethod]
    #[pyo3(signature = (
        centers, radii, colors=None, opacity=None, kappa=None, *, semi_axes=None,
        rotations=None, lights=None, camera=None, size=None, mode=None, model=None,
        background=None, tol=None, lambda_=None, light_weight=None, emission_weight=None,
        ambient=None, defaults=None
    ))]
    #[allow(clippy::too_many_arguments)]
    fn from_arrays(
        py: Python<'_>,
        centers: &Bound<'_, PyAny>,
        radii: Option<&Bound<'_, PyAny>>,
        colors: Option<&Bound<'_, PyAny>>,
        opacity: Option<&Bound<'_, PyAny>>,
        kappa: Option<&Bound<'_, PyAny>>,
        semi_axes: Option<&Bound<'_, PyAny>>,
        rotations: Option<&Bound<'_, PyAny>>,
        lights: Option<&Bound<'_, PyAny>>,
        camera: Option<&Bound<'_, PyAny>>,
        size: Option<&Bound<'_, PyAny>>,
        mode: Option<&Bound<'_, PyAny>>,
        model: Option<&Bound<'_, PyAny>>,
        background: Option<&Bound<'_, PyAny>>,
        tol: Option<&Bound<'_, PyAny>>,
        lambda_: Option<&Bound<'_, PyAny>>,
        light_weight: Option<&Bound<'_, PyAny>>,
        emission_weight: Option<&Bound<'_, PyAny>>,
        ambient: Option<&Bound<'_, PyAny>>,
        defaults: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Scene> {
        let centers: Floats<Ix2> = floats("centers", centers, &[Size::Any("n"), Size::Is(3)])?;
        let n = centers.shape()[0];
        let (radii, semi_axes, rotations) = (
            radii.filter(|v| !v.is_none()),
            semi_axes.filter(|v| !v.is_none()),
            rotations.filter(|v| !v.is_none()),
        );
        shape_arguments(
            py,
            radii.is_some(),
            semi_axes.is_some(),
            rotations.is_some(),
        )?;
        let radii: Option<Floats<Ix1>> = radii
            .map(|r| floats("radii", r, &[Size::Is(n)]))
            .transpose()
            .map_err(|e| with_n(py, e, n))?;
        let semi_axes: Option<Floats<Ix2>> = semi_axes
            .map(|a| floats("semi_axes", a, &[Size::Is(n), Size::Is(3)]))
            .transpose()
            .map_err(|e| with_n(py, e, n))?;
        let rotations: Option<Floats<Ix2>> = rotations
            .map(|q| floats("rotations", q, &[Size::Is(n), Size::Is(4)]))
            .transpose()
            .map_err(|e| with_n(py, e, n))?;
        let colors: Option<Floats<Ix2>> = colors
            .filter(|c| !c.is_none())
            .map(|c| floats("colors", c, &[Size::Is(n), Size::Is(3)]))
            .transpose()
            .map_err(|e| with_n(py, e, n))?;
        let opacity = per_particle("opacity", opacity, n).map_err(|e| with_n(py, e, n))?;
        let kappa = per_particle("kappa", kappa, n).map_err(|e| with_n(py, e, n))?;
        if !matches!(opacity, PerParticle::None) && !matches!(kappa, PerParticle::None) {
            return Err(input_error(
                py,
                format!("{FROM_ARRAYS}: give opacity or kappa, not both"),
            ));
        }

        let mut file = toml::Table::new();
        let mut render = toml::Table::new();
        put(&mut render, "mode", mode)?;
        put(&mut render, "model", model)?;
        put(&mut render, "background", background)?;
        put(&mut render, "tol", tol)?;
        put(&mut render, "lambda", lambda_)?;
        put(&mut render, "light_weight", light_weight)?;
        put(&mut render, "emission_weight", emission_weight)?;
        put(&mut render, "ambient", ambient)?;
        if !render.is_empty() {
            file.insert("render".into(), toml::Value::Table(render));
        }
        put(&mut file, "camera", camera)?;
        put(&mut file, "lights", lights)?;
        put(&mut file, "defaults", defaults)?;
        let text = settings::text(py, &file, FROM_ARRAYS)?;
        let options = SceneLoadOptions {
            size: parse_size(py, size)?,
            ..SceneLoadOptions::default()
        };
        let default_lights = lights.is_none_or(|l| l.is_none());
        let particles = (0..n).map(|i| ParticleInput {
            center: [
                centers.get((i, 0)),
                centers.get((i, 1)),
                centers.get((i, 2)),
            ],
            radius: radii.as_ref().map_or(0.0, |r| r.get(i)),
            semi_axes: semi_axes
                .as_ref()
                .map(|a| [a.get((i, 0)), a.get((i, 1)), a.get((i, 2))]),
            rotation: rotations
                .as_ref()
                .map(|q| [q.get((i, 0)), q.get((i, 1)), q.get((i, 2)), q.get((i, 3))]),
            color: colors
                .as_ref()
                .map(|c| [c.get((i, 0)), c.get((i, 1)), c.get((i, 2))]),
            opacity: opacity.get(i),
            kappa: kappa.get(i),
        });
        let scene = pgt::Scene::from_settings_and_particles(
            &text,
            Path::new(FROM_ARRAYS),
            &options,
            particles,
            default_lights,
        )
        .map_err(|e| settings::without_location(e, FROM_ARRAYS))
        .py_err(py)?;
        warn_all(py, &scene, 1)?;
        Ok(Scene {
            inner: Arc::new(scene),
        })
    }

    /// A scene of 3D Gaussians from the tensors of 3D Gaussian splatting (means, log scales,
    /// w-x-y-z quaternions, logit opacities, SH coefficients (n, K, 3) or colours (n, 3)),
    /// with the particles a 3DGS PLY of the same values gives (`pgt.load_scene`), bit for bit.
    /// Implemented in Python (`pgt._gaussians.from_gaussians`, whose docstring lists the
    /// arguments) over `Scene.from_arrays`.
    #[staticmethod]
    #[pyo3(signature = (*args, **kwargs))]
    fn from_gaussians<'py>(
        py: Python<'py>,
        args: &Bound<'py, PyTuple>,
        kwargs: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        py.import("pgt._gaussians")?
            .getattr("from_gaussians")?
            .call(args, kwargs)
    }

    /// The resolved particles, as `pgt export` writes them: a dict of float64 arrays
    /// "center" (n, 3), "radius" (n,), "color" (n, 3) linear RGB, "opacity" (n,) Theta_max
    /// along a diameter (an ellipsoid's shortest) and "sigma" (n,) the extinction in 1/m (inf
    /// for opacity 1); where any particle is an ellipsoid also "semi_axes" (n, 3) and
    /// "rotation" (n, 4) quaternions (w, x, y, z) (a sphere: its radius three times and the
    /// identity), and "radius" is each one's longest semi-axis.
    fn particles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let particles = &self.inner.particles;
        let n = particles.len();
        let (mut center, mut radius, mut color, mut opacity, mut sigma) = (
            Vec::with_capacity(3 * n),
            Vec::with_capacity(n),
            Vec::with_capacity(3 * n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        for p in particles {
            let [x, y, z, r, red, green, blue, theta, s] = pgt::scene::export::row(p);
            center.extend([x, y, z]);
            radius.push(r);
            color.extend([red, green, blue]);
            opacity.push(theta);
            sigma.push(s);
        }
        let out = PyDict::new(py);
        out.set_item("center", vec_to_array(py, center, Ix2(n, 3)))?;
        out.set_item("radius", vec_to_array(py, radius, Ix1(n)))?;
        out.set_item("color", vec_to_array(py, color, Ix2(n, 3)))?;
        out.set_item("opacity", vec_to_array(py, opacity, Ix1(n)))?;
        out.set_item("sigma", vec_to_array(py, sigma, Ix1(n)))?;
        if particles.iter().any(|p| p.ellipsoid.is_some()) {
            let (mut axes, mut rotation) = (Vec::with_capacity(3 * n), Vec::with_capacity(4 * n));
            for p in particles {
                let row = pgt::scene::export::ellipsoid_row(p);
                axes.extend_from_slice(&row[3..6]);
                rotation.extend_from_slice(&row[6..10]);
            }
            out.set_item("semi_axes", vec_to_array(py, axes, Ix2(n, 3)))?;
            out.set_item("rotation", vec_to_array(py, rotation, Ix2(n, 4)))?;
        }
        Ok(out)
    }

    /// The camera as a rasterising engine wants it for one graphics API ("opengl", "vulkan",
    /// "webgpu" or "direct3d"), as `pgt camera` prints it: "view" and "projection" are (4, 4)
    /// float64 arrays indexed [row, column], acting on column vectors
    /// (clip = projection @ view @ (x, y, z, 1)); with them the eye, basis, fields of view,
    /// size, near/far planes (from the particles' bounds), depth range and the conventions in
    /// words.
    #[pyo3(signature = (api = "opengl"))]
    fn camera_matrices<'py>(&self, py: Python<'py>, api: &str) -> PyResult<Bound<'py, PyDict>> {
        let Some(chosen) = GraphicsApi::ALL.iter().find(|a| a.key() == api) else {
            let keys: Vec<&str> = GraphicsApi::ALL.iter().map(|a| a.key()).collect();
            return Err(input_error(
                py,
                format!(
                    "api: unknown graphics API '{api}'; expected one of {}",
                    keys.join(", ")
                ),
            ));
        };
        let cam = self.inner.camera_json();
        let projection = &cam.projection[chosen.key()];
        let matrix = |rows: &[[f64; 4]; 4]| {
            vec_to_array(py, rows.iter().flatten().copied().collect(), Ix2(4, 4))
        };
        let vec3 = |v: [f64; 3]| vec_to_array(py, v.to_vec(), Ix1(3));
        let out = PyDict::new(py);
        out.set_item("api", chosen.key())?;
        out.set_item("view", matrix(&cam.view.row_major))?;
        out.set_item("projection", matrix(&projection.matrix.row_major))?;
        out.set_item(
            "depth_range",
            (projection.depth_range[0], projection.depth_range[1]),
        )?;
        out.set_item("convention", &projection.convention)?;
        out.set_item("eye", vec3(cam.eye))?;
        out.set_item("eye_plus_forward", vec3(cam.eye_plus_forward))?;
        out.set_item("forward", vec3(cam.forward))?;
        out.set_item("right", vec3(cam.right))?;
        out.set_item("up", vec3(cam.up))?;
        out.set_item("fov_y_deg", cam.fov_y_deg)?;
        out.set_item("fov_x_deg", cam.fov_x_deg)?;
        out.set_item("tan_half_fov_y", cam.tan_half_fov_y)?;
        out.set_item("width", cam.width)?;
        out.set_item("height", cam.height)?;
        out.set_item("aspect", cam.aspect)?;
        out.set_item("near", cam.near)?;
        out.set_item("far", cam.far)?;
        out.set_item("pixel_convention", &cam.pixel_convention)?;
        out.set_item("matrix_convention", &cam.matrix_convention)?;
        out.set_item("background", vec3(cam.background))?;
        Ok(out)
    }

    /// The file the scene came from; None for a scene from arrays.
    #[getter]
    fn source(&self) -> Option<PathBuf> {
        Some(self.inner.source.clone()).filter(|p| p.as_os_str() != FROM_ARRAYS)
    }

    /// Image width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.inner.camera.width
    }

    /// Image height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.inner.camera.height
    }

    /// "volume" or "opaque".
    #[getter]
    fn mode(&self) -> &'static str {
        mode_name(self.inner.render.mode)
    }

    /// The optical model: "emission", "lit" or "single-scatter".
    #[getter]
    fn model(&self) -> &'static str {
        self.inner.render.model.name()
    }

    /// The reference's absolute radiance tolerance per pixel and channel.
    #[getter]
    fn tol(&self) -> f64 {
        self.inner.render.tol
    }

    /// L_bg, linear RGB.
    #[getter]
    fn background(&self) -> (f64, f64, f64) {
        self.inner.render.background.into()
    }

    /// The lights as dicts in the scene file's terms (directions normalised).
    #[getter]
    fn lights<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let out = PyList::empty(py);
        for light in &self.inner.lights {
            let d = PyDict::new(py);
            match light {
                Light::Directional {
                    direction,
                    irradiance,
                } => {
                    d.set_item("type", "directional")?;
                    d.set_item("direction", <(f64, f64, f64)>::from(*direction))?;
                    d.set_item("irradiance", <(f64, f64, f64)>::from(*irradiance))?;
                }
                Light::Point {
                    position,
                    intensity,
                    falloff,
                } => {
                    d.set_item("type", "point")?;
                    d.set_item("position", <(f64, f64, f64)>::from(*position))?;
                    d.set_item("intensity", <(f64, f64, f64)>::from(*intensity))?;
                    let f = match falloff {
                        pgt::scene::Falloff::InverseSquare => "inverse-square",
                        pgt::scene::Falloff::None => "none",
                    };
                    d.set_item("falloff", f)?;
                }
            }
            out.append(d)?;
        }
        Ok(out)
    }

    /// Non-fatal remarks made while loading (also issued as pgt.PgtWarning).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings.clone()
    }

    /// The number of particles.
    fn __len__(&self) -> usize {
        self.inner.particles.len()
    }

    fn __repr__(&self) -> String {
        let s = &self.inner;
        format!(
            "<pgt.Scene {}: {} particles, {} lights, {}x{}, {} {}>",
            s.source.display(),
            s.particles.len(),
            s.lights.len(),
            s.camera.width,
            s.camera.height,
            mode_name(s.render.mode),
            s.render.model.name()
        )
    }
}

/// A shape error of a per-particle array says what n is.
fn with_n(py: Python<'_>, e: PyErr, n: usize) -> PyErr {
    let text = e.value(py).to_string();
    if text.contains("expected an array of shape") {
        input_error(py, format!("{text} (n = {n}, the rows of centers)"))
    } else {
        e
    }
}
