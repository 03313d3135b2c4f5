//! A config's TOML error as one bounded line.

/// The longest excerpt of a file that an error message quotes, in characters.
const MAX_EXCERPT_CHARS: usize = 120;

/// A config's TOML error in one line: the line number, the offending line (cut to
/// [`MAX_EXCERPT_CHARS`], so that a file of one 50 MB line does not come back as a 50 MB
/// message) and the parser's reason.
pub fn describe_toml_error(text: &str, error: &toml::de::Error) -> String {
    let reason = error.message().trim();
    match error.span() {
        Some(span) => {
            let start = span.start.min(text.len());
            let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
            let line_number = text[..start].matches('\n').count() + 1;
            let line = text[line_start..].lines().next().unwrap_or("").trim();
            let mut excerpt: String = line.chars().take(MAX_EXCERPT_CHARS).collect();
            if excerpt.len() < line.len() {
                excerpt.push('…');
            }
            format!("line {line_number} (`{excerpt}`): {reason}")
        }
        None => reason.to_owned(),
    }
}
