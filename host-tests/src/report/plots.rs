//! SVG line charts (plotters) for the figure files (`paper --out`, `diagnose --plots`), on linear or
//! true logarithmic axes (decade ticks labelled with the values, not their logarithms).

use std::path::Path;

use plotters::coord::ranged1d::ValueFormatter;
use plotters::prelude::*;

/// One named series of `(x, y)` points.
pub struct Series<'a> {
    /// Legend label.
    pub name: &'a str,
    /// The points.
    pub points: Vec<(f64, f64)>,
}

/// How the axes map the values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Both axes linear.
    Linear,
    /// Linear x, logarithmic y (non-positive y left out).
    LogY,
    /// Both axes logarithmic (non-positive x or y left out).
    LogLog,
}

impl Scale {
    /// The point can be drawn: finite, and positive on a logarithmic axis.
    fn shows(self, (x, y): (f64, f64)) -> bool {
        let positive = match self {
            Self::Linear => true,
            Self::LogY => y > 0.0,
            Self::LogLog => x > 0.0 && y > 0.0,
        };
        x.is_finite() && y.is_finite() && positive
    }
}

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// The x and y ranges of the points `scale` can draw (a linear y padded by 5 %), `None` without any.
fn extent(series: &[Series<'_>], scale: Scale) -> Option<((f64, f64), (f64, f64))> {
    let mut xs = (f64::INFINITY, f64::NEG_INFINITY);
    let mut ys = (f64::INFINITY, f64::NEG_INFINITY);
    for &(x, y) in series.iter().flat_map(|s| &s.points).filter(|p| scale.shows(**p)) {
        xs = (xs.0.min(x), xs.1.max(x));
        ys = (ys.0.min(y), ys.1.max(y));
    }
    if !(xs.0.is_finite() && ys.0.is_finite()) {
        return None;
    }
    let widen = |(lo, hi): (f64, f64), log: bool| match log {
        true if hi <= lo * 1.000_001 => (lo / 2.0, hi * 2.0),
        true => (lo, hi),
        false if hi - lo < 1e-12 => (lo - 1.0, hi + 1.0),
        false => (lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo)),
    };
    let xs = if scale == Scale::LogLog { widen(xs, true) } else { (xs.0, xs.1.max(xs.0 + 1e-9)) };
    Some((xs, widen(ys, scale != Scale::Linear)))
}

/// Draws `series` as lines into the SVG file `path` on `scale`'s axes.
pub fn line_chart(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series<'_>],
    scale: Scale,
) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let (xs, ys) = extent(series, scale).ok_or_else(|| err(&"nothing to plot"))?;
    let root = SVGBackend::new(path, (800, 500)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut builder = ChartBuilder::on(&root);
    builder.caption(title, ("sans-serif", 20)).margin(12).x_label_area_size(40).y_label_area_size(70);
    let chart = Chart { labels: (x_label, y_label), series, scale };
    let drawn = match scale {
        Scale::Linear => builder.build_cartesian_2d(xs.0..xs.1, ys.0..ys.1).map(|c| chart.draw(c)),
        Scale::LogY => builder.build_cartesian_2d(xs.0..xs.1, (ys.0..ys.1).log_scale()).map(|c| chart.draw(c)),
        Scale::LogLog => {
            builder.build_cartesian_2d((xs.0..xs.1).log_scale(), (ys.0..ys.1).log_scale()).map(|c| chart.draw(c))
        }
    };
    drawn.map_err(|e| err(&e))?.map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))
}

/// A tick label: six significant digits without float noise (`0.7000000000001` is `0.7`), decades
/// far from 1 as `1e-5`.
fn tick(v: &f64) -> String {
    let rounded: f64 = format!("{v:.5e}").parse().unwrap_or(*v);
    if rounded != 0.0 && !(1e-3..1e5).contains(&rounded.abs()) { format!("{rounded:e}") } else { format!("{rounded}") }
}

/// What a chart draws on its axes.
struct Chart<'a> {
    labels: (&'a str, &'a str),
    series: &'a [Series<'a>],
    scale: Scale,
}

impl Chart<'_> {
    /// The mesh, the lines and the legend on axes `X`, `Y`.
    fn draw<'b, X, Y>(&self, mut chart: ChartContext<'b, SVGBackend<'b>, Cartesian2d<X, Y>>) -> Result<(), String>
    where
        X: Ranged<ValueType = f64> + ValueFormatter<f64>,
        Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let text = |e: &dyn std::fmt::Display| e.to_string();
        let mut mesh = chart.configure_mesh();
        mesh.x_desc(self.labels.0).y_desc(self.labels.1).x_label_formatter(&tick).y_label_formatter(&tick);
        mesh.draw().map_err(|e| text(&e))?;
        for (i, s) in self.series.iter().enumerate() {
            let color = COLORS[i % COLORS.len()];
            let points: Vec<(f64, f64)> = s.points.iter().copied().filter(|p| self.scale.shows(*p)).collect();
            chart
                .draw_series(LineSeries::new(points, color.stroke_width(2)))
                .map_err(|e| text(&e))?
                .label(s.name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
        }
        let mut labels = chart.configure_series_labels();
        labels.background_style(WHITE.mix(0.8)).border_style(BLACK).draw().map_err(|e| text(&e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_read_without_float_noise() {
        assert_eq!(tick(&0.700_000_000_000_1), "0.7");
        assert_eq!(tick(&9.999_999_999_999e-6), "1e-5");
        assert_eq!(tick(&20.0), "20");
        assert_eq!(tick(&0.0), "0");
    }

    #[test]
    fn log_scales_leave_out_what_they_cannot_draw() {
        let series = [Series { name: "s", points: vec![(0.0, 1.0), (1.0, 0.0), (2.0, 10.0), (4.0, 100.0)] }];
        assert_eq!(extent(&series, Scale::LogLog), Some(((2.0, 4.0), (10.0, 100.0))));
        assert_eq!(extent(&series, Scale::LogY), Some(((0.0, 4.0), (1.0, 100.0))));
        let (_, linear_y) = extent(&series, Scale::Linear).unwrap();
        assert_eq!(linear_y, (-5.0, 105.0), "padded by 5 %");
        assert_eq!(extent(&[Series { name: "z", points: vec![(1.0, 0.0)] }], Scale::LogY), None);
    }
}
