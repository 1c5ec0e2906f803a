//! The self-contained HTML report of one comparison (docs/design.md §5): reference | approximation |
//! error heatmap with its colour bar | SSIM map, relative error and FLIP maps, a metrics table and
//! the gates, and the interactive viewer (`viewer.rs`). The page references only the files
//! written beside it (PNGs, `pgt-data.js`, `pgt-viewer.js`) and has no external resources;
//! an inline script marks `<body data-pgt-images="ok">` once every image has decoded (the
//! browser test reads that mark from the DOM).

use super::colorbar::colorbar_svg;
use super::colormap::{ColorMap, Scale};
use super::heatmap::heatmap;
use super::summary::{format_db, short, Summary};
use super::text::{escape, write_text};
use super::viewer::{write_viewer, Viewer, ViewerImage};
use crate::error::{PgtError, Result};
use crate::image_io::{write_image, RgbImage};
use crate::metrics::{maps, Comparison, PerChannel};
use std::fmt::Write as _;
use std::path::Path;

/// Options of the report's pictures.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ReportOptions {
    /// Fixed top of the absolute-error scale (`--error-scale`); automatic (the map's max) if `None`.
    pub error_scale: Option<f64>,
    /// Fixed top of the relative-error scale (`--rel-scale`); automatic if `None`.
    pub rel_scale: Option<f64>,
}

/// What a report needs.
pub struct ReportInputs<'a> {
    pub reference: &'a RgbImage,
    pub approximation: &'a RgbImage,
    /// The reference's per-pixel error estimate (its EXR `err` layer), for the pixel probe.
    pub estimate: Option<&'a RgbImage>,
    pub comparison: &'a Comparison,
    pub summary: &'a Summary,
    pub options: ReportOptions,
}

/// One picture of the report with its caption and, for heatmaps, its colour bar (inline SVG).
struct Figure {
    file: &'static str,
    title: String,
    caption: String,
    bar: Option<String>,
}

/// Writes the maps and the page into `dir` (created if missing): `index.html`,
/// `reference.png`, `approximation.png`, `abs_error.png`, `rel_error.png`, `ssim.png`,
/// `flip.png` (LDR- or HDR-FLIP, unless FLIP is off or undefined), `maps.exr` (the values:
/// main layer = abs error, layers `rel`, `ssim`, `flip`) and `summary.json`. Returns the path of
/// the page.
pub fn write_report(dir: &Path, inputs: &ReportInputs) -> Result<std::path::PathBuf> {
    super::text::create_folder(dir)?;
    let cmp = inputs.comparison;
    let (w, h) = (cmp.width, cmp.height);
    // The inputs as the eye sees them: scaled so the data range maps to white.
    let exposure = -(cmp.data_range.max(f64::MIN_POSITIVE)).log2() as f32;
    for (name, img) in [
        ("reference.png", inputs.reference),
        ("approximation.png", inputs.approximation),
    ] {
        write_image(&dir.join(name), img, &[], exposure)?;
    }
    let exposure_note = if exposure == 0.0 {
        "sRGB of the linear values".to_string()
    } else {
        format!("sRGB of the linear values × 1/{}", short(cmp.data_range))
    };

    let abs = maps::abs_error(inputs.reference, inputs.approximation);
    let rel = maps::rel_error(inputs.reference, inputs.approximation, cmp.data_range);
    let abs_mean = maps::channel_mean(&abs);
    let rel_mean = maps::channel_mean(&rel);
    let abs_scale = fixed_or_auto(inputs.options.error_scale, &abs_mean);
    let rel_scale = fixed_or_auto(inputs.options.rel_scale, &rel_mean);
    heatmap(&abs_mean, w, h, abs_scale, ColorMap::Magma).write_png(&dir.join("abs_error.png"))?;
    heatmap(&rel_mean, w, h, rel_scale, ColorMap::Magma).write_png(&dir.join("rel_error.png"))?;

    let mut figures = vec![
        Figure {
            file: "reference.png",
            title: "Reference".into(),
            caption: exposure_note.clone(),
            bar: None,
        },
        Figure {
            file: "approximation.png",
            title: "Approximation".into(),
            caption: exposure_note,
            bar: None,
        },
        Figure {
            file: "abs_error.png",
            title: "Absolute error".into(),
            caption: format!(
                "|a − r|, mean over R, G, B; magma, scale {} … {}{}",
                short(abs_scale.lo),
                short(abs_scale.hi),
                if inputs.options.error_scale.is_some() {
                    " (fixed)"
                } else {
                    " (max of the map)"
                }
            ),
            bar: Some(colorbar_svg(
                abs_scale,
                ColorMap::Magma,
                "absolute error",
                "bar-abs",
            )),
        },
    ];
    let mut layers_owned: Vec<(&str, RgbImage)> = vec![("rel", rel)];
    if let Ok(ssim) = &cmp.ssim {
        let img = maps::ssim_image(w, h, ssim);
        let mean = maps::channel_mean(&img);
        heatmap(&mean, w, h, UNIT, ColorMap::Viridis).write_png(&dir.join("ssim.png"))?;
        figures.push(Figure {
            file: "ssim.png",
            title: "SSIM map".into(),
            caption: "mean over R, G, B; viridis, scale 0 … 1 (values below 0 shown as 0)".into(),
            bar: Some(colorbar_svg(UNIT, ColorMap::Viridis, "SSIM", "bar-ssim")),
        });
        layers_owned.push(("ssim", img));
    }
    figures.push(Figure {
        file: "rel_error.png",
        title: "Relative error".into(),
        caption: format!(
            "|a − r| / (|r| + 0.01·R), mean over R, G, B; magma, scale {} … {}",
            short(rel_scale.lo),
            short(rel_scale.hi)
        ),
        bar: Some(colorbar_svg(
            rel_scale,
            ColorMap::Magma,
            "relative error",
            "bar-rel",
        )),
    });
    if let Ok(flip) = &cmp.flip {
        figures.push(flip_figure(dir, flip, w, h)?);
        layers_owned.push(("flip", maps::gray_image(w, h, &flip.map)));
    }
    let layers: Vec<(&str, &RgbImage)> = layers_owned.iter().map(|(n, i)| (*n, i)).collect();
    write_maps_exr(&dir.join("maps.exr"), &abs, &layers)?;
    let json =
        serde_json::to_string_pretty(inputs.summary).map_err(|e| PgtError::Usage(e.to_string()))?;
    write_text(&dir.join("summary.json"), &(json + "\n"))?;

    let viewer_html = compare_viewer(dir, inputs, exposure, abs_scale)?;
    let page = comparison_page(inputs.summary, &figures, &viewer_html);
    let path = dir.join("index.html");
    write_text(&path, &page)?;
    Ok(path)
}

/// The FLIP map's heatmap, written into `dir`, and its figure (LDR- or HDR-FLIP).
fn flip_figure(dir: &Path, flip: &crate::metrics::Flip, w: u32, h: u32) -> Result<Figure> {
    heatmap(&flip.map, w, h, UNIT, ColorMap::Magma).write_png(&dir.join("flip.png"))?;
    Ok(Figure {
        file: "flip.png",
        title: if flip.exposures.is_some() { "HDR-FLIP" } else { "FLIP (LDR)" }.into(),
        caption: match flip.exposures {
            Some((a, b, n)) => format!(
                "magma, scale 0 … 1, {:.1} pixels per degree, ACES, {n} exposures {a:.2} … {b:.2} stops, 8-bit per exposure",
                flip.pixels_per_degree
            ),
            None => format!(
                "magma, scale 0 … 1, {:.1} pixels per degree",
                flip.pixels_per_degree
            ),
        },
        bar: Some(colorbar_svg(UNIT, ColorMap::Magma, "FLIP", "bar-flip")),
    })
}

/// The viewer of one comparison: reference against approximation, the abs-error heatmap in the
/// error pane, the reference's error estimate in the probe.
fn compare_viewer(
    dir: &Path,
    inputs: &ReportInputs,
    exposure: f32,
    abs_scale: Scale,
) -> Result<String> {
    let viewer = Viewer {
        reference: inputs.reference,
        reference_png: "reference.png".into(),
        estimate: inputs.estimate,
        approximations: vec![ViewerImage {
            label: "approximation".into(),
            png: "approximation.png".into(),
            heatmap: "abs_error.png".into(),
            image: inputs.approximation,
        }],
        exposure,
        error_caption: format!(
            "|a − r|, mean over R, G, B, magma 0 … {}",
            short(abs_scale.hi)
        ),
    };
    write_viewer(dir, &viewer)
}

fn fixed_or_auto(fixed: Option<f64>, values: &[f32]) -> Scale {
    match fixed {
        Some(hi) => Scale { lo: 0.0, hi },
        None => Scale::zero_to_max(values),
    }
}

/// The scale of SSIM and FLIP maps.
const UNIT: Scale = Scale { lo: 0.0, hi: 1.0 };

fn comparison_page(s: &Summary, figures: &[Figure], viewer: &str) -> String {
    let mut body = String::new();
    let _ = write!(
        body,
        "<h1>pgt compare</h1>\n<p class=\"verdict {}\">{}</p>\n<p>reference <code>{}</code>, approximation <code>{}</code>, {}×{} pixels, data range {} ({:?}), {:.2} s</p>\n",
        match s.passed {
            Some(true) => "pass",
            Some(false) => "fail",
            None => "",
        },
        escape(&s.verdict()),
        escape(&s.reference),
        escape(&s.approximation),
        s.width,
        s.height,
        short(s.data_range),
        s.data_range_source,
        s.seconds
    );
    body += viewer;
    body += "<div class=\"grid\">\n";
    for f in figures {
        let _ = writeln!(
            body,
            "<figure><div class=\"heat\"><img src=\"{}\" alt=\"{}\">{}</div><figcaption><b>{}</b><br>{}</figcaption></figure>",
            f.file,
            escape(&f.title),
            f.bar.as_deref().unwrap_or(""),
            escape(&f.title),
            escape(&f.caption)
        );
    }
    body += "</div>\n";
    body += &metrics_table(s);
    if !s.gates.is_empty() {
        body += "<h2>Gates</h2>\n<table><tr><th>threshold</th><th>value</th><th>limit</th><th>result</th></tr>\n";
        for g in &s.gates {
            let _ = writeln!(
                body,
                "<tr class=\"{}\"><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                if g.passed { "pass" } else { "fail" },
                escape(&g.name),
                short(g.value),
                short(g.threshold),
                if g.passed { "pass" } else { "FAIL" }
            );
        }
        body += "</table>\n";
    }
    page("pgt compare", &body)
}

/// The metrics table: rows are metrics, columns R, G, B and their mean.
pub fn metrics_table(s: &Summary) -> String {
    let mut t = String::from("<h2>Metrics</h2>\n<table><tr><th>metric</th><th>R</th><th>G</th><th>B</th><th>mean</th></tr>\n");
    let mut row = |name: &str, v: &PerChannel, fmt: &dyn Fn(f64) -> String| {
        let _ = writeln!(
            t,
            "<tr><td>{name}</td><td>{}</td><td>{}</td><td>{}</td><td><b>{}</b></td></tr>",
            fmt(v.r),
            fmt(v.g),
            fmt(v.b),
            fmt(v.mean)
        );
    };
    if let Some(v) = &s.ssim {
        row("SSIM", v, &|x| format!("{x:.6}"));
    }
    row("RMSE", &s.rmse, &|x| format!("{x:.4e}"));
    row("PSNR", &s.psnr, &format_db);
    row("mean abs error", &s.mean_abs, &|x| format!("{x:.4e}"));
    row("mean rel error", &s.mean_rel, &|x| format!("{x:.4e}"));
    let cells: Vec<String> = s
        .max_abs
        .iter()
        .map(|m| format!("{:.4e} at ({}, {})", m.value, m.pixel[0], m.pixel[1]))
        .collect();
    let _ = writeln!(
        t,
        "<tr><td>max abs error</td><td>{}</td><td>{}</td><td>{}</td><td><b>{:.4e}</b></td></tr>",
        cells[0],
        cells[1],
        cells[2],
        s.worst_max_abs().value
    );
    match s.flip {
        Some(f) => {
            let kind = if s.flip_kind == Some("hdr") {
                "HDR-FLIP"
            } else {
                "FLIP (LDR)"
            };
            let _ = writeln!(
                t,
                "<tr><td>{kind}</td><td colspan=\"3\"></td><td><b>{f:.6}</b></td></tr>"
            );
        }
        None => {
            let _ = writeln!(
                t,
                "<tr><td>FLIP</td><td colspan=\"4\">{}</td></tr>",
                escape(s.flip_note.as_deref().unwrap_or("n/a"))
            );
        }
    }
    if let Some(u) = &s.reference_uncertainty {
        let _ = writeln!(
            t,
            "<tr><td>reference error estimate</td><td colspan=\"4\">max {:.3e}, mean {:.3e}; |a − r| exceeds it at {:.3}% of pixel-channels</td></tr>",
            u.max_estimate,
            u.mean_estimate,
            100.0 * u.exceeding_fraction
        );
    }
    if let Some(note) = &s.ssim_note {
        let _ = writeln!(
            t,
            "<tr><td>SSIM</td><td colspan=\"4\">{}</td></tr>",
            escape(note)
        );
    }
    t += "</table>\n";
    t
}

/// A complete page around `body`, with the style sheet and the image-check script inline.
pub fn page(title: &str, body: &str) -> String {
    format!(
        r#"<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
body {{ font-family: sans-serif; margin: 1.5em; color: #222; }}
.grid {{ display: flex; flex-wrap: wrap; gap: 1em; }}
figure {{ margin: 0; max-width: 32em; }}
figure img, .plot img {{ max-width: 100%; image-rendering: pixelated; border: 1px solid #ccc; }}
.heat {{ display: flex; align-items: flex-start; gap: 0.3em; }}
.heat img {{ min-width: 0; flex: 0 1 auto; }}
.colorbar {{ flex: none; }}
#pgt-viewer .controls {{ display: flex; flex-wrap: wrap; gap: 0.6em; align-items: center; margin: 0.5em 0; }}
#pgt-viewer .panes {{ display: flex; flex-wrap: wrap; gap: 1em; }}
#pgt-viewer .viewport {{ position: relative; overflow: hidden; border: 1px solid #888; background: #777; cursor: crosshair; touch-action: none; }}
#pgt-viewer canvas {{ position: absolute; left: 0; top: 0; transform-origin: 0 0; image-rendering: pixelated; }}
#pgt-viewer .pane-title {{ font-size: 0.85em; font-weight: bold; }}
#pgt-probe td {{ font-family: monospace; }}
figcaption {{ font-size: 0.85em; }}
table {{ border-collapse: collapse; margin: 1em 0; }}
td, th {{ border: 1px solid #bbb; padding: 0.2em 0.6em; text-align: right; }}
td:first-child {{ text-align: left; }}
.pass {{ color: #060; }} .fail {{ color: #a00; font-weight: bold; }}
.verdict {{ font-family: monospace; }}
</style>
</head>
<body data-pgt-images="pending">
{body}
<script>
// Marks the page once every image has loaded and decoded (naturalWidth > 0); the browser test
// reads the mark from the DOM.
window.addEventListener("load", function () {{
  var imgs = Array.prototype.slice.call(document.images);
  var broken = imgs.filter(function (i) {{ return !(i.complete && i.naturalWidth > 0); }});
  document.body.setAttribute("data-pgt-images", broken.length === 0 ? "ok" : "missing");
  document.body.setAttribute("data-pgt-image-count", String(imgs.length));
  if (broken.length > 0) {{
    document.body.setAttribute("data-pgt-broken", broken.map(function (i) {{ return i.getAttribute("src"); }}).join(" "));
  }}
}});
</script>
</body>
</html>
"#
    )
}

/// Writes the maps as a float32 EXR, atomically: `abs` as the unnamed `R`, `G`, `B`, each of
/// `layers` as `NAME.R/G/B` (run-length compressed: see `image_io`).
fn write_maps_exr(path: &Path, abs: &RgbImage, layers: &[(&str, &RgbImage)]) -> Result<()> {
    write_image(path, abs, layers, 0.0)
}
