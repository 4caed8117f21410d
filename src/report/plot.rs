//! The reports' time-against-error charts as SVG text (plotters): log-log axes fitted to the
//! points, one coloured series per group with a legend, points ringed or labelled where a
//! report marks them, and the Pareto front as a line.

use plotters::prelude::*;

/// One point of a series: its time (ms) and error, and how the report marks it.
pub struct PlotPoint {
    pub time_ms: f64,
    pub error: f64,
    /// Drawn with a black ring (e.g. the scene's own setting).
    pub ringed: bool,
    /// Written next to the point (e.g. its tessellation).
    pub label: Option<String>,
}

/// The points of one group, in one colour, named in the legend.
pub struct Series {
    pub name: String,
    pub colour: RGBColor,
    pub points: Vec<PlotPoint>,
}

/// A chart: its title, size in pixels, the error axis's label, the series and the front.
pub struct TimeErrorChart<'a> {
    pub title: &'a str,
    pub size: (u32, u32),
    pub error_axis: &'a str,
    pub series: Vec<Series>,
    /// The Pareto front, sorted by time; drawn as a line.
    pub front: Vec<(f64, f64)>,
    pub front_legend: &'a str,
}

/// The points not beaten on both time and error by another, sorted by time.
pub fn pareto_front(points: impl IntoIterator<Item = (f64, f64)>) -> Vec<(f64, f64)> {
    let mut order: Vec<(f64, f64)> = points.into_iter().collect();
    order.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for (time, error) in order {
        if error < best {
            front.push((time, error));
            best = error;
        }
    }
    front
}

impl TimeErrorChart<'_> {
    /// The chart as SVG text; an error names what plotters refused.
    pub fn to_svg(&self) -> Result<String, String> {
        let all = || self.series.iter().flat_map(|series| &series.points);
        if all().next().is_none() {
            return Err("nothing to plot".to_string());
        }
        let (mut t_lo, mut t_hi, mut e_lo, mut e_hi) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
        for point in all() {
            (t_lo, t_hi) = (t_lo.min(point.time_ms), t_hi.max(point.time_ms));
            (e_lo, e_hi) = (e_lo.min(point.error), e_hi.max(point.error));
        }
        let failed = |e: &dyn std::fmt::Display| format!("plotting failed: {e}");
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, self.size).into_drawing_area();
            root.fill(&WHITE).map_err(|e| failed(&e))?;
            // A margin of a quarter decade-ish around the points, so none sits on an axis.
            let mut chart = ChartBuilder::on(&root)
                .caption(self.title, ("sans-serif", 20))
                .margin(15)
                .x_label_area_size(45)
                .y_label_area_size(70)
                .build_cartesian_2d(
                    ((t_lo * 0.8)..(t_hi * 1.25)).log_scale(),
                    ((e_lo * 0.8)..(e_hi * 1.25)).log_scale(),
                )
                .map_err(|e| failed(&e))?;
            chart
                .configure_mesh()
                .x_labels(8)
                .y_labels(8)
                .x_desc("render time, ms (median)")
                .y_desc(self.error_axis)
                .draw()
                .map_err(|e| failed(&e))?;
            for series in &self.series {
                let colour = series.colour;
                let at = |point: &PlotPoint| (point.time_ms, point.error);
                chart
                    .draw_series(
                        series
                            .points
                            .iter()
                            .map(|p| Circle::new(at(p), 5, colour.filled())),
                    )
                    .map_err(|e| failed(&e))?
                    .label(series.name.as_str())
                    .legend(move |(x, y)| Circle::new((x, y), 5, colour.filled()));
                chart
                    .draw_series(
                        series
                            .points
                            .iter()
                            .filter(|p| p.ringed)
                            .map(|p| Circle::new(at(p), 9, BLACK.stroke_width(1))),
                    )
                    .map_err(|e| failed(&e))?;
                chart
                    .draw_series(series.points.iter().filter_map(|p| {
                        let label = p.label.as_ref()?;
                        Some(Text::new(
                            label.clone(),
                            at(p),
                            ("sans-serif", 11).into_font().color(&colour),
                        ))
                    }))
                    .map_err(|e| failed(&e))?;
            }
            chart
                .draw_series(LineSeries::new(self.front.iter().copied(), BLACK.stroke_width(2)))
                .map_err(|e| failed(&e))?
                .label(self.front_legend)
                .legend(|(x, y)| PathElement::new(vec![(x - 10, y), (x + 10, y)], BLACK.stroke_width(2)));
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(|e| failed(&e))?;
            root.present().map_err(|e| failed(&e))?;
        }
        Ok(svg)
    }
}
