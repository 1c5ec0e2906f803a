//! A scene over frames (docs/design.md §10): the scene of frame t built from the parts that do
//! not change (render settings, lights, inline particles, includes that show one frame) and
//! those that do (includes whose source plays frames, the camera path).
//!
//! An include **plays** when its source has frames ([`crate::formats::frames::open_frames`]:
//! MMPLD frames, PDB/mmCIF models, XYZ frames, a trajectory, a sequence) and it does not pin
//! one (`frame = k`, `model = m`): an include that names a `trajectory`, `sequence` or `frames`
//! plays whatever their count (one frame is a sequence of one); a file that merely has frames
//! (a multi-model PDB) plays when its selection holds more than one. Every playing include must play the same number of frames: that is the
//! scene's frame count (without a playing include the count is open: only the camera moves).
//! Scene frame i shows source frame `start + i·step` of each playing include.
//!
//! Every frame's particles with SH coefficients (`sh = "view"`) take the colour seen from that
//! frame's camera position ([`super::view_color`]).
//!
//! Frame 0 is [`Scene::load`]'s scene; [`SceneFrames::frame`] reads one frame of each playing
//! include on demand (nothing holds more than the frame being built) and is `&self`, so workers
//! may build different frames at once.

use super::load::{load_bare, load_toml, IncludeGroup, Loaded, ParticleMaker};
use super::view_color::{recolor, ShRun};
use super::{Scene, SceneLoadOptions};
use crate::error::{PgtError, Result};
use crate::formats::frames::{open_frames, uses_frames, FrameInfo, FrameSelection, FrameSource};
use crate::formats::{format_of, IncludeSpec};
use crate::geometry::CameraPath;
use crate::optics::particle::Particle;
use glam::DVec3;
use std::path::Path;

/// An include whose particles change with the frame.
struct Playing {
    source: Box<dyn FrameSource>,
    selection: FrameSelection,
    /// Its particles' range in frame 0's particle list (replaced per frame).
    range: std::ops::Range<usize>,
    /// The file the records' locations point into (a trajectory's topology, else the source).
    record_path: std::path::PathBuf,
    /// The include's `density`.
    density: Option<crate::optics::Profile>,
}

/// A scene file (or bare particle file) as a sequence of frames.
pub struct SceneFrames {
    first: Scene,
    camera_path: CameraPath,
    playing: Vec<Playing>,
    maker: ParticleMaker,
    frame_count: Option<usize>,
    /// The SH coefficients of the includes that do not play (`sh = "view"`): every frame's
    /// particles of these runs take the colour seen from that frame's eye
    /// ([`super::view_color`]).
    still_sh: Vec<ShRun>,
}

impl std::fmt::Debug for SceneFrames {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneFrames")
            .field("source", &self.first.source)
            .field("frame_count", &self.frame_count)
            .field("playing", &self.playing.len())
            .finish()
    }
}

impl SceneFrames {
    /// Loads a scene file or a bare particle file (as [`Scene::load`]) and opens the frame
    /// sources of its playing includes.
    pub fn load(path: &Path, options: &SceneLoadOptions) -> Result<SceneFrames> {
        let is_toml = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
        let loaded = if is_toml {
            let text = std::fs::read_to_string(path).map_err(|e| PgtError::io(path, e))?;
            load_toml(&text, path, options)?
        } else {
            load_bare(path, options)?
        };
        SceneFrames::from_loaded(loaded)
    }

    fn from_loaded(loaded: Loaded) -> Result<SceneFrames> {
        let Loaded {
            scene,
            camera_path,
            includes,
            maker,
        } = loaded;
        let mut playing: Vec<Playing> = Vec::new();
        let mut still_sh = Vec::new();
        for group in &includes {
            let opened = open_playing(&scene, group)?;
            if let (None, Some(sh)) = (&opened, &group.sh) {
                still_sh.push(ShRun {
                    range: group.range.clone(),
                    sh: sh.clone(),
                });
            }
            if let Some(p) = opened {
                if let Some(first) = playing.first() {
                    if first.selection.len() != p.selection.len() {
                        return Err(PgtError::Input {
                            path: scene.source.clone(),
                            location: group.location.clone(),
                            message: format!(
                                "the include of {} plays {} frames, but the include of {} plays {}: every moving include plays the same number of frames (choose them with `frames` and `frame_step`)",
                                p.source.path().display(),
                                p.selection.len(),
                                first.source.path().display(),
                                first.selection.len(),
                            ),
                        });
                    }
                }
                playing.push(p);
            }
        }
        let mut frame_count = playing.first().map(|p| p.selection.len());
        if let Some(n) = camera_path.frame_count() {
            if frame_count.is_some_and(|m| m != n) {
                return Err(PgtError::in_file(
                    &scene.source,
                    format!(
                        "the camera sequence has {n} cameras, but the includes play {} frames: the two must agree",
                        frame_count.unwrap_or_default()
                    ),
                ));
            }
            frame_count = Some(n);
        }
        Ok(SceneFrames {
            first: scene,
            camera_path,
            playing,
            maker,
            frame_count,
            still_sh,
        })
    }

    /// The number of frames: the playing includes' or the camera sequence's; `None` when neither
    /// sets it (any frame count: only the camera moves).
    pub fn frame_count(&self) -> Option<usize> {
        self.frame_count
    }

    /// Frame facts of the scene: its frame count, particles per frame where every playing
    /// source keeps its count, the first playing source's time step.
    pub fn frame_info(&self) -> Option<FrameInfo> {
        let count = self.frame_count?;
        let steps: Vec<FrameInfo> = self.playing.iter().map(|p| p.source.info()).collect();
        let constant = steps.iter().all(|i| i.atoms_per_frame.is_some());
        Some(FrameInfo {
            count,
            atoms_per_frame: constant.then_some(self.first.particles.len()),
            time_step_ps: steps
                .first()
                .and_then(|i| i.time_step_ps)
                .map(|dt| dt * self.playing.first().map_or(1, |p| p.selection.step) as f64),
        })
    }

    /// The camera of every frame.
    pub fn camera_path(&self) -> &CameraPath {
        &self.camera_path
    }

    /// Frame 0, as [`Scene::load`] gives it.
    pub fn first(&self) -> &Scene {
        &self.first
    }

    /// The scene of frame `index`: the static particles of frame 0, each playing include's
    /// particles of its source frame, the camera of the path, and the particles with SH
    /// coefficients coloured for that camera's eye. A frame past the end, or a frame a source
    /// cannot read, is an error naming the file and the frame.
    pub fn frame(&self, index: usize) -> Result<Scene> {
        if let Some(n) = self.frame_count.filter(|&n| index >= n) {
            return Err(PgtError::in_file(
                &self.first.source,
                format!("frame {index} requested, but the scene has {n} frame(s) (0-based)"),
            ));
        }
        let camera = self
            .camera_path
            .camera_at(index)
            .map_err(|m| PgtError::in_file(&self.first.source, format!("camera: {m}")))?;
        if index == 0 {
            return Ok(Scene {
                camera,
                ..self.first.clone()
            });
        }
        let eye = camera.position;
        let follows = self.maker.albedo_follows();
        let mut particles: Vec<Particle> = Vec::with_capacity(self.first.particles.len());
        let mut warnings = Vec::new();
        let mut taken = 0usize;
        for p in &self.playing {
            self.copy_still(&mut particles, taken..p.range.start, eye);
            taken = p.range.end;
            let source_index = p.selection.source_index(index).unwrap_or(p.selection.start);
            let frame = p.source.read_frame(source_index)?;
            let start = particles.len();
            for rec in &frame.particles.records {
                particles.push(self.maker.particle(&p.record_path, rec, p.density)?);
            }
            if let Some(sh) = &frame.particles.sh {
                recolor(&mut particles[start..], sh, eye, follows);
            }
            warnings.extend(frame.particles.warnings);
        }
        self.copy_still(&mut particles, taken..self.first.particles.len(), eye);
        Ok(Scene {
            source: self.first.source.clone(),
            camera,
            render: self.first.render,
            lights: self.first.lights.clone(),
            particles,
            warnings,
            provenance: self.first.provenance.clone(),
        })
    }

    /// Appends frame 0's particles `run` (between playing includes) to `particles`, those with
    /// SH coefficients coloured for `eye`.
    fn copy_still(&self, particles: &mut Vec<Particle>, run: std::ops::Range<usize>, eye: DVec3) {
        let offset = particles.len();
        particles.extend_from_slice(self.first.particles.get(run.clone()).unwrap_or_default());
        for r in &self.still_sh {
            if r.range.start >= run.start && r.range.end <= run.end {
                let at = offset + r.range.start - run.start..offset + r.range.end - run.start;
                recolor(&mut particles[at], &r.sh, eye, self.maker.albedo_follows());
            }
        }
    }
}

/// The playing source of an include, if it plays (see the module doc); errors name the scene's
/// include line.
fn open_playing(scene: &Scene, group: &IncludeGroup) -> Result<Option<Playing>> {
    let spec: &IncludeSpec = &group.spec;
    if spec.frame.is_some() || spec.model.is_some() {
        return Ok(None);
    }
    let has_frames = uses_frames(spec) || format_of(spec).is_ok_and(|f| f.frames.is_some());
    if !has_frames {
        return Ok(None);
    }
    let at = |e: PgtError| match e {
        PgtError::Io { path, source } => PgtError::Input {
            path: scene.source.clone(),
            location: group.location.clone(),
            message: format!("include: cannot read {}: {source}", path.display()),
        },
        e => e,
    };
    let source = open_frames(spec).map_err(at)?;
    let selection = FrameSelection::of(spec, source.as_ref())?;
    let record_path = match &spec.trajectory {
        Some(_) => spec.path.clone(),
        None => source.path().to_path_buf(),
    };
    // A trajectory, sequence or frame selection named in the include plays even when it holds
    // one frame (a sequence of one); a file that merely has frames plays when it has several.
    Ok((selection.len() > 1 || uses_frames(spec)).then(|| Playing {
        source,
        selection,
        range: group.range.clone(),
        record_path,
        density: spec.density,
    }))
}
