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

/// Evaluation tick labels of a logarithmic axis. plotters puts a tick at every multiple of a
/// decade (10000, 20000, …, 90000), and their labels run into each other towards the decade's
/// end (40000, 50000, 60000 within a label's width): only the ticks at 1, 2 and 5 of a decade
/// are labelled, the others keep their grid line.
fn evals_fmt(v: &Real) -> String {
    let label = fmt_num(*v, 3);
    let mantissa = label.split('e').next().unwrap_or("");
    let mut digits = mantissa
        .chars()
        .filter(char::is_ascii_digit)
        .skip_while(|&c| c == '0');
    let lead = digits.next();
    if matches!(lead, Some('1' | '2' | '5')) && digits.all(|c| c == '0') {
        label
    } else {
        String::new()
    }
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

    #[test]
    fn an_evaluation_axis_labels_only_1_2_and_5_of_each_decade() {
        let labelled = |v: Real| !evals_fmt(&v).is_empty();
        let decade: Vec<Real> = (1..=9).map(|m| m as Real * 1e4).collect();
        let shown: Vec<Real> = decade.iter().copied().filter(|&v| labelled(v)).collect();
        assert_eq!(shown, [1e4, 2e4, 5e4]);
        assert_eq!(evals_fmt(&20000.000000000004), "20000");
        assert_eq!(evals_fmt(&0.5), "0.5");
        assert_eq!(evals_fmt(&2e6), "2e6");
        assert!(!labelled(3e6) && !labelled(1.5e4) && !labelled(Real::NAN));
        // The span of Qiao's fig. 4 read as evaluations, whose labels ran into each other
        // (40000, 50000, 60000, 70000): in the drawn figure, only 10000, 20000 and 50000.
        let dir = crate::test_dir("ecdf-ticks");
        let series = [("bas".to_string(), vec![(1300.0, 0.25), (65000.0, 1.0)])];
        runtime_ecdf(&dir.join("e"), "ECDF", &series).unwrap();
        let svg = std::fs::read_to_string(dir.join("e.svg")).unwrap();
        let drawn: Vec<Real> = decade
            .iter()
            .copied()
            .filter(|v| svg.contains(&format!(">\n{}\n</text>", fmt_num(*v, 3))))
            .collect();
        assert_eq!(drawn, [1e4, 2e4, 5e4], "{svg}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
