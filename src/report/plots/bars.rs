//! Grouped bars with error bars (η per parameter, Guo 2024 fig. 8; the headline figures),
//! drawn by [`super::render`].

use super::*;

struct GroupedBars<'d> {
    title: &'d str,
    y_label: &'d str,
    categories: &'d [String],
    series: &'d [(String, Vec<Real>)],
    /// Per series and category, the interval drawn as an error bar on the bar (none: no bar).
    intervals: &'d [Vec<Option<[Real; 2]>>],
    /// The bottom of the axis when values or bounds lie below it: a bar below is cut there
    /// and its value written at its foot, so that one far value does not flatten the rest.
    floor: Option<Real>,
}

impl GroupedBars<'_> {
    /// The finite interval of series `s` at category `i`.
    fn interval(&self, s: usize, i: usize) -> Option<[Real; 2]> {
        self.intervals
            .get(s)
            .and_then(|v| v.get(i).copied().flatten())
            .filter(|[lo, hi]| lo.is_finite() && hi.is_finite() && lo <= hi)
    }
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
        let bounds = (0..self.series.len())
            .flat_map(|s| (0..n).filter_map(move |i| self.interval(s, i)))
            .flatten();
        let floor = self.floor.unwrap_or(Real::NEG_INFINITY);
        let y = with_headroom(
            span(
                self.series
                    .iter()
                    .flat_map(|(_, v)| finite(v))
                    .chain(bounds)
                    .map(|v| v.max(floor)),
                true,
            ),
            self.series.len(),
        );
        let bottom = y.start;
        let clipped = |v: Real| v.max(bottom);
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
                            Rectangle::new([(left, 0.0), (left + w, clipped(v))], c.filled())
                        }),
                )?
                .label(name.as_str())
                .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 14, y + 6)], c.filled()));
        }
        // The error bars over the bars, in black so that they show on every colour.
        for (s, (_, values)) in self.series.iter().enumerate() {
            let x0 = -0.4 + s as Real * w;
            chart.draw_series(values.iter().enumerate().filter_map(|(i, &v)| {
                let [lo, hi] = self.interval(s, i)?;
                let mid = if v.is_finite() { v } else { (lo + hi) / 2.0 };
                let x = i as Real + x0 + w / 2.0;
                (hi > bottom).then(|| {
                    ErrorBar::new_vertical(
                        x,
                        clipped(lo),
                        clipped(mid),
                        hi,
                        BLACK.stroke_width(1),
                        6,
                    )
                })
            }))?;
        }
        // The value of each bar cut at the floor, written up from its foot.
        let style = TextStyle::from((FAMILY, 13).into_font())
            .transform(FontTransform::Rotate270)
            .pos(Pos::new(HPos::Left, VPos::Center))
            .color(&BLACK);
        for (s, (_, values)) in self.series.iter().enumerate() {
            let x0 = -0.4 + s as Real * w;
            for (i, &v) in values.iter().enumerate() {
                if v.is_finite() && v < bottom {
                    let (px, py) = chart.backend_coord(&(i as Real + x0 + w / 2.0, bottom));
                    root.draw_text(&format!("{} ▼", fmt_num(v, 4)), &style, (px, py - 6))?;
                }
            }
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
    grouped_bars_with_floor(stem, title, y_label, categories, series, &[], None)
}

/// [`grouped_bars`] with an error bar on each bar that has an interval: `intervals[s][i]`
/// is the `[lo, hi]` of series `s` at category `i` (the 95 % interval of a mean), drawn as a
/// black vertical bar with caps; a missing, non-finite or reversed interval draws none, and
/// the axis reaches the bounds drawn. With a `floor`, the axis stops there when values or
/// bounds lie below it (η per parameter at −200 %: a parameter whose injected error is tiny against
/// the noise has an η of −1615 % that would flatten every other bar): a bar below is cut at
/// the axis and its value written at its foot with a ▼, its interval drawn down to the axis.
pub fn grouped_bars_with_floor(
    stem: &Path,
    title: &str,
    y_label: &str,
    categories: &[String],
    series: &[(String, Vec<Real>)],
    intervals: &[Vec<Option<[Real; 2]>>],
    floor: Option<Real>,
) -> Result<()> {
    render(
        stem,
        &GroupedBars {
            title,
            y_label,
            categories,
            series,
            intervals,
            floor,
        },
    )
}
