//! The server's loop figures, read from its log: each loop logs a "loop rate" line with its
//! frames, their rate, mean, 99th-percentile and longest time at the end of every window
//! (every ten seconds, at a restart, and when it ends). The lines are tracing's default format,
//! `TIME LEVEL TARGET: loop rate loop_name="collision" frames=5120 ... p50_us=20.1 p99_us=41.2 ...`
//! (the clearance stage logs the same lines, as `loop_name="clearance"`), read
//! field by field so that their order and any colour codes do not matter.

use std::collections::BTreeMap;

use anyhow::{Context, Result, bail};
use serde::Serialize;

/// One window of one loop, as a log line gives it.
#[derive(Debug, Clone, PartialEq)]
pub struct Window {
    /// `grasping`, `sliding` or `collision`.
    pub name: String,
    pub frames: u64,
    /// The window's median, when the line gives it.
    pub p50_us: Option<f64>,
    pub p99_us: f64,
    pub max_us: f64,
}

/// A loop's figures over several windows.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct LoopFigures {
    /// Frames processed.
    pub frames: u64,
    /// The largest of the windows' medians (their own when there is one window; 0 when no line
    /// gives one).
    pub p50_us: f64,
    /// The largest of the windows' 99th percentiles (their own when there is one window).
    pub p99_us: f64,
    /// The longest frame.
    pub max_us: f64,
}

/// The windows logged in `log` (a server's stderr), in order.
pub fn windows(log: &str) -> Result<Vec<Window>> {
    log.lines()
        .filter(|line| line.contains("loop rate"))
        .map(|line| parse(line).with_context(|| format!("reading the log line {line:?}")))
        .collect()
}

/// Each loop's figures over `windows`, by loop name.
pub fn figures(windows: &[Window]) -> BTreeMap<String, LoopFigures> {
    let mut figures: BTreeMap<String, LoopFigures> = BTreeMap::new();
    for window in windows {
        let loop_figures = figures.entry(window.name.clone()).or_default();
        loop_figures.frames += window.frames;
        loop_figures.p50_us = loop_figures.p50_us.max(window.p50_us.unwrap_or(0.0));
        loop_figures.p99_us = loop_figures.p99_us.max(window.p99_us);
        loop_figures.max_us = loop_figures.max_us.max(window.max_us);
    }
    figures
}

/// One "loop rate" line.
fn parse(line: &str) -> Result<Window> {
    let plain = strip_colours(line);
    let fields: BTreeMap<&str, &str> = plain
        .split_whitespace()
        .filter_map(|token| token.split_once('='))
        .map(|(key, value)| (key, value.trim_matches('"')))
        .collect();
    let text = |key: &str| {
        fields
            .get(key)
            .copied()
            .with_context(|| format!("no {key} field"))
    };
    let number = |key: &str| -> Result<f64> {
        let value: f64 = text(key)?
            .parse()
            .with_context(|| format!("{key} is not a number"))?;
        if !value.is_finite() || value < 0.0 {
            bail!("{key} is {value}");
        }
        Ok(value)
    };
    Ok(Window {
        name: text("loop_name")?.to_owned(),
        frames: text("frames")?.parse().context("frames is not a count")?,
        p50_us: fields
            .contains_key("p50_us")
            .then(|| number("p50_us"))
            .transpose()?,
        p99_us: number("p99_us")?,
        max_us: number("max_us")?,
    })
}

/// `line` without ANSI colour codes (ESC `[` ... `m`), which tracing writes to a terminal.
fn strip_colours(line: &str) -> String {
    let mut plain = String::with_capacity(line.len());
    let mut chars = line.chars();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            chars.by_ref().find(|&c| c == 'm');
        } else {
            plain.push(c);
        }
    }
    plain
}

#[cfg(test)]
mod tests {
    use super::*;

    const LOG: &str = "\
2026-12-03T10:00:00.000001Z  INFO vas_server::runtime::io: serving lockstep=false
2026-12-03T10:00:01.000001Z  INFO vas_server::runtime::loops: loop rate loop_name=\"grasping\" \
frames=1000 frames_per_s=998 busy_percent=20.0 mean_us=200.0 p99_us=400.5 max_us=900.0 sustains_per_s=5000
2026-12-03T10:00:01.000002Z  INFO vas_server::runtime::loops: loop rate loop_name=\"collision\" \
frames=3000 frames_per_s=2990 busy_percent=3.0 mean_us=10.0 p50_us=9.5 p99_us=30.0 max_us=80.0 sustains_per_s=100000
2026-12-03T10:00:02.000001Z  INFO vas_server::runtime::loops: loop rate loop_name=\"grasping\" \
frames=3000 frames_per_s=1000 busy_percent=60.0 mean_us=600.0 p99_us=300.0 max_us=1000.0 sustains_per_s=1666
";

    #[test]
    fn windows_are_read_and_combined_per_loop() {
        let windows = windows(LOG).expect("the log reads");
        assert_eq!(windows.len(), 3);
        assert_eq!(windows[1].name, "collision");
        let figures = figures(&windows);
        let grasping = figures["grasping"];
        assert_eq!(grasping.frames, 4000);
        assert_eq!((grasping.p99_us, grasping.max_us), (400.5, 1000.0));
        assert_eq!(figures["collision"].frames, 3000);
        assert_eq!((figures["collision"].p50_us, grasping.p50_us), (9.5, 0.0));
        assert!(!figures.contains_key("sliding"));
    }

    #[test]
    fn colour_codes_and_field_order_do_not_matter() {
        let line = "\u{1b}[2m2026\u{1b}[0m \u{1b}[32m INFO\u{1b}[0m loop rate \
                    \u{1b}[3mp99_us\u{1b}[0m\u{1b}[2m=\u{1b}[0m12.5 max_us=20 mean_us=4 frames=7 \
                    loop_name=\"sliding\"";
        let window = parse(line).expect("the line reads");
        assert_eq!(window.name, "sliding");
        assert_eq!(
            (window.frames, window.p99_us, window.max_us),
            (7, 12.5, 20.0)
        );
    }

    #[test]
    fn a_line_without_a_figure_is_an_error() {
        assert!(windows("INFO loop rate loop_name=\"sliding\" frames=7 max_us=1").is_err());
        assert!(
            windows("INFO loop rate loop_name=\"sliding\" frames=x mean_us=1 p99_us=1 max_us=1")
                .is_err()
        );
    }
}
