//! The command line, and what the viewer makes of it before it listens: where, whether over
//! TLS, with which access token, and its limits. A viewer that would listen beyond this machine
//! without TLS refuses to start here, before anything is bound.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use clap::Parser;
use tokio_rustls::TlsAcceptor;

use crate::access;
use crate::listen::{ListenAddress, beyond_loopback};
use crate::tls;

/// Serves a browser and WebXR view of a running vas server.
#[derive(Debug, Parser)]
#[command(name = "vas-viewer", version, about)]
pub struct Options {
    /// iceoryx2 prefix of the server (its `--prefix`); default: the iceoryx2 configuration's.
    #[arg(long)]
    pub prefix: Option<String>,
    /// Address to serve the page on, HOST:PORT (a host name is resolved). The default accepts
    /// connections from this machine only; a headset reaches it over USB with `adb reverse`.
    /// Beyond loopback the viewer needs --tls-cert and --tls-key, and asks for a token.
    #[arg(long, default_value = "127.0.0.1:8080")]
    pub listen: ListenAddress,
    /// The certificate chain to serve HTTPS with (PEM).
    #[arg(long, value_name = "FILE", requires = "tls_key")]
    pub tls_cert: Option<PathBuf>,
    /// The certificate's private key (PEM).
    #[arg(long, value_name = "FILE", requires = "tls_cert")]
    pub tls_key: Option<PathBuf>,
    /// The access token a page must give once (at least 16 letters, digits, '-', '_', '.' or
    /// '~'). Listening beyond loopback without one, the viewer makes one and prints it.
    #[arg(long)]
    pub token: Option<String>,
    /// The most pages connected at once; one more is refused (503) until another closes.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..))]
    pub max_pages: u32,
    /// Seconds a page may send nothing (not even the answer to a ping) before it is closed.
    #[arg(long, value_name = "SECONDS", default_value = "60", value_parser = seconds)]
    pub idle_timeout: Duration,
    /// Seconds a connection has to send a whole request head (or its TLS handshake), and an
    /// idle keep-alive connection its next one, before it is closed.
    #[arg(long, value_name = "SECONDS", default_value = "10", value_parser = seconds)]
    pub header_timeout: Duration,
}

/// A positive number of seconds.
fn seconds(text: &str) -> Result<Duration, String> {
    match text.parse::<f64>().map(Duration::try_from_secs_f64) {
        Ok(Ok(duration)) if !duration.is_zero() => Ok(duration),
        _ => Err(format!("{text:?} is not a positive number of seconds")),
    }
}

/// The access token, and whether the viewer made it (then it prints it).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Token {
    /// The token.
    pub token: String,
    /// Made by the viewer, not given.
    pub generated: bool,
}

/// What the viewer serves with.
pub struct Settings {
    /// `--listen` as given.
    pub listen: ListenAddress,
    /// Its addresses.
    pub addresses: Vec<SocketAddr>,
    /// HTTPS, when given a certificate.
    pub tls: Option<TlsAcceptor>,
    /// The token pages must give, if any.
    pub token: Option<Token>,
    /// The most pages at once.
    pub max_pages: usize,
    /// See [`Options::idle_timeout`].
    pub idle_timeout: Duration,
    /// See [`Options::header_timeout`].
    pub header_timeout: Duration,
}

impl Settings {
    /// The settings of `options`, or why the viewer must not start with them.
    pub fn new(options: &Options) -> anyhow::Result<Self> {
        let addresses = options.listen.resolve()?;
        let tls = match (&options.tls_cert, &options.tls_key) {
            (Some(cert), Some(key)) => Some(tls::acceptor(cert, key)?),
            _ => None,
        };
        let beyond = beyond_loopback(&addresses);
        anyhow::ensure!(
            !beyond || tls.is_some(),
            "refusing to listen on {} ({}) without TLS: beyond this machine anyone on the network \
             could watch and drive the scene. Give --tls-cert FILE and --tls-key FILE (the page \
             then asks for an access token), or listen on 127.0.0.1",
            options.listen,
            addresses
                .iter()
                .map(|a| a.ip().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
        let token = match &options.token {
            Some(token) => {
                access::check_token(token).map_err(anyhow::Error::msg)?;
                Some(Token {
                    token: token.clone(),
                    generated: false,
                })
            }
            None if beyond => Some(Token {
                token: access::generate_token()?,
                generated: true,
            }),
            None => None,
        };
        Ok(Self {
            listen: options.listen.clone(),
            addresses,
            tls,
            token,
            max_pages: options.max_pages as usize,
            idle_timeout: options.idle_timeout,
            header_timeout: options.header_timeout,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options(args: &[&str]) -> Options {
        Options::try_parse_from(std::iter::once("vas-viewer").chain(args.iter().copied()))
            .expect("options")
    }

    /// A self-signed certificate for localhost, written to a scratch folder.
    fn certificate() -> (tempfile::TempDir, String, String) {
        let folder = tempfile::tempdir().unwrap();
        let made = rcgen::generate_simple_self_signed(vec!["localhost".into()]).unwrap();
        let (cert, key) = (
            folder.path().join("cert.pem"),
            folder.path().join("key.pem"),
        );
        std::fs::write(&cert, made.cert.pem()).unwrap();
        std::fs::write(&key, made.signing_key.serialize_pem()).unwrap();
        let path = |p: std::path::PathBuf| p.to_str().unwrap().to_owned();
        (folder, path(cert), path(key))
    }

    #[test]
    fn beyond_loopback_needs_tls_and_gets_a_token() {
        let error = Settings::new(&options(&["--listen", "0.0.0.0:8443"]))
            .err()
            .unwrap();
        assert!(error.to_string().contains("without TLS"), "{error}");
        let (_folder, cert, key) = certificate();
        let tls = ["--tls-cert", &cert, "--tls-key", &key];
        let any = Settings::new(&options(
            &[&["--listen", "0.0.0.0:8443"], &tls[..]].concat(),
        ));
        let token = any.unwrap().token.unwrap();
        assert!(token.generated && access::check_token(&token.token).is_ok());

        let loopback = Settings::new(&options(&["--listen", "localhost:0"])).unwrap();
        assert_eq!(loopback.token, None);
        let given = [&["--token", "0123456789abcdef"], &tls[..]].concat();
        let given = Settings::new(&options(&given)).unwrap().token.unwrap();
        assert!(!given.generated);
        assert!(Settings::new(&options(&["--token", "short"])).is_err());
        assert!(Settings::new(&options(&["--tls-cert", &key, "--tls-key", &key])).is_err());
        let half = Options::try_parse_from(["vas-viewer", "--tls-cert", &cert]);
        assert!(half.is_err());
    }

    #[test]
    fn time_outs_are_positive_seconds() {
        assert_eq!(seconds("0.5"), Ok(Duration::from_millis(500)));
        for bad in ["0", "-1", "NaN", "inf", "1e300", "soon"] {
            assert!(seconds(bad).is_err(), "{bad}");
        }
    }
}
