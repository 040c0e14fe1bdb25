//! SVG line charts (plotters) for the reports.

use std::path::Path;

use plotters::prelude::*;

/// One named series of `(x, y)` points.
pub struct Series<'a> {
    /// Legend label.
    pub name: &'a str,
    /// The points.
    pub points: Vec<(f64, f64)>,
}

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// Draws `series` as lines into the SVG file `path`; `log_y` plots log10 of y (non-positive values
/// are left out).
pub fn line_chart(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series<'_>],
    log_y: bool,
) -> Result<(), String> {
    let transform = |y: f64| if log_y { if y > 0.0 { Some(y.log10()) } else { None } } else { Some(y) };
    let mut xs = (f64::INFINITY, f64::NEG_INFINITY);
    let mut ys = (f64::INFINITY, f64::NEG_INFINITY);
    for s in series {
        for &(x, y) in &s.points {
            if let Some(y) = transform(y).filter(|v| v.is_finite()) {
                xs = (xs.0.min(x), xs.1.max(x));
                ys = (ys.0.min(y), ys.1.max(y));
            }
        }
    }
    if !(xs.0.is_finite() && ys.0.is_finite()) {
        return Err(format!("{}: nothing to plot", path.display()));
    }
    if ys.1 - ys.0 < 1e-12 {
        ys = (ys.0 - 1.0, ys.1 + 1.0);
    }
    let pad = 0.05 * (ys.1 - ys.0);
    let root = SVGBackend::new(path, (800, 500)).into_drawing_area();
    let err = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let y_desc = if log_y { format!("log10 {y_label}") } else { y_label.to_string() };
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(xs.0..xs.1.max(xs.0 + 1e-9), (ys.0 - pad)..(ys.1 + pad))
        .map_err(|e| err(&e))?;
    chart.configure_mesh().x_desc(x_label).y_desc(y_desc).draw().map_err(|e| err(&e))?;
    for (i, s) in series.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        let points: Vec<(f64, f64)> =
            s.points.iter().filter_map(|&(x, y)| transform(y).filter(|v| v.is_finite()).map(|y| (x, y))).collect();
        chart
            .draw_series(LineSeries::new(points, color.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label(s.name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw().map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))
}
