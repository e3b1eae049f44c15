//! The report's plots, each written as `<stem>.png` and `<stem>.svg` (docs/formats.md, `run`
//! outputs).
//!
//! Every function takes already-computed numbers (plots only read results), skips
//! non-finite values, and draws an empty chart carrying its title when nothing is left to
//! draw; it never panics on its data. Output is deterministic: the same data gives the same
//! bytes (text is laid out with the bundled DejaVu Sans, no system fonts).

mod bars;
mod changes;
mod ecdf;
mod figures;

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
use super::output::Output;
use crate::numeric::Real;
use crate::{Error, Result};
pub use bars::{grouped_bars, grouped_bars_with_floor};
pub use changes::{changes_svg, ChangePoint};
pub use ecdf::{fixed_budget, runtime_ecdf, BudgetSeries, EcdfSeries};
pub use figures::{
    before_after, before_after_in, box_plot, box_plot_with_marks, box_stats, heatmap, sweep,
    traces, BoxStats, Mark, SweepSeries,
};

/// Size of every plot in pixels (PNG) or user units (SVG), width × height.
pub const PLOT_SIZE: (u32, u32) = (960, 600);

/// The font family under which the bundled DejaVu Sans is registered.
const FAMILY: &str = "sans-serif";

/// DejaVu Sans (Bitstream Vera licence, see `assets/DejaVuSans-LICENSE.txt`); covers the
/// Greek letters of the parameter names (θ, α, β, η).
static FONT: &[u8] = include_bytes!("../../../assets/DejaVuSans.ttf");

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
    super::output::text(&svg_path, &svg)?;

    let root = BitMapBackend::new(&png_path, PLOT_SIZE).into_drawing_area();
    paint(&root, fig).map_err(|e| cannot(&png_path, &e))?;
    root.present()
        .map_err(|e| Error::io(&png_path, std::io::Error::other(e.to_string())))?;
    Ok(())
}

/// A metric against a swept setting ([`sweep`]), as `<name>.png` and `<name>.svg`.
pub struct SweepFigure<'a> {
    /// The figure's stem.
    pub name: &'a str,
    /// Its title.
    pub title: &'a str,
    /// The labels of the x and y axes.
    pub axes: (&'a str, &'a str),
    /// The series drawn.
    pub series: Vec<SweepSeries>,
}

impl Output for SweepFigure<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn write(&self, path: &Path) -> Result<()> {
        let (x, y) = self.axes;
        sweep(path, self.title, x, y, &self.series)
    }
    fn files(&self) -> Vec<String> {
        crate::report::output::figure_files(self.name)
    }
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

/// The label of a tick at `v` on a value axis spanning `axis`: [`fmt_num`] to 3 digits, and
/// `0` for a tick within 10⁻⁹ of the span of 0 on an axis that holds 0 — the tick
/// arithmetic's rounding (−0.02 + 0.02 = −2.78e-17) is no value of the data. A logarithmic
/// axis never holds 0, so its small ticks keep their value.
fn y_fmt(v: Real, axis: &Range<Real>) -> String {
    let (lo, hi) = (axis.start.min(axis.end), axis.start.max(axis.end));
    if lo <= 0.0 && hi >= 0.0 && v.abs() <= 1e-9 * (hi - lo) {
        return "0".into();
    }
    fmt_num(v, 3)
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

/// Draws the mesh every chart shares: tick labels by `x_fmt` and [`y_fmt`] (over the chart's
/// y range), `y_desc` along the y axis, the common fonts, and what `more` sets that is
/// particular to one chart.
fn styled_mesh<'a, DB, X, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    x_fmt: &dyn Fn(&Real) -> String,
    y_desc: &str,
    more: impl FnOnce(&mut MeshStyle<'a, '_, X, Y, DB>),
) -> DrawResult<DB>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = Real> + ValueFormatter<Real>,
    Y: Ranged<ValueType = Real> + ValueFormatter<Real>,
{
    let axis = chart.y_range();
    let ticks = move |v: &Real| y_fmt(*v, &axis);
    let mut mesh = chart.configure_mesh();
    mesh.x_label_formatter(x_fmt)
        .y_label_formatter(&ticks)
        .y_desc(y_desc)
        .axis_desc_style((FAMILY, 17))
        .label_style((FAMILY, 14));
    more(&mut mesh);
    mesh.draw()
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
    styled_mesh(&mut chart, &x_fmt, y_label, |m| {
        m.disable_x_mesh().x_labels(n.max(1));
    })?;
    if rotate {
        rotated_category_labels(root, &chart, names, y_bottom)?;
    }
    Ok(chart)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ticks plotters puts on a linear axis over `axis` (the mesh asks for 10).
    fn ticks(axis: Range<Real>) -> Vec<Real> {
        RangedCoordf64::from(axis).key_points(10)
    }

    #[test]
    fn a_tick_at_zero_reads_0_whatever_the_tick_arithmetic_left() {
        // Axes whose tick arithmetic leaves a residue at 0 (−0.02 + 0.02 = −2.78e-17): the
        // paired RMS differences of li2018-irb2600 at 150 trials were on the first.
        let axes = [-0.1933..0.0293, -0.3..0.1, -0.7..0.15, -1.3..0.2];
        let mut residues = 0;
        for axis in axes {
            for v in ticks(axis.clone()) {
                if v != 0.0 && v.abs() < 1e-12 {
                    residues += 1;
                    assert_eq!(y_fmt(v, &axis), "0", "{v} on {axis:?}");
                }
            }
        }
        assert!(
            residues > 0,
            "no axis left a residue: the check has no teeth"
        );
        // Every other tick keeps its value; a logarithmic axis (no 0 on it) keeps its small
        // ticks.
        assert_eq!(y_fmt(-0.02, &(-0.1933..0.0293)), "-0.02");
        assert_eq!(y_fmt(0.0, &(-1.0..1.0)), "0");
        assert_eq!(y_fmt(1e-12, &(1e-13..1.0)), "1e-12");
        assert_eq!(y_fmt(3e-9, &(0.0..1.0)), "3e-9");
        assert_eq!(y_fmt(1e-10, &(0.0..1.0)), "0");
    }

    #[test]
    fn a_drawn_box_plot_labels_no_residue_of_zero() {
        let dir = crate::test_dir("ticks");
        let stem = dir.join("paired");
        let near: Vec<Real> = (0..40).map(|i| (i as Real - 20.0) * 2.5e-4).collect();
        let far: Vec<Real> = (0..40).map(|i| -0.184 + i as Real * 4.5e-3).collect();
        let groups = vec![("a".to_string(), near), ("b".to_string(), far)];
        box_plot(&stem, "t", "b − a (mm)", &groups).unwrap();
        let svg = std::fs::read_to_string(with_suffix(&stem, "svg")).unwrap();
        let labels: Vec<&str> = svg
            .split("</text>")
            .filter_map(|t| t.rsplit('>').next())
            .map(str::trim)
            .collect();
        assert!(labels.contains(&"0"), "{labels:?}");
        assert!(
            labels
                .iter()
                .all(|l| !l.contains("e-1") && !l.contains("e-2")),
            "{labels:?}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

#[cfg(test)]
mod floor_tests {
    use super::*;

    #[test]
    fn a_bar_below_the_floor_is_cut_and_its_value_written() {
        let dir = crate::test_dir("floor");
        let stem = dir.join("eta");
        let params: Vec<String> = ["a1", "d6", "theta2"].map(String::from).to_vec();
        let series = vec![("ls / random".to_string(), vec![95.0, -1615.0, 80.0])];
        let ci = vec![vec![Some([90.0, 99.0]), Some([-1900.0, -1300.0]), None]];
        grouped_bars_with_floor(&stem, "t", "η (%)", &params, &series, &ci, Some(-200.0)).unwrap();
        let svg = std::fs::read_to_string(with_suffix(&stem, "svg")).unwrap();
        let labels: Vec<Real> = svg
            .split("</text>")
            .filter_map(|t| t.rsplit('>').next()?.trim().parse().ok())
            .collect();
        assert!(svg.contains("-1615 ▼"), "the cut bar's value is written");
        let lowest = labels.iter().copied().fold(Real::INFINITY, Real::min);
        assert!(
            (-200.0..0.0).contains(&lowest),
            "the axis stops at the floor: lowest tick {lowest}"
        );
        // Without a floor the axis reaches the far value.
        grouped_bars_with_floor(&stem, "t", "η (%)", &params, &series, &ci, None).unwrap();
        let svg = std::fs::read_to_string(with_suffix(&stem, "svg")).unwrap();
        assert!(!svg.contains('▼'));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
