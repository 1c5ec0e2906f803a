//! What `render --frames` and `approx --frames` share: opening the scene as frames, choosing the
//! frames, checking the output pattern before any work, and the progress over frames (with the
//! current frames' own progress on a terminal).

use super::output::{check_outputs, Output, OutputKind};
use pgt::approx::dispatch::PassProgress;
use pgt::parts::PartOf;
use pgt::reference::RenderControl;
use pgt::scene::{SceneFrames, SceneLoadOptions};
use pgt::sequence::render::{FrameDone, FrameWatch};
use pgt::sequence::{frames_in, frames_of_part, FrameRange, SequencePattern};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
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

/// How often a progress line is printed off a terminal.
const LINE_EVERY: Duration = Duration::from_secs(10);

/// How often the bar on a terminal reads the frames in flight.
const TICK: Duration = Duration::from_millis(100);

/// The bar counts frames in these units, so that the frames in flight move it between frames.
const UNITS_PER_FRAME: u64 = 1000;

/// How far a frame in flight is.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Share {
    /// The reference: blocks done of the frame's blocks (0 of 0 before it has started).
    Blocks(u64, u64),
    /// A GPU method: passes ended (their number is not known in advance; 0 before the first).
    Passes(u32),
}

/// What the frames in flight are, by frame number.
enum InFlight {
    Reference(Arc<RenderControl>),
    Passes(u32),
}

impl InFlight {
    fn share(&self) -> Share {
        match self {
            InFlight::Reference(c) => {
                let (done, total) = c.progress();
                Share::Blocks(done, total)
            }
            InFlight::Passes(n) => Share::Passes(*n),
        }
    }
}

/// Frames listed by name in the bar's message; more are counted.
const NAMED_IN_FLIGHT: usize = 3;

/// The bar's position (in [`UNITS_PER_FRAME`]ths of a frame) and message: the frames done, plus
/// the share done of each reference frame in flight, each named with its own progress.
fn bar_state(done: usize, total: usize, in_flight: &[(usize, Share)]) -> (u64, String) {
    let mut position = done as u64 * UNITS_PER_FRAME;
    let mut named = Vec::new();
    for (k, &(frame, share)) in in_flight.iter().enumerate() {
        let text = match share {
            Share::Blocks(d, t) if t > 0 => {
                position += d.min(t) * UNITS_PER_FRAME / t;
                format!("frame {frame} {}%", d.min(t) * 100 / t)
            }
            Share::Blocks(..) | Share::Passes(0) => format!("frame {frame} starting"),
            Share::Passes(n) => format!("frame {frame} pass {n}"),
        };
        if k < NAMED_IN_FLIGHT {
            named.push(text);
        }
    }
    if in_flight.len() > NAMED_IN_FLIGHT {
        named.push(format!("{} more", in_flight.len() - NAMED_IN_FLIGHT));
    }
    let mut message = format!("{done}/{total} frames");
    if !named.is_empty() {
        message += &format!(", {}", named.join(", "));
    }
    (position.min(total as u64 * UNITS_PER_FRAME), message)
}

/// What the bar and the lines count.
struct Live {
    done: usize,
    in_flight: BTreeMap<usize, InFlight>,
    last_line: Instant,
    /// The file of the frame that ended last.
    last_path: Option<PathBuf>,
}

/// Progress over frames, watching a sequence render ([`FrameWatch`]): on a terminal a bar over
/// the frames that also moves with the frames in flight (the reference's blocks done of each,
/// a GPU method's passes), redrawn every [`TICK`]; off one, every [`LINE_EVERY`] a line with the
/// same words and the last frame written, also while one long frame renders.
pub struct FrameProgress {
    bar: Option<indicatif::ProgressBar>,
    live: Arc<Mutex<Live>>,
    stop: Arc<AtomicBool>,
    ticker: Mutex<Option<std::thread::JoinHandle<()>>>,
}

impl FrameProgress {
    pub fn new(what: &'static str, total: usize) -> FrameProgress {
        let start = Instant::now();
        let live = Arc::new(Mutex::new(Live {
            done: 0,
            in_flight: BTreeMap::new(),
            last_line: start,
            last_path: None,
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let bar = super::stderr_is_terminal().then(|| {
            let bar = indicatif::ProgressBar::new(total as u64 * UNITS_PER_FRAME);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{elapsed_precise} [{bar:30}] {msg}, eta {eta}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar
        });
        let ticker = {
            let (live, stop, bar) = (Arc::clone(&live), Arc::clone(&stop), bar.clone());
            std::thread::spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    if let Ok(mut l) = live.lock() {
                        let now = Instant::now();
                        // Off a terminal the words are made only when a line is due.
                        if bar.is_some() || now >= l.last_line + LINE_EVERY {
                            let shares: Vec<(usize, Share)> =
                                l.in_flight.iter().map(|(f, s)| (*f, s.share())).collect();
                            let (position, message) = bar_state(l.done, total, &shares);
                            if let Some(bar) = &bar {
                                bar.set_position(position);
                                bar.set_message(message);
                            } else {
                                l.last_line = now;
                                let last = l.last_path.as_ref().map_or(String::new(), |p| {
                                    format!(", the last {}", p.display())
                                });
                                eprintln!(
                                    "{what}: {:.0} s, {message}{last}",
                                    (now - start).as_secs_f64()
                                );
                            }
                        }
                    }
                    std::thread::sleep(TICK);
                }
            })
        };
        FrameProgress {
            bar,
            live,
            stop,
            ticker: Mutex::new(Some(ticker)),
        }
    }

    pub fn finish(&self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.ticker.lock().ok().and_then(|mut t| t.take()) {
            let _ = t.join();
        }
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

impl Drop for FrameProgress {
    /// The ticker stops with the progress, also where an error skipped [`FrameProgress::finish`].
    fn drop(&mut self) {
        self.finish();
    }
}

impl FrameWatch for FrameProgress {
    fn started(&self, frame: usize, control: Option<&Arc<RenderControl>>) {
        if let Ok(mut l) = self.live.lock() {
            let what = control.map_or(InFlight::Passes(0), |c| InFlight::Reference(Arc::clone(c)));
            l.in_flight.insert(frame, what);
        }
    }

    fn pass(&self, frame: usize, progress: PassProgress) {
        if let Ok(mut l) = self.live.lock() {
            l.in_flight.insert(frame, InFlight::Passes(progress.passes));
        }
    }

    /// One more frame ended.
    fn done(&self, d: &FrameDone) {
        let Ok(mut l) = self.live.lock() else {
            return;
        };
        l.in_flight.remove(&d.frame());
        l.done += 1;
        let path = match d {
            FrameDone::Rendered { path, .. } | FrameDone::Skipped { path, .. } => path,
        };
        l.last_path = Some(path.clone());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bar_moves_with_the_frames_in_flight() {
        assert_eq!(bar_state(0, 4, &[]), (0, "0/4 frames".to_string()));
        // Two frames done, frame 2 a quarter through its blocks, frame 3 not started.
        let (position, message) = bar_state(
            2,
            4,
            &[(2, Share::Blocks(16, 64)), (3, Share::Blocks(0, 0))],
        );
        assert_eq!(position, 2 * UNITS_PER_FRAME + UNITS_PER_FRAME / 4);
        assert_eq!(message, "2/4 frames, frame 2 25%, frame 3 starting");
        // A GPU frame counts its passes and does not move the bar.
        let (position, message) = bar_state(1, 3, &[(1, Share::Passes(7))]);
        assert_eq!(position, UNITS_PER_FRAME);
        assert_eq!(message, "1/3 frames, frame 1 pass 7");
        let (_, message) = bar_state(1, 3, &[(1, Share::Passes(0))]);
        assert_eq!(message, "1/3 frames, frame 1 starting");
        // Many frames side by side: three named, the rest counted; the bar never passes the end.
        let many: Vec<(usize, Share)> = (0..5).map(|f| (f, Share::Blocks(9, 9))).collect();
        let (position, message) = bar_state(0, 5, &many);
        assert_eq!(position, 5 * UNITS_PER_FRAME);
        assert!(message.ends_with("frame 2 100%, 2 more"), "{message}");
    }

    #[test]
    fn the_watch_counts_frames_and_forgets_those_that_ended() {
        let p = FrameProgress::new("render", 2);
        let control = Arc::new(RenderControl::default());
        p.started(0, Some(&control));
        p.started(1, None);
        p.pass(
            1,
            PassProgress {
                passes: 3,
                items_done: 0,
                redone: false,
            },
        );
        let frames = |p: &FrameProgress| {
            let l = p.live.lock().unwrap();
            (l.done, l.in_flight.keys().copied().collect::<Vec<_>>())
        };
        assert_eq!(frames(&p), (0, vec![0, 1]));
        p.done(&FrameDone::Skipped {
            frame: 0,
            path: "f_0.exr".into(),
        });
        assert_eq!(frames(&p), (1, vec![1]));
        p.finish();
    }
}
