//! Benchmark procedures of BENCHMARKS.md, shared by the `vas-server bench` subcommands and tests.

use clap::builder::TypedValueParser;

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

/// clap's parser of a count of passes or runs of a benchmark, which must be at least one: with
/// none there is nothing to time (and a table that says "fastest of 0 rounds").
pub fn pass_count() -> impl TypedValueParser<Value = usize> {
    clap::value_parser!(u64)
        .range(1..)
        .map(|count| count as usize)
}

/// clap's parser of the triangle count of a procedural shape: from 1 to
/// [`MAX_TRIANGLES`](crate::geometry::shapes::MAX_TRIANGLES), as a scene config allows.
pub fn triangle_count() -> impl TypedValueParser<Value = usize> {
    clap::value_parser!(u64)
        .range(1..=crate::geometry::shapes::MAX_TRIANGLES as u64)
        .map(|count| count as usize)
}

#[cfg(test)]
mod tests {
    use super::{finite_number, pass_count, triangle_count};
    use clap::Parser;

    #[test]
    fn only_finite_numbers_pass_the_command_line() {
        assert_eq!(finite_number("2.5"), Ok(2.5));
        assert_eq!(finite_number(" -1e-3"), Ok(-1e-3));
        for text in ["NaN", "nan", "inf", "-inf", "infinity", "1e400", "x", ""] {
            assert!(finite_number(text).is_err(), "{text:?} passed");
        }
    }

    /// A command line with one count, parsed by the given parser.
    #[derive(Parser)]
    struct Counts {
        #[arg(long, value_parser = pass_count())]
        passes: Option<usize>,
        #[arg(long, value_parser = triangle_count())]
        triangles: Option<usize>,
    }

    fn parse(flag: &str, text: &str) -> Result<Counts, clap::Error> {
        Counts::try_parse_from(["bench", &format!("--{flag}={text}")])
    }

    #[test]
    fn counts_of_passes_and_triangles_must_be_in_range() {
        assert_eq!(parse("passes", "3").unwrap().passes, Some(3));
        assert_eq!(parse("triangles", "1").unwrap().triangles, Some(1));
        assert_eq!(
            parse("triangles", "20000000").unwrap().triangles,
            Some(20_000_000)
        );
        for text in ["0", "-1", "x", ""] {
            assert!(parse("passes", text).is_err(), "{text:?} passed");
        }
        for text in ["0", "20000001", "-5", "1.5"] {
            assert!(parse("triangles", text).is_err(), "{text:?} passed");
        }
    }
}
