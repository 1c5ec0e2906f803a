//! SVG line plots of a swept parameter (DESIGN.md §5 "plots (error and time against a swept
//! parameter) as SVG"), drawn with plotters: one series per value of the other parameters, like
//! the thesis's Figures 6.2/6.3 (time against samples, one line per N).

use crate::error::{PgtError, Result};
use plotters::prelude::*;
use std::path::Path;

/// One line of a plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub label: String,
    /// (x, y) points, in any order (sorted by x before drawing).
    pub points: Vec<(f64, f64)>,
}

/// A plot's axes.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotSpec<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    /// Logarithmic x axis (for sample counts spanning decades).
    pub log_x: bool,
    /// Logarithmic y axis (for errors spanning decades); non-positive values are dropped.
    pub log_y: bool,
}

const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// Draws `series` into an SVG file at `path` (640×400).
pub fn line_plot_svg(path: &Path, spec: &PlotSpec, series: &[Series]) -> Result<()> {
    let keep = |(x, y): &(f64, f64)| {
        x.is_finite() && y.is_finite() && (!spec.log_x || *x > 0.0) && (!spec.log_y || *y > 0.0)
    };
    let series: Vec<Series> = series
        .iter()
        .map(|s| {
            let mut points: Vec<(f64, f64)> = s.points.iter().copied().filter(keep).collect();
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            Series {
                label: s.label.clone(),
                points,
            }
        })
        .collect();
    let all: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .collect();
    let (mut x0, mut x1, mut y0, mut y1) = all.iter().fold(
        (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ),
        |(a, b, c, d), &(x, y)| (a.min(x), b.max(x), c.min(y), d.max(y)),
    );
    if all.is_empty() {
        (x0, x1, y0, y1) = (1.0, 10.0, 1.0, 10.0);
    }
    let widen = |lo: f64, hi: f64, log: bool| -> (f64, f64) {
        if log {
            let (lo, hi) = if hi / lo < 1.5 {
                (lo / 1.5, hi * 1.5)
            } else {
                (lo, hi)
            };
            (lo / 1.1, hi * 1.1)
        } else {
            let pad = if hi > lo {
                0.05 * (hi - lo)
            } else {
                0.5 * lo.abs().max(1e-3)
            };
            (lo - pad, hi + pad)
        }
    };
    let (x0, x1) = widen(x0, x1, spec.log_x);
    let (y0, y1) = widen(y0, y1, spec.log_y);
    let err = |e: &dyn std::fmt::Display| PgtError::io(path, std::io::Error::other(e.to_string()));
    let root = SVGBackend::new(path, (640, 400)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    macro_rules! draw {
        ($xr:expr, $yr:expr) => {{
            let mut chart = ChartBuilder::on(&root)
                .caption(spec.title, ("sans-serif", 18))
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(70)
                .build_cartesian_2d($xr, $yr)
                .map_err(|e| err(&e))?;
            chart
                .configure_mesh()
                .x_desc(spec.x_label)
                .y_desc(spec.y_label)
                .x_label_formatter(&|v| crate::report::heatmap::format_label(*v))
                .y_label_formatter(&|v| crate::report::heatmap::format_label(*v))
                .draw()
                .map_err(|e| err(&e))?;
            for (i, s) in series.iter().enumerate() {
                let color = PALETTE[i % PALETTE.len()];
                chart
                    .draw_series(LineSeries::new(
                        s.points.iter().copied(),
                        color.stroke_width(2),
                    ))
                    .map_err(|e| err(&e))?
                    .label(s.label.clone())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 16, y)], color.stroke_width(2))
                    });
                chart
                    .draw_series(s.points.iter().map(|&p| Circle::new(p, 3, color.filled())))
                    .map_err(|e| err(&e))?;
            }
            if series.iter().any(|s| !s.label.is_empty()) {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .draw()
                    .map_err(|e| err(&e))?;
            }
        }};
    }
    match (spec.log_x, spec.log_y) {
        (false, false) => draw!(x0..x1, y0..y1),
        (true, false) => draw!((x0..x1).log_scale(), y0..y1),
        (false, true) => draw!(x0..x1, (y0..y1).log_scale()),
        (true, true) => draw!((x0..x1).log_scale(), (y0..y1).log_scale()),
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
