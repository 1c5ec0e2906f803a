//! SVG line plots of a swept parameter (docs/design.md §5 "plots (error and time against a swept
//! parameter) as SVG"), drawn with plotters: one series per value of the other parameters, like
//! the thesis's Figures 6.2/6.3 (time against samples, one line per N).
//!
//! Ticks are placed here, not by plotters, so that labels stay readable: on a log axis at
//! 1, 2, 5 × 10^k (or every decade, or every few decades, whichever keeps them apart), written
//! `1`, `10`, `0.001` (and `1e-7` outside 0.001..100000); on a category axis (e.g. `n_exact` =
//! 1, 2, 5, all) at each category, or every n-th where their labels would overlap; linear axes
//! keep plotters' round ticks. A test checks that no two tick labels overlap.

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
    /// A category axis: x values are indices into these names (`log_x` is then ignored).
    pub x_categories: Option<&'a [String]>,
}

/// Most ticks on the x and the y axis (640×400 plots: about 55 and 35 pixels apart at least).
const MAX_X_TICKS: usize = 10;
const MAX_Y_TICKS: usize = 8;

/// Ticks of a log axis over [lo, hi] (0 < lo < hi): 1, 2, 5 × 10^k where that gives at most
/// `max` ticks, else every decade, else every n-th decade; 1…9 × 10^k for ranges too short to
/// hold two of those.
pub fn log_ticks(lo: f64, hi: f64, max: usize) -> Vec<f64> {
    let (k0, k1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let within = |mantissas: &[u32], every: i32| -> Vec<f64> {
        let mut out = Vec::new();
        for k in (k0..=k1).filter(|k| k.rem_euclid(every) == 0) {
            for &m in mantissas {
                // Parsed from text, so that 2e-7 is the double nearest 2·10⁻⁷ (and prints so).
                let v: f64 = format!("{m}e{k}").parse().unwrap_or(f64::NAN);
                if v >= lo && v <= hi {
                    out.push(v);
                }
            }
        }
        out
    };
    let fine = within(&[1, 2, 5], 1);
    if fine.len() >= 2 && fine.len() <= max {
        return fine;
    }
    if fine.len() < 2 {
        return within(&[1, 2, 3, 4, 5, 6, 7, 8, 9], 1);
    }
    let mut every = 1;
    loop {
        let decades = within(&[1], every);
        if decades.len() <= max {
            return decades;
        }
        every += 1;
    }
}

/// A tick label: the shortest decimal for 0.001 ≤ |v| < 100000 (`1`, `10`, `0.002`, `0.35`),
/// else `2e-7`, with at most three significant digits.
pub fn tick_label(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 {
        return "0".into();
    }
    let rounded: f64 = format!("{v:.2e}").parse().unwrap_or(v);
    if (1e-3..1e5).contains(&a) {
        format!("{rounded}")
    } else {
        format!("{rounded:e}")
    }
}

/// A tick label on a linear axis spanning `span` with about `ticks` ticks: like [`tick_label`],
/// with as many significant digits as the spacing of the ticks needs (at least three), so that
/// neighbouring ticks of a narrow range (0.9975, 0.998) do not print alike.
pub fn span_label(v: f64, span: f64, ticks: usize) -> String {
    let step = span / ticks.max(1) as f64;
    if v == 0.0 || !(step > 0.0 && step.is_finite()) {
        return tick_label(v);
    }
    let magnitude = v.abs().max(span);
    let digits = (magnitude.log10().floor() - step.log10().floor() + 2.0).clamp(3.0, 15.0) as usize;
    let rounded: f64 = format!("{v:.*e}", digits - 1).parse().unwrap_or(v);
    if (1e-3..1e5).contains(&v.abs()) {
        format!("{rounded}")
    } else {
        format!("{rounded:e}")
    }
}

const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// An axis: its range and its ticks.
struct Axis {
    lo: f64,
    hi: f64,
    ticks: Vec<f64>,
}

/// The drawable points of `series` (finite, positive on log axes, sorted by x) and the axes
/// that hold them with a margin.
fn layout(spec: &PlotSpec, series: &[Series]) -> (Vec<Series>, Axis, Axis) {
    let log_x = spec.log_x && spec.x_categories.is_none();
    let keep = |(x, y): &(f64, f64)| {
        x.is_finite() && y.is_finite() && (!log_x || *x > 0.0) && (!spec.log_y || *y > 0.0)
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
    let x = match spec.x_categories {
        Some(c) => Axis {
            lo: -0.5,
            hi: c.len().max(1) as f64 - 0.5,
            ticks: (0..c.len()).map(|i| i as f64).collect(),
        },
        None => Axis::around(x0, x1, log_x, MAX_X_TICKS),
    };
    let y = Axis::around(y0, y1, spec.log_y, MAX_Y_TICKS);
    (series, x, y)
}

impl Axis {
    /// [lo, hi] with a margin (a factor on log axes), and its ticks.
    fn around(lo: f64, hi: f64, log: bool, max_ticks: usize) -> Axis {
        let (lo, hi) = if log {
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
        };
        // Linear axes keep plotters' ticks (round numbers already), at most `max_ticks`.
        let ticks = if log {
            log_ticks(lo, hi, max_ticks)
        } else {
            Vec::new()
        };
        Axis { lo, hi, ticks }
    }
}

/// Width of the plot area in SVG pixels (640 minus the y label area and the margins), and the
/// width of a label character at plotters' label font (about 9.7 px sans-serif: at most
/// 0.6 em per digit), with a gap between neighbouring labels.
const PLOT_AREA_W: f64 = 640.0 - 70.0 - 2.0 * 12.0;
const LABEL_CHAR_W: f64 = 6.0;
const LABEL_GAP: f64 = 8.0;

/// Label every n-th category so that neighbouring labels do not overlap: categories sit
/// `PLOT_AREA_W / count` apart, a label needs its characters plus a gap.
fn category_step(categories: &[String]) -> usize {
    let chars = categories
        .iter()
        .map(|c| c.chars().count())
        .max()
        .unwrap_or(1);
    let need = chars as f64 * LABEL_CHAR_W + LABEL_GAP;
    let room = PLOT_AREA_W / categories.len().max(1) as f64;
    ((need / room).ceil() as usize).max(1)
}

/// Draws `series` into an SVG file at `path` (640×400).
pub fn line_plot_svg(path: &Path, spec: &PlotSpec, series: &[Series]) -> Result<()> {
    let log_x = spec.log_x && spec.x_categories.is_none();
    let (series, x, y) = layout(spec, series);
    let (x0, x1, xt) = (x.lo, x.hi, x.ticks);
    let (y0, y1, yt) = (y.lo, y.hi, y.ticks);
    let every = spec.x_categories.map_or(1, category_step);
    let x_label = |v: &f64| match spec.x_categories {
        Some(c)
            if (v - v.round()).abs() < 1e-6 && *v >= 0.0 && (v.round() as usize) % every == 0 =>
        {
            c.get(v.round() as usize).cloned().unwrap_or_default()
        }
        Some(_) => String::new(),
        None => tick_label(*v),
    };
    let y_label = |v: &f64| {
        if spec.log_y {
            tick_label(*v)
        } else {
            span_label(*v, y1 - y0, MAX_Y_TICKS)
        }
    };
    // A category axis is linear from −0.5 to n − 0.5: plotters puts its ticks on the integers
    // when asked for n + 1 at most, and the formatter leaves any others blank.
    let x_labels = spec.x_categories.map_or(MAX_X_TICKS, |c| c.len() + 1);
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
                .x_labels(x_labels)
                .y_labels(MAX_Y_TICKS)
                .x_label_formatter(&x_label)
                .y_label_formatter(&y_label)
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
    match (log_x, spec.log_y) {
        (false, false) => draw!(x0..x1, y0..y1),
        (true, false) => draw!((x0..x1).log_scale().with_key_points(xt), y0..y1),
        (false, true) => draw!(x0..x1, (y0..y1).log_scale().with_key_points(yt)),
        (true, true) => draw!(
            (x0..x1).log_scale().with_key_points(xt),
            (y0..y1).log_scale().with_key_points(yt)
        ),
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tick labels of an SVG written by [`line_plot_svg`]: (x, y, anchor, text).
    fn tick_labels(svg: &str) -> Vec<(f64, f64, String, String)> {
        svg.split("<text ")
            .skip(1)
            .filter_map(|t| {
                let attr = |name: &str| -> Option<String> {
                    let v = t.split(&format!("{name}=\"")).nth(1)?;
                    Some(v[..v.find('"')?].to_string())
                };
                let text = t.split('>').nth(1)?.split('<').next()?.trim().to_string();
                Some((
                    attr("x")?.parse().ok()?,
                    attr("y")?.parse().ok()?,
                    attr("text-anchor")?,
                    text,
                ))
            })
            .filter(|l: &(f64, f64, String, String)| !l.3.is_empty())
            .collect()
    }

    #[test]
    fn tick_labels_never_overlap() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.svg");
        let many: Vec<String> = (0..40).map(|i| (1000 + 37 * i).to_string()).collect();
        let few: Vec<String> = ["1", "2", "5", "all"].map(String::from).to_vec();
        // (log x, log y, categories, points)
        type Case<'a> = (bool, bool, Option<&'a [String]>, Vec<(f64, f64)>);
        let cases: Vec<Case> = vec![
            (true, true, None, vec![(1.0, 1e-9), (1e6, 0.5)]),
            (true, false, None, vec![(1.0, 1.234e-4), (3000.0, 9.87e-4)]),
            (true, true, None, vec![(2.0, 3e-3), (3.0, 4e-3)]),
            (
                false,
                false,
                None,
                vec![(0.000_123, 1.0), (0.000_987, 123_456.0)],
            ),
            (
                true,
                true,
                Some(&many),
                (0..40).map(|i| (i as f64, 1e-3 / (i + 1) as f64)).collect(),
            ),
            (
                true,
                true,
                Some(&few),
                (0..4).map(|i| (i as f64, 1e-3 / (i + 1) as f64)).collect(),
            ),
        ];
        for (log_x, log_y, categories, points) in cases {
            let spec = PlotSpec {
                title: "t",
                x_label: "x",
                y_label: "y",
                log_x,
                log_y,
                x_categories: categories,
            };
            let series = [Series {
                label: String::new(),
                points,
            }];
            line_plot_svg(&path, &spec, &series).unwrap();
            let svg = std::fs::read_to_string(&path).unwrap();
            let labels = tick_labels(&svg);
            // x tick labels: centred, on the row below the plot; y tick labels: right-aligned.
            let mut xs: Vec<_> = labels
                .iter()
                .filter(|l| l.2 == "middle" && l.1 > 340.0 && l.1 < 380.0)
                .collect();
            let mut ys: Vec<_> = labels.iter().filter(|l| l.2 == "end").collect();
            assert!(xs.len() >= 2 && ys.len() >= 2, "{labels:?}");
            xs.sort_by(|a, b| a.0.total_cmp(&b.0));
            ys.sort_by(|a, b| a.1.total_cmp(&b.1));
            for p in xs.windows(2) {
                let half = |t: &str| t.chars().count() as f64 * LABEL_CHAR_W / 2.0;
                assert!(
                    p[1].0 - p[0].0 >= half(&p[0].3) + half(&p[1].3) + 2.0,
                    "x labels overlap: {:?} {:?} (categories {categories:?})",
                    p[0],
                    p[1]
                );
            }
            for p in ys.windows(2) {
                assert!(
                    p[1].1 - p[0].1 >= 12.0,
                    "y labels overlap: {:?} {:?}",
                    p[0],
                    p[1]
                );
            }
        }
        // The many categories are thinned, the few all labelled.
        assert!(category_step(&many) > 1);
        assert_eq!(category_step(&few), 1);
    }

    #[test]
    fn log_ticks_are_round_and_few() {
        assert_eq!(
            log_ticks(0.9, 70.0, 10),
            vec![1.0, 2.0, 5.0, 10.0, 20.0, 50.0]
        );
        assert_eq!(log_ticks(1e-7, 2e-3, 8), vec![1e-7, 1e-6, 1e-5, 1e-4, 1e-3]);
        assert_eq!(
            log_ticks(1e-12, 1.0, 8),
            vec![1e-12, 1e-10, 1e-8, 1e-6, 1e-4, 1e-2, 1.0]
        );
        assert_eq!(log_ticks(2.1, 5.7, 10), vec![3.0, 4.0, 5.0]);
        assert_eq!(tick_label(1.0), "1");
        assert_eq!(tick_label(100.0), "100");
        assert_eq!(tick_label(0.002), "0.002");
        assert_eq!(tick_label(2e-7), "2e-7");
        assert_eq!(tick_label(123456.0), "1.23e5");
    }

    /// The texts of an SVG's `<text>` elements, trimmed, the empty ones left out.
    fn svg_texts(svg: &str) -> Vec<&str> {
        svg.split("</text>")
            .filter_map(|t| t.rsplit('>').next())
            .map(str::trim)
            .filter(|t| !t.is_empty())
            .collect()
    }

    #[test]
    fn a_narrow_linear_range_keeps_its_labels_apart() {
        // The SSIM of a sequence: 0.9972 … 0.9987 over the frames.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ssim.svg");
        let series = [Series {
            label: "ssim".into(),
            points: (0..64)
                .map(|f| (f as f64, 0.9972 + 0.0015 * (f as f64 / 10.0).sin().abs()))
                .collect(),
        }];
        let spec = PlotSpec {
            title: "SSIM",
            x_label: "frame",
            y_label: "ssim",
            log_x: false,
            log_y: false,
            x_categories: None,
        };
        line_plot_svg(&path, &spec, &series).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        let labels: Vec<&str> = svg_texts(&svg)
            .into_iter()
            .filter(|t| t.starts_with("0.99"))
            .collect();
        assert!(labels.len() >= 3, "{labels:?}");
        let mut sorted = labels.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), labels.len(), "repeated labels: {labels:?}");
        assert_eq!(span_label(0.9975, 0.002, 8), "0.9975");
        assert_eq!(span_label(0.998, 0.002, 8), "0.998");
        assert_eq!(span_label(250.0, 1000.0, 8), "250");
    }

    #[test]
    fn labels_do_not_repeat_or_crowd() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.svg");
        let series = [Series {
            label: "thesis".into(),
            points: vec![(1.0, 1e-3), (4.0, 2e-5), (16.0, 3e-7), (64.0, 1e-7)],
        }];
        let spec = PlotSpec {
            title: "t",
            x_label: "samples",
            y_label: "e",
            log_x: true,
            log_y: true,
            x_categories: None,
        };
        line_plot_svg(&path, &spec, &series).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        let labels = svg_texts(&svg);
        for l in ["1", "10", "1e-7", "0.001"] {
            assert!(labels.contains(&l), "{l} not in {labels:?}");
        }
        assert!(!labels.iter().any(|l| l.contains(".00e")), "{labels:?}");
        let mut sorted = labels.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), labels.len(), "repeated labels: {labels:?}");
        let categories = ["1".to_string(), "2".into(), "all".into()];
        let spec = PlotSpec {
            x_categories: Some(&categories),
            ..spec
        };
        let series = [Series {
            label: String::new(),
            points: vec![(0.0, 1e-3), (1.0, 1e-4), (2.0, 1e-5)],
        }];
        line_plot_svg(&path, &spec, &series).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.contains("all") && !svg.contains("4294967295"), "{svg}");
    }
}
