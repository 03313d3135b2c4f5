//! The report as one self-contained HTML page: the summary table (clash, contact, clearance, as
//! CATIA names them), a timeline figure per pair (inline SVG) and the worst moments. No script,
//! no file beside it: it opens anywhere.

use std::fmt::Write;

use super::{PairReport, Report, timeline};

/// How many of the closest moments the page lists.
const WORST_MOMENTS: usize = 10;

const STYLE: &str = "body{font-family:sans-serif;margin:2em;color:#222}\
table{border-collapse:collapse;margin:1em 0}th,td{border:1px solid #bbb;padding:.3em .6em}\
td.n{text-align:right;font-variant-numeric:tabular-nums}th{background:#eee}\
tr.clash td.s{background:#f4b6b6}tr.contact td.s{background:#f7e3a1}\
tr.clearance td.s{background:#cfe8cf}figure{margin:1em 0}";

/// The page of `report`.
pub fn page(report: &Report) -> String {
    let mut html = String::new();
    let title = format!(
        "Session report: {} in {}",
        escape(&report.recording),
        escape(&report.scene)
    );
    let _ = write!(
        html,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{title}</title>\
         <style>{STYLE}</style></head><body>\n<h1>{title}</h1>\n<p>{} samples, {} frames \
         ({} samples refused); threshold {:.3} mm; {} part pairs measured, {} came within the \
         threshold.</p>\n",
        report.samples,
        report.frames,
        report.rejected,
        report.threshold_m * 1e3,
        report.pairs_measured,
        report.pairs.len(),
    );
    summary(&mut html, report);
    html.push_str("<h2>Timelines</h2>\n");
    for pair in &report.pairs {
        let _ = writeln!(
            html,
            "<figure>{}<figcaption>{} – {}: clearance against sample; the red line is the \
             threshold, the dot the minimum.</figcaption></figure>",
            timeline::svg(pair, report.samples, report.threshold_m),
            escape(&pair.a),
            escape(&pair.b),
        );
    }
    worst_moments(&mut html, report);
    html.push_str("</body></html>\n");
    html
}

/// The summary table: one row per pair, the worst first.
fn summary(html: &mut String, report: &Report) {
    html.push_str(
        "<h2>Summary</h2>\n<table id=\"summary\"><thead><tr><th>part</th><th>part</th>\
         <th>status</th><th>minimum clearance (mm)</th><th>at sample</th><th>time (s)</th>\
         <th>below threshold (s)</th><th>contacts (samples)</th><th>clash frames</th></tr>\
         </thead><tbody>\n",
    );
    for pair in &report.pairs {
        let (clearance, sample, time) = match &pair.minimum {
            Some(m) => (
                format!("{:.4}", m.clearance_m * 1e3),
                m.sample.to_string(),
                format!("{:.3}", m.time_s),
            ),
            None => ("–".to_owned(), "–".to_owned(), "–".to_owned()),
        };
        let _ = writeln!(
            html,
            "<tr class=\"pair {status}\"><td>{}</td><td>{}</td><td class=\"s\">{status}</td>\
             <td class=\"n\">{clearance}</td><td class=\"n\">{sample}</td><td class=\"n\">{time}\
             </td><td class=\"n\">{:.3}</td><td>{}</td><td class=\"n\">{}</td></tr>",
            escape(&pair.a),
            escape(&pair.b),
            pair.seconds_below,
            contacts(pair),
            pair.clash_frames,
            status = pair.status.name(),
        );
    }
    html.push_str("</tbody></table>\n");
}

/// A pair's contact intervals: `177–198, 240–…`.
fn contacts(pair: &PairReport) -> String {
    if pair.contacts.is_empty() {
        return "none".to_owned();
    }
    (pair.contacts.iter())
        .map(|interval| match interval.end {
            Some(end) => format!("{}–{end}", interval.begin),
            None => format!("{}–end", interval.begin),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The closest moments of the session: each pair's minimum, and each clash's first sample.
fn worst_moments(html: &mut String, report: &Report) {
    html.push_str(
        "<h2>Worst moments</h2>\n<table id=\"worst\"><thead><tr><th>part</th><th>part</th>\
         <th>sample</th><th>time (s)</th><th>clearance (mm)</th><th>closest point on the first \
         (m)</th><th>closest point on the second (m)</th></tr></thead><tbody>\n",
    );
    let mut moments: Vec<&PairReport> = report.pairs.iter().collect();
    moments.sort_by(|x, y| {
        let clearance = |p: &PairReport| p.minimum.as_ref().map_or(0.0, |m| m.clearance_m);
        clearance(x).total_cmp(&clearance(y))
    });
    let point = |p: [f64; 3]| format!("({:.5}, {:.5}, {:.5})", p[0], p[1], p[2]);
    for pair in moments.into_iter().take(WORST_MOMENTS) {
        if let Some(first) = pair.first_clash {
            let _ = writeln!(
                html,
                "<tr><td>{}</td><td>{}</td><td class=\"n\">{first}</td><td></td>\
                 <td>clash ({} frames)</td><td></td><td></td></tr>",
                escape(&pair.a),
                escape(&pair.b),
                pair.clash_frames,
            );
        }
        if let Some(m) = &pair.minimum {
            let _ = writeln!(
                html,
                "<tr><td>{}</td><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{:.3}</td>\
                 <td class=\"n\">{:.4}</td><td>{}</td><td>{}</td></tr>",
                escape(&pair.a),
                escape(&pair.b),
                m.sample,
                m.time_s,
                m.clearance_m * 1e3,
                point(m.point_a),
                point(m.point_b),
            );
        }
    }
    html.push_str("</tbody></table>\n");
}

/// `text` with HTML's special characters escaped.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::escape;

    #[test]
    fn names_are_escaped() {
        assert_eq!(escape("<a & 'b'>"), "&lt;a &amp; &#39;b&#39;&gt;");
    }
}
