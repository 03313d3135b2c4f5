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

#[cfg(test)]
mod tests {
    use super::finite_number;

    #[test]
    fn only_finite_numbers_pass_the_command_line() {
        assert_eq!(finite_number("2.5"), Ok(2.5));
        assert_eq!(finite_number(" -1e-3"), Ok(-1e-3));
        for text in ["NaN", "nan", "inf", "-inf", "infinity", "1e400", "x", ""] {
            assert!(finite_number(text).is_err(), "{text:?} passed");
        }
    }
}
