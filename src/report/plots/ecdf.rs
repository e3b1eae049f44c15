//! The searches compared as COCO does (Hansen et al., "COCO: a platform for comparing
//! continuous optimizers in a black-box setting", 2021; docs/formats.md "Searches
//! compared"): the runtime ECDF of each search, its targets aggregated, and the fixed-budget
//! curve of its best fitness with the intervals of the means.

use super::*;

/// One search's runtime ECDF: its name and its steps `(evaluations, share)`, evaluations
/// increasing.
pub type EcdfSeries = (String, Vec<(Real, Real)>);

/// One search's fixed-budget curve: its name and, per budget, `(evaluations, mean best
/// fitness, its 95 % interval)`.
pub type BudgetSeries = (String, Vec<(Real, Real, Option<[Real; 2]>)>);

/// Evaluation tick labels of a logarithmic axis.
fn evals_fmt(v: &Real) -> String {
    fmt_num(*v, 3)
}

/// Draws the mesh of a chart whose x axis counts evaluations: ticks as [`evals_fmt`],
/// `x_desc` under the axis and `y_desc` beside the other.
fn evals_mesh<DB, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    x_desc: &str,
    y_desc: &str,
) -> DrawResult<DB>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = Real> + ValueFormatter<Real>,
    Y: Ranged<ValueType = Real> + ValueFormatter<Real>,
{
    styled_mesh(chart, &evals_fmt, y_desc, |m| {
        m.x_desc(x_desc);
    })
}

struct Ecdf<'d> {
    title: &'d str,
    series: &'d [EcdfSeries],
}

impl Figure for Ecdf<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let x = log_span(self.series.iter().flat_map(|(_, v)| v.iter().map(|p| p.0)));
        let (x_lo, x_hi) = (x.start, x.end);
        let y = with_headroom(0.0..1.0, self.series.len());
        let mut chart = chart_builder(root, self.title, 50).build_cartesian_2d(x.log_scale(), y)?;
        let y_desc = "share of (trial, target) pairs reached";
        evals_mesh(&mut chart, "evaluations (log scale)", y_desc)?;
        for (s, (name, v)) in self.series.iter().enumerate() {
            let c = color(s);
            // A step function: 0 before the first hit, each share from its evaluations on.
            let mut path = vec![(x_lo, 0.0)];
            let mut last = 0.0;
            for &(e, share) in v.iter().filter(|p| p.0 > 0.0 && p.1.is_finite()) {
                path.push((e, last));
                path.push((e, share));
                last = share;
            }
            path.push((x_hi, last));
            chart
                .draw_series(LineSeries::new(path, c.stroke_width(2)))?
                .label(name.as_str())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], c.stroke_width(2)));
        }
        legend(&mut chart, !self.series.is_empty())
    }
}

/// The runtime ECDFs of the searches, one step line per search against the evaluations on a
/// logarithmic axis (COCO's aggregate over targets: the share of the (trial, target) pairs
/// reached within so many evaluations). Writes `<stem>.png` and `<stem>.svg`.
pub fn runtime_ecdf(stem: &Path, title: &str, series: &[EcdfSeries]) -> Result<()> {
    render(stem, &Ecdf { title, series })
}

struct Budget<'d> {
    title: &'d str,
    series: &'d [BudgetSeries],
}

impl Figure for Budget<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let points = || self.series.iter().flat_map(|(_, v)| v.iter());
        let x = log_span(points().map(|p| p.0));
        let y = with_log_headroom(
            log_span(points().flat_map(|&(_, m, ci)| {
                let [lo, hi] = ci.unwrap_or([m; 2]);
                [m, lo, hi]
            })),
            self.series.len(),
        );
        let y_floor = y.start;
        let mut chart =
            chart_builder(root, self.title, 50).build_cartesian_2d(x.log_scale(), y.log_scale())?;
        let y_desc = "mean best fitness (eq. 14) with its 95 % interval";
        evals_mesh(&mut chart, "budget in evaluations (log scale)", y_desc)?;
        for (s, (name, v)) in self.series.iter().enumerate() {
            let c = color(s);
            let pts: Vec<_> = v
                .iter()
                .filter(|p| p.0 > 0.0 && p.1.is_finite() && p.1 > 0.0)
                .collect();
            chart.draw_series(LineSeries::new(
                pts.iter().map(|p| (p.0, p.1)),
                c.stroke_width(2),
            ))?;
            // A lower end at or below 0 has no place on a log axis: the bar runs to its foot.
            chart.draw_series(pts.iter().filter_map(|&&(x, m, ci)| {
                let [lo, hi] = ci?;
                let lo = if lo > 0.0 { lo } else { y_floor };
                Some(ErrorBar::new_vertical(x, lo, m, hi, c.filled(), 10))
            }))?;
            chart
                .draw_series(pts.iter().map(|p| Circle::new((p.0, p.1), 4, c.filled())))?
                .label(name.as_str())
                .legend(move |(x, y)| Circle::new((x + 7, y), 4, c.filled()));
        }
        legend(&mut chart, !self.series.is_empty())
    }
}

/// The fixed-budget curves of the searches: the mean over trials of the best fitness within
/// each budget, with its 95 % interval as an error bar, both axes logarithmic. Writes
/// `<stem>.png` and `<stem>.svg`.
pub fn fixed_budget(stem: &Path, title: &str, series: &[BudgetSeries]) -> Result<()> {
    render(stem, &Budget { title, series })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_plots_draw_and_empty_or_odd_data_give_a_chart() {
        let dir = crate::test_dir("ecdf-plot");
        let ecdf = [
            ("bas".to_string(), vec![(100.0, 0.25), (300.0, 1.0)]),
            ("pso".to_string(), vec![]),
        ];
        let budget = [(
            "bas".to_string(),
            vec![
                (30.0, 5.0, Some([-1.0, 11.0])),
                (300.0, 0.5, None),
                (0.0, Real::NAN, None),
            ],
        )];
        for (i, (e, b)) in [(&ecdf[..], &budget[..]), (&[][..], &[][..])]
            .into_iter()
            .enumerate()
        {
            runtime_ecdf(&dir.join(format!("e{i}")), "ECDF", e).unwrap();
            fixed_budget(&dir.join(format!("b{i}")), "budget", b).unwrap();
        }
        let svg = std::fs::read_to_string(dir.join("e0.svg")).unwrap();
        assert!(svg.contains("bas") && svg.contains("pso"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
