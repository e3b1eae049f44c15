//! The report's plots, each written as `<stem>.png` and `<stem>.svg` (docs/formats.md, `run`
//! outputs).
//!
//! Every function takes already-computed numbers (plots only read results), skips
//! non-finite values, and draws an empty chart carrying its title when nothing is left to
//! draw; it never panics on its data. Output is deterministic: the same data gives the same
//! bytes (text is laid out with the bundled DejaVu Sans, no system fonts; see
//! `notes/plotters-fonts.md`).

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::chart::MeshStyle;
use plotters::coord::ranged1d::{AsRangedCoord, DefaultFormatting, KeyPointHint, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{register_font, FontStyle, FontTransform};

use super::markdown::fmt_num;
use crate::numeric::Real;
use crate::{Error, Result};

/// Size of every plot in pixels (PNG) or user units (SVG), width × height.
pub const PLOT_SIZE: (u32, u32) = (960, 600);

/// The font family under which the bundled DejaVu Sans is registered.
const FAMILY: &str = "sans-serif";

/// DejaVu Sans (Bitstream Vera licence, see `assets/DejaVuSans-LICENSE.txt`); covers the
/// Greek letters of the parameter names (θ, α, β, η).
static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// Colours of successive series (the "tab10" palette), so method colours stay the same from
/// one plot to the next.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

fn color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// Registers the bundled font as family `sans-serif`, once per process.
fn fonts() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    if *REGISTERED.get_or_init(|| register_font(FAMILY, FontStyle::Normal, FONT).is_ok()) {
        Ok(())
    } else {
        Err(Error::Compute(
            "the bundled font assets/DejaVuSans.ttf could not be loaded".into(),
        ))
    }
}

/// `<stem>.<ext>`, appending (a stem such as `eta.v2` keeps its dot).
fn with_suffix(stem: &Path, ext: &str) -> PathBuf {
    let mut s = stem.as_os_str().to_owned();
    s.push(".");
    s.push(ext);
    PathBuf::from(s)
}

/// The result of drawing on back end `DB`: `T` (nothing by default) or the back end's error.
type DrawResult<DB, T = ()> =
    std::result::Result<T, DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// A figure that can be drawn on any plotters back end (so one description gives both the
/// PNG and the SVG).
trait Figure {
    /// Draws the figure on `root`, already filled white.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB>;
}

/// Fills `root` white and draws `fig` on it.
fn paint<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, fig: &impl Figure) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    fig.draw(root)
}

/// Draws `fig` to `<stem>.svg` and `<stem>.png`.
fn render(stem: &Path, fig: &impl Figure) -> Result<()> {
    fonts()?;
    let svg_path = with_suffix(stem, "svg");
    let png_path = with_suffix(stem, "png");
    let cannot = |path: &Path, e: &dyn std::fmt::Display| {
        Error::Compute(format!("{}: cannot draw the plot: {e}", path.display()))
    };

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, PLOT_SIZE).into_drawing_area();
        paint(&root, fig).map_err(|e| cannot(&svg_path, &e))?;
        root.present().map_err(|e| cannot(&svg_path, &e))?;
    }
    std::fs::write(&svg_path, svg.as_bytes()).map_err(|e| Error::io(&svg_path, e))?;

    let root = BitMapBackend::new(&png_path, PLOT_SIZE).into_drawing_area();
    paint(&root, fig).map_err(|e| cannot(&png_path, &e))?;
    root.present()
        .map_err(|e| Error::io(&png_path, std::io::Error::other(e.to_string())))?;
    Ok(())
}

/// The finite values of `v`.
fn finite(v: &[Real]) -> impl Iterator<Item = Real> + '_ {
    v.iter().copied().filter(|x| x.is_finite())
}

/// A padded axis range over the finite values of `values` (and 0 when `include_zero`);
/// `0..1` when there are none.
fn span(values: impl Iterator<Item = Real>, include_zero: bool) -> Range<Real> {
    let (mut lo, mut hi) = (Real::INFINITY, Real::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if include_zero {
        lo = lo.min(0.0);
        hi = hi.max(0.0);
    }
    if lo > hi {
        return 0.0..1.0;
    }
    let width = hi - lo;
    if !width.is_finite() {
        return lo.max(-Real::MAX / 4.0)..hi.min(Real::MAX / 4.0);
    }
    if width <= 1e-12 * hi.abs().max(lo.abs()).max(1e-300) {
        let d = (hi.abs() * 0.1).max(1e-9);
        return lo - d..hi + d;
    }
    let pad = 0.05 * width;
    let lo = if include_zero && lo == 0.0 {
        0.0
    } else {
        lo - pad
    };
    let hi = if include_zero && hi == 0.0 {
        0.0
    } else {
        hi + pad
    };
    lo..hi
}

/// A padded logarithmic range over the positive finite values; `1..10` when there are none.
fn log_span(values: impl Iterator<Item = Real>) -> Range<Real> {
    let (mut lo, mut hi) = (Real::INFINITY, Real::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return 1.0..10.0;
    }
    if hi <= lo * (1.0 + 1e-9) {
        return lo / 2.0..hi * 2.0;
    }
    let f = (hi / lo).powf(0.05);
    (lo / f).max(Real::MIN_POSITIVE)..(hi * f).min(Real::MAX)
}

/// A categorical axis: category `i` sits at `i` on `-0.5 .. n-0.5`, with one tick (and label)
/// per category, so bars and boxes can be placed at fractional offsets within a category.
#[derive(Clone, Copy)]
struct Categories {
    n: usize,
}

impl Ranged for Categories {
    type FormatOption = DefaultFormatting;
    type ValueType = Real;

    fn map(&self, value: &Real, limit: (i32, i32)) -> i32 {
        let r = self.range();
        let t = (value - r.start) / (r.end - r.start);
        limit.0 + (t * f64::from(limit.1 - limit.0)).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<Real> {
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            (0..self.n).map(|i| i as Real).collect()
        }
    }

    fn range(&self) -> Range<Real> {
        -0.5..(self.n.max(1) as Real - 0.5)
    }
}

/// The category name at an axis position (blank between categories).
fn category_label(names: &[String], v: Real) -> String {
    let i = v.round();
    if (v - i).abs() > 1e-6 || i < 0.0 {
        return String::new();
    }
    names.get(i as usize).cloned().unwrap_or_default()
}

/// Bottom label-area height and label style for category names: rotated when there are many
/// or long ones (a 6-DOF robot has some 30 parameters).
fn category_label_layout(names: &[String]) -> (u32, bool) {
    let longest = names.iter().map(|s| s.chars().count()).max().unwrap_or(0);
    let rotate = names.len() * (longest + 2) > 90;
    if rotate {
        (24 + 8 * longest.min(40) as u32, true)
    } else {
        (50, false)
    }
}

/// Caption, margins and label areas common to every plot.
fn chart_builder<'a, 'b, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    x_area: u32,
) -> ChartBuilder<'a, 'b, DB> {
    let mut b = ChartBuilder::on(root);
    b.caption(title, (FAMILY, 26))
        .margin(16)
        .x_label_area_size(x_area)
        .y_label_area_size(80);
    b
}

/// Draws the legend when there is at least one series.
fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    any: bool,
) -> DrawResult<DB> {
    if !any {
        return Ok(());
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.5))
        .label_font((FAMILY, 15))
        .draw()
}

fn y_fmt(v: &Real) -> String {
    fmt_num(*v, 3)
}

/// Integer tick labels (point or iteration numbers); blank between integers.
fn int_fmt(v: &Real) -> String {
    let r = v.round();
    if (v - r).abs() < 1e-6 {
        format!("{}", r as i64)
    } else {
        String::new()
    }
}

/// The fraction of the plot height kept free at the top for a legend of `entries` lines.
fn legend_fraction(entries: usize) -> Real {
    if entries == 0 {
        0.0
    } else {
        ((entries as Real * 22.0 + 24.0) / 470.0).min(0.5)
    }
}

/// Raises the top of a linear range so the data stay below a legend of `entries` lines.
fn with_headroom(r: Range<Real>, entries: usize) -> Range<Real> {
    let f = legend_fraction(entries);
    let hi = r.start + (r.end - r.start) / (1.0 - f);
    r.start..if hi.is_finite() { hi } else { r.end }
}

/// The same for a logarithmic range (headroom in decades).
fn with_log_headroom(r: Range<Real>, entries: usize) -> Range<Real> {
    let f = legend_fraction(entries);
    let hi = r.start * (r.end / r.start).powf(1.0 / (1.0 - f));
    r.start..if hi.is_finite() { hi } else { r.end }
}

/// Writes category names under a categorical x axis, turned a quarter turn so that long
/// lists fit: each name starts just below its tick and runs downwards. (plotters centres a
/// rotated axis label on its tick, which puts half of it over the plot.)
fn rotated_category_labels<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    chart: &ChartContext<'_, DB, Cartesian2d<Categories, RangedCoordf64>>,
    names: &[String],
    y_bottom: Real,
) -> DrawResult<DB> {
    let style = TextStyle::from((FAMILY, 14).into_font())
        .transform(FontTransform::Rotate90)
        .pos(Pos::new(HPos::Left, VPos::Center))
        .color(&BLACK);
    for (i, name) in names.iter().enumerate() {
        let (px, py) = chart.backend_coord(&(i as Real, y_bottom));
        root.draw_text(name, &style, (px, py + 10))?;
    }
    Ok(())
}

/// The mesh every chart shares, ready for what is particular to one chart before `draw`:
/// tick labels by `x_fmt` and [`y_fmt`], `y_desc` along the y axis, the common fonts.
fn styled_mesh<'a, 'b, DB, X, Y>(
    chart: &'b mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    x_fmt: &'b dyn Fn(&Real) -> String,
    y_desc: &str,
) -> MeshStyle<'a, 'b, X, Y, DB>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = Real> + ValueFormatter<Real>,
    Y: Ranged<ValueType = Real> + ValueFormatter<Real>,
{
    let mut mesh = chart.configure_mesh();
    mesh.x_label_formatter(x_fmt)
        .y_label_formatter(&y_fmt)
        .y_desc(y_desc)
        .axis_desc_style((FAMILY, 17))
        .label_style((FAMILY, 14));
    mesh
}

/// A chart of `n` categories along x (named by `names`, blank past the names) over the y
/// range `y`, with its mesh drawn: the names stand under their ticks, or run downwards from
/// them when there are many or long ones ([`category_label_layout`]).
fn categorical_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    y_label: &str,
    names: &[String],
    n: usize,
    y: Range<Real>,
) -> DrawResult<DB, ChartContext<'a, DB, Cartesian2d<Categories, RangedCoordf64>>> {
    let (x_area, rotate) = category_label_layout(names);
    let y_bottom = y.start;
    let mut chart = chart_builder(root, title, x_area).build_cartesian_2d(Categories { n }, y)?;
    let x_fmt = |v: &Real| {
        if rotate {
            String::new()
        } else {
            category_label(names, *v)
        }
    };
    styled_mesh(&mut chart, &x_fmt, y_label)
        .disable_x_mesh()
        .x_labels(n.max(1))
        .draw()?;
    if rotate {
        rotated_category_labels(root, &chart, names, y_bottom)?;
    }
    Ok(chart)
}

// ---------------------------------------------------------------------------------------------
// Grouped bars

struct GroupedBars<'d> {
    title: &'d str,
    y_label: &'d str,
    categories: &'d [String],
    series: &'d [(String, Vec<Real>)],
}

impl Figure for GroupedBars<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let n = self
            .series
            .iter()
            .map(|(_, v)| v.len())
            .max()
            .unwrap_or(0)
            .max(self.categories.len());
        let y = with_headroom(
            span(self.series.iter().flat_map(|(_, v)| finite(v)), true),
            self.series.len(),
        );
        let mut chart = categorical_chart(root, self.title, self.y_label, self.categories, n, y)?;

        let m = self.series.len().max(1) as Real;
        let w = 0.8 / m;
        for (s, (name, values)) in self.series.iter().enumerate() {
            let c = color(s);
            let x0 = -0.4 + s as Real * w;
            chart
                .draw_series(
                    values
                        .iter()
                        .enumerate()
                        .filter(|(_, v)| v.is_finite())
                        .map(|(i, &v)| {
                            let left = i as Real + x0;
                            Rectangle::new([(left, 0.0), (left + w, v)], c.filled())
                        }),
                )?
                .label(name.as_str())
                .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 14, y + 6)], c.filled()));
        }
        legend(&mut chart, !self.series.is_empty())
    }
}

/// Grouped bar chart: one group per category (parameter), one bar per series (method or pose
/// set) — the identification accuracy η_i = (1 − |x_i − x̂_i| / |x_i|) · 100 % per parameter
/// (Guo 2024, eq. 29) as in Guo 2024, fig. 8. Bars start at zero; a value missing from a
/// series (or non-finite) leaves a gap. Long category lists are written a quarter turn under
/// the axis. Writes `<stem>.png` and `<stem>.svg`.
pub fn grouped_bars(
    stem: &Path,
    title: &str,
    y_label: &str,
    categories: &[String],
    series: &[(String, Vec<Real>)],
) -> Result<()> {
    render(
        stem,
        &GroupedBars {
            title,
            y_label,
            categories,
            series,
        },
    )
}

// ---------------------------------------------------------------------------------------------
// Before / after

struct BeforeAfter<'d> {
    title: &'d str,
    /// The quantity and its unit, e.g. `error (mm)`; the unit (in brackets) is repeated in
    /// the legend's RMS.
    y_label: &'d str,
    before: &'d [Real],
    after: &'d [Real],
}

fn rms(v: &[Real]) -> Real {
    let (s, n) = finite(v).fold((0.0, 0usize), |(s, n), x| (s + x * x, n + 1));
    if n == 0 {
        Real::NAN
    } else {
        (s / n as Real).sqrt()
    }
}

impl Figure for BeforeAfter<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let n = self.before.len().max(self.after.len()).max(1);
        let unit = self
            .y_label
            .rsplit_once('(')
            .map_or("", |(_, u)| u.trim_end_matches(')'));
        let y = with_headroom(span(finite(self.before).chain(finite(self.after)), true), 2);
        let mut chart =
            chart_builder(root, self.title, 50).build_cartesian_2d(0.5..n as Real + 0.5, y)?;
        styled_mesh(&mut chart, &int_fmt, self.y_label)
            .x_desc("validation point")
            .draw()?;
        for (s, (name, v)) in [("before", self.before), ("after", self.after)]
            .into_iter()
            .enumerate()
        {
            let c = color(if s == 0 { 3 } else { 0 });
            let pts: Vec<(Real, Real)> = v
                .iter()
                .enumerate()
                .filter(|(_, y)| y.is_finite())
                .map(|(i, &y)| ((i + 1) as Real, y))
                .collect();
            chart.draw_series(LineSeries::new(
                pts.iter().copied(),
                c.mix(0.6).stroke_width(1),
            ))?;
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 3, c.filled())))?
                .label(format!("{name} (rms {} {unit})", fmt_num(rms(v), 3)))
                .legend(move |(x, y)| Circle::new((x + 7, y), 4, c.filled()));
        }
        legend(&mut chart, true)
    }
}

/// Validation error per point before and after calibration, in mm (Li 2018, fig. 3; Ban,
/// fig. 7): one line with markers per series, the legend giving each series' RMS. Point `i`
/// (0-based) is drawn at x = i + 1. Writes `<stem>.png` and `<stem>.svg`.
pub fn before_after(stem: &Path, title: &str, before: &[Real], after: &[Real]) -> Result<()> {
    before_after_in(stem, title, "error (mm)", before, after)
}

/// [`before_after`] for another quantity, named with its unit by `y_label` (e.g. `attitude
/// error (deg)`, Qiao 2021 fig. 6).
pub fn before_after_in(
    stem: &Path,
    title: &str,
    y_label: &str,
    before: &[Real],
    after: &[Real],
) -> Result<()> {
    render(
        stem,
        &BeforeAfter {
            title,
            y_label,
            before,
            after,
        },
    )
}

// ---------------------------------------------------------------------------------------------
// Box plot

/// Five-number summary of a sample for a box plot (Tukey): quartiles by linear interpolation
/// between order statistics (the "type 7" quantile of R and NumPy's default), whiskers at the
/// most extreme values within 1.5 × IQR of the box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxStats {
    /// First quartile (25 %).
    pub q1: Real,
    /// Median.
    pub median: Real,
    /// Third quartile (75 %).
    pub q3: Real,
    /// Lower whisker: the smallest value ≥ q1 − 1.5·(q3 − q1).
    pub lo: Real,
    /// Upper whisker: the largest value ≤ q3 + 1.5·(q3 − q1).
    pub hi: Real,
}

/// The box-plot statistics of the finite values of `v`; `None` when there are none.
pub fn box_stats(v: &[Real]) -> Option<BoxStats> {
    let mut s: Vec<Real> = finite(v).collect();
    if s.is_empty() {
        return None;
    }
    s.sort_by(|a, b| a.total_cmp(b));
    let q = |p: Real| {
        let r = p * (s.len() - 1) as Real;
        let i = r.floor() as usize;
        let f = r - i as Real;
        match s.get(i + 1) {
            Some(&next) => s[i] + (next - s[i]) * f,
            None => s[i],
        }
    };
    let (q1, median, q3) = (q(0.25), q(0.5), q(0.75));
    let iqr = q3 - q1;
    let (fence_lo, fence_hi) = (q1 - 1.5 * iqr, q3 + 1.5 * iqr);
    let lo = s.iter().copied().find(|&x| x >= fence_lo).unwrap_or(q1);
    let hi = s
        .iter()
        .rev()
        .copied()
        .find(|&x| x <= fence_hi)
        .unwrap_or(q3);
    Some(BoxStats {
        q1,
        median,
        q3,
        lo,
        hi,
    })
}

struct BoxPlot<'d> {
    title: &'d str,
    y_label: &'d str,
    groups: &'d [(String, Vec<Real>)],
}

impl Figure for BoxPlot<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let names: Vec<String> = self.groups.iter().map(|(n, _)| n.clone()).collect();
        let y = span(self.groups.iter().flat_map(|(_, v)| finite(v)), false);
        let mut chart = categorical_chart(root, self.title, self.y_label, &names, names.len(), y)?;

        for (g, (_, v)) in self.groups.iter().enumerate() {
            let Some(b) = box_stats(v) else { continue };
            let c = color(g);
            let x = g as Real;
            let (hw, cap) = (0.25, 0.12);
            let line = c.stroke_width(2);
            chart.draw_series([
                Rectangle::new([(x - hw, b.q1), (x + hw, b.q3)], c.mix(0.25).filled()),
                Rectangle::new([(x - hw, b.q1), (x + hw, b.q3)], line),
            ])?;
            chart.draw_series(
                [
                    vec![(x - hw, b.median), (x + hw, b.median)],
                    vec![(x, b.q3), (x, b.hi)],
                    vec![(x, b.q1), (x, b.lo)],
                    vec![(x - cap, b.hi), (x + cap, b.hi)],
                    vec![(x - cap, b.lo), (x + cap, b.lo)],
                ]
                .into_iter()
                .map(|p| PathElement::new(p, line)),
            )?;
            chart.draw_series(
                finite(v)
                    .filter(|&y| y < b.lo || y > b.hi)
                    .map(|y| Circle::new((x, y), 3, c.stroke_width(1))),
            )?;
        }
        Ok(())
    }
}

/// Box plot of one sample per group — the validation RMS over Monte-Carlo trials per method,
/// the spread of repeated stochastic identifications that Qiao 2021, fig. 7 reports for
/// BAS-PSO. Boxes from [`box_stats`] (quartiles, Tukey whiskers); values beyond the whiskers
/// are drawn as circles. A group with no finite value is left empty. Writes `<stem>.png` and
/// `<stem>.svg`.
pub fn box_plot(
    stem: &Path,
    title: &str,
    y_label: &str,
    groups: &[(String, Vec<Real>)],
) -> Result<()> {
    render(
        stem,
        &BoxPlot {
            title,
            y_label,
            groups,
        },
    )
}

// ---------------------------------------------------------------------------------------------
// Traces

struct Traces<'d> {
    title: &'d str,
    x_label: &'d str,
    y_label: &'d str,
    series: &'d [(String, Vec<Real>)],
    log_y: bool,
}

impl Traces<'_> {
    fn keep(&self, y: Real) -> bool {
        y.is_finite() && (!self.log_y || y > 0.0)
    }

    fn draw_with<DB: DrawingBackend, Y>(
        &self,
        root: &DrawingArea<DB, Shift>,
        y: Y,
    ) -> DrawResult<DB>
    where
        Y: AsRangedCoord<Value = Real>,
        Y::CoordDescType: ValueFormatter<Real>,
    {
        let len = self.series.iter().map(|(_, v)| v.len()).max().unwrap_or(0);
        let x = 0.0..(len.max(2) - 1) as Real;
        let mut chart = chart_builder(root, self.title, 50).build_cartesian_2d(x, y)?;
        styled_mesh(&mut chart, &int_fmt, self.y_label)
            .x_desc(self.x_label)
            .draw()?;
        for (s, (name, v)) in self.series.iter().enumerate() {
            let c = color(s);
            let pts = v
                .iter()
                .enumerate()
                .filter(|(_, &y)| self.keep(y))
                .map(|(i, &y)| (i as Real, y));
            chart
                .draw_series(LineSeries::new(pts, c.stroke_width(2)))?
                .label(name.as_str())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], c.stroke_width(2)));
        }
        legend(&mut chart, !self.series.is_empty())
    }
}

impl Figure for Traces<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let ys = self
            .series
            .iter()
            .flat_map(|(_, v)| v.iter().copied())
            .filter(|&y| self.keep(y));
        let m = self.series.len();
        if self.log_y {
            self.draw_with(root, with_log_headroom(log_span(ys), m).log_scale())
        } else {
            self.draw_with(root, with_headroom(span(ys, false), m))
        }
    }
}

/// Objective or fitness per iteration, one line per series: the convergence curves of
/// BAS / PSO / BAS-PSO (Qiao 2021, fig. 4), of DETMAX-IDE (Guo 2024, eqs. 19–26, iterations to
/// convergence) or the LM objective (Ban, fig. 2 flow). Value `i` (0-based) is
/// iteration `i`. With `log_y` the y axis is logarithmic and values ≤ 0 are skipped like
/// non-finite ones. Writes `<stem>.png` and `<stem>.svg`.
pub fn traces(
    stem: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[(String, Vec<Real>)],
    log_y: bool,
) -> Result<()> {
    render(
        stem,
        &Traces {
            title,
            x_label,
            y_label,
            series,
            log_y,
        },
    )
}

// ---------------------------------------------------------------------------------------------
// Sweep

/// One series of a [`sweep`] plot: its name and its points `(x, mean, std)`.
pub type SweepSeries = (String, Vec<(Real, Real, Real)>);

struct Sweep<'d> {
    title: &'d str,
    x_label: &'d str,
    y_label: &'d str,
    series: &'d [SweepSeries],
}

/// The drawable points of a sweep series, sorted by x: (x, mean, |std| or 0 if non-finite).
fn sweep_points(v: &[(Real, Real, Real)]) -> Vec<(Real, Real, Real)> {
    let mut p: Vec<(Real, Real, Real)> = v
        .iter()
        .filter(|(x, m, _)| x.is_finite() && m.is_finite())
        .map(|&(x, m, s)| (x, m, if s.is_finite() { s.abs() } else { 0.0 }))
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    p
}

impl Figure for Sweep<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let pts: Vec<Vec<(Real, Real, Real)>> =
            self.series.iter().map(|(_, v)| sweep_points(v)).collect();
        let x = span(pts.iter().flatten().map(|p| p.0), false);
        let y = with_headroom(
            span(
                pts.iter().flatten().flat_map(|&(_, m, s)| [m - s, m + s]),
                false,
            ),
            self.series.len(),
        );
        let mut chart = chart_builder(root, self.title, 50).build_cartesian_2d(x, y)?;
        let x_fmt = |v: &Real| fmt_num(*v, 3);
        styled_mesh(&mut chart, &x_fmt, self.y_label)
            .x_desc(self.x_label)
            .draw()?;
        for (s, ((name, _), p)) in self.series.iter().zip(&pts).enumerate() {
            let c = color(s);
            chart.draw_series(LineSeries::new(
                p.iter().map(|&(x, m, _)| (x, m)),
                c.stroke_width(2),
            ))?;
            chart.draw_series(
                p.iter().map(|&(x, m, sd)| {
                    ErrorBar::new_vertical(x, m - sd, m, m + sd, c.filled(), 10)
                }),
            )?;
            chart
                .draw_series(
                    p.iter()
                        .map(|&(x, m, _)| Circle::new((x, m), 4, c.filled())),
                )?
                .label(name.as_str())
                .legend(move |(x, y)| Circle::new((x + 7, y), 4, c.filled()));
        }
        legend(&mut chart, !self.series.is_empty())
    }
}

/// A metric against a swept setting, one line per series with ± one standard deviation error
/// bars: Guo 2024, fig. 7 (objective against the pose count), Ban, fig. 3 (mean absolute
/// error of SVD and weighted-SVD registration against outlier count and size). Each point is
/// `(x, mean, std)`; points are joined in increasing x; a point with a non-finite x or mean is
/// skipped, a non-finite std draws no bar. Writes `<stem>.png` and `<stem>.svg`.
pub fn sweep(
    stem: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[SweepSeries],
) -> Result<()> {
    render(
        stem,
        &Sweep {
            title,
            x_label,
            y_label,
            series,
        },
    )
}

// ---------------------------------------------------------------------------------------------
// Heat map

struct HeatMap<'d> {
    title: &'d str,
    x_label: &'d str,
    y_label: &'d str,
    x_names: &'d [String],
    y_names: &'d [String],
    values: &'d [Vec<Real>],
}

/// The colour of `t` in 0..1 on a light-to-dark blue scale (NaN: grey).
fn heat_colour(t: Real) -> RGBColor {
    if !t.is_finite() {
        return RGBColor(200, 200, 200);
    }
    let t = t.clamp(0.0, 1.0);
    let mix = |a: u8, b: u8| (Real::from(a) + (Real::from(b) - Real::from(a)) * t).round() as u8;
    RGBColor(mix(247, 8), mix(251, 48), mix(255, 107))
}

impl Figure for HeatMap<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let (nx, ny) = (self.x_names.len(), self.y_names.len());
        let mut chart = chart_builder(root, self.title, 50)
            .build_cartesian_2d(Categories { n: nx }, Categories { n: ny })?;
        let x_fmt = |v: &Real| category_label(self.x_names, *v);
        let y_fmt = |v: &Real| category_label(self.y_names, *v);
        chart
            .configure_mesh()
            .disable_mesh()
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .x_labels(nx.max(1))
            .y_labels(ny.max(1))
            .x_desc(self.x_label)
            .y_desc(self.y_label)
            .axis_desc_style((FAMILY, 17))
            .label_style((FAMILY, 14))
            .draw()?;
        let all: Vec<Real> = self.values.iter().flatten().copied().collect();
        let r = span(finite(&all), false);
        let scale = |v: Real| (v - r.start) / (r.end - r.start);
        for (i, col) in self.values.iter().enumerate().take(nx) {
            for (j, &v) in col.iter().enumerate().take(ny) {
                let (x, y) = (i as Real, j as Real);
                let t = scale(v);
                chart.draw_series(std::iter::once(Rectangle::new(
                    [(x - 0.5, y - 0.5), (x + 0.5, y + 0.5)],
                    heat_colour(t).filled(),
                )))?;
                let ink = if t.is_finite() && t > 0.55 {
                    WHITE
                } else {
                    BLACK
                };
                let style = TextStyle::from((FAMILY, 16).into_font())
                    .color(&ink)
                    .pos(Pos::new(HPos::Center, VPos::Center));
                chart.draw_series(std::iter::once(Text::new(
                    if v.is_finite() {
                        fmt_num(v, 4)
                    } else {
                        "–".into()
                    },
                    (x, y),
                    style,
                )))?;
            }
        }
        Ok(())
    }
}

/// A metric over a two-axis grid, one cell per pair of values, coloured light to dark from
/// the smallest to the largest finite value and labelled with its value (the grid sweeps'
/// plot). `values[i][j]` belongs to `x_names[i]` and `y_names[j]`; a non-finite value is a
/// grey cell marked "–". Writes `<stem>.png` and `<stem>.svg`.
pub fn heatmap(
    stem: &Path,
    title: &str,
    (x_label, x_names): (&str, &[String]),
    (y_label, y_names): (&str, &[String]),
    values: &[Vec<Real>],
) -> Result<()> {
    render(
        stem,
        &HeatMap {
            title,
            x_label,
            y_label,
            x_names,
            y_names,
            values,
        },
    )
}
