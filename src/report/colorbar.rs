//! Colour bars as SVG with real text (docs/design.md §5: "error heatmap with a colour bar and its
//! scale"): a vertical gradient of the colour map from the scale's bottom to its top, framed,
//! with tick marks and labels that a browser sets in its own font (sharp at any zoom, readable
//! by screen readers and searchable), inlined into the report beside each heatmap.

use super::colormap::{ColorMap, Scale};
use super::plot::tick_label;
use std::fmt::Write as _;

/// Gradient stops of the bar: enough that the piecewise-linear gradient is within one 8-bit
/// step of the 256-entry colour map for magma and viridis.
const STOPS: usize = 33;
/// Labelled ticks on the bar (bottom, quarter, middle, three quarters, top).
const TICKS: usize = 5;
/// The bar's geometry in SVG user units (pixels at 100 % zoom).
const BAR_X: f64 = 4.0;
const BAR_W: f64 = 16.0;
const BAR_TOP: f64 = 8.0;
const BAR_H: f64 = 184.0;
const FONT_PX: f64 = 12.0;

/// The colour bar of `scale` on `cmap` as an inline `<svg>` element (class `colorbar`), with
/// `title` as its accessible name. The top of the bar is `scale.hi`, the bottom `scale.lo`;
/// the labels are [`tick_label`]s (three significant digits) of evenly spaced values.
pub fn colorbar_svg(scale: Scale, cmap: ColorMap, title: &str, id: &str) -> String {
    let labels: Vec<(f64, String)> = (0..TICKS)
        .map(|i| {
            let t = i as f64 / (TICKS - 1) as f64;
            (t, tick_label(scale.lo + t * (scale.hi - scale.lo)))
        })
        .collect();
    // Width: the bar, the tick, and the longest label at ~0.62 em per character.
    let chars = labels
        .iter()
        .map(|(_, l)| l.chars().count())
        .max()
        .unwrap_or(1);
    let width = (BAR_X + BAR_W + 6.0 + chars as f64 * 0.62 * FONT_PX + 4.0).ceil();
    let height = BAR_TOP * 2.0 + BAR_H;
    let mut s = String::new();
    let _ = write!(
        s,
        "<svg class=\"colorbar\" xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" viewBox=\"0 0 {width} {height}\" role=\"img\" aria-label=\"{}\">",
        super::text::escape(title)
    );
    let _ = write!(
        s,
        "<defs><linearGradient id=\"{id}\" x1=\"0\" y1=\"1\" x2=\"0\" y2=\"0\">"
    );
    for i in 0..STOPS {
        let t = i as f64 / (STOPS - 1) as f64;
        let [r, g, b] = cmap.at(t);
        let _ = write!(
            s,
            "<stop offset=\"{:.4}\" stop-color=\"#{r:02x}{g:02x}{b:02x}\"/>",
            t
        );
    }
    s += "</linearGradient></defs>";
    let _ = write!(
        s,
        "<rect x=\"{BAR_X}\" y=\"{BAR_TOP}\" width=\"{BAR_W}\" height=\"{BAR_H}\" fill=\"url(#{id})\" stroke=\"#000\" stroke-width=\"1\"/>"
    );
    for (t, label) in &labels {
        let y = BAR_TOP + (1.0 - t) * BAR_H;
        let x0 = BAR_X + BAR_W;
        let _ = write!(
            s,
            "<line x1=\"{x0}\" y1=\"{y:.2}\" x2=\"{:.2}\" y2=\"{y:.2}\" stroke=\"#000\"/><text x=\"{:.2}\" y=\"{y:.2}\" dominant-baseline=\"middle\" font-family=\"sans-serif\" font-size=\"{FONT_PX}\">{}</text>",
            x0 + 4.0,
            x0 + 6.0,
            super::text::escape(label)
        );
    }
    s += "</svg>";
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bar_has_gradient_and_labelled_ticks() {
        let svg = colorbar_svg(
            Scale { lo: 0.0, hi: 0.01 },
            ColorMap::Magma,
            "abs error",
            "g1",
        );
        assert!(svg.starts_with("<svg class=\"colorbar\"") && svg.ends_with("</svg>"));
        // Ends of the gradient are the colour map's ends: magma(0) at offset 0 (the bottom,
        // y1 = 1), magma(1) at offset 1 (the top).
        assert!(svg.contains("<stop offset=\"0.0000\" stop-color=\"#000004\"/>"));
        assert!(svg.contains("<stop offset=\"1.0000\" stop-color=\"#fcfdbf\"/>"));
        assert!(svg.contains("fill=\"url(#g1)\""));
        let texts: Vec<&str> = svg
            .split("</text>")
            .filter_map(|t| t.rsplit('>').next())
            .filter(|t| !t.is_empty())
            .collect();
        assert_eq!(texts, ["0", "0.0025", "0.005", "0.0075", "0.01"]);
        // The top label (0.01) sits at the top of the bar, the bottom one at its bottom.
        assert!(svg.contains(&format!("y=\"{:.2}\" dominant-baseline=\"middle\" font-family=\"sans-serif\" font-size=\"12\">0.01<", BAR_TOP)));
        assert!(svg.contains(&format!(
            "y=\"{:.2}\" dominant-baseline=\"middle\" font-family=\"sans-serif\" font-size=\"12\">0<",
            BAR_TOP + BAR_H
        )));
    }

    #[test]
    fn wide_labels_widen_the_bar() {
        let narrow = colorbar_svg(Scale { lo: 0.0, hi: 1.0 }, ColorMap::Viridis, "", "a");
        let wide = colorbar_svg(
            Scale {
                lo: 0.0,
                hi: 1.234e-7,
            },
            ColorMap::Viridis,
            "",
            "b",
        );
        let width = |s: &str| -> f64 {
            let w = s.split("width=\"").nth(1).unwrap();
            w[..w.find('"').unwrap()].parse().unwrap()
        };
        assert!(width(&wide) > width(&narrow) + 20.0);
        assert!(wide.contains(">1.23e-7</text>"));
    }
}
