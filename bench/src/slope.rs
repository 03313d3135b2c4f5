//! The least-squares slope that turns the soak's memory series into a growth rate.

/// A line cannot be fitted through the points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum FitError {
    /// A slope needs at least two points.
    #[error("a line needs at least two points, got {0}")]
    TooFewPoints(usize),
    /// Every point has the same abscissa (or a coordinate is not finite).
    #[error("the points do not spread along x (or hold a non-finite value)")]
    Degenerate,
}

/// The slope of the least-squares line through `(x, y)` points.
pub fn least_squares_slope(points: &[(f64, f64)]) -> Result<f64, FitError> {
    if points.len() < 2 {
        return Err(FitError::TooFewPoints(points.len()));
    }
    let count = points.len() as f64;
    let mean_x = points.iter().map(|(x, _)| x).sum::<f64>() / count;
    let mean_y = points.iter().map(|(_, y)| y).sum::<f64>() / count;
    let (covariance, variance) = points.iter().fold((0.0, 0.0), |(cov, var), (x, y)| {
        let dx = x - mean_x;
        (cov + dx * (y - mean_y), var + dx * dx)
    });
    let slope = covariance / variance;
    if variance > 0.0 && slope.is_finite() {
        Ok(slope)
    } else {
        Err(FitError::Degenerate)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_slope_of_a_line_is_recovered() {
        let points: Vec<(f64, f64)> = (0..50)
            .map(|i| (f64::from(i) * 0.5, 3.0 - 2.5 * f64::from(i) * 0.5))
            .collect();
        let slope = least_squares_slope(&points).expect("fit");
        assert!((slope + 2.5).abs() < 1e-12, "slope {slope}");
    }

    #[test]
    fn noise_symmetric_about_a_line_leaves_its_slope() {
        // Alternating +-1 around y = 4x + 1 at pairs of equal x cancels exactly.
        let points: Vec<(f64, f64)> = (0..40)
            .map(|i| {
                let x = f64::from(i / 2);
                let noise = if i % 2 == 0 { 1.0 } else { -1.0 };
                (x, 4.0 * x + 1.0 + noise)
            })
            .collect();
        let slope = least_squares_slope(&points).expect("fit");
        assert!((slope - 4.0).abs() < 1e-12, "slope {slope}");
    }

    #[test]
    fn flat_series_have_zero_slope() {
        let points = [(0.0, 7.0), (1.0, 7.0), (2.0, 7.0)];
        assert_eq!(least_squares_slope(&points), Ok(0.0));
    }

    #[test]
    fn degenerate_fits_are_errors() {
        assert_eq!(least_squares_slope(&[]), Err(FitError::TooFewPoints(0)));
        assert_eq!(
            least_squares_slope(&[(1.0, 2.0)]),
            Err(FitError::TooFewPoints(1))
        );
        assert_eq!(
            least_squares_slope(&[(1.0, 2.0), (1.0, 5.0)]),
            Err(FitError::Degenerate)
        );
        assert_eq!(
            least_squares_slope(&[(0.0, 2.0), (f64::NAN, 5.0)]),
            Err(FitError::Degenerate)
        );
    }
}
