//! What `render --frames` and `approx --frames` share: opening the scene as frames, choosing the
//! frames, checking the output pattern before any work, and the progress over frames.

use super::output::{check_outputs, Output, OutputKind};
use crate::parts::PartOf;
use crate::scene::{SceneFrames, SceneLoadOptions};
use crate::sequence::render::FrameDone;
use crate::sequence::{frames_in, frames_of_part, FrameRange, SequencePattern};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Loads the scene's frames, the frames to render (the range, or this task's part of it) and
/// the output pattern, checked as an output before any work.
pub fn open_sequence(
    scene: &Path,
    options: &SceneLoadOptions,
    exposure: f32,
    range: FrameRange,
    part: Option<PartOf>,
    output: &Path,
) -> anyhow::Result<(SceneFrames, Vec<usize>, SequencePattern)> {
    let pattern_problem = |e: String| {
        anyhow::anyhow!(
            "--output {}: with --frames the output names each frame's file with %d or %0Nd, e.g. out/frame_%04d.exr ({e})",
            output.display()
        )
    };
    let pattern = SequencePattern::parse(output).map_err(|e| pattern_problem(e.to_string()))?;
    let first = pattern.path_for(range.start).map_err(pattern_problem)?;
    check_outputs(&[Output::new("--output", &first, OutputKind::Image)])?;
    if !exposure.is_finite() {
        anyhow::bail!("--exposure must be a finite number");
    }
    let frames = SceneFrames::load(scene, options)?;
    for w in &frames.first().warnings {
        eprintln!("warning: {w}");
    }
    let mut list = frames_in(range, scene, frames.frame_count())?;
    if let Some(part) = part {
        let all = list.len();
        list = frames_of_part(&list, part);
        if list.is_empty() {
            eprintln!("part {part} of {all} frame(s) holds no frame: nothing to do");
        }
    }
    Ok((frames, list, pattern))
}

/// The scene of frame `frame` of a scene file (`--frame K` of `pgt camera` and `pgt export`), or
/// the scene as `pgt render` loads it without one; a frame past the end is an error naming the
/// scene and its frame count.
pub fn scene_at_frame(
    scene: &Path,
    options: &SceneLoadOptions,
    frame: Option<usize>,
) -> anyhow::Result<crate::scene::Scene> {
    match frame {
        None => Ok(crate::scene::Scene::load(scene, options)?),
        Some(k) => Ok(SceneFrames::load(scene, options)?.frame(k)?),
    }
}

/// How often a progress line is printed off a terminal.
const LINE_EVERY: Duration = Duration::from_secs(10);

/// Progress over frames: a bar on a terminal; off one, a line at most every ten seconds.
pub struct FrameProgress {
    bar: Option<indicatif::ProgressBar>,
    what: &'static str,
    total: usize,
    state: Mutex<(usize, Instant, PathBuf)>,
    start: Instant,
}

impl FrameProgress {
    pub fn new(what: &'static str, total: usize) -> FrameProgress {
        let bar = super::stderr_is_terminal().then(|| {
            let bar = indicatif::ProgressBar::new(total as u64);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{elapsed_precise} [{bar:30}] {pos}/{len} frames, eta {eta} {msg}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar
        });
        let start = Instant::now();
        FrameProgress {
            bar,
            what,
            total,
            state: Mutex::new((0, start, PathBuf::new())),
            start,
        }
    }

    /// One more frame ended.
    pub fn done(&self, d: &FrameDone) {
        let path = match d {
            FrameDone::Rendered { path, .. } | FrameDone::Skipped { path, .. } => path.clone(),
        };
        if let Some(bar) = &self.bar {
            bar.inc(1);
            bar.set_message(format!("(frame {} done)", d.frame()));
            return;
        }
        let Ok(mut s) = self.state.lock() else {
            return;
        };
        s.0 += 1;
        s.2 = path;
        let now = Instant::now();
        if now >= s.1 + LINE_EVERY {
            s.1 = now;
            eprintln!(
                "{}: {:.0} s, {}/{} frames done, the last {}",
                self.what,
                (now - self.start).as_secs_f64(),
                s.0,
                self.total,
                s.2.display()
            );
        }
    }

    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
