//! Every frame of a sequence (docs/design.md §10): the exact reference (`pgt render --frames`)
//! and a GPU method (`pgt approx --frames`), one file per frame.
//!
//! Each frame is an independent render of [`SceneFrames::frame`]: its pixels are the bits that
//! `pgt render` gives for that frame alone. An EXR frame carries its render hash (the hash of
//! the cluster parts, [`crate::parts::render_hash`]) and its frame number in its header; a frame
//! whose file exists with the same hash is skipped, so an interrupted sequence resumes where it
//! stopped and a changed scene or option renders again. PNG frames carry no header and are always
//! rendered. Every file is written atomically, so a frame that fails leaves the frames written
//! before it whole.
//!
//! The reference renders small frames side by side (one worker each) and large frames one after
//! the other with all workers on the frame's pixels ([`frames_side_by_side`]); either way one
//! frame's scene is held per worker, never the whole sequence. The GPU reference (`--gpu`,
//! [`Device::Gpu`]) renders the frames one after the other; its frames' hash names the GPU
//! ([`crate::parts::render_hash_on`]), so a CPU frame is never taken for a GPU one.
//!
//! A [`FrameWatch`] follows the work: each frame as it starts (with the [`RenderControl`] that
//! counts its blocks, or its GPU passes) and as it ends; the CLI draws its progress from it.

use super::{exr_text_attributes, SequencePattern};
use crate::approx::dispatch::PassProgress;
use crate::approx::{ApproxParams, ApproxPipeline, GpuContext, Method};
use crate::error::{PgtError, Result};
use crate::image_io::{write_exr_with_header, write_image, ImageFormat, RgbImage};
use crate::reference::{self, Device, RenderControl, RenderOptions, RenderStats};
use crate::scene::{Scene, SceneFrames};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// The header attribute that holds a frame's render hash (the parts' attribute).
pub use crate::parts::RENDER_HASH_ATTRIBUTE as HASH_ATTRIBUTE;
/// The header attribute that holds a frame's number.
pub const FRAME_ATTRIBUTE: &str = "pgtFrame";

/// Pixel blocks per worker below which frames render side by side: a frame of fewer blocks
/// keeps a pool of workers busy only in part, and its tail (the last, slowest blocks) idles them.
const BLOCKS_PER_WORKER: u64 = 8;

/// The side of the reference's square block of pixels, its unit of parallel work.
const BLOCK: u64 = 16;

/// What became of one frame.
#[derive(Debug, Clone, PartialEq)]
pub enum FrameDone {
    /// Rendered and written.
    Rendered {
        frame: usize,
        path: PathBuf,
        /// The reference's figures (`None` for a GPU method).
        stats: Option<RenderStats>,
        seconds: f64,
    },
    /// Its file already held this render (same hash).
    Skipped { frame: usize, path: PathBuf },
}

impl FrameDone {
    pub fn frame(&self) -> usize {
        match self {
            FrameDone::Rendered { frame, .. } | FrameDone::Skipped { frame, .. } => *frame,
        }
    }
}

/// What a sequence render tells its caller as it goes (the CLI's progress). Calls come from any
/// worker, several frames at a time where frames render side by side.
pub trait FrameWatch: Sync {
    /// Frame `frame` starts: the CPU reference's with the `control` that counts its blocks until
    /// it ends, a GPU method's (its passes follow) or the GPU reference's with none.
    fn started(&self, _frame: usize, _control: Option<&Arc<RenderControl>>) {}
    /// A GPU method ended a pass of frame `frame`.
    fn pass(&self, _frame: usize, _progress: PassProgress) {}
    /// Frame `d.frame()` ended: rendered and written, or skipped.
    fn done(&self, d: &FrameDone);
}

/// A closure watches the ends of frames only.
impl<F: Fn(&FrameDone) + Sync> FrameWatch for F {
    fn done(&self, d: &FrameDone) {
        self(d)
    }
}

/// What a sequence render did, frame by frame in frame order.
#[derive(Debug, Clone, Default)]
pub struct SequenceSummary {
    pub frames: Vec<FrameDone>,
}

impl SequenceSummary {
    /// Frames rendered and frames skipped.
    pub fn counts(&self) -> (usize, usize) {
        let rendered = self
            .frames
            .iter()
            .filter(|f| matches!(f, FrameDone::Rendered { .. }))
            .count();
        (rendered, self.frames.len() - rendered)
    }

    /// The reference's figures summed over the rendered frames (counts and seconds; no error
    /// estimates).
    pub fn totals(&self) -> RenderStats {
        let mut t = RenderStats {
            pixels: 0,
            primary_rays: 0,
            shadow_rays: 0,
            seconds: 0.0,
            max_error: None,
            mean_error: None,
            unconverged: 0,
            worst_unconverged: None,
        };
        for f in &self.frames {
            if let FrameDone::Rendered { stats: Some(s), .. } = f {
                t.pixels += s.pixels;
                t.primary_rays += s.primary_rays;
                t.shadow_rays += s.shadow_rays;
                t.seconds += s.seconds;
                t.unconverged += s.unconverged;
            }
        }
        t
    }

    /// The frame with the most unconverged pixels: (frame, its count), if any has one.
    pub fn worst_unconverged(&self) -> Option<(usize, u64)> {
        self.frames
            .iter()
            .filter_map(|f| match f {
                FrameDone::Rendered {
                    frame,
                    stats: Some(s),
                    ..
                } if s.unconverged > 0 => Some((*frame, s.unconverged)),
                _ => None,
            })
            .max_by_key(|&(f, n)| (n, std::cmp::Reverse(f)))
    }
}

/// Whether the frames of `scene`'s size render side by side on `workers` workers (see the module
/// docs) rather than one after the other.
pub fn frames_side_by_side(scene: &Scene, workers: usize) -> bool {
    let blocks =
        (scene.camera.width as u64).div_ceil(BLOCK) * (scene.camera.height as u64).div_ceil(BLOCK);
    blocks < BLOCKS_PER_WORKER * workers as u64
}

/// Whether `path` already holds the render with `hash` (an EXR whose header says so).
fn already_rendered(path: &Path, hash: &str) -> bool {
    ImageFormat::from_path(path).is_ok_and(|f| f == ImageFormat::Exr)
        && exr_text_attributes(path)
            .is_some_and(|a| a.get(HASH_ATTRIBUTE).is_some_and(|h| h == hash))
}

/// Writes one frame: an EXR with its hash and number in the header, or a PNG.
pub fn write_frame(
    path: &Path,
    frame: usize,
    hash: &str,
    image: &RgbImage,
    error: Option<&RgbImage>,
    exposure: f32,
) -> Result<()> {
    let layers: Vec<(&str, &RgbImage)> = error.iter().map(|e| ("err", *e)).collect();
    match ImageFormat::from_path(path)? {
        ImageFormat::Exr => write_exr_with_header(
            path,
            image,
            &layers,
            &[
                (FRAME_ATTRIBUTE, frame.to_string()),
                (HASH_ATTRIBUTE, hash.to_string()),
            ],
        ),
        ImageFormat::Png => write_image(path, image, &layers, exposure),
    }
}

/// The file of frame `frame` (the pattern was checked to name files to write).
fn output_path(pattern: &SequencePattern, frame: usize) -> Result<PathBuf> {
    pattern.path_for(frame).map_err(PgtError::Usage)
}

/// Names the frame in an error that does not already.
fn in_frame(frame: usize) -> impl Fn(PgtError) -> PgtError {
    move |e| e.context(format!("frame {frame}"))
}

/// Renders the reference of each frame of `list` on `device` into `pattern`'s files, telling
/// `watch` as each frame starts and ends (from any worker). Frames start in the order of `list`;
/// the first error, by frame order, ends the sequence: frames not yet started are not started,
/// frames written stay. On the GPU the frames render one after the other, each with the whole
/// device, and a scene the GPU reference cannot render is refused before the first frame.
pub fn render_frames(
    frames: &SceneFrames,
    list: &[usize],
    pattern: &SequencePattern,
    options: &RenderOptions,
    device: Device,
    exposure: f32,
    watch: &dyn FrameWatch,
) -> Result<SequenceSummary> {
    let workers = options
        .threads
        .unwrap_or_else(rayon::current_num_threads)
        .max(1);
    if let Device::Gpu(_) = device {
        reference::gpu::check_supported(frames.first(), options)?;
    }
    let side_by_side =
        matches!(device, Device::Cpu) && frames_side_by_side(frames.first(), workers);
    let failed = AtomicBool::new(false);
    let one = |frame: usize| -> Option<Result<FrameDone>> {
        if failed.load(Ordering::Relaxed) {
            return None;
        }
        let result = render_one(
            frames,
            frame,
            pattern,
            options,
            (device, side_by_side),
            exposure,
            watch,
        );
        match &result {
            Ok(d) => watch.done(d),
            Err(_) => failed.store(true, Ordering::Relaxed),
        }
        Some(result)
    };
    let results: Vec<Option<Result<FrameDone>>> = if side_by_side {
        // Workers take the frames in order, so that when a frame fails every frame before it
        // has been started (and is written unless it fails too).
        let next = AtomicUsize::new(0);
        let slots: Vec<Mutex<Option<Result<FrameDone>>>> =
            list.iter().map(|_| Mutex::new(None)).collect();
        std::thread::scope(|scope| {
            for _ in 0..workers.min(list.len()) {
                scope.spawn(|| loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&frame) = list.get(k) else { break };
                    let Some(r) = one(frame) else { break };
                    if let Ok(mut slot) = slots[k].lock() {
                        *slot = Some(r);
                    }
                });
            }
        });
        slots
            .into_iter()
            .map(|m| m.into_inner().unwrap_or_else(|p| p.into_inner()))
            .collect()
    } else {
        list.iter().map(|&f| one(f)).collect()
    };
    let mut summary = SequenceSummary::default();
    for r in results.into_iter().flatten() {
        summary.frames.push(r?);
    }
    Ok(summary)
}

/// One frame on `device`; `side_by_side`: with other frames, on one worker.
fn render_one(
    frames: &SceneFrames,
    frame: usize,
    pattern: &SequencePattern,
    options: &RenderOptions,
    (device, side_by_side): (Device, bool),
    exposure: f32,
    watch: &dyn FrameWatch,
) -> Result<FrameDone> {
    // The frame sources' errors name the frame already.
    let scene = frames.frame(frame)?;
    let path = output_path(pattern, frame)?;
    let hash = crate::parts::render_hash_on(&scene, options, device);
    if already_rendered(&path, &hash) {
        return Ok(FrameDone::Skipped { frame, path });
    }
    let frame_options = RenderOptions {
        threads: if side_by_side {
            Some(1)
        } else {
            options.threads
        },
        progress: false,
        ..*options
    };
    let out = match device {
        Device::Cpu => {
            let control = Arc::new(RenderControl::default());
            watch.started(frame, Some(&control));
            reference::render_controlled(&scene, &frame_options, &control)
        }
        Device::Gpu(ctx) => {
            watch.started(frame, None);
            reference::gpu::render_on(ctx, &scene, &frame_options)
        }
    }
    .map_err(in_frame(frame))?;
    write_frame(
        &path,
        frame,
        &hash,
        &out.image,
        out.error.as_ref(),
        exposure,
    )
    .map_err(in_frame(frame))?;
    Ok(FrameDone::Rendered {
        frame,
        path,
        seconds: out.stats.seconds,
        stats: Some(out.stats),
    })
}

/// What a GPU method's sequence adds to [`SequenceSummary`]: the method, the adapter, and the
/// pixels a method flagged (summed over the frames).
#[derive(Debug, Clone)]
pub struct ApproxSequence {
    pub summary: SequenceSummary,
    pub method: Method,
    pub params: Vec<(String, u32)>,
    pub adapter_name: String,
    pub hit_overflow_pixels: u64,
    pub loop_limited_pixels: u64,
}

/// The hash of a GPU method's render of a scene: the scene (as [`crate::parts::render_hash`]),
/// the method, its parameter values and the adapter (another device may compute other bits).
pub fn approx_hash(
    scene: &Scene,
    method: &Method,
    values: &[(String, u32)],
    adapter: &str,
) -> String {
    crate::parts::hash_with(
        scene,
        &format!("approx {} | {values:?} | adapter {adapter}", method.name()),
    )
}

/// Renders each frame of `list` with a GPU method, one after the other on one device and one
/// compiled pipeline, telling `watch` after each pass and each frame.
pub fn approx_frames(
    frames: &SceneFrames,
    list: &[usize],
    pattern: &SequencePattern,
    params: &ApproxParams,
    exposure: f32,
    watch: &dyn FrameWatch,
) -> Result<ApproxSequence> {
    let method = params
        .method
        .clone()
        .unwrap_or_else(|| Method::default_for(frames.first()));
    method.check_scene(frames.first())?;
    let values = params.resolve(&method)?;
    let ctx = GpuContext::new(params.adapter.as_deref())?;
    let pipeline = ApproxPipeline::new(&ctx, &method, params)?;
    let mut out = ApproxSequence {
        summary: SequenceSummary::default(),
        method: method.clone(),
        params: values.clone(),
        adapter_name: ctx.adapter.name.clone(),
        hit_overflow_pixels: 0,
        loop_limited_pixels: 0,
    };
    for &frame in list {
        let scene = frames.frame(frame)?;
        let path = output_path(pattern, frame)?;
        let hash = approx_hash(&scene, &method, &values, &ctx.adapter.name);
        let d = if already_rendered(&path, &hash) {
            FrameDone::Skipped { frame, path }
        } else {
            watch.started(frame, None);
            let r = pipeline
                .render_with_progress(&ctx, &scene, params, &mut |p| watch.pass(frame, p))
                .map_err(in_frame(frame))?;
            out.hit_overflow_pixels += r.hit_overflow_pixels as u64;
            out.loop_limited_pixels += r.loop_limited_pixels as u64;
            write_frame(&path, frame, &hash, &r.image, None, exposure).map_err(in_frame(frame))?;
            FrameDone::Rendered {
                frame,
                path,
                stats: None,
                seconds: r.gpu_seconds,
            }
        };
        watch.done(&d);
        out.summary.frames.push(d);
    }
    Ok(out)
}
