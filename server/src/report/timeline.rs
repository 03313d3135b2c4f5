//! A pair's timeline figure: its clearance against the recording's samples, the threshold drawn
//! across, as an SVG document (plotters) for the report's page.

use plotters::prelude::*;

use super::PairReport;
use super::session::CEILING;

/// The figure's size, pixels.
const SIZE: (u32, u32) = (720, 260);

/// The clearance of `pair` (millimetres) against the sample, over `samples` samples, with
/// `threshold` (metres) as a red line; the curve breaks where the pair was farther than
/// the figure's top (twice the threshold).
pub fn svg(pair: &PairReport, samples: usize, threshold: f64) -> String {
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, SIZE).into_drawing_area();
        draw(&root, pair, samples, threshold).expect("drawing into a string does not fail");
        root.present().expect("drawing into a string does not fail");
    }
    out
}

fn draw(
    root: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    pair: &PairReport,
    samples: usize,
    threshold: f64,
) -> Result<(), DrawingAreaErrorKind<std::io::Error>> {
    let top = CEILING * threshold * 1e3;
    let last = samples.max(2) as f64 - 1.0;
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!("{} – {}: clearance", pair.a, pair.b),
            ("sans-serif", 16),
        )
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(56)
        .build_cartesian_2d(0.0..last, 0.0..top)?;
    chart
        .configure_mesh()
        .x_desc("sample")
        .y_desc("clearance (mm)")
        .x_labels(8)
        .y_labels(5)
        .x_label_formatter(&|sample| format!("{sample:.0}"))
        .draw()?;
    chart.draw_series(LineSeries::new(
        [(0.0, threshold * 1e3), (last, threshold * 1e3)],
        ShapeStyle::from(&RED).stroke_width(1),
    ))?;
    chart.draw_series(std::iter::once(Text::new(
        format!("threshold {:.3} mm", threshold * 1e3),
        (0.01 * last, threshold * 1e3 * 1.08),
        ("sans-serif", 12).into_font().color(&RED),
    )))?;
    for run in runs(&pair.timeline) {
        chart.draw_series(LineSeries::new(run, BLUE.stroke_width(2)))?;
    }
    if let Some(minimum) = &pair.minimum {
        chart.draw_series(std::iter::once(Circle::new(
            (minimum.sample as f64, minimum.clearance_m * 1e3),
            4,
            BLACK.filled(),
        )))?;
    }
    Ok(())
}

/// The timeline's unbroken stretches, as (sample, millimetres) points.
fn runs(timeline: &[(usize, Option<f64>)]) -> Vec<Vec<(f64, f64)>> {
    let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut open = false;
    for &(sample, clearance) in timeline {
        match clearance {
            Some(metres) => {
                let point = (sample as f64, metres * 1e3);
                match runs.last_mut() {
                    Some(run) if open => run.push(point),
                    _ => runs.push(vec![point]),
                }
                open = true;
            }
            None => open = false,
        }
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::runs;

    #[test]
    fn the_curve_breaks_where_the_pair_was_beyond_the_top() {
        let timeline = [
            (0, Some(0.001)),
            (1, Some(0.002)),
            (2, None),
            (3, Some(0.003)),
        ];
        assert_eq!(
            runs(&timeline),
            [vec![(0.0, 1.0), (1.0, 2.0)], vec![(3.0, 3.0)]]
        );
    }
}
