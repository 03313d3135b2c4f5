//! Benchmark procedures of BENCHMARKS.md, shared by the `vas-server bench` subcommands and tests.

pub mod bounce;
pub mod grasp;
pub mod orbit;
pub mod random;
pub mod report;
pub mod slide;
pub mod tumble;

/// Parses a number of a benchmark's command line that must be finite: a NaN or infinite
/// distance or speed makes the poses meaningless, and the exact arithmetic of the triangle
/// tests stalls on NaN coordinates (the server's own poses and meshes are checked before they
/// get there).
pub fn finite_number(text: &str) -> Result<f64, String> {
    let value: f64 = text.trim().parse().map_err(|error| format!("{error}"))?;
    if value.is_finite() {
        Ok(value)
    } else {
        Err(format!("{text} is not a finite number"))
    }
}

/// Parses a count of passes or runs of a benchmark, which must be at least one: with none there
/// is nothing to time (and a table that says "fastest of 0 rounds").
pub fn pass_count(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(0) => Err("must be at least 1".to_owned()),
        Ok(count) => Ok(count),
        Err(error) => Err(format!("{error}")),
    }
}

/// Parses the triangle count of a procedural shape: from 1 to
/// [`MAX_TRIANGLES`](crate::geometry::shapes::MAX_TRIANGLES), as a scene config allows.
pub fn triangle_count(text: &str) -> Result<usize, String> {
    let max = crate::geometry::shapes::MAX_TRIANGLES;
    match text.trim().parse::<usize>() {
        Ok(count) if (1..=max).contains(&count) => Ok(count),
        Ok(count) => Err(format!("must be between 1 and {max}, not {count}")),
        Err(error) => Err(format!("{error}")),
    }
}

#[cfg(test)]
mod tests {
    use super::{finite_number, pass_count, triangle_count};

    #[test]
    fn only_finite_numbers_pass_the_command_line() {
        assert_eq!(finite_number("2.5"), Ok(2.5));
        assert_eq!(finite_number(" -1e-3"), Ok(-1e-3));
        for text in ["NaN", "nan", "inf", "-inf", "infinity", "1e400", "x", ""] {
            assert!(finite_number(text).is_err(), "{text:?} passed");
        }
    }

    #[test]
    fn counts_of_passes_and_triangles_must_be_in_range() {
        assert_eq!(pass_count("3"), Ok(3));
        assert_eq!(triangle_count("1"), Ok(1));
        assert_eq!(triangle_count("20000000"), Ok(20_000_000));
        for text in ["0", "-1", "x", ""] {
            assert!(pass_count(text).is_err(), "{text:?} passed");
        }
        for text in ["0", "20000001", "-5", "1.5"] {
            assert!(triangle_count(text).is_err(), "{text:?} passed");
        }
    }
}
