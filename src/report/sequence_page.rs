//! The report of a sequence comparison (docs/design.md §10): every frame's reference,
//! approximation and temporal-error map as PNGs in `frames/`, plots of each metric over the
//! frames (SVG) with the worst frames listed as links, and one page. The page reads without
//! JavaScript (a table of every frame with its images); with it, a player shows the three
//! images of one frame side by side and steps, plays, or jumps to a frame from the slider, the
//! table or a worst-frame link. A pixel probe under the player shows, for the frame shown, the
//! linear R, G, B of the reference, the approximation and e_t at the pixel hovered or clicked in
//! any pane; its values are per-frame files that the player loads when it shows a frame
//! ([`super::sequence_probe`] says how they are encoded and why).
//!
//! The temporal-error maps share one scale, 0 … 2 × the pop threshold (magma), so that frames
//! compare at a glance and a pop is in the upper half of the colour bar.

use super::colorbar::colorbar_svg;
use super::colormap::{ColorMap, Scale};
use super::heatmap::heatmap;
use super::html::page;
use super::plot::{line_plot_svg, PlotSpec, Series};
use super::sequence_probe::write_probe_frame;
use super::summary::short;
use super::text::escape;
use crate::error::Result;
use crate::image_io::write_image;
use crate::metrics::gate::GateCheck;
use crate::metrics::maps;
use crate::sequence::compare::{FrameFigures, FrameView, SequenceComparison};
use std::fmt::Write as _;
use std::path::Path;

/// The folder of the per-frame images, inside the report.
pub const FRAMES_DIR: &str = "frames";

/// Worst frames listed under each plot.
const WORST_LISTED: usize = 5;

fn frame_file(kind: &str, frame: usize) -> String {
    format!("{FRAMES_DIR}/{kind}_{frame:06}.png")
}

/// The scale of every temporal-error map of a sequence with this pop threshold.
pub fn temporal_scale(pop_threshold: f64) -> Scale {
    Scale {
        lo: 0.0,
        hi: (2.0 * pop_threshold).max(f64::MIN_POSITIVE),
    }
}

/// Writes one frame's images into the report folder `dir`.
pub fn write_frame_images(dir: &Path, view: &FrameView, pop_threshold: f64) -> Result<()> {
    let frames = dir.join(FRAMES_DIR);
    super::text::create_folder(&frames)?;
    let exposure = -(view.comparison.data_range.max(f64::MIN_POSITIVE)).log2() as f32;
    let f = view.figures.frame;
    write_image(&dir.join(frame_file("r", f)), view.reference, &[], exposure)?;
    write_image(
        &dir.join(frame_file("a", f)),
        view.approximation,
        &[],
        exposure,
    )?;
    if let Some(t) = view.temporal {
        let mean = maps::channel_mean(&t.map);
        heatmap(
            &mean,
            t.map.width,
            t.map.height,
            temporal_scale(pop_threshold),
            ColorMap::Magma,
        )
        .write_png(&dir.join(frame_file("t", f)))?;
    }
    write_probe_frame(
        dir,
        FRAMES_DIR,
        f,
        view.reference,
        view.approximation,
        view.temporal.map(|t| &t.map),
    )?;
    Ok(())
}

/// One metric over the frames: its name, file stem, the value of a frame, and whether larger
/// is worse.
struct Metric {
    title: &'static str,
    stem: &'static str,
    value: fn(&FrameFigures) -> Option<f64>,
    larger_is_worse: bool,
}

const METRICS: [Metric; 5] = [
    Metric {
        title: "SSIM (mean over R, G, B)",
        stem: "ssim",
        value: |f| f.ssim,
        larger_is_worse: false,
    },
    Metric {
        title: "RMSE (mean over R, G, B)",
        stem: "rmse",
        value: |f| Some(f.rmse),
        larger_is_worse: true,
    },
    Metric {
        title: "FLIP (mean)",
        stem: "flip",
        value: |f| f.flip,
        larger_is_worse: true,
    },
    Metric {
        title: "Temporal error, 99th percentile (mean over R, G, B)",
        stem: "temporal_p99",
        value: |f| f.temporal.as_ref().map(|t| t.p99.mean),
        larger_is_worse: true,
    },
    Metric {
        title: "Pops (pixels above the threshold)",
        stem: "pops",
        value: |f| f.temporal.as_ref().map(|t| t.pops as f64),
        larger_is_worse: true,
    },
];

/// The frames of `figures` ordered from the worst by `m`, at most `n`.
fn worst(figures: &[FrameFigures], m: &Metric, n: usize) -> Vec<(usize, f64)> {
    let mut v: Vec<(usize, f64)> = figures
        .iter()
        .filter_map(|f| (m.value)(f).map(|v| (f.frame, v)))
        .collect();
    v.sort_by(|a, b| {
        let o = a.1.total_cmp(&b.1);
        if m.larger_is_worse {
            o.reverse()
        } else {
            o
        }
    });
    v.truncate(n);
    v
}

/// What the page says besides the figures.
pub struct SequencePage<'a> {
    pub reference: &'a str,
    pub approximation: &'a str,
    pub verdict: &'a str,
    pub checks: &'a [GateCheck],
}

/// Writes the plots and `index.html` into `dir` (after [`write_frame_images`] for every frame);
/// returns the page's path.
pub fn write_sequence_page(
    dir: &Path,
    cmp: &SequenceComparison,
    text: &SequencePage,
) -> Result<std::path::PathBuf> {
    let mut body = String::new();
    let _ = write!(
        body,
        "<h1>Sequence comparison</h1>\n<p>Reference <code>{}</code>, approximation <code>{}</code>: {} frames.</p>\n<p class=\"verdict\">{}</p>\n",
        escape(text.reference),
        escape(text.approximation),
        cmp.frames.len(),
        escape(text.verdict)
    );
    body += &summary_table(cmp, text.checks);
    body += &player_section(cmp);
    body += "<h2>Over the frames</h2>\n<div class=\"grid\">\n";
    for m in &METRICS {
        let points: Vec<(f64, f64)> = cmp
            .frames
            .iter()
            .filter_map(|f| (m.value)(f).map(|v| (f.frame as f64, v)))
            .collect();
        if points.is_empty() {
            continue;
        }
        let file = format!("{}.svg", m.stem);
        line_plot_svg(
            &dir.join(&file),
            &PlotSpec {
                title: m.title,
                x_label: "frame",
                y_label: m.stem,
                log_x: false,
                log_y: false,
                x_categories: None,
            },
            &[Series {
                label: m.stem.to_string(),
                points,
            }],
        )?;
        let links: Vec<String> = worst(&cmp.frames, m, WORST_LISTED)
            .into_iter()
            .map(|(f, v)| {
                format!(
                    "<a href=\"#frame-{f}\" data-frame=\"{f}\">frame {f}</a> ({})",
                    short(v)
                )
            })
            .collect();
        let _ = writeln!(
            body,
            "<figure class=\"plot\"><img src=\"{file}\" alt=\"{}\"><figcaption>{}. Worst: {}</figcaption></figure>",
            escape(m.title),
            escape(m.title),
            links.join(", ")
        );
    }
    body += "</div>\n";
    body += &frames_table(cmp);
    body += PLAYER_SCRIPT;
    let index = dir.join("index.html");
    super::text::write_text(&index, &page("pgt sequence comparison", &body))?;
    Ok(index)
}

fn summary_table(cmp: &SequenceComparison, checks: &[GateCheck]) -> String {
    let mut t = String::from("<table>\n");
    let row = |t: &mut String, k: &str, v: String| {
        let _ = writeln!(t, "<tr><td>{k}</td><td>{v}</td></tr>");
    };
    row(&mut t, "frames", cmp.frames.len().to_string());
    row(
        &mut t,
        "data range (SSIM, PSNR, images)",
        short(cmp.data_range),
    );
    row(
        &mut t,
        "pop threshold (max over channels of e<sub>t</sub>)",
        short(cmp.pop_threshold),
    );
    if let Some(f) = cmp.worst_ssim() {
        row(
            &mut t,
            "lowest SSIM",
            format!(
                "{} at <a href=\"#frame-{f}\" data-frame=\"{f}\">frame {f}</a>",
                short(f.ssim.unwrap_or(f64::NAN)),
                f = f.frame
            ),
        );
    }
    if let Some(f) = cmp.worst_temporal() {
        let p = f.temporal.as_ref().map_or(0.0, |t| t.p99.mean);
        row(
            &mut t,
            "largest temporal p99",
            format!(
                "{} at <a href=\"#frame-{f}\" data-frame=\"{f}\">frame {f}</a>",
                short(p),
                f = f.frame
            ),
        );
    }
    let pops: usize = cmp
        .frames
        .iter()
        .filter_map(|f| f.temporal.as_ref().map(|t| t.pops))
        .sum();
    row(&mut t, "pops over all frames", pops.to_string());
    for c in checks {
        let class = if c.passed { "pass" } else { "fail" };
        row(
            &mut t,
            &escape(&c.name),
            format!(
                "<span class=\"{class}\">{} (threshold {}) {}</span>",
                short(c.value),
                short(c.threshold),
                if c.passed { "pass" } else { "FAIL" }
            ),
        );
    }
    t += "</table>\n";
    t
}

fn player_section(cmp: &SequenceComparison) -> String {
    let Some(first) = cmp.frames.first() else {
        return String::new();
    };
    let scale = temporal_scale(cmp.pop_threshold);
    let frames: Vec<String> = cmp.frames.iter().map(|f| f.frame.to_string()).collect();
    format!(
        r#"<section id="pgt-player" hidden data-frames="{list}">
<style>#pgt-player figure img {{ width: 20em; image-rendering: pixelated; cursor: crosshair; }}</style>
<h2>Player</h2>
<div class="controls"><button type="button" data-step="-1">◀ step</button><button type="button" id="pgt-play">play</button><button type="button" data-step="1">step ▶</button>
<input type="range" id="pgt-slider" min="0" max="{max}" value="0"> <span id="pgt-frame">frame {f0}</span></div>
<div class="grid">
<figure><img id="pgt-r" src="{r0}" alt="reference"><figcaption>Reference</figcaption></figure>
<figure><img id="pgt-a" src="{a0}" alt="approximation"><figcaption>Approximation</figcaption></figure>
<figure><div class="heat"><img id="pgt-t" src="{t0}" alt="temporal error"><span class="colorbar">{bar}</span></div><figcaption>Temporal error e<sub>t</sub> against the previous frame (mean over R, G, B; magma, 0 … {hi}; none for the first frame)</figcaption></figure>
</div>
<p class="help">Hover or click a pixel of any pane to probe it: the linear values of the frame shown (float16, three significant digits).</p>
<table id="pgt-probe"><tr><th id="pgt-probe-pixel">pixel</th><th>R</th><th>G</th><th>B</th></tr>
{rows}</table>
<p id="pgt-probe-note"></p>
</section>
"#,
        list = frames.join(" "),
        rows = probe_rows(),
        max = cmp.frames.len() - 1,
        f0 = first.frame,
        r0 = frame_file("r", first.frame),
        a0 = frame_file("a", first.frame),
        t0 = cmp
            .frames
            .get(1)
            .map_or_else(String::new, |f| frame_file("t", f.frame)),
        bar = colorbar_svg(scale, ColorMap::Magma, "temporal error", "bar-temporal"),
        hi = short(scale.hi),
    )
}

/// The probe table's rows: reference, approximation and e_t, a cell per channel.
fn probe_rows() -> String {
    let mut rows = String::new();
    for (key, name) in [
        ("reference", "reference"),
        ("approximation", "approximation"),
        ("temporal", "e<sub>t</sub>"),
    ] {
        let _ = write!(rows, "<tr><td>{name}</td>");
        for c in 0..3 {
            let _ = write!(rows, "<td data-probe=\"{key}-{c}\">—</td>");
        }
        rows += "</tr>\n";
    }
    rows
}

fn frames_table(cmp: &SequenceComparison) -> String {
    let mut t = String::from(
        "<h2>Every frame</h2>\n<table id=\"pgt-frames\">\n<tr><th>frame</th><th>SSIM</th><th>RMSE</th><th>FLIP</th><th>temporal mean</th><th>temporal p99</th><th>pops</th><th>reference</th><th>approximation</th><th>temporal error</th></tr>\n",
    );
    let opt = |v: Option<f64>| v.map_or_else(|| "–".to_string(), short);
    for f in &cmp.frames {
        let temporal_img = match &f.temporal {
            Some(_) => format!(
                "<img src=\"{}\" alt=\"temporal error of frame {}\" width=\"96\">",
                frame_file("t", f.frame),
                f.frame
            ),
            None => "–".into(),
        };
        let _ = writeln!(
            t,
            "<tr id=\"frame-{n}\"><td><a href=\"#frame-{n}\" data-frame=\"{n}\">{n}</a></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td><img src=\"{}\" alt=\"reference of frame {n}\" width=\"96\"></td><td><img src=\"{}\" alt=\"approximation of frame {n}\" width=\"96\"></td><td>{temporal_img}</td></tr>",
            opt(f.ssim),
            short(f.rmse),
            opt(f.flip),
            opt(f.temporal.as_ref().map(|t| t.mean.mean)),
            opt(f.temporal.as_ref().map(|t| t.p99.mean)),
            f.temporal.as_ref().map_or_else(|| "–".into(), |t| t.pops.to_string()),
            frame_file("r", f.frame),
            frame_file("a", f.frame),
            n = f.frame,
        );
    }
    t += "</table>\n";
    t
}

/// The player: shown only when scripts run; frame files follow [`frame_file`]'s names.
const PLAYER_SCRIPT: &str = r#"<script>
(function () {
  var section = document.getElementById("pgt-player");
  if (!section) { return; }
  var frames = section.getAttribute("data-frames").split(" ").map(Number);
  var slider = document.getElementById("pgt-slider");
  var label = document.getElementById("pgt-frame");
  var play = document.getElementById("pgt-play");
  var timer = null;
  function file(kind, f) { return "frames/" + kind + "_" + String(f).padStart(6, "0") + ".png"; }
  function show(i) {
    i = Math.max(0, Math.min(frames.length - 1, i));
    slider.value = String(i);
    var f = frames[i];
    label.textContent = "frame " + f;
    document.getElementById("pgt-r").src = file("r", f);
    document.getElementById("pgt-a").src = file("a", f);
    var t = document.getElementById("pgt-t");
    if (i > 0) { t.src = file("t", f); t.style.visibility = "visible"; } else { t.style.visibility = "hidden"; }
    shown = f;
    load(f);
    showProbe();
  }

  // The pixel probe (src/report/sequence_probe.rs): frame f's values are frames/p_NNNNNN.js,
  // loaded by <script src> the first time the frame is shown; it calls pgtProbeFrame.
  var probe = document.getElementById("pgt-probe");
  var note = document.getElementById("pgt-probe-note");
  var values = {}, requested = {}, pixel = null, shown = frames[0];
  var canDecode = typeof DecompressionStream === "function" && typeof Response === "function";
  if (!canDecode) { probe.hidden = true; note.textContent = "This browser cannot decompress the probe's values (no DecompressionStream)."; }
  function half(h) {
    var s = (h & 0x8000) ? -1 : 1, e = (h >> 10) & 0x1f, m = h & 0x3ff;
    if (e === 0) { return s * m * Math.pow(2, -24); }
    if (e === 31) { return m ? NaN : s * Infinity; }
    return s * (1 + m / 1024) * Math.pow(2, e - 15);
  }
  // base64 of zlib of little-endian float16 (R, G, B interleaved, row-major) → Float32Array.
  function decode(b64) {
    if (!b64) { return Promise.resolve(null); }
    var bin = atob(b64), bytes = new Uint8Array(bin.length);
    for (var i = 0; i < bin.length; i++) { bytes[i] = bin.charCodeAt(i); }
    var stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
    return new Response(stream).arrayBuffer().then(function (buf) {
      var dv = new DataView(buf), out = new Float32Array(buf.byteLength / 2);
      for (var k = 0; k < out.length; k++) { out[k] = half(dv.getUint16(2 * k, true)); }
      return out;
    });
  }
  window.pgtProbeFrame = function (f, d) {
    Promise.all([decode(d.reference), decode(d.approximation), decode(d.temporal)]).then(function (v) {
      values[f] = { width: d.width, reference: v[0], approximation: v[1], temporal: v[2] };
      if (f === shown) { showProbe(); }
    });
  };
  function load(f) {
    if (!canDecode || requested[f]) { return; }
    requested[f] = true;
    var s = document.createElement("script");
    s.src = "frames/p_" + String(f).padStart(6, "0") + ".js";
    document.head.appendChild(s);
  }
  function fmt(v) { return isFinite(v) ? Number(v).toPrecision(4) : String(v); }
  function setCells(key, data, i) {
    for (var c = 0; c < 3; c++) {
      probe.querySelector('td[data-probe="' + key + "-" + c + '"]').textContent = data ? fmt(data[i + c]) : "—";
    }
  }
  function showProbe() {
    if (!pixel) { return; }
    var d = values[shown];
    document.getElementById("pgt-probe-pixel").textContent = "frame " + shown + ", pixel (" + pixel.x + ", " + pixel.y + ")";
    probe.setAttribute("data-x", String(pixel.x));
    probe.setAttribute("data-y", String(pixel.y));
    var i = d ? 3 * (pixel.y * d.width + pixel.x) : 0;
    setCells("reference", d && d.reference, i);
    setCells("approximation", d && d.approximation, i);
    setCells("temporal", d && d.temporal, i);
    // The frame whose values the cells hold (none while its file loads).
    probe.setAttribute("data-frame", d ? String(shown) : "");
  }
  ["pgt-r", "pgt-a", "pgt-t"].forEach(function (id) {
    var img = document.getElementById(id);
    function at(ev) {
      var box = img.getBoundingClientRect(), w = img.naturalWidth, h = img.naturalHeight;
      var x = Math.floor((ev.clientX - box.left) / box.width * w);
      var y = Math.floor((ev.clientY - box.top) / box.height * h);
      if (x >= 0 && y >= 0 && x < w && y < h) { pixel = { x: x, y: y }; showProbe(); }
    }
    img.addEventListener("mousemove", at);
    img.addEventListener("click", at);
  });
  function stop() { if (timer) { clearInterval(timer); timer = null; play.textContent = "play"; } }
  slider.addEventListener("input", function () { stop(); show(Number(slider.value)); });
  Array.prototype.forEach.call(section.querySelectorAll("[data-step]"), function (b) {
    b.addEventListener("click", function () { stop(); show(Number(slider.value) + Number(b.getAttribute("data-step"))); });
  });
  play.addEventListener("click", function () {
    if (timer) { stop(); return; }
    play.textContent = "pause";
    timer = setInterval(function () {
      var i = Number(slider.value) + 1;
      show(i >= frames.length ? 0 : i);
    }, 200);
  });
  Array.prototype.forEach.call(document.querySelectorAll("a[data-frame]"), function (a) {
    a.addEventListener("click", function (e) {
      e.preventDefault(); stop();
      show(frames.indexOf(Number(a.getAttribute("data-frame"))));
      section.scrollIntoView();
    });
  });
  section.hidden = false;
  show(0);
})();
</script>
"#;
