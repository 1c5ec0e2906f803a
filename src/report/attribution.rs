//! The error attribution's part of a sweep report (docs/design.md §5 "error attribution"): per
//! attributed run a stacked bar of the causes' shares (SSIM share and MSE share with the
//! interaction term, as defined in [`crate::sweep::attribution`]), an error map per cause on one
//! scale, and a table.

use super::colorbar::colorbar_svg;
use super::text::escape;
use super::{heatmap, ColorMap, Scale};
use crate::error::Result;
use crate::sweep::AttributionResult;
use std::fmt::Write as _;
use std::path::Path;

/// Colours of the causes, in chain order (Tableau 10), and of the interaction term.
const COLORS: [&str; 8] = [
    "#4e79a7", "#f28e2b", "#e15759", "#76b7b2", "#59a14f", "#edc948", "#b07aa1", "#ff9da7",
];
const INTERACTION: &str = "#9c9c9c";

/// `attribution_STEM.svg`.
pub fn bar_file(a: &AttributionResult) -> String {
    format!("attribution_{}.svg", a.stem)
}

/// `attribution_STEM_scale.svg`: the colour bar of the run's error maps.
pub fn scale_file(a: &AttributionResult) -> String {
    format!("attribution_{}_scale.svg", a.stem)
}

/// The one scale of a run's error maps (all causes on it, so that the maps compare by eye):
/// 0 to the largest value of any cause's map.
fn map_scale(a: &AttributionResult) -> Scale {
    let highs: Vec<f32> = a
        .causes
        .iter()
        .map(|c| Scale::zero_to_max(&c.map).hi as f32)
        .collect();
    Scale::zero_to_max(&highs)
}

/// The colour bar of a run's error maps on their `scale`; `id` tells the bars of one page apart.
fn map_colorbar(scale: Scale, id: &str) -> String {
    colorbar_svg(scale, ColorMap::Magma, "|before − after|", id)
}

/// `attribution_STEM_CAUSE.png`.
pub fn map_file(a: &AttributionResult, cause: &str) -> String {
    format!(
        "attribution_{}_{}.png",
        a.stem,
        cause.replace([' ', '/'], "_")
    )
}

/// One horizontal stacked bar at `y`: segments (label, share, colour); negative shares (a
/// cause whose removal alone makes the image worse, or causes that cancel) are drawn left of
/// the 0 line, so that they are seen rather than hidden.
fn bar(svg: &mut String, y: f64, title: &str, segments: &[(String, f64, &str)]) {
    let (x0, width) = (150.0, 600.0);
    let neg: f64 = segments.iter().map(|s| s.1.min(0.0)).sum::<f64>().abs();
    let pos: f64 = segments.iter().map(|s| s.1.max(0.0)).sum();
    let scale = width / (neg + pos).max(1.0);
    let zero = x0 + neg * scale;
    let _ = writeln!(
        svg,
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\" font-size=\"13\">{}</text>",
        x0 - 8.0,
        y + 20.0,
        escape(title)
    );
    let (mut right, mut left) = (zero, zero);
    for (label, share, color) in segments {
        let w = share.abs() * scale;
        let x = if *share >= 0.0 {
            right += w;
            right - w
        } else {
            left -= w;
            left
        };
        let _ = writeln!(
            svg,
            "<rect x=\"{x:.1}\" y=\"{y:.1}\" width=\"{w:.1}\" height=\"30\" fill=\"{color}\"><title>{}: {:.1}%</title></rect>",
            escape(label),
            100.0 * share
        );
        if w > 60.0 {
            let _ = writeln!(
                svg,
                "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" font-size=\"11\" fill=\"white\">{} {:.0}%</text>",
                x + w / 2.0,
                y + 19.0,
                escape(label),
                100.0 * share
            );
        }
    }
    let _ = writeln!(
        svg,
        "<line x1=\"{zero:.1}\" x2=\"{zero:.1}\" y1=\"{:.1}\" y2=\"{:.1}\" stroke=\"black\"/>",
        y - 4.0,
        y + 34.0
    );
}

/// The stacked bars of one attribution as a self-contained SVG.
pub fn bars_svg(a: &AttributionResult) -> String {
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"780\" height=\"170\" viewBox=\"0 0 780 170\" font-family=\"sans-serif\">\n<rect width=\"780\" height=\"170\" fill=\"white\"/>\n<text x=\"10\" y=\"18\" font-size=\"14\">{}: shares of the error by cause (chain order left to right)</text>",
        escape(&a.label)
    );
    let color = |i: usize| COLORS[i % COLORS.len()];
    let ssim: Vec<(String, f64, &str)> = a
        .causes
        .iter()
        .enumerate()
        .map(|(i, c)| (c.cause.clone(), c.ssim_share, color(i)))
        .collect();
    bar(&mut svg, 35.0, "1 − SSIM", &ssim);
    let mut mse: Vec<(String, f64, &str)> = a
        .causes
        .iter()
        .enumerate()
        .map(|(i, c)| (c.cause.clone(), c.mse_share, color(i)))
        .collect();
    mse.push(("interaction".into(), a.interaction, INTERACTION));
    bar(&mut svg, 85.0, "MSE", &mse);
    let mut x = 150.0;
    for (label, _, c) in &mse {
        let _ = writeln!(
            svg,
            "<rect x=\"{x:.1}\" y=\"140\" width=\"12\" height=\"12\" fill=\"{c}\"/><text x=\"{:.1}\" y=\"151\" font-size=\"12\">{}</text>",
            x + 16.0,
            escape(label)
        );
        x += 24.0 + 7.5 * label.chars().count() as f64;
    }
    svg + "</svg>\n"
}

/// Writes the bars and the maps of every attribution into `dir`.
pub fn write_attribution_files(
    dir: &Path,
    attributions: &[AttributionResult],
    width: u32,
    height: u32,
) -> Result<()> {
    for a in attributions {
        super::text::write_text(&dir.join(bar_file(a)), &bars_svg(a))?;
        // A standalone file for pages that show the maps outside the sweep's own page (the
        // thesis report); the sweep page inlines the same bar.
        let scale = map_scale(a);
        super::text::write_text(&dir.join(scale_file(a)), &map_colorbar(scale, "bar"))?;
        for c in &a.causes {
            heatmap(&c.map, width, height, scale, ColorMap::Magma)
                .write_png(&dir.join(map_file(a, &c.cause)))?;
        }
    }
    Ok(())
}

/// The page's section: what a share means, then per run its bars, table and maps.
pub fn attribution_section(attributions: &[AttributionResult]) -> String {
    if attributions.is_empty() {
        return String::new();
    }
    let mut b = String::from(
        "<h2 id=\"attribution\">Error attribution</h2>\n<p>Each run's error is split into causes by swapping one stage at a time for its exact counterpart, in the order listed (each image has the stages above it exact too); the last image is the exact reference. A cause's error map is the difference between the images before and after its swap; these maps add up exactly to the run's error. <b>SSIM share</b>: the part of the run's SSIM loss (1 − SSIM against the reference) that the swap wins back; these add up to 100%. <b>MSE share</b>: the squared norm of the cause's map over the squared norm of the run's error; they add up to 100% only if the causes' maps were orthogonal, and the remainder (the cross terms between causes) is shown as <b>interaction</b> (negative where causes cancel). Both depend on the order of the chain.</p>\n",
    );
    for a in attributions {
        let _ = writeln!(
            b,
            "<h3>{}</h3>\n<p>RMSE {:.4e}, SSIM {:.4}% against the reference.</p>\n<div class=\"plot\"><img src=\"{}\" alt=\"attribution of {}\"></div>\n<table><tr><th>cause</th><th>swap</th><th>RMSE of the cause's map</th><th>SSIM (before vs after)</th><th>SSIM share</th><th>MSE share</th></tr>",
            escape(&a.label),
            a.rmse,
            100.0 * a.ssim,
            escape(&bar_file(a)),
            escape(&a.label)
        );
        for c in &a.causes {
            let _ = writeln!(
                b,
                "<tr><td>{}</td><td>{} → {}</td><td>{:.4e}</td><td>{:.4}%</td><td>{:.1}%</td><td>{:.1}%</td></tr>",
                escape(&c.cause),
                escape(&c.from),
                escape(&c.to),
                c.rmse,
                100.0 * c.ssim,
                100.0 * c.ssim_share,
                100.0 * c.mse_share
            );
        }
        let _ = writeln!(
            b,
            "<tr><td>interaction</td><td>cross terms</td><td></td><td></td><td></td><td>{:.1}%</td></tr>\n</table>\n<div class=\"grid\">",
            100.0 * a.interaction
        );
        let scale = map_scale(a);
        for (k, c) in a.causes.iter().enumerate() {
            let bar = map_colorbar(scale, &format!("bar-{}-{k}", a.stem));
            let _ = writeln!(
                b,
                "<figure><div class=\"heat\"><img src=\"{}\" alt=\"error map of {}\">{bar}</div><figcaption>{}: |before − after|, mean over R, G, B; magma, one scale per run</figcaption></figure>",
                escape(&map_file(a, &c.cause)),
                escape(&c.cause),
                escape(&c.cause)
            );
        }
        b += "</div>\n";
    }
    b
}

/// The attributions as JSON (in `sweep.json`).
pub fn attribution_json(attributions: &[AttributionResult]) -> serde_json::Value {
    serde_json::Value::Array(
        attributions
            .iter()
            .map(|a| {
                let causes: Vec<serde_json::Value> = a
                    .causes
                    .iter()
                    .map(|c| {
                        serde_json::json!({
                            "cause": c.cause, "from": c.from, "to": c.to, "rmse": c.rmse,
                            "ssim": c.ssim, "ssim_share": c.ssim_share, "mse_share": c.mse_share,
                            "map": map_file(a, &c.cause),
                        })
                    })
                    .collect();
                serde_json::json!({
                    "run": a.label, "rmse": a.rmse, "ssim": a.ssim, "causes": causes,
                    "interaction": a.interaction, "bars": bar_file(a), "scale": scale_file(a),
                })
            })
            .collect(),
    )
}
