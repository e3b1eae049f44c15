//! The figures of the reports: before/after residuals, box plots, traces, sweep curves and
//! heat maps, each drawn by [`super::render`] (grouped bars: [`super::bars`]).

use super::*;

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
        styled_mesh(&mut chart, &int_fmt, self.y_label, |m| {
            m.x_desc("validation point");
        })?;
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
    /// Per group, an estimate and its interval drawn as an error bar beside the box.
    marks: &'d [Option<Mark>],
}

/// An estimate and its 95 % interval `[lo, hi]`, drawn as a black error bar with a dot.
pub type Mark = (Real, [Real; 2]);

impl BoxPlot<'_> {
    /// The finite mark of group `g`.
    fn mark(&self, g: usize) -> Option<Mark> {
        self.marks
            .get(g)
            .copied()
            .flatten()
            .filter(|(m, [lo, hi])| m.is_finite() && lo.is_finite() && hi.is_finite() && lo <= hi)
    }
}

impl Figure for BoxPlot<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let names: Vec<String> = self.groups.iter().map(|(n, _)| n.clone()).collect();
        let marked: Vec<Mark> = (0..self.groups.len())
            .filter_map(|g| self.mark(g))
            .collect();
        let y = span(
            self.groups
                .iter()
                .flat_map(|(_, v)| finite(v))
                .chain(marked.iter().flat_map(|(_, [lo, hi])| [*lo, *hi])),
            false,
        );
        let y = if marked.is_empty() {
            y
        } else {
            with_headroom(y, 1)
        };
        let zero = y.start <= 0.0 && y.end >= 0.0 && !marked.is_empty();
        let mut chart = categorical_chart(root, self.title, self.y_label, &names, names.len(), y)?;
        if zero {
            // Where b − a is 0: the side of it the interval lies on is the verdict.
            let n = names.len().max(1) as Real;
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(-0.5, 0.0), (n - 0.5, 0.0)],
                BLACK.mix(0.5).stroke_width(1),
            )))?;
        }

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
        // The estimate and interval of each group's test, right of its box.
        let mut first = true;
        for g in 0..self.groups.len() {
            let Some((m, [lo, hi])) = self.mark(g) else {
                continue;
            };
            let x = g as Real + 0.36;
            let bar = chart.draw_series([ErrorBar::new_vertical(
                x,
                lo,
                m,
                hi,
                BLACK.stroke_width(2),
                10,
            )])?;
            if std::mem::take(&mut first) {
                bar.label("estimate and 95 % interval of the verdict's test")
                    .legend(|(x, y)| Circle::new((x + 7, y), 4, BLACK.filled()));
            }
            chart.draw_series(std::iter::once(Circle::new((x, m), 4, BLACK.filled())))?;
        }
        legend(&mut chart, !first)
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
    box_plot_with_marks(stem, title, y_label, groups, &[])
}

/// [`box_plot`] with, right of box `g`, the estimate and 95 % interval `marks[g]` (a paired
/// comparison's test: the mean and its t interval, or the median and its sign-test
/// interval) as a black error bar with a dot, a legend line saying so, and a grey line at
/// 0 when the axis holds it; a missing, non-finite or reversed mark draws none, and the
/// axis reaches the bounds drawn.
pub fn box_plot_with_marks(
    stem: &Path,
    title: &str,
    y_label: &str,
    groups: &[(String, Vec<Real>)],
    marks: &[Option<Mark>],
) -> Result<()> {
    render(
        stem,
        &BoxPlot {
            title,
            y_label,
            groups,
            marks,
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
        styled_mesh(&mut chart, &int_fmt, self.y_label, |m| {
            m.x_desc(self.x_label);
        })?;
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
        let x_axis = x.clone();
        let mut chart = chart_builder(root, self.title, 50).build_cartesian_2d(x, y)?;
        let x_fmt = |v: &Real| y_fmt(*v, &x_axis);
        styled_mesh(&mut chart, &x_fmt, self.y_label, |m| {
            m.x_desc(self.x_label);
        })?;
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
