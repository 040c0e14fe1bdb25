//! Inline SVG drawing with `format!`: a plot area with linear axes and ticks, stems, points, and
//! pose directions on two orthographic hemispheres. Every text is escaped; no script, no network.

use std::fmt::Write as _;

use super::escape;

/// Width of every figure, px.
pub const WIDTH_PX: f64 = 720.0;
/// Height of a plot, px.
pub const HEIGHT_PX: f64 = 300.0;
/// Margins (left, right, top, bottom), px.
const MARGIN_PX: (f64, f64, f64, f64) = (64.0, 16.0, 28.0, 44.0);

/// Colour of the "before" series.
pub const BEFORE: &str = "#9a9a9a";
/// Colour of the "after" series.
pub const AFTER: &str = "#1f5fbf";
/// Colour of a pose left out of the fit.
pub const LEFT_OUT: &str = "#c62828";

/// A plot area mapping data coordinates to pixels.
#[derive(Debug, Clone, Copy)]
pub struct Axes {
    x_range: (f64, f64),
    y_range: (f64, f64),
    /// The x axis logarithmic (its range is then in log10 units).
    log_x: bool,
    /// The y axis logarithmic, likewise.
    log_y: bool,
    /// Numeric ticks on the x axis (off for categories labelled with [`Axes::x_label`]).
    x_ticks: bool,
}

impl Axes {
    /// Log-log axes spanning whole decades around the positive finite values of `xs` and `ys`.
    pub fn fit_log_log(xs: &[f64], ys: &[f64]) -> Self {
        Self { x_range: decades(xs), y_range: decades(ys), log_x: true, log_y: true, x_ticks: true }
    }

    /// A linear x axis spanning the finite `xs` (padded by 5 %), a logarithmic y axis spanning whole
    /// decades around the positive finite `ys`.
    pub fn fit_log_y(xs: &[f64], ys: &[f64]) -> Self {
        Self { x_range: pad(span(xs.iter().copied())), y_range: decades(ys), log_x: false, log_y: true, x_ticks: true }
    }

    /// Axes spanning the finite values of `xs` and `ys`, padded by 5 % (and `y` always including 0).
    pub fn fit(xs: &[f64], ys: &[f64]) -> Self {
        let y = span(ys.iter().copied().chain([0.0]));
        Self { x_range: pad(span(xs.iter().copied())), y_range: pad(y), log_x: false, log_y: false, x_ticks: true }
    }

    /// The same axes without numeric x ticks: categories, labelled with [`Axes::x_label`].
    pub fn categorical_x(self) -> Self {
        Self { x_ticks: false, ..self }
    }

    /// A category label under the x axis at `x`.
    pub fn x_label(&self, out: &mut String, x: f64, label: &str) {
        let _ = writeln!(
            out,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle" class="tick">{}</text>"#,
            self.px(x),
            HEIGHT_PX - MARGIN_PX.3 + 14.0,
            escape(label)
        );
    }

    /// A dashed vertical reference line at `x` (not data), labelled at its top.
    pub fn reference_x(&self, out: &mut String, x: f64, label: &str) {
        let (px, top, bottom) = (self.px(x), MARGIN_PX.2, HEIGHT_PX - MARGIN_PX.3);
        let _ = writeln!(
            out,
            r##"<line x1="{px:.1}" y1="{top}" x2="{px:.1}" y2="{bottom}" stroke="#c62828" stroke-dasharray="3 3"/><text x="{tx:.1}" y="{ty}" class="tick">{}</text>"##,
            escape(label),
            tx = px + 4.0,
            ty = top + 12.0,
        );
    }

    /// `(x, y)` can be drawn: finite, and positive on a logarithmic axis.
    pub fn shows(&self, x: f64, y: f64) -> bool {
        x.is_finite() && y.is_finite() && (!self.log_x || x > 0.0) && (!self.log_y || y > 0.0)
    }

    /// Pixel x of `x`.
    pub fn px(&self, x: f64) -> f64 {
        let (l, r, ..) = MARGIN_PX;
        let x = if self.log_x { x.log10() } else { x };
        l + (x - self.x_range.0) / (self.x_range.1 - self.x_range.0) * (WIDTH_PX - l - r)
    }

    /// Pixel y of `y`.
    pub fn py(&self, y: f64) -> f64 {
        let (.., t, b) = MARGIN_PX;
        let y = if self.log_y { y.log10() } else { y };
        HEIGHT_PX - b - (y - self.y_range.0) / (self.y_range.1 - self.y_range.0) * (HEIGHT_PX - t - b)
    }

    /// Opens an `<svg>` with the frame, ticks, grid, axis labels and title.
    pub fn open(&self, out: &mut String, title: &str, x_label: &str, y_label: &str) {
        let (l, r, t, b) = MARGIN_PX;
        let _ = write!(
            out,
            r##"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH_PX}" height="{HEIGHT_PX}" viewBox="0 0 {WIDTH_PX} {HEIGHT_PX}" role="img" aria-label="{title}">
<text x="{l}" y="18" class="title">{title}</text>
<rect x="{l}" y="{t}" width="{w}" height="{h}" fill="none" stroke="#444"/>
"##,
            title = escape(title),
            w = WIDTH_PX - l - r,
            h = HEIGHT_PX - t - b,
        );
        self.ticks(out);
        let _ = write!(
            out,
            r#"<text x="{x}" y="{y}" text-anchor="middle">{x_label}</text>
<text transform="translate(14 {ym}) rotate(-90)" text-anchor="middle">{y_label}</text>
"#,
            x = (l + WIDTH_PX - r) / 2.0,
            y = HEIGHT_PX - 8.0,
            ym = (t + HEIGHT_PX - b) / 2.0,
            x_label = escape(x_label),
            y_label = escape(y_label),
        );
    }

    fn ticks(&self, out: &mut String) {
        let (l, r, t, b) = MARGIN_PX;
        let x_ticks = if self.x_ticks { tick_values(self.x_range, self.log_x) } else { Vec::new() };
        for x in x_ticks {
            let px = self.px(x);
            let _ = writeln!(
                out,
                r##"<line x1="{px:.1}" y1="{t}" x2="{px:.1}" y2="{y2}" stroke="#e4e4e4"/><text x="{px:.1}" y="{ty}" text-anchor="middle" class="tick">{x}</text>"##,
                y2 = HEIGHT_PX - b,
                ty = HEIGHT_PX - b + 14.0,
                x = tick_label(x),
            );
        }
        for y in tick_values(self.y_range, self.log_y) {
            let py = self.py(y);
            let _ = writeln!(
                out,
                r##"<line x1="{l}" y1="{py:.1}" x2="{x2}" y2="{py:.1}" stroke="{c}"/><text x="{tx}" y="{ty:.1}" text-anchor="end" class="tick">{y}</text>"##,
                x2 = WIDTH_PX - r,
                c = if y == 0.0 { "#888" } else { "#e4e4e4" },
                tx = l - 4.0,
                ty = py + 4.0,
                y = tick_label(y),
            );
        }
    }

    /// A polyline through the points with positive coordinates (log axes) or finite ones.
    pub fn polyline(&self, out: &mut String, points: &[(f64, f64)], colour: &str, dashed: bool) {
        let coords: Vec<String> = points
            .iter()
            .filter(|(x, y)| self.shows(*x, *y))
            .map(|(x, y)| format!("{:.1},{:.1}", self.px(*x), self.py(*y)))
            .collect();
        let dash = if dashed { r#" stroke-dasharray="5 4""# } else { "" };
        let _ = writeln!(
            out,
            r#"<polyline class="datum" points="{}" fill="none" stroke="{colour}" stroke-width="2"{dash}/>"#,
            coords.join(" ")
        );
    }

    /// A vertical stem from 0 to `y` at `x`, with a dot at its tip.
    pub fn stem(&self, out: &mut String, x: f64, y: f64, colour: &str, tip: &str) {
        let (px, p0, py) = (self.px(x), self.py(0.0), self.py(y));
        let _ = writeln!(
            out,
            r#"<g class="stem datum"><title>{tip}</title><line x1="{px:.1}" y1="{p0:.1}" x2="{px:.1}" y2="{py:.1}" stroke="{colour}" stroke-width="2"/><circle cx="{px:.1}" cy="{py:.1}" r="3" fill="{colour}"/></g>"#,
            tip = escape(tip),
        );
    }

    /// A dot at `(x, y)`.
    pub fn dot(&self, out: &mut String, x: f64, y: f64, colour: &str, tip: &str) {
        let _ = writeln!(
            out,
            r#"<circle class="datum" cx="{:.1}" cy="{:.1}" r="3.5" fill="{colour}"><title>{}</title></circle>"#,
            self.px(x),
            self.py(y),
            escape(tip),
        );
    }
}

/// A legend entry at the top right, `row` from 0.
pub fn legend(out: &mut String, row: usize, colour: &str, label: &str) {
    let (x, y) = (WIDTH_PX - MARGIN_PX.1 - 150.0, MARGIN_PX.2 + 14.0 + 16.0 * row as f64);
    let _ = writeln!(
        out,
        r#"<circle cx="{x}" cy="{cy}" r="4" fill="{colour}"/><text x="{tx}" y="{y}" class="tick">{}</text>"#,
        escape(label),
        cy = y - 4.0,
        tx = x + 8.0,
    );
}

/// Tick values in data units: round values, or every decade on a log axis.
fn tick_values(range: (f64, f64), log: bool) -> Vec<f64> {
    if log { (range.0 as i32..=range.1 as i32).map(|k| 10f64.powi(k)).collect() } else { nice_ticks(range) }
}

/// Whole decades (log10 units) around the positive finite values.
fn decades(values: &[f64]) -> (f64, f64) {
    let (lo, hi) = span(values.iter().filter(|x| **x > 0.0).map(|x| x.log10()));
    (lo.floor(), hi.ceil().max(lo.floor() + 1.0))
}

/// The smallest and largest finite value, `(0, 1)` when there is none.
fn span(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) =
        values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) }
}

/// `range` widened by 5 % each side (by 1 when it is a single value).
fn pad((lo, hi): (f64, f64)) -> (f64, f64) {
    let d = if hi > lo { (hi - lo) * 0.05 } else { 1.0 };
    (lo - d, hi + d)
}

/// About six round tick values (1, 2 or 5 times a power of ten apart) within `range`.
pub fn nice_ticks((lo, hi): (f64, f64)) -> Vec<f64> {
    let raw = (hi - lo) / 6.0;
    if !(raw > 0.0) || !raw.is_finite() {
        return Vec::new();
    }
    let power = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0].into_iter().map(|m| m * power).find(|s| *s >= raw).unwrap_or(10.0 * power);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// A tick value without float noise (`0.30000000000000004` is `0.3`; decades far from 1 as `1e-4`).
fn tick_label(v: f64) -> String {
    if v != 0.0 && !(1e-3..1e5).contains(&v.abs()) {
        return format!("{v:e}");
    }
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

/// Radius of a hemisphere disc, px.
const SPHERE_R_PX: f64 = 130.0;

/// One pose direction for [`hemispheres`].
pub struct Direction {
    /// Unit vector.
    pub unit: [f64; 3],
    /// Dot colour.
    pub colour: &'static str,
    /// Tooltip.
    pub tip: String,
}

/// Pose directions on two orthographic hemispheres: the upper one seen from +z (x right, y up), the
/// lower one seen from -z (x mirrored so that it reads as from below).
pub fn hemispheres(out: &mut String, title: &str, directions: &[Direction]) {
    let h = 2.0 * SPHERE_R_PX + 70.0;
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH_PX}" height="{h}" viewBox="0 0 {WIDTH_PX} {h}" role="img" aria-label="{t}"><text x="{l}" y="18" class="title">{t}</text>"#,
        t = escape(title),
        l = MARGIN_PX.0,
    );
    for (k, (label, sign)) in
        [("upper hemisphere (z > 0), seen from +z", 1.0), ("lower hemisphere (z < 0), seen from -z", -1.0)]
            .into_iter()
            .enumerate()
    {
        let (cx, cy) = (WIDTH_PX / 4.0 * (1.0 + 2.0 * k as f64), SPHERE_R_PX + 36.0);
        disc(out, cx, cy, label);
        for d in directions.iter().filter(|d| (d.unit[2] >= 0.0) == (sign > 0.0)) {
            let (x, y) = (cx + sign * d.unit[0] * SPHERE_R_PX, cy - d.unit[1] * SPHERE_R_PX);
            let _ = writeln!(
                out,
                r#"<circle class="datum" cx="{x:.1}" cy="{y:.1}" r="4" fill="{}"><title>{}</title></circle>"#,
                d.colour,
                escape(&d.tip)
            );
        }
    }
    out.push_str("</svg>\n");
}

/// A hemisphere's outline, its x/y axes and its caption.
fn disc(out: &mut String, cx: f64, cy: f64, label: &str) {
    let r = SPHERE_R_PX;
    let _ = writeln!(
        out,
        r##"<circle cx="{cx}" cy="{cy}" r="{r}" fill="#f6f8fb" stroke="#444"/><circle cx="{cx}" cy="{cy}" r="{r2:.1}" fill="none" stroke="#ddd"/><line x1="{x0}" y1="{cy}" x2="{x1}" y2="{cy}" stroke="#ccc"/><line x1="{cx}" y1="{y0}" x2="{cx}" y2="{y1}" stroke="#ccc"/><text x="{cx}" y="{ty}" text-anchor="middle" class="tick">{}</text>"##,
        escape(label),
        r2 = r * std::f64::consts::FRAC_1_SQRT_2,
        x0 = cx - r,
        x1 = cx + r,
        y0 = cy - r,
        y1 = cy + r,
        ty = cy + r + 20.0,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_inside_the_range() {
        assert_eq!(nice_ticks((0.0, 12.0)), vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0, 12.0]);
        let t = nice_ticks((-0.37, 0.52));
        assert!(t.iter().all(|v| (-0.37..=0.52).contains(v)) && t.len() >= 4, "{t:?}");
        assert!(nice_ticks((1.0, 1.0)).is_empty());
        assert_eq!(tick_label(0.1 + 0.2), "0.3");
        assert_eq!(tick_label(1e-4), "1e-4");
    }

    #[test]
    fn log_y_axes_keep_x_linear_and_leave_out_non_positive_y() {
        let a = Axes::fit_log_y(&[0.0, 100.0], &[1e-5, 0.02, 0.0]);
        assert_eq!(a.y_range, (-5.0, -1.0));
        assert!(!a.log_x && a.log_y);
        assert!((a.px(50.0) - (a.px(0.0) + a.px(100.0)) / 2.0).abs() < 1e-9, "x is linear");
        assert!(!a.shows(10.0, 0.0) && a.shows(10.0, 1e-3) && !a.shows(f64::NAN, 1.0));
        let ticks = tick_values(a.y_range, a.log_y);
        let expected = [1e-5, 1e-4, 1e-3, 1e-2, 1e-1];
        assert_eq!(ticks.len(), expected.len());
        assert!(ticks.iter().zip(expected).all(|(t, e)| (t / e - 1.0).abs() < 1e-12), "{ticks:?}");
    }

    #[test]
    fn log_log_axes_span_whole_decades_with_a_tick_each() {
        let a = Axes::fit_log_log(&[0.02, 30.0], &[0.003, 0.8, -1.0]);
        assert_eq!((a.x_range, a.y_range), ((-2.0, 2.0), (-3.0, 0.0)));
        assert_eq!(tick_values(a.x_range, a.log_x), vec![0.01, 0.1, 1.0, 10.0, 100.0]);
        let (p1, p10, p100) = (a.px(1.0), a.px(10.0), a.px(100.0));
        assert!(((p10 - p1) - (p100 - p10)).abs() < 1e-9, "a decade is the same width everywhere");
    }

    #[test]
    fn axes_map_the_range_into_the_plot_area() {
        let a = Axes::fit(&[0.0, 10.0], &[-1.0, 2.0]);
        assert!(a.px(0.0) > MARGIN_PX.0 && a.px(10.0) < WIDTH_PX - MARGIN_PX.1);
        assert!(a.py(2.0) < a.py(0.0) && a.py(-1.0) < HEIGHT_PX - MARGIN_PX.3);
    }
}
