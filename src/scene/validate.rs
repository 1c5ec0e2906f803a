//! Scene validation: the raw TOML tables become a [`Scene`], or an error that names the file,
//! the line and the field (docs/design.md §6 "Bad input").

use super::file::{
    CameraTable, KeyframeTable, LightKind, LightTable, OrbitTable, ParticleDefaults, ParticleTable,
    RenderTable, SceneFile,
};
use super::framing::{default_camera, thesis_lights, DEFAULT_FOV_Y, DEFAULT_SIZE};
use super::{IncludeSpec, ParticleInput, ParticleRecord, RenderSettings, Scene, SceneLoadOptions};
use crate::error::{line_of, toml_error, At, Location, PgtError, Result, SourceText};
use crate::formats::EllipsoidRecord;
use crate::geometry::{Camera, CameraPath, Ellipsoid, Keyframe};
use crate::optics::extinction::Extinction;
use crate::optics::light::{Falloff, Light};
use crate::optics::particle::{Particle, Profile};
use glam::DVec3;
use std::path::Path;
use toml::Spanned;

/// A validated scene file with what a sequence of frames needs besides frame 0: the camera of
/// every frame, where each include's particles sit in `scene.particles`, and the defaults that
/// turn a file's records into particles.
pub(super) struct Loaded {
    /// Frame 0.
    pub scene: Scene,
    pub camera_path: CameraPath,
    /// The particles of each include, in order, as ranges of `scene.particles` (the inline
    /// particles come first, before every include).
    pub includes: Vec<IncludeGroup>,
    pub maker: ParticleMaker,
}

/// An include and where its frame-0 particles are.
pub(super) struct IncludeGroup {
    /// The include, its paths joined to the scene file's folder.
    pub spec: IncludeSpec,
    /// The scene file's line of the include (the whole file for a bare particle file).
    pub location: Location,
    pub range: std::ops::Range<usize>,
}

/// Turns a format's records into particles with the scene's `[defaults]` and λ.
pub(super) struct ParticleMaker {
    defaults: ResolvedDefaults,
    lambda: f64,
}

impl ParticleMaker {
    /// A particle of the file `path`, checked with the location the format recorded.
    pub fn particle(
        &self,
        path: &Path,
        rec: &ParticleRecord,
        density: Option<Profile>,
    ) -> Result<Particle> {
        record_particle(path, rec, &self.defaults, self.lambda, density)
    }
}

pub(super) fn scene_from_toml(
    text: &str,
    path: &Path,
    options: &SceneLoadOptions,
) -> Result<Scene> {
    load_toml(text, path, options).map(|l| l.scene)
}

/// An `[[include]]`'s keys that say where its files are, checked and joined to the scene file's
/// folder `base` (docs/design.md §10: `path`, `trajectory`, `sequence`, `frame`, `frames`,
/// `frame_step`).
fn resolve_include(at: &At, base: &Path, mut spec: IncludeSpec) -> Result<IncludeSpec> {
    at.in_range(
        "include.radius_scale",
        spec.radius_scale,
        f64::MIN_POSITIVE,
        f64::MAX,
        "> 0",
    )?;
    if let Some(k) = spec.extent {
        at.in_range("include.extent", k, f64::MIN_POSITIVE, f64::MAX, "> 0")?;
    }
    let has_path = !spec.path.as_os_str().is_empty();
    match (has_path, spec.sequence.is_some(), spec.trajectory.is_some()) {
        (false, false, _) => {
            return Err(at.err(
                "include: set `path` (a particle file, or a trajectory's topology) or `sequence` (numbered files)",
            ))
        }
        (true, true, _) => {
            return Err(at.err("include: set `path` or `sequence`, not both"))
        }
        (false, true, true) => {
            return Err(at.err(
                "include.trajectory needs `path` (its topology: PDB, mmCIF, GRO or PSF), not `sequence`",
            ))
        }
        _ => {}
    }
    if spec.frame.is_some() && spec.frames.is_some() {
        return Err(at.err(
            "include: set `frame` (one frame in every scene frame) or `frames` (the frames to play), not both",
        ));
    }
    if spec.model.is_some() && spec.frames.is_some() {
        return Err(at.err(
            "include: set `model` (one model in every scene frame) or `frames` (the models to play), not both",
        ));
    }
    if spec.frame_step == Some(0) {
        return Err(at.err("include.frame_step must be ≥ 1, got 0"));
    }
    if has_path {
        spec.path = base.join(&spec.path);
    }
    spec.trajectory = spec.trajectory.map(|t| base.join(t));
    spec.sequence = spec.sequence.map(|q| base.join(q));
    Ok(spec)
}

/// Validates scene TOML into frame 0 and what the other frames need ([`Loaded`]).
pub(super) fn load_toml(text: &str, path: &Path, options: &SceneLoadOptions) -> Result<Loaded> {
    load_toml_and_particles(text, path, options, std::iter::empty(), false)
}

/// [`scene_from_toml`] plus `given` particles, each checked as an inline `[[particles]]` table
/// (and numbered after them in messages); with `default_lights`, settings without `[[lights]]`
/// get the thesis's two lights, as a bare particle file does.
pub(super) fn scene_from_toml_and_particles(
    text: &str,
    path: &Path,
    options: &SceneLoadOptions,
    given: impl Iterator<Item = ParticleInput>,
    default_lights: bool,
) -> Result<Scene> {
    load_toml_and_particles(text, path, options, given, default_lights).map(|l| l.scene)
}

/// [`load_toml`] with the particles and lights of [`scene_from_toml_and_particles`].
fn load_toml_and_particles(
    text: &str,
    path: &Path,
    options: &SceneLoadOptions,
    given: impl Iterator<Item = ParticleInput>,
    default_lights: bool,
) -> Result<Loaded> {
    let file: SceneFile = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
    let source = SourceText { path, text };
    let at = |span: std::ops::Range<usize>| source.at(span);
    let whole = source.whole();

    let render = match &file.render {
        Some(r) => render_settings(&at(r.span()), r.get_ref())?,
        None => RenderSettings::default(),
    };
    let render = apply_overrides(render, options, &whole)?;

    let defaults_at = file
        .defaults
        .as_ref()
        .map_or(whole.clone(), |d| source.at(d.span()));
    let empty = ParticleDefaults::default();
    let defaults = file.defaults.as_ref().map_or(&empty, |d| d.get_ref());
    let resolved_defaults = ResolvedDefaults::new(&defaults_at, defaults, render.lambda)?;

    let mut particles = inline_particles(
        &file.particles,
        &at,
        &whole,
        given,
        &resolved_defaults,
        render.lambda,
    )?;
    let mut warnings = Vec::new();
    let base = path.parent().unwrap_or(Path::new("."));
    let mut includes = Vec::with_capacity(file.include.len());
    for inc in &file.include {
        let spec_at = at(inc.span());
        let written = inc.get_ref().path.clone();
        let mut spec = resolve_include(&spec_at, base, inc.get_ref().clone())?;
        if spec.sh == Some(crate::formats::ShColor::View) {
            spec.view_from = Some(view_position(&spec_at, &file.camera)?);
        }
        // The readers see the density the particles get (a splatting file's semi-axes are its
        // standard deviations for Gaussians).
        spec.density = Some(spec.density.unwrap_or(resolved_defaults.density));
        // A file that cannot be read is named with the scene's include line (a typo in the
        // path is the usual cause); errors inside a file that was read name that file's line.
        // Errors of a frame source (a trajectory, a sequence, a `frames` range) also name the
        // include's line, since the keys that chose the frames are there.
        let loaded = crate::formats::load_particles(&spec).map_err(|e| match e {
            PgtError::Io { path, source } => {
                unreadable_include(&spec_at, base, &written, &path, &source)
            }
            e if crate::formats::frames::uses_frames(&spec) => e.context(format!(
                "{}:{}: [[include]]",
                path.display(),
                line_of(text, inc.span().start)
            )),
            e => e,
        })?;
        warnings.extend(loaded.warnings);
        let start = particles.len();
        for rec in &loaded.records {
            particles.push(record_particle(
                &spec.path,
                rec,
                &resolved_defaults,
                render.lambda,
                spec.density,
            )?);
        }
        includes.push(IncludeGroup {
            spec,
            location: spec_at.location.clone(),
            range: start..particles.len(),
        });
    }

    let lights = file
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| light(&at(l.span()), i, l.get_ref()))
        .collect::<Result<Vec<_>>>()?;
    let lights = if lights.is_empty() && default_lights {
        thesis_lights()
    } else {
        lights
    };

    let camera_path = camera(&file.camera, &at, &whole, options, &particles)?;
    let camera = first_camera(&camera_path, &file.camera, &at, &whole)?;
    if particles.is_empty() {
        warnings.push(format!(
            "{}: the scene has no particles; it renders the background",
            path.display()
        ));
    }
    Ok(Loaded {
        scene: Scene {
            source: path.to_path_buf(),
            camera,
            render,
            lights,
            particles,
            warnings,
        },
        camera_path,
        includes,
        maker: ParticleMaker {
            defaults: resolved_defaults,
            lambda: render.lambda,
        },
    })
}

/// The camera position an include with `sh = "view"` evaluates its colours for: the `[camera]`
/// table's `position`, which a fixed camera must set (a framed camera is placed after the
/// particles are read, an orbit or keyframes move it).
fn view_position(at: &At, table: &Option<Spanned<CameraTable>>) -> Result<DVec3> {
    let t = table.as_ref().map(|t| t.get_ref());
    match t {
        Some(t) if t.orbit.is_none() && t.keyframes.is_empty() && t.position.is_some() => {
            at.vec3("camera.position", t.position.unwrap_or_default())
        }
        _ => Err(at.err(
            "include.sh = \"view\" evaluates the colours for the camera's position: set [camera] position (and look_at) for a fixed camera; a framed, orbiting or keyframed camera has no one position when the file is read",
        )),
    }
}

/// The camera of frame 0, with a degenerate one named at the camera table's line.
fn first_camera<'a>(
    path: &CameraPath,
    table: &Option<Spanned<CameraTable>>,
    at: &dyn Fn(std::ops::Range<usize>) -> At<'a>,
    whole: &At<'a>,
) -> Result<Camera> {
    path.camera_at(0).map_err(|m| {
        let camera_at = table.as_ref().map_or_else(
            || At {
                path: whole.path,
                location: whole.location.clone(),
            },
            |t| at(t.span()),
        );
        camera_at.err(format!("camera: {m}"))
    })
}

/// An include that cannot be read: named with the scene's include line, the file, the cause,
/// and, for a relative path, the folder it was taken relative to (the scene file's `base`,
/// not the working directory: the usual surprise).
fn unreadable_include(
    at: &At,
    base: &Path,
    written: &Path,
    path: &Path,
    source: &std::io::Error,
) -> PgtError {
    let relative = if written.is_absolute() {
        String::new()
    } else {
        let folder = if base.as_os_str().is_empty() {
            "the current folder, where the scene file is".to_string()
        } else {
            format!("{}, the scene file's folder", base.display())
        };
        format!(
            " (the path `{}` is taken relative to {folder})",
            written.display()
        )
    };
    at.err(format!(
        "include: cannot read {}: {source}{relative}",
        path.display()
    ))
}

/// The scene file's `[[particles]]` tables, then the `given` particles checked as tables of
/// the same kind (numbered after them, named with the whole file: no line wrote them).
fn inline_particles<'a>(
    tables: &[Spanned<ParticleTable>],
    at: &dyn Fn(std::ops::Range<usize>) -> At<'a>,
    whole: &At<'a>,
    given: impl Iterator<Item = ParticleInput>,
    defaults: &ResolvedDefaults,
    lambda: f64,
) -> Result<Vec<Particle>> {
    let mut particles = Vec::with_capacity(tables.len());
    for (i, p) in tables.iter().enumerate() {
        particles.push(inline_particle(
            &at(p.span()),
            i,
            p.get_ref(),
            defaults,
            lambda,
        )?);
    }
    for (k, p) in given.enumerate() {
        let i = tables.len() + k;
        particles.push(inline_particle(
            whole,
            i,
            &given_table(p),
            defaults,
            lambda,
        )?);
    }
    Ok(particles)
}

/// A particle given by a program as the inline table it stands for.
fn given_table(p: ParticleInput) -> ParticleTable {
    ParticleTable {
        center: p.center,
        radius: p.semi_axes.is_none().then_some(p.radius),
        semi_axes: p.semi_axes,
        rotation: p.rotation,
        color: p.color,
        opacity: p.opacity,
        kappa: p.kappa,
        albedo: None,
        ks: None,
        shininess: None,
        density: None,
    }
}

/// A bare particle file with the default scene of docs/design.md §1.
pub(super) fn bare_particle_file(path: &Path, options: &SceneLoadOptions) -> Result<Scene> {
    load_bare(path, options).map(|l| l.scene)
}

/// [`bare_particle_file`] with what a sequence of frames needs ([`Loaded`]).
pub(super) fn load_bare(path: &Path, options: &SceneLoadOptions) -> Result<Loaded> {
    let whole = At::whole(path);
    let render = apply_overrides(RenderSettings::default(), options, &whole)?;
    let defaults = ResolvedDefaults::new(&whole, &ParticleDefaults::default(), render.lambda)?;
    let spec = IncludeSpec {
        format: options.format,
        ..IncludeSpec::bare(path)
    };
    let loaded = crate::formats::load_particles(&spec)?;
    let particles = loaded
        .records
        .iter()
        .map(|rec| record_particle(path, rec, &defaults, render.lambda, None))
        .collect::<Result<Vec<_>>>()?;
    let mut warnings = loaded.warnings;
    if particles.is_empty() {
        warnings.push(format!(
            "{}: the file has no particles; it renders the background",
            path.display()
        ));
    }
    let (w, h) = options.size.unwrap_or(DEFAULT_SIZE);
    check_size(&whole, w as i64, h as i64)?;
    let camera = default_camera(&particles, w, h);
    let range = 0..particles.len();
    Ok(Loaded {
        scene: Scene {
            source: path.to_path_buf(),
            camera,
            render,
            lights: thesis_lights(),
            particles,
            warnings,
        },
        camera_path: CameraPath::Fixed(camera),
        includes: vec![IncludeGroup {
            spec: IncludeSpec::bare(path),
            location: Location::File,
            range,
        }],
        maker: ParticleMaker {
            defaults,
            lambda: render.lambda,
        },
    })
}

fn render_settings(at: &At, t: &RenderTable) -> Result<RenderSettings> {
    let d = RenderSettings::default();
    Ok(RenderSettings {
        mode: t.mode.unwrap_or(d.mode),
        model: t.model.unwrap_or(d.model),
        background: t.background.map_or(Ok(d.background), |v| {
            at.non_negative3("render.background", v)
        })?,
        lambda: t.lambda.map_or(Ok(d.lambda), |v| {
            let v = at.finite("render.lambda", v)?;
            if v > 0.0 && v <= 1.0 {
                Ok(v)
            } else {
                Err(at.err(format!("render.lambda must be in (0, 1], got {v}")))
            }
        })?,
        light_weight: t.light_weight.unwrap_or(d.light_weight),
        emission_weight: t.emission_weight.map_or(Ok(d.emission_weight), |v| {
            at.in_range("render.emission_weight", v, 0.0, 1.0, "in [0, 1]")
        })?,
        ambient: t.ambient.map_or(Ok(d.ambient), |v| {
            at.in_range("render.ambient", v, 0.0, f64::MAX, "≥ 0")
        })?,
        tol: t.tol.map_or(Ok(d.tol), |v| check_tol(at, v))?,
        gaussian_cutoff: t
            .gaussian_cutoff
            .map(|k| at.in_range("render.gaussian_cutoff", k, 0.5, 40.0, "in [0.5, 40]"))
            .transpose()?,
    })
}

fn check_tol(at: &At, v: f64) -> Result<f64> {
    let v = at.finite("render.tol", v)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(at.err(format!("render.tol must be > 0, got {v}")))
    }
}

fn apply_overrides(
    mut r: RenderSettings,
    o: &SceneLoadOptions,
    whole: &At,
) -> Result<RenderSettings> {
    if let Some(m) = o.mode {
        r.mode = m;
    }
    if let Some(m) = o.model {
        r.model = m;
    }
    if let Some(t) = o.tol {
        r.tol = checked_tol_override(t)?;
    }
    let _ = whole;
    Ok(r)
}

/// A tolerance given on the command line (`--tol`), or to the Python package's `render`.
pub fn checked_tol_override(t: f64) -> Result<f64> {
    if !(t.is_finite() && t > 0.0) {
        return Err(PgtError::Usage(format!(
            "--tol must be a finite number > 0, got {t}"
        )));
    }
    Ok(t)
}

/// `[defaults]` with each field checked once.
struct ResolvedDefaults {
    color: DVec3,
    /// σ source for particles that set neither opacity nor kappa.
    opacity: Option<f64>,
    kappa: Option<f64>,
    albedo: Option<DVec3>,
    ks: f64,
    shininess: f64,
    density: Profile,
}

/// Θmax used when neither the particle nor `[defaults]` sets opacity or kappa.
const DEFAULT_OPACITY: f64 = 0.5;
const DEFAULT_SHININESS: f64 = 32.0;

impl ResolvedDefaults {
    fn new(at: &At, d: &ParticleDefaults, _lambda: f64) -> Result<Self> {
        if d.opacity.is_some() && d.kappa.is_some() {
            return Err(at.err("defaults: set opacity or kappa, not both"));
        }
        Ok(ResolvedDefaults {
            color: d
                .color
                .map_or(Ok(DVec3::ONE), |c| at.non_negative3("defaults.color", c))?,
            opacity: d
                .opacity
                .map(|o| at.in_range("defaults.opacity", o, 0.0, 1.0, "in [0, 1]"))
                .transpose()?,
            kappa: d
                .kappa
                .map(|k| at.in_range("defaults.kappa", k, 0.0, f64::MAX, "≥ 0"))
                .transpose()?,
            albedo: d
                .albedo
                .map(|a| at.non_negative3("defaults.albedo", a))
                .transpose()?,
            ks: d.ks.map_or(Ok(0.0), |v| {
                at.in_range("defaults.ks", v, 0.0, f64::MAX, "≥ 0")
            })?,
            shininess: d.shininess.map_or(Ok(DEFAULT_SHININESS), |v| {
                at.in_range("defaults.shininess", v, 0.0, f64::MAX, "≥ 0")
            })?,
            density: d.density.unwrap_or_default(),
        })
    }

    /// σ from the particle's own opacity/kappa, else the defaults, else Θmax =
    /// [`DEFAULT_OPACITY`] (docs/design.md §1); the equation itself is [`Extinction::sigma`],
    /// for a Gaussian [`Extinction::peak_sigma`] (docs/design.md §9). `radius` is the shortest
    /// semi-axis (the shortest standard deviation of a Gaussian).
    fn sigma(
        &self,
        opacity: Option<f64>,
        kappa: Option<f64>,
        radius: f64,
        lambda: f64,
        profile: Profile,
    ) -> f64 {
        let extinction = match (opacity, kappa) {
            (Some(o), _) => Extinction::Opacity(o),
            (None, Some(k)) => Extinction::Kappa(k),
            (None, None) => match (self.opacity, self.kappa) {
                (_, Some(k)) => Extinction::Kappa(k),
                (Some(o), None) => Extinction::Opacity(o),
                (None, None) => Extinction::Opacity(DEFAULT_OPACITY),
            },
        };
        match profile {
            Profile::Constant => extinction.sigma(radius, lambda),
            Profile::Gaussian => extinction.peak_sigma(radius, lambda),
        }
    }
}

fn inline_particle(
    at: &At,
    i: usize,
    p: &ParticleTable,
    d: &ResolvedDefaults,
    lambda: f64,
) -> Result<Particle> {
    let name = |f: &str| format!("particles[{i}].{f}");
    let center = at.vec3(&name("center"), p.center)?;
    let (radius, ellipsoid) = match (p.radius, p.semi_axes) {
        (Some(radius), None) => {
            if p.rotation.is_some() {
                return Err(at.err(format!(
                    "{} turns an ellipsoid: give semi_axes = [a, b, c] instead of radius",
                    name("rotation")
                )));
            }
            let radius = at.finite(&name("radius"), radius)?;
            if radius <= 0.0 {
                return Err(at.err(format!("{} must be > 0, got {radius}", name("radius"))));
            }
            (radius, None)
        }
        (None, Some(semi_axes)) => {
            let record = EllipsoidRecord {
                semi_axes: DVec3::from(semi_axes),
                rotation: p.rotation.unwrap_or([1.0, 0.0, 0.0, 0.0]),
            };
            let axes = [0, 1, 2].map(|k| name(&format!("semi_axes[{k}]")));
            if let Some(problem) =
                record.problem(axes.each_ref().map(|s| s.as_str()), &name("rotation"))
            {
                return Err(at.err(problem));
            }
            resolve_ellipsoid(&record)
        }
        (Some(_), Some(_)) => {
            return Err(at.err(format!(
                "particles[{i}]: give radius (a sphere) or semi_axes (an ellipsoid), not both"
            )))
        }
        (None, None) => {
            return Err(at.err(format!(
                "particles[{i}]: give radius = r (a sphere) or semi_axes = [a, b, c] (an ellipsoid)"
            )))
        }
    };
    // Θmax is the opacity along the shortest diameter (docs/design.md §9).
    let sigma_radius = ellipsoid.map_or(radius, |e| e.shortest_semi_axis());
    if p.opacity.is_some() && p.kappa.is_some() {
        return Err(at.err(format!("particles[{i}]: set opacity or kappa, not both")));
    }
    let opacity = p
        .opacity
        .map(|o| at.in_range(&name("opacity"), o, 0.0, 1.0, "in [0, 1]"))
        .transpose()?;
    let kappa = p
        .kappa
        .map(|k| at.in_range(&name("kappa"), k, 0.0, f64::MAX, "≥ 0"))
        .transpose()?;
    let color = p
        .color
        .map_or(Ok(d.color), |c| at.non_negative3(&name("color"), c))?;
    let profile = p.density.unwrap_or(d.density);
    check_gaussian_opacity(at, &name("opacity"), profile, opacity.or(d.opacity))?;
    Ok(Particle {
        center,
        radius,
        color,
        sigma: d.sigma(opacity, kappa, sigma_radius, lambda, profile),
        albedo: p.albedo.map_or(Ok(d.albedo.unwrap_or(color)), |a| {
            at.non_negative3(&name("albedo"), a)
        })?,
        ks: p.ks.map_or(Ok(d.ks), |v| {
            at.in_range(&name("ks"), v, 0.0, f64::MAX, "≥ 0")
        })?,
        shininess: p.shininess.map_or(Ok(d.shininess), |v| {
            at.in_range(&name("shininess"), v, 0.0, f64::MAX, "≥ 0")
        })?,
        ellipsoid,
        profile,
    })
}

/// A particle from a file format, checked with the location the format recorded.
fn record_particle(
    path: &Path,
    rec: &ParticleRecord,
    d: &ResolvedDefaults,
    lambda: f64,
    density: Option<Profile>,
) -> Result<Particle> {
    let at = At {
        path,
        location: rec.location.clone(),
    };
    let center = at.vec3("particle position", rec.center.to_array())?;
    let (radius, ellipsoid) = match &rec.ellipsoid {
        Some(e) => {
            if let Some(problem) = e.problem(["sx", "sy", "sz"], "the rotation qw, qx, qy, qz") {
                return Err(at.err(format!("the particle's {problem}")));
            }
            resolve_ellipsoid(e)
        }
        None => (at.finite("particle radius", rec.radius)?, None),
    };
    if radius <= 0.0 {
        return Err(at.err(format!("particle radius must be > 0, got {radius}")));
    }
    // Θmax is the opacity along the shortest diameter (docs/design.md §9).
    let sigma_radius = ellipsoid.map_or(radius, |e| e.shortest_semi_axis());
    let color = rec.color.map_or(Ok(d.color), |c| {
        at.non_negative3("particle colour", c.to_array())
    })?;
    let opacity = rec
        .opacity
        .map(|o| at.in_range("particle opacity", o, 0.0, 1.0, "in [0, 1]"))
        .transpose()?;
    let profile = density.unwrap_or(d.density);
    if rec.sigma.is_none() {
        check_gaussian_opacity(&at, "particle opacity", profile, opacity.or(d.opacity))?;
    }
    Ok(Particle {
        center,
        radius,
        color,
        // A σ the file gives is the particle's σ exactly (crate::formats::xyz_csv, "σ and opacity").
        sigma: rec
            .sigma
            .unwrap_or_else(|| d.sigma(opacity, None, sigma_radius, lambda, profile)),
        albedo: d.albedo.unwrap_or(color),
        ks: d.ks,
        shininess: d.shininess,
        ellipsoid,
        profile,
    })
}

/// A Gaussian's opacity must be < 1: Θmax = 1 would be an infinite peak density, which has no
/// meaning for a density without an edge (docs/design.md §9).
fn check_gaussian_opacity(
    at: &At,
    field: &str,
    profile: Profile,
    opacity: Option<f64>,
) -> Result<()> {
    match (profile, opacity) {
        (Profile::Gaussian, Some(o)) if o >= 1.0 => Err(at.err(format!(
            "{field} is {o}: a Gaussian particle's opacity must be < 1 (1 would be an infinite peak density)"
        ))),
        _ => Ok(()),
    }
}

/// The shape an ellipsoid record describes, checked by [`EllipsoidRecord::problem`] first: the
/// radius of the particle (the longest semi-axis) and its ellipsoid with the quaternion
/// normalised, or no ellipsoid where the three semi-axes are equal (docs/design.md §9: that is
/// the sphere, bit for bit, whatever the rotation).
fn resolve_ellipsoid(e: &EllipsoidRecord) -> (f64, Option<Ellipsoid>) {
    let s = e.semi_axes;
    if s.x == s.y && s.y == s.z {
        return (s.x, None);
    }
    let [w, x, y, z] = e.rotation;
    // Scaled first, so that a quaternion of huge or tiny components normalises without
    // overflow or underflow.
    let q = glam::DVec4::new(x, y, z, w);
    let q = q / q.abs().max_element();
    let ellipsoid = Ellipsoid::new(s, glam::DQuat::from_vec4(q.normalize()));
    (ellipsoid.bounding_radius(), Some(ellipsoid))
}

fn light(at: &At, i: usize, l: &LightTable) -> Result<Light> {
    let field = |f: &str| format!("lights[{i}].{f}");
    let required = |f: &str, v: Option<[f64; 3]>| {
        v.ok_or_else(|| {
            at.err(format!("{} is required for a {:?} light", field(f), l.kind).to_lowercase())
        })
    };
    let forbidden = |f: &str, present: bool| {
        if present {
            Err(at
                .err(format!("{} does not apply to a {:?} light", field(f), l.kind).to_lowercase()))
        } else {
            Ok(())
        }
    };
    match l.kind {
        LightKind::Directional => {
            forbidden("position", l.position.is_some())?;
            forbidden("intensity", l.intensity.is_some())?;
            forbidden("falloff", l.falloff.is_some())?;
            Ok(Light::Directional {
                direction: at
                    .direction(&field("direction"), required("direction", l.direction)?)?,
                irradiance: at
                    .non_negative3(&field("irradiance"), required("irradiance", l.irradiance)?)?,
            })
        }
        LightKind::Point => {
            forbidden("direction", l.direction.is_some())?;
            forbidden("irradiance", l.irradiance.is_some())?;
            Ok(Light::Point {
                position: at.vec3(&field("position"), required("position", l.position)?)?,
                intensity: at
                    .non_negative3(&field("intensity"), required("intensity", l.intensity)?)?,
                falloff: l.falloff.unwrap_or(Falloff::InverseSquare),
            })
        }
    }
}

fn check_size(at: &At, w: i64, h: i64) -> Result<(u32, u32)> {
    super::check_image_size(w, h).map_err(|e| at.err(e))
}

/// The camera of every frame (docs/design.md §1, §10): the `[camera]` table's fixed camera, an
/// orbit (`[camera.orbit]`) that starts from it, or `[[camera.keyframes]]`.
fn camera<'a>(
    table: &Option<Spanned<CameraTable>>,
    at: &dyn Fn(std::ops::Range<usize>) -> At<'a>,
    whole: &At<'a>,
    options: &SceneLoadOptions,
    particles: &[Particle],
) -> Result<CameraPath> {
    let Some(table) = table else {
        let (w, h) = options.size.unwrap_or(DEFAULT_SIZE);
        check_size(whole, w as i64, h as i64)?;
        return Ok(CameraPath::Fixed(default_camera(particles, w, h)));
    };
    let t = table.get_ref();
    let table_at = at(table.span());
    let (w, h) = match options.size {
        Some((w, h)) => check_size(whole, w as i64, h as i64)?,
        None => check_size(
            &table_at,
            t.width.unwrap_or(DEFAULT_SIZE.0 as i64),
            t.height.unwrap_or(DEFAULT_SIZE.1 as i64),
        )?,
    };
    let fov_y = camera_fov(&table_at, t)?;
    if t.interpolation.is_some() && t.keyframes.is_empty() {
        return Err(table_at
            .err("camera.interpolation applies to [[camera.keyframes]], and there are none"));
    }
    if !t.keyframes.is_empty() {
        if t.orbit.is_some() {
            return Err(
                table_at.err("camera: set [camera.orbit] or [[camera.keyframes]], not both")
            );
        }
        if let Some(key) = [
            ("position", t.position.is_some()),
            ("look_at", t.look_at.is_some()),
        ]
        .iter()
        .find(|(_, set)| *set)
        {
            return Err(table_at.err(format!(
                "camera.{}: the keyframes set the camera's position and look_at; remove one or the other",
                key.0
            )));
        }
        return keyframe_path(&table_at, at, t, fov_y, (w, h));
    }
    let (camera, look_at) = fixed_camera(&table_at, t, particles, fov_y, (w, h))?;
    match &t.orbit {
        None => Ok(CameraPath::Fixed(camera)),
        Some(orbit) => {
            let start = Keyframe {
                frame: 0,
                position: camera.position,
                look_at,
                up: table_at.direction("camera.up", t.up.unwrap_or([0.0, 1.0, 0.0]))?,
                fov_y,
            };
            orbit_path(&at(orbit.span()), orbit.get_ref(), start, (w, h), particles)
        }
    }
}

/// `camera.fov_y` or `camera.focal_length` (degrees), [`DEFAULT_FOV_Y`] by default.
fn camera_fov(at: &At, t: &CameraTable) -> Result<f64> {
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

/// The `[camera]` table's own camera (framing the particles where position and look_at are
/// absent).
fn fixed_camera(
    at: &At,
    t: &CameraTable,
    particles: &[Particle],
    fov_y: f64,
    (w, h): (u32, u32),
) -> Result<(Camera, DVec3)> {
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
    Ok((Camera::new(position, look_at, up, fov_y, w, h), look_at))
}

/// `[camera.orbit]`: the fixed camera turned about `axis` through `center` (the particles'
/// centre at frame 0 by default), `degrees_per_frame` per frame.
fn orbit_path(
    at: &At,
    orbit: &OrbitTable,
    start: Keyframe,
    (width, height): (u32, u32),
    particles: &[Particle],
) -> Result<CameraPath> {
    let axis = at.direction("camera.orbit.axis", orbit.axis)?;
    let degrees_per_frame = at.finite("camera.orbit.degrees_per_frame", orbit.degrees_per_frame)?;
    let center = match orbit.center {
        Some(c) => at.vec3("camera.orbit.center", c)?,
        None => super::framing::bounding_sphere(particles).0,
    };
    Ok(CameraPath::Orbit {
        start,
        center,
        axis,
        degrees_per_frame,
        width,
        height,
    })
}

/// `[[camera.keyframes]]`: at least two, frames ≥ 0 and strictly increasing; `up` and `fov_y`
/// default to the `[camera]` table's. Each keyframe's camera is checked (an error names its
/// line and key).
fn keyframe_path<'a>(
    table_at: &At<'a>,
    at: &dyn Fn(std::ops::Range<usize>) -> At<'a>,
    t: &CameraTable,
    fov_y: f64,
    (width, height): (u32, u32),
) -> Result<CameraPath> {
    if t.keyframes.len() < 2 {
        return Err(table_at.err(format!(
            "camera.keyframes: a keyframe path needs at least two keyframes, got {}",
            t.keyframes.len()
        )));
    }
    let default_up = t.up.unwrap_or([0.0, 1.0, 0.0]);
    let mut keys: Vec<Keyframe> = Vec::with_capacity(t.keyframes.len());
    for (i, k) in t.keyframes.iter().enumerate() {
        let k_at = at(k.span());
        let key = keyframe(&k_at, i, k.get_ref(), default_up, fov_y)?;
        if let Some(prev) = keys.last() {
            if key.frame <= prev.frame {
                return Err(k_at.err(format!(
                    "camera.keyframes[{i}].frame = {} must be greater than the previous keyframe's frame {} (keyframes in order)",
                    key.frame, prev.frame
                )));
            }
        }
        let single = CameraPath::Keyframes {
            keys: vec![
                key,
                Keyframe {
                    frame: key.frame + 1,
                    ..key
                },
            ],
            interpolation: Default::default(),
            width,
            height,
        };
        single
            .camera_at(key.frame as usize)
            .map_err(|m| k_at.err(format!("camera.keyframes[{i}]: {m}")))?;
        keys.push(key);
    }
    Ok(CameraPath::Keyframes {
        keys,
        interpolation: t.interpolation.unwrap_or_default(),
        width,
        height,
    })
}

/// One keyframe's values, checked.
fn keyframe(
    at: &At,
    i: usize,
    k: &KeyframeTable,
    default_up: [f64; 3],
    fov_y: f64,
) -> Result<Keyframe> {
    let name = |f: &str| format!("camera.keyframes[{i}].{f}");
    let frame = u64::try_from(k.frame)
        .map_err(|_| at.err(format!("{} must be ≥ 0, got {}", name("frame"), k.frame)))?;
    let fov = match k.fov_y {
        Some(f) => at.in_range(
            &name("fov_y"),
            f,
            f64::MIN_POSITIVE,
            179.999_999,
            "in (0, 180) degrees",
        )?,
        None => fov_y,
    };
    Ok(Keyframe {
        frame,
        position: at.vec3(&name("position"), k.position)?,
        look_at: at.vec3(&name("look_at"), k.look_at)?,
        up: at.direction(&name("up"), k.up.unwrap_or(default_up))?,
        fov_y: fov,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(text: &str) -> Result<Scene> {
        Scene::from_toml_str(text, Path::new("s.toml"), &SceneLoadOptions::default())
    }

    fn err_text(text: &str) -> String {
        load(text).unwrap_err().to_string()
    }

    #[test]
    fn full_design_example_parses() {
        let text = r#"
[camera]
position = [0.0, 0.0, -10.0]
look_at  = [0.0, 0.0, 0.0]
up       = [0.0, 1.0, 0.0]
fov_y    = 40.0
width    = 64
height   = 32

[render]
mode  = "volume"
model = "lit"
background = [0.0, 0.0, 0.0]
lambda = 1.0
light_weight = "mean"
emission_weight = 0.0
ambient = 0.0
tol = 1e-5

[[lights]]
type = "directional"
direction  = [0.0, -1.0, 0.0]
irradiance = [0.0, 1.0, 0.0]

[[lights]]
type = "point"
position  = [0.0, 5.0, 0.0]
intensity = [10.0, 10.0, 10.0]
falloff   = "inverse-square"

[defaults]
color = [1.0, 1.0, 1.0]
opacity = 0.5
ks = 0.0
shininess = 32.0

[[particles]]
center = [0.0, 0.0, 0.0]
radius = 1.0
color  = [1.0, 0.2, 0.2]
opacity = 0.8
"#;
        let s = load(text).unwrap();
        assert_eq!((s.camera.width, s.camera.height), (64, 32));
        assert_eq!(s.lights.len(), 2);
        let p = s.particles[0];
        assert!((p.sigma - (-(0.2f64).ln() / 2.0)).abs() < 1e-15);
        assert_eq!(p.albedo, p.color);
    }

    #[test]
    fn kappa_is_scaled_by_lambda_but_opacity_is_not() {
        let s = load(
            "[render]\nlambda = 0.5\n[[particles]]\ncenter=[0,0,0]\nradius=2.0\nkappa=3.0\n[[particles]]\ncenter=[5,0,0]\nradius=2.0\nopacity=0.5\n",
        )
        .unwrap();
        assert_eq!(s.particles[0].sigma, 1.5);
        assert!((s.particles[1].sigma - 2f64.ln() / 4.0).abs() < 1e-15);
    }

    #[test]
    fn errors_name_the_line_and_field() {
        let e = err_text("[[particles]]\ncenter=[0,0,0]\nradius=1.0\n\n[[particles]]\ncenter=[0,0,0]\nradius=-1.0\n");
        assert!(e.starts_with("s.toml:5:"), "{e}");
        assert!(e.contains("particles[1].radius must be > 0"), "{e}");
        let e = err_text("[render]\nmodle = \"lit\"\n");
        assert!(e.starts_with("s.toml:2:") && e.contains("modle"), "{e}");
        let e = err_text("[render]\nmodel = \"glow\"\n");
        assert!(e.starts_with("s.toml:2:") && e.contains("glow"), "{e}");
        assert!(e.contains("`emission`, `lit`, `single-scatter`"), "{e}");
        let e =
            err_text("[[lights]]\ntype=\"directional\"\ndirection=[0,0,0]\nirradiance=[1,1,1]\n");
        assert!(
            e.contains("lights[0].direction must be a non-zero vector"),
            "{e}"
        );
        let e = err_text("[camera]\nwidth = 0\n");
        assert!(e.contains("image size"), "{e}");
        let e = err_text("[[particles]]\ncenter=[0,0,0]\nradius=1.0\nopacity=1.5\n");
        assert!(e.contains("opacity must be in [0, 1]"), "{e}");
        let e = err_text("[[particles]]\ncenter=[0,nan,0]\nradius=1.0\n");
        assert!(e.contains("finite"), "{e}");
    }

    #[test]
    fn empty_scene_is_valid_with_a_warning() {
        let s = load("").unwrap();
        assert!(s.particles.is_empty());
        assert_eq!(s.warnings.len(), 1);
    }

    #[test]
    fn overrides_win() {
        let o = SceneLoadOptions {
            size: Some((7, 3)),
            mode: Some(super::super::RenderMode::Opaque),
            model: None,
            tol: Some(1e-3),
            format: None,
        };
        let s = Scene::from_toml_str("[camera]\nwidth=100\nheight=100\n", Path::new("s.toml"), &o)
            .unwrap();
        assert_eq!((s.camera.width, s.camera.height), (7, 3));
        assert_eq!(s.render.mode, super::super::RenderMode::Opaque);
        assert_eq!(s.render.tol, 1e-3);
    }
}
