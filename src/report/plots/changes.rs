//! The compare page's plot of the changes: each compared metric's change from run A to run
//! B toward worse, in % of A, with its interval, against the tolerance.

use super::*;

/// One compared metric as the plot of the changes draws it.
pub struct ChangePoint {
    /// `entry: metric`.
    pub label: String,
    /// The change toward worse in % of A's magnitude: (B − A) for a metric better lower,
    /// (A − B) for one better higher, over |A|, × 100.
    pub worse_pct: Real,
    /// Its interval, on the same scale (none: no bar).
    pub interval: Option<[Real; 2]>,
    /// The index of its status in the `statuses` of [`changes_svg`].
    pub status: usize,
}

/// The colours of the statuses, in the order `check` names them: regression (red),
/// unresolved (orange), changed within tolerance (blue), improved (green) from the series
/// palette, no change (grey).
const STATUS_COLOURS: [RGBColor; 5] = [
    super::PALETTE[3],
    super::PALETTE[1],
    super::PALETTE[0],
    super::PALETTE[2],
    RGBColor(127, 127, 127),
];

struct Changes<'d> {
    title: &'d str,
    points: &'d [ChangePoint],
    statuses: &'d [&'d str],
    tolerance_pct: Real,
}

impl Figure for Changes<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let names: Vec<String> = self.points.iter().map(|p| p.label.clone()).collect();
        let n = names.len();
        let values = self
            .points
            .iter()
            .flat_map(|p| {
                let [lo, hi] = p.interval.unwrap_or([Real::NAN; 2]);
                [p.worse_pct, lo, hi]
            })
            .chain([self.tolerance_pct, -self.tolerance_pct]);
        let present: Vec<usize> = (0..self.statuses.len())
            .filter(|s| self.points.iter().any(|p| p.status == *s))
            .collect();
        let y = with_headroom(span(values, true), present.len() + 1);
        let mut chart = categorical_chart(
            root,
            self.title,
            "change toward worse (% of A)",
            &names,
            n,
            y,
        )?;
        let x = -0.5..(n.max(1) as Real - 0.5);
        chart.draw_series(LineSeries::new(
            [(x.start, 0.0), (x.end, 0.0)],
            BLACK.mix(0.6).stroke_width(1),
        ))?;
        let red = STATUS_COLOURS[0];
        chart
            .draw_series(DashedLineSeries::new(
                [(x.start, self.tolerance_pct), (x.end, self.tolerance_pct)],
                8,
                5,
                red.stroke_width(2),
            ))?
            .label(format!("tolerance (+{} %)", fmt_num(self.tolerance_pct, 3)))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 14, y)], red.stroke_width(2)));
        for s in present {
            let c = STATUS_COLOURS[s % STATUS_COLOURS.len()];
            let mine = || {
                self.points
                    .iter()
                    .enumerate()
                    .filter(move |(_, p)| p.status == s && p.worse_pct.is_finite())
            };
            chart.draw_series(mine().filter_map(|(i, p)| {
                let [lo, hi] = p
                    .interval
                    .filter(|[lo, hi]| lo.is_finite() && hi.is_finite())?;
                Some(ErrorBar::new_vertical(
                    i as Real,
                    lo,
                    p.worse_pct,
                    hi,
                    c.stroke_width(2),
                    6,
                ))
            }))?;
            chart
                .draw_series(
                    mine().map(|(i, p)| Circle::new((i as Real, p.worse_pct), 4, c.filled())),
                )?
                .label(self.statuses.get(s).copied().unwrap_or(""))
                .legend(move |(x, y)| Circle::new((x + 7, y), 4, c.filled()));
        }
        legend(&mut chart, true)
    }
}

/// The plot of the changes as an SVG document: one point per metric, its interval as a
/// bar, coloured by its status (`statuses[p.status]` names it in the legend), a dashed line
/// at the tolerance `tolerance_pct` (% of A): a regression lies above it with its whole bar
/// above zero. The drawing grows in height with the length of the names under the axis.
pub fn changes_svg(
    title: &str,
    points: &[ChangePoint],
    statuses: &[&str],
    tolerance_pct: Real,
) -> Result<String> {
    fonts()?;
    let names: Vec<String> = points.iter().map(|p| p.label.clone()).collect();
    let (x_area, _) = category_label_layout(&names);
    let size = (PLOT_SIZE.0, 450 + x_area);
    let fig = Changes {
        title,
        points,
        statuses,
        tolerance_pct,
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        let cannot = |e: &dyn std::fmt::Display| {
            Error::Compute(format!("the plot of the changes cannot be drawn: {e}"))
        };
        paint(&root, &fig).map_err(|e| cannot(&e))?;
        root.present().map_err(|e| cannot(&e))?;
    }
    Ok(svg)
}
