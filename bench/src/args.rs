//! Command-line pieces every benchmark shares: where results go (`--json`, `--svg`), the
//! parsers of finite numbers and counts, and the connection of the benchmarks that talk to a
//! running server.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context;
use clap::builder::TypedValueParser;
use serde::Serialize;
use vas_client::Client;

use crate::report::{LinePlot, write_json, write_svg_line_plot};

/// Where a benchmark writes its results besides the table it prints; nothing is written by
/// default, so a run never litters the working directory.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct OutputArgs {
    /// Write the results as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Draw the benchmark's figure as an SVG plot to this file.
    #[arg(long, value_name = "FILE")]
    pub svg: Option<PathBuf>,
}

impl OutputArgs {
    /// Writes `results` as JSON and draws `plot()` as SVG, each only where a file was asked for.
    pub fn write(
        &self,
        results: &impl Serialize,
        plot: impl FnOnce() -> LinePlot,
    ) -> anyhow::Result<()> {
        if let Some(path) = &self.json {
            write_json(path, results)?;
        }
        if let Some(path) = &self.svg {
            write_svg_line_plot(path, &plot())?;
        }
        Ok(())
    }
}

/// The server a benchmark talks to: the iceoryx2 prefix it was started with.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct ServerArgs {
    /// iceoryx2 prefix of the server (its `--prefix`); default: the iceoryx2 configuration's.
    #[arg(long, value_name = "P")]
    pub prefix: Option<String>,
}

/// How long a control request (scene info) may take before a benchmark gives up.
pub const CONTROL_TIMEOUT: Duration = Duration::from_secs(5);

/// The longest answer timeout the benchmarks accept, in milliseconds (an hour).
pub const MAX_TIMEOUT_MS: u64 = 3_600_000;

/// Connects with SIGINT and SIGTERM handled, so that long runs end cleanly.
pub fn connect(prefix: Option<&str>) -> anyhow::Result<Client> {
    Client::builder()
        .handle_termination_signals(true)
        .prefix(prefix)
        .connect()
        .context("cannot connect to the vas services")
}

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
/// [`MAX_TRIANGLES`](vas_server::geometry::shapes::MAX_TRIANGLES), as a scene config allows.
pub fn triangle_count() -> impl TypedValueParser<Value = usize> {
    clap::value_parser!(u64)
        .range(1..=vas_server::geometry::shapes::MAX_TRIANGLES as u64)
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
