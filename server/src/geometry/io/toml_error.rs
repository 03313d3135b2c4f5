//! A config's TOML error as one line that says where and what is wrong, and quotes no text of
//! the file: a server asked to load any file it can read (`load-scene /etc/shadow`) must not
//! answer with what the file holds.

/// Stands for a value of the file that the parser's reason quoted.
const LEFT_OUT: &str = "(a value of the file)";

/// A config's TOML error in one line: the line and column, and the parser's reason with every
/// value of the file it quotes (a string, a number, an unknown variant) left out. Only a key
/// that the config does not take is named, as the key is what is wrong.
pub fn describe_toml_error(text: &str, error: &toml::de::Error) -> String {
    let span = error
        .span()
        .map(|span| span.start.min(text.len())..span.end.min(text.len()));
    let quoted = span.as_ref().map_or("", |span| &text[span.clone()]);
    let reason = without_values(error.message().trim(), quoted);
    match span {
        Some(span) => {
            let before = &text[..span.start];
            let line_start = before.rfind('\n').map_or(0, |i| i + 1);
            let line = before.matches('\n').count() + 1;
            let column = before[line_start..].chars().count() + 1;
            format!("line {line}, column {column}: {reason}")
        }
        None => reason,
    }
}

/// `reason` with the values it quotes replaced by [`LEFT_OUT`]: every `"string"` (serde quotes
/// the file's strings so), and every `` `word` `` that is part of `span_text` (the file's text
/// the error is about), but for the key named by "unknown field" or "duplicate key". Other
/// `` `words` `` are the config's own names (`expected one of `name`, `parts``) and stay.
fn without_values(reason: &str, span_text: &str) -> String {
    let mut out = String::with_capacity(reason.len());
    let mut rest = reason;
    while let Some(open) = rest.find(['"', '`']) {
        let (before, from_quote) = rest.split_at(open);
        out.push_str(before);
        let quote = from_quote.as_bytes()[0] as char;
        let Some(length) = closing(&from_quote[1..], quote) else {
            // An unclosed quote: nothing after it is kept.
            out.push_str(LEFT_OUT);
            return out;
        };
        let word = &from_quote[1..1 + length];
        let names_a_key = out.ends_with("unknown field ") || out.ends_with("duplicate key ");
        let value = quote == '"' || (!names_a_key && span_text.contains(word));
        if value {
            out.push_str(LEFT_OUT);
        } else {
            out.push_str(&from_quote[..length + 2]);
        }
        rest = &from_quote[length + 2..];
    }
    out.push_str(rest);
    out
}

/// The length of the quoted text before the `quote` that closes it in `text` (a `"` escaped with
/// a backslash does not close).
fn closing(text: &str, quote: char) -> Option<usize> {
    let mut escaped = false;
    for (i, c) in text.char_indices() {
        match c {
            _ if escaped => escaped = false,
            '\\' if quote == '"' => escaped = true,
            _ if c == quote => return Some(i),
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use serde::Deserialize;

    use super::*;

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    #[expect(dead_code, reason = "only deserialised, to get serde's errors")]
    struct Config {
        name: String,
        count: Option<u32>,
        side: Option<Side>,
    }

    #[derive(Debug, Deserialize)]
    #[serde(rename_all = "lowercase")]
    enum Side {
        Left,
        Right,
    }

    fn described(text: &str) -> String {
        let error = toml::from_str::<Config>(text).expect_err("refused");
        describe_toml_error(text, &error)
    }

    #[test]
    fn errors_say_where_and_what_and_quote_no_value_of_the_file() {
        let secret = "hunter2-Secret";
        for (text, expected) in [
            // A file that is not TOML at all, such as a password file.
            (
                format!("root:{secret}:19000:0:99999:7:::\n"),
                "line 1, column 39: key with no value",
            ),
            (format!("name = {secret}\n"), "line 1, column 8"),
            (
                format!("name = 'a'\ncount = \"{secret}\"\n"),
                "line 2, column 9",
            ),
            (
                format!("name = \"{secret}\"\ncount = -{secret}\n"),
                "line 2",
            ),
            (
                format!("name = 'a'\nside = \"{secret}\"\n"),
                "expected `left` or `right`",
            ),
            (
                format!("name = 'a'\ncount = 4{}\n", "0".repeat(20)),
                "line 2",
            ),
            (format!("name = [\"{secret}\"]\n"), "line 1, column 8"),
        ] {
            let message = described(&text);
            assert!(message.contains(expected), "{expected:?} in {message:?}");
            assert!(!message.contains("hunter2"), "{message}");
            assert!(!message.contains("40000"), "{message}");
        }
        // A key the config does not take is named: the key is what is wrong.
        let message = described("name = 'a'\ncolour = 1\n");
        assert!(
            message.contains("line 2, column 1: unknown field `colour`, expected one of `name`"),
            "{message}"
        );
    }
}
