//! Shared output of every benchmark: an aligned text table for people, JSON for machines, an SVG
//! line plot (log axes where the data spans decades), and the summary statistics the tables show.
//!
//! The benchmarks of the collision, pipeline, sliding and grasping modules all report through
//! these helpers so that their outputs look alike and are parsed alike.

use std::fmt::Write as _;
use std::path::Path;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use serde::Serialize;

/// A table of text cells printed with aligned columns (numbers right-aligned, text left-aligned).
#[derive(Debug, Clone, Default)]
pub struct Table {
    headers: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with these column headers and no rows yet.
    pub fn new<S: Into<String>>(headers: impl IntoIterator<Item = S>) -> Self {
        Table {
            headers: headers.into_iter().map(Into::into).collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row; it must have one cell per header.
    pub fn push_row<S: Into<String>>(&mut self, cells: impl IntoIterator<Item = S>) {
        let row: Vec<String> = cells.into_iter().map(Into::into).collect();
        assert_eq!(
            row.len(),
            self.headers.len(),
            "a table row needs one cell per column"
        );
        self.rows.push(row);
    }

    /// The table as text: header, a rule, then the rows, columns separated by two spaces.
    pub fn render(&self) -> String {
        let mut widths: Vec<usize> = self.headers.iter().map(|h| h.chars().count()).collect();
        for row in &self.rows {
            for (w, cell) in widths.iter_mut().zip(row) {
                *w = (*w).max(cell.chars().count());
            }
        }
        let mut out = String::new();
        let line = |out: &mut String, cells: &[String]| {
            let parts: Vec<String> = cells
                .iter()
                .zip(&widths)
                .map(|(cell, &w)| {
                    if looks_numeric(cell) {
                        format!("{cell:>w$}")
                    } else {
                        format!("{cell:<w$}")
                    }
                })
                .collect();
            let _ = writeln!(out, "{}", parts.join("  ").trim_end());
        };
        line(&mut out, &self.headers);
        let rule: Vec<String> = widths.iter().map(|&w| "-".repeat(w)).collect();
        let _ = writeln!(out, "{}", rule.join("  "));
        for row in &self.rows {
            line(&mut out, row);
        }
        out
    }
}

/// True for cells such as `12.5`, `-3`, `1e-4`, `57%`: those are right-aligned.
fn looks_numeric(cell: &str) -> bool {
    let trimmed = cell.trim_end_matches('%');
    !trimmed.is_empty() && trimmed.parse::<f64>().is_ok()
}

/// Formats a number with a precision that suits its magnitude (3 significant digits or more).
pub fn format_number(value: f64) -> String {
    let magnitude = value.abs();
    if magnitude >= 100.0 || value == 0.0 {
        format!("{value:.0}")
    } else if magnitude >= 10.0 {
        format!("{value:.1}")
    } else if magnitude >= 1.0 {
        format!("{value:.2}")
    } else {
        format!("{value:.3}")
    }
}

/// Writes `value` as pretty-printed JSON to `path`, naming the file in any error.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value).context("serialising the benchmark results")?;
    std::fs::write(path, text + "\n").with_context(|| format!("writing {}", path.display()))
}

/// Mean, median and maximum of a set of timings, in microseconds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TimingSummary {
    /// Arithmetic mean.
    pub mean_us: f64,
    /// Median (the middle value, or the mean of the two middle ones).
    pub median_us: f64,
    /// Largest value.
    pub max_us: f64,
}

impl TimingSummary {
    /// Summarises the durations; all zeros for an empty set.
    pub fn from_durations(durations: &[Duration]) -> Self {
        let mut micros: Vec<f64> = durations.iter().map(|d| d.as_secs_f64() * 1e6).collect();
        if micros.is_empty() {
            return TimingSummary {
                mean_us: 0.0,
                median_us: 0.0,
                max_us: 0.0,
            };
        }
        let mean_us = micros.iter().sum::<f64>() / micros.len() as f64;
        let max_us = micros.iter().copied().fold(f64::MIN, f64::max);
        TimingSummary {
            mean_us,
            median_us: median(&mut micros),
            max_us,
        }
    }
}

/// The cost of timing one call with two `Instant::now()` readings, measured here (median of many
/// empty readings). Benchmarks subtract it from each sample so that sub-microsecond queries are
/// not dominated by the clock.
pub fn timer_overhead() -> Duration {
    let mut samples: Vec<f64> = (0..2001)
        .map(|_| {
            let start = Instant::now();
            std::hint::black_box(());
            start.elapsed().as_secs_f64()
        })
        .collect();
    Duration::from_secs_f64(median(&mut samples))
}

/// The median of `values` (reordered in place); NaN for an empty slice.
pub fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let mid = values.len() / 2;
    if values.len() % 2 == 1 {
        values[mid]
    } else {
        0.5 * (values[mid - 1] + values[mid])
    }
}

/// One curve of a [`LinePlot`]: a name for the legend and its (x, y) points in drawing order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Series {
    /// Legend label.
    pub name: String,
    /// Points, drawn joined in this order.
    pub points: Vec<(f64, f64)>,
}

/// A line plot of several series, written as SVG by [`write_svg_line_plot`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinePlot {
    /// Caption above the plot.
    pub title: String,
    /// Label of the horizontal axis.
    pub x_label: String,
    /// Label of the vertical axis.
    pub y_label: String,
    /// Logarithmic horizontal axis (all x must be positive).
    pub log_x: bool,
    /// Logarithmic vertical axis (all y must be positive).
    pub log_y: bool,
    /// The curves.
    pub series: Vec<Series>,
}

/// Colours of successive series: distinguishable and readable on white.
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// Width and height of a figure, and the width of the legend's column at its right.
const FIGURE_SIZE: (u32, u32) = (1000, 600);
const LEGEND_WIDTH: u32 = 240;

/// Draws `plot` into an SVG file: the chart at the left, its legend in a column of its own at
/// the right (so that it never covers data), each series in its own colour and marker shape.
///
/// A logarithmic axis is kept only where the data spans at least a decade: over less, the
/// logarithmic scale has no tick inside the range to label, and looks linear anyway.
///
/// Fails (naming the file) when there is nothing to draw, when a log axis meets a non-positive
/// value, or when the file cannot be written.
pub fn write_svg_line_plot(path: &Path, plot: &LinePlot) -> Result<()> {
    let points: Vec<(f64, f64)> = plot
        .series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    if points.is_empty() {
        bail!("{}: the plot has no finite point to draw", path.display());
    }
    let axis = |values: Vec<f64>, log: bool, name: &str| {
        padded_range(&values, log)
            .with_context(|| format!("{}: {name} axis of '{}'", path.display(), plot.title))
    };
    let (x_range, log_x) = axis(points.iter().map(|p| p.0).collect(), plot.log_x, "x")?;
    let (y_range, log_y) = axis(points.iter().map(|p| p.1).collect(), plot.log_y, "y")?;
    let root = SVGBackend::new(path, FIGURE_SIZE).into_drawing_area();
    let drawn = match (log_x, log_y) {
        (false, false) => draw(&root, plot, x_range, y_range),
        (true, false) => draw(&root, plot, x_range.log_scale(), y_range),
        (false, true) => draw(&root, plot, x_range, y_range.log_scale()),
        (true, true) => draw(&root, plot, x_range.log_scale(), y_range.log_scale()),
    };
    drawn
        .and_then(|()| root.present().map_err(|e| anyhow::anyhow!("{e}")))
        .with_context(|| format!("drawing {}", path.display()))
}

/// The range spanned by `values`, widened a little so that no point sits on the frame, and
/// whether it is drawn logarithmically (asked for, and spanning at least a decade).
fn padded_range(values: &[f64], log: bool) -> Result<(std::ops::Range<f64>, bool)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &v in values {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if log && lo <= 0.0 {
        bail!("a logarithmic axis needs positive values, found {lo}");
    }
    if log && hi >= 10.0 * lo {
        Ok((lo / 1.25..hi * 1.25, true))
    } else {
        let pad = if hi > lo { 0.05 * (hi - lo) } else { 1.0 };
        Ok((lo - pad..hi + pad, false))
    }
}

/// The marker of series `index`: shapes change once the palette's colours are used up, so that
/// no two series of a plot look alike.
fn marker<DB: DrawingBackend>(
    index: usize,
    at: (i32, i32),
    color: RGBColor,
) -> DynElement<'static, DB, (i32, i32)> {
    let style = color.filled();
    match (index / PALETTE.len()) % 3 {
        0 => Circle::new(at, 4, style).into_dyn(),
        1 => TriangleMarker::new(at, 6, style).into_dyn(),
        _ => Rectangle::new([(at.0 - 4, at.1 - 4), (at.0 + 4, at.1 + 4)], style).into_dyn(),
    }
}

/// Draws mesh, labels, one line with markers per series, and the legend in its own column.
fn draw<X, Y>(
    root: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    plot: &LinePlot,
    x: X,
    y: Y,
) -> Result<()>
where
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let err = |e: DrawingAreaErrorKind<std::io::Error>| anyhow::anyhow!("{e}");
    root.fill(&WHITE).map_err(err)?;
    let (chart_area, legend_area) = root.split_horizontally(FIGURE_SIZE.0 - LEGEND_WIDTH);
    let mut chart = ChartBuilder::on(&chart_area)
        .caption(&plot.title, ("sans-serif", 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d(x, y)
        .map_err(err)?;
    // A few labels per axis, written as the tables write numbers: a logarithmic axis over a
    // decade or two would otherwise label every minor tick, one over the other.
    let tick = |value: &f64| format_number(*value);
    chart
        .configure_mesh()
        .x_desc(plot.x_label.as_str())
        .y_desc(plot.y_label.as_str())
        .x_labels(8)
        .y_labels(8)
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .draw()
        .map_err(err)?;
    for (index, series) in plot.series.iter().enumerate() {
        let color = PALETTE[index % PALETTE.len()];
        let points: Vec<(f64, f64)> = series
            .points
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .collect();
        chart
            .draw_series(LineSeries::new(points.clone(), color.stroke_width(2)))
            .map_err(err)?;
        chart
            .draw_series(
                points
                    .into_iter()
                    .map(|p| EmptyElement::at(p) + marker(index, (0, 0), color)),
            )
            .map_err(err)?;
    }
    for (index, series) in plot.series.iter().enumerate() {
        let color = PALETTE[index % PALETTE.len()];
        let row = 60 + 24 * index as i32;
        legend_area
            .draw(&PathElement::new(
                [(10, row), (40, row)],
                color.stroke_width(2),
            ))
            .map_err(err)?;
        legend_area
            .draw(&marker(index, (25, row), color))
            .map_err(err)?;
        legend_area
            .draw(&Text::new(
                series.name.clone(),
                (48, row - 7),
                ("sans-serif", 14).into_font().color(&BLACK),
            ))
            .map_err(err)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_aligns_numbers_right_and_text_left() {
        let mut table = Table::new(["algo", "mean_us"]);
        table.push_row(["doptree", "3.5"]);
        table.push_row(["obbtree-long", "12.25"]);
        let text = table.render();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "algo          mean_us");
        assert_eq!(lines[2], "doptree           3.5");
        assert_eq!(lines[3], "obbtree-long    12.25");
    }

    #[test]
    fn summary_statistics() {
        let durations: Vec<Duration> = [4u64, 1, 3, 2].map(Duration::from_micros).to_vec();
        let summary = TimingSummary::from_durations(&durations);
        assert_eq!(summary.mean_us, 2.5);
        assert_eq!(summary.median_us, 2.5);
        assert_eq!(summary.max_us, 4.0);
        assert_eq!(median(&mut [5.0, 1.0, 3.0]), 3.0);
        assert!(timer_overhead() < Duration::from_millis(1));
    }

    #[test]
    fn svg_plot_is_written_with_every_series_name() {
        let dir = std::env::temp_dir().join(format!("vas-report-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("plot.svg");
        let plot = LinePlot {
            title: "time per query".into(),
            x_label: "triangles".into(),
            y_label: "us".into(),
            log_x: true,
            log_y: true,
            series: vec![
                Series {
                    name: "alpha".into(),
                    points: vec![(1e3, 2.0), (1e4, 5.0), (1e5, 9.0)],
                },
                Series {
                    name: "beta".into(),
                    points: vec![(1e3, 20.0), (1e5, 900.0)],
                },
            ],
        };
        write_svg_line_plot(&path, &plot).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("alpha") && svg.contains("beta"));
        let bad = LinePlot {
            series: vec![Series {
                name: "zero".into(),
                points: vec![(0.0, 1.0)],
            }],
            ..plot
        };
        assert!(write_svg_line_plot(&path, &bad).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
