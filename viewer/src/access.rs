//! The access token: who may see and drive the scene when the viewer listens beyond loopback
//! (or is given `--token`).
//!
//! The page asks for the token once, in a form (`POST /login`), and the viewer answers a right
//! one with a session cookie: `HttpOnly` (no script reads it), `SameSite=Strict` (no other site's
//! page sends it) and `Secure` over HTTPS. Why a cookie rather than the token in the WebSocket's
//! URL or first message: the browser sends it with every request of the page, the page itself,
//! its scripts, `/stats` and the WebSocket's handshake alike, so nothing is served before the
//! token was given and the page's code needs no change; a URL's query ends up in the history
//! and logs, and a first message would leave the page and `/stats` open. The cookie holds a
//! random session secret, not the token. Tools send `Authorization: Bearer TOKEN` instead.
//!
//! A token is at least [`MIN_TOKEN_CHARS`] characters of letters, digits, `-`, `_`, `.` and `~`
//! (those a form sends unencoded), so that guessing one over the network is hopeless.

use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};

/// The fewest characters of a token.
pub const MIN_TOKEN_CHARS: usize = 16;

/// The token and the session secret of a viewer that asks for one.
#[derive(Debug, Clone)]
pub struct Access {
    token: String,
    /// The cookie's value once the token was given: random, one per run of the viewer.
    session: String,
    /// The cookie's name, with the port: browsers share cookies across a host's ports.
    cookie: String,
    https: bool,
}

/// `bytes` random bytes from the operating system, as hexadecimal.
fn random_hex(bytes: usize) -> anyhow::Result<String> {
    let mut random = vec![0u8; bytes];
    getrandom::fill(&mut random).map_err(|error| anyhow::anyhow!("random bytes: {error}"))?;
    Ok(random.iter().map(|byte| format!("{byte:02x}")).collect())
}

/// A new random token (128 bits).
pub fn generate_token() -> anyhow::Result<String> {
    random_hex(16)
}

/// Whether `token` is one the viewer takes, or why not.
pub fn check_token(token: &str) -> Result<(), String> {
    let allowed = |c: char| c.is_ascii_alphanumeric() || "-_.~".contains(c);
    if token.chars().count() < MIN_TOKEN_CHARS || !token.chars().all(allowed) {
        return Err(format!(
            "--token must be at least {MIN_TOKEN_CHARS} characters of letters, digits, '-', \
             '_', '.' and '~'"
        ));
    }
    Ok(())
}

/// Compares in a time that does not depend on where `a` and `b` differ.
fn same_secret(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0, |differ, (x, y)| differ | (x ^ y)) == 0
}

impl Access {
    /// Access by `token` (checked with [`check_token`]) to a viewer on `port`.
    pub fn new(token: String, port: u16, https: bool) -> anyhow::Result<Self> {
        check_token(&token).map_err(anyhow::Error::msg)?;
        Ok(Self {
            token,
            session: random_hex(32)?,
            cookie: format!("vas_viewer_{port}"),
            https,
        })
    }

    /// Whether a request with `headers` carries the session cookie or the token.
    pub fn admits(&self, headers: &HeaderMap) -> bool {
        let cookie = headers
            .get_all(header::COOKIE)
            .iter()
            .filter_map(|value| value.to_str().ok())
            .flat_map(|value| value.split(';'))
            .filter_map(|pair| pair.trim().split_once('='))
            .any(|(name, value)| name == self.cookie && self.is_session(value));
        let bearer = (headers.get(header::AUTHORIZATION))
            .and_then(|value| value.to_str().ok())
            .and_then(|value| value.strip_prefix("Bearer "))
            .is_some_and(|token| same_secret(token.as_bytes(), self.token.as_bytes()));
        cookie || bearer
    }

    fn is_session(&self, value: &str) -> bool {
        same_secret(value.as_bytes(), self.session.as_bytes())
    }

    /// Whether a login form's `body` (`token=...`, among other fields) holds the token.
    pub fn takes(&self, body: &[u8]) -> bool {
        let given = (body.split(|&byte| byte == b'&'))
            .find_map(|field| field.strip_prefix(b"token="))
            .unwrap_or_default();
        same_secret(given, self.token.as_bytes())
    }

    /// The answer to a form that gave the token: to the page, with the session cookie.
    pub fn session(&self) -> Response {
        let secure = if self.https { "; Secure" } else { "" };
        let cookie = format!(
            "{}={}; Path=/; HttpOnly; SameSite=Strict{secure}",
            self.cookie, self.session
        );
        let headers = [
            (header::LOCATION, "/".to_owned()),
            (header::SET_COOKIE, cookie),
        ];
        (StatusCode::SEE_OTHER, headers).into_response()
    }

    /// The page asking for the token, with `status` and a `note` above the form.
    pub fn form(&self, status: StatusCode, note: &str) -> Response {
        let page = LOGIN_PAGE.replace("{note}", note);
        (
            status,
            [
                (header::CONTENT_TYPE, "text/html; charset=utf-8"),
                (header::CACHE_CONTROL, "no-store"),
            ],
            page,
        )
            .into_response()
    }
}

/// The form the page asks for the token with; `{note}` is a fixed sentence, never input.
const LOGIN_PAGE: &str = r#"<!doctype html>
<html lang="en">
<head><meta charset="utf-8"><meta name="viewport" content="width=device-width, initial-scale=1">
<title>vas viewer: token</title><link rel="icon" href="data:,"></head>
<body style="font-family: sans-serif; margin: 2em">
<h1>vas viewer</h1>
<p>{note}</p>
<form method="post" action="/login">
<label>Access token <input id="token" name="token" type="password" autocomplete="off" autofocus></label>
<button id="enter" type="submit">Enter</button>
</form>
</body>
</html>
"#;

#[cfg(test)]
mod tests {
    use super::*;
    use axum::http::HeaderValue;

    const TOKEN: &str = "a-token-of-20-chars.";

    fn headers(name: header::HeaderName, value: &str) -> HeaderMap {
        let mut headers = HeaderMap::new();
        headers.insert(name, HeaderValue::from_str(value).unwrap());
        headers
    }

    #[test]
    fn the_token_opens_a_session_and_nothing_else_does() {
        let access = Access::new(TOKEN.into(), 8443, true).unwrap();
        assert!(!access.takes(b"token=wrong"));
        assert!(!access.takes(b"nothing"));
        assert!(!access.takes(format!("token={TOKEN}x").as_bytes()));
        assert!(access.takes(format!("x=1&token={TOKEN}").as_bytes()));
        let answer = access.session();
        assert_eq!(answer.status(), StatusCode::SEE_OTHER);
        let cookie = answer.headers()[header::SET_COOKIE].to_str().unwrap();
        assert!(
            cookie.contains("HttpOnly; SameSite=Strict; Secure"),
            "{cookie}"
        );
        let session = cookie.split(';').next().unwrap();
        assert!(!session.contains(TOKEN));

        assert!(access.admits(&headers(header::COOKIE, &format!("a=b; {session}"))));
        assert!(access.admits(&headers(header::AUTHORIZATION, &format!("Bearer {TOKEN}"))));
        assert!(!access.admits(&HeaderMap::new()));
        assert!(!access.admits(&headers(header::COOKIE, "vas_viewer_8443=00")));
        assert!(!access.admits(&headers(
            header::COOKIE,
            &format!("vas_viewer_8443={TOKEN}")
        )));
        assert!(!access.admits(&headers(header::AUTHORIZATION, "Bearer short")));
    }

    #[test]
    fn short_or_odd_tokens_are_refused() {
        assert!(check_token("short").is_err());
        assert!(check_token("sixteen chars !!").is_err());
        assert!(check_token(TOKEN).is_ok());
        let generated = generate_token().unwrap();
        assert!(check_token(&generated).is_ok());
        assert_ne!(generated, generate_token().unwrap());
    }
}
