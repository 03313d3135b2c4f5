//! B11's outputs: the table, the bars checked against the rows, and the figure (mean time per
//! query against the tumbling distance, per pair and method).

use std::fmt;

use serde::Serialize;

use super::compare::Row;
use crate::report::{LinePlot, Series, Table, format_number};

/// The coherent bar: the DOP-tree's mean at most this times coal's where the pair is apart.
const COHERENT_BAR: f64 = 0.05;

/// The random bar: the DOP-tree's mean at most this times coal's.
const RANDOM_BAR: f64 = 0.5;

/// One bar of B11 and whether this run met it.
#[derive(Debug, Clone, Serialize)]
pub struct Bar {
    /// What the bar asks.
    pub name: String,
    /// Met or missed; none when not measured (coal missing).
    pub met: Option<bool>,
    /// The figures it was judged on.
    pub detail: String,
}

impl fmt::Display for Bar {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let verdict = match self.met {
            Some(true) => "met",
            Some(false) => "MISSED",
            None => "not measured",
        };
        write!(f, "bar: {}: {verdict}; {}", self.name, self.detail)
    }
}

/// The rows as a table.
pub fn table(rows: &[Row]) -> Table {
    let mut table = Table::new([
        "pair",
        "proc",
        "d",
        "method",
        "touch",
        "mean_us",
        "p99_us",
        "max_us",
        "coal_x",
        "max_diff",
        "pt_err",
        "bv_tests",
        "tri_tests",
    ]);
    let optional = |value: Option<f64>, format: fn(f64) -> String| value.map_or("-".into(), format);
    for r in rows {
        table.push_row([
            r.pair.clone(),
            r.procedure.to_owned(),
            optional(r.distance, |d| d.to_string()),
            r.method.clone(),
            format!("{:.0}%", 100.0 * r.touching),
            format_number(r.mean_us),
            format_number(r.p99_us),
            format_number(r.max_us),
            optional(r.reference_ratio, format_number),
            optional(r.max_difference, |d| format!("{d:.1e}")),
            format!("{:.1e}", r.point_error),
            optional(r.stats.map(|s| s.bv_tests), format_number),
            optional(r.stats.map(|s| s.tri_tests), format_number),
        ]);
    }
    table
}

/// The bars of B11 judged on `rows`.
pub fn bars(rows: &[Row]) -> Vec<Bar> {
    let ours = |r: &&Row| r.method == "doptree";
    let measured = rows.iter().any(|r| r.reference_ratio.is_some());
    let judged = |name: &str, checks: Vec<(String, bool)>| Bar {
        name: name.to_owned(),
        met: (measured && !checks.is_empty()).then(|| checks.iter().all(|(_, ok)| *ok)),
        detail: checks
            .iter()
            .map(|(what, _)| what.as_str())
            .collect::<Vec<_>>()
            .join(", "),
    };
    let differences = rows
        .iter()
        .filter(|r| r.method.starts_with("doptree"))
        .filter_map(|r| Some((r, r.max_difference?)))
        .map(|(r, difference)| {
            (
                format!(
                    "{} {}{} {}: {:.1e} of {:.1e}",
                    r.pair,
                    r.procedure,
                    r.distance.map(|d| format!(" {d}")).unwrap_or_default(),
                    r.method,
                    difference,
                    r.tolerance
                ),
                difference <= r.tolerance,
            )
        })
        .filter(|(_, ok)| !ok)
        .collect::<Vec<_>>();
    let equal = Bar {
        name: "distance equals coal's at every pose within 1e-6 of the meshes' size".into(),
        met: measured.then_some(differences.is_empty()),
        detail: if differences.is_empty() {
            "largest difference over the tolerance: ".to_owned()
                + &format!(
                    "{:.1e}",
                    rows.iter()
                        .filter(|r| r.method.starts_with("doptree"))
                        .filter_map(|r| Some(r.max_difference? / r.tolerance))
                        .fold(0.0, f64::max),
                )
        } else {
            differences
                .into_iter()
                .map(|(what, _)| what)
                .collect::<Vec<_>>()
                .join(", ")
        },
    };
    let ratio = |r: &Row, bar: f64| {
        r.reference_ratio.map(|x| {
            let at = r.distance.map(|d| format!(" {d}")).unwrap_or_default();
            (
                format!(
                    "{}{at}: {:.3}x (max {} us)",
                    r.pair,
                    x,
                    format_number(r.max_us)
                ),
                x <= bar,
            )
        })
    };
    let apart = |r: &&Row| {
        r.procedure == "coherent"
            && rows
                .iter()
                .filter(|o| {
                    o.pair == r.pair && o.procedure == r.procedure && o.distance == r.distance
                })
                .all(|o| o.touching == 0.0)
    };
    let coherent = rows
        .iter()
        .filter(ours)
        .filter(apart)
        .filter_map(|r| ratio(r, COHERENT_BAR))
        .collect();
    let random = rows
        .iter()
        .filter(ours)
        .filter(|r| r.procedure == "random")
        .filter_map(|r| ratio(r, RANDOM_BAR))
        .collect();
    // A cost in work, not time: the bounding-volume tests and triangle distances a query makes
    // are what the memory decides, and both are counted exactly, where two means of a few
    // microseconds differ by the timer's noise alone (the times are reported beside).
    let carried = rows
        .iter()
        .filter(ours)
        .filter(|r| r.procedure == "random")
        .filter_map(|r| {
            let cold = rows.iter().find(|o| {
                o.pair == r.pair && o.procedure == r.procedure && o.method == "doptree-cold"
            })?;
            let (work, cold_work) = (r.stats.as_ref()?, cold.stats.as_ref()?);
            Some((
                format!(
                    "{}: {} / {} bv / triangle tests carried, {} / {} cold ({} against {} us)",
                    r.pair,
                    format_number(work.bv_tests),
                    format_number(work.tri_tests),
                    format_number(cold_work.bv_tests),
                    format_number(cold_work.tri_tests),
                    format_number(r.mean_us),
                    format_number(cold.mean_us)
                ),
                work.bv_tests <= cold_work.bv_tests && work.tri_tests <= cold_work.tri_tests,
            ))
        })
        .collect::<Vec<_>>();
    let carried = Bar {
        name: "random: a carried memory costs no more work than a cold query".into(),
        met: (!carried.is_empty()).then(|| carried.iter().all(|(_, ok)| *ok)),
        detail: carried
            .into_iter()
            .map(|(what, _)| what)
            .collect::<Vec<_>>()
            .join(", "),
    };
    vec![
        equal,
        judged(
            "coherent: DOP-tree mean at most 0.05x coal's at every separated distance",
            coherent,
        ),
        judged("random: DOP-tree mean at most 0.5x coal's", random),
        carried,
    ]
}

/// Mean time per query against the tumbling distance, one curve per pair and method (the
/// DOP-tree with its memory carried, and the peers), log time axis.
pub fn plot(rows: &[Row]) -> LinePlot {
    let mut series: Vec<Series> = Vec::new();
    for r in rows.iter().filter(|r| r.method != "doptree-cold") {
        let Some(d) = r.distance else { continue };
        let name = format!("{} {}", r.pair, r.method);
        let point = (d, r.mean_us.max(1e-3));
        match series.iter_mut().find(|s| s.name == name) {
            Some(s) => s.points.push(point),
            None => series.push(Series {
                name,
                points: vec![point],
            }),
        }
    }
    for s in &mut series {
        s.points.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    LinePlot {
        title: "Distance, tumbling pairs: mean time per query".into(),
        x_label: "distance d".into(),
        y_label: "microseconds per query".into(),
        log_x: false,
        log_y: true,
        series,
    }
}
