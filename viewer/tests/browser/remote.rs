//! Remote viewing: beyond loopback the viewer refuses to start without TLS; over HTTPS with an
//! access token nothing is served before the token is given (no page, no `/stats`, no
//! WebSocket), and a browser enters by giving it once in the page's form.

use std::net::SocketAddr;
use std::sync::Arc;

use fantoccini::Locator;
use serde_json::json;
use tokio::net::TcpStream;
use tokio_rustls::TlsConnector;
use tokio_rustls::client::TlsStream;
use tokio_rustls::rustls::pki_types::{CertificateDer, ServerName};
use tokio_rustls::rustls::{ClientConfig, RootCertStore};
use vas_testkit::{Server, configs_dir};

use crate::harness::{Browser, Viewer};
use crate::requests::{exchange, request, upgrade_headers};

const TOKEN: &str = "correct-horse-battery-staple";

/// A self-signed certificate for localhost and 127.0.0.1, made for the test, and its key, in
/// PEM files.
struct Certificate {
    folder: tempfile::TempDir,
    der: CertificateDer<'static>,
}

impl Certificate {
    fn new() -> Self {
        let names = vec!["localhost".to_owned(), "127.0.0.1".to_owned()];
        let made = rcgen::generate_simple_self_signed(names).expect("a certificate");
        let folder = tempfile::tempdir().expect("a scratch folder");
        std::fs::write(folder.path().join("cert.pem"), made.cert.pem()).expect("write");
        let key = made.signing_key.serialize_pem();
        std::fs::write(folder.path().join("key.pem"), key).expect("write");
        let der = made.cert.der().clone();
        Self { folder, der }
    }

    fn file(&self, name: &str) -> String {
        let path = self.folder.path().join(name);
        path.to_str().expect("UTF-8").to_owned()
    }

    /// A TLS connection to `address` that trusts this certificate alone.
    async fn connect(&self, address: SocketAddr) -> TlsStream<TcpStream> {
        let mut roots = RootCertStore::empty();
        roots.add(self.der.clone()).expect("a root");
        let config = ClientConfig::builder()
            .with_root_certificates(roots)
            .with_no_client_auth();
        let tcp = TcpStream::connect(address).await.expect("connect");
        let name = ServerName::IpAddress(address.ip().into());
        let connector = TlsConnector::from(Arc::new(config));
        connector.connect(name, tcp).await.expect("a TLS handshake")
    }
}

#[test]
fn beyond_loopback_without_tls_the_viewer_refuses_to_start() {
    let certificate = Certificate::new();
    let (cert, key) = (certificate.file("cert.pem"), certificate.file("key.pem"));
    let refusals: [(&[&str], &str); 3] = [
        (&["--listen", "0.0.0.0:8443"], "without TLS"),
        (
            &["--listen", "0.0.0.0:8443", "--token", TOKEN],
            "without TLS",
        ),
        (
            &[
                "--listen",
                "0.0.0.0:8443",
                "--tls-cert",
                &cert,
                "--tls-key",
                &key,
                "--token",
                "short",
            ],
            "at least 16 characters",
        ),
    ];
    for (args, reason) in refusals {
        let (status, log) = Viewer::refusal(args);
        assert!(!status.success(), "{args:?} started");
        assert!(log.contains(reason), "{args:?}: {log}");
        assert!(!log.contains("serving the viewer"), "{args:?}: {log}");
    }
}

#[tokio::test]
async fn over_https_a_page_enters_with_the_token() {
    let scene = configs_dir().join("peg_insert.toml");
    let mut server =
        Server::start_with("viewer_https", &["--scene", scene.to_str().expect("UTF-8")]);
    let _client = server.connect();
    let certificate = Certificate::new();
    let (cert, key) = (certificate.file("cert.pem"), certificate.file("key.pem"));
    let args = [
        "--listen",
        "127.0.0.1:0",
        "--tls-cert",
        &cert,
        "--tls-key",
        &key,
        "--token",
        TOKEN,
    ];
    let viewer = Viewer::start_with(server.prefix(), &args);
    let host = viewer.address.to_string();
    assert_eq!(viewer.url(), format!("https://{host}/"));
    let (trusted, address) = (&certificate, viewer.address);
    let ask = move |request: String| async move {
        let stream = trusted.connect(address).await;
        exchange(stream, &request).await
    };

    // Without the token: the form asking for it, and nothing else.
    let origin = format!("https://{host}");
    let without = [
        request("GET", "/", &host, ""),
        request("GET", "/main.js", &host, ""),
        request("GET", "/stats", &host, ""),
        request("GET", "/ws", &host, &upgrade_headers(&origin)),
        request(
            "GET",
            "/stats",
            &host,
            "Authorization: Bearer wrong-token-of-some-length\r\n",
        ),
    ];
    for asked in &without {
        let (status, answer) = ask(asked.clone()).await;
        assert_eq!(status, 401, "{asked:?}: {answer}");
        assert!(answer.contains(r#"name="token""#), "{answer}");
        assert!(!answer.contains("pages_open"), "{answer}");
    }
    let login = |token: &str| {
        let body = format!("token={token}");
        format!(
            "POST /login HTTP/1.1\r\nHost: {host}\r\nOrigin: {origin}\r\n\
             Content-Type: application/x-www-form-urlencoded\r\nContent-Length: {}\r\n\
             Connection: close\r\n\r\n{body}",
            body.len()
        )
    };
    let (status, _) = ask(login("not-the-token-at-all")).await;
    assert_eq!(status, 401);
    // The right token opens a session: a cookie that lets the page's requests through.
    let (status, answer) = ask(login(TOKEN)).await;
    assert_eq!(status, 303, "{answer}");
    let cookie = (answer.lines())
        .find_map(|line| line.strip_prefix("set-cookie: "))
        .and_then(|cookie| cookie.split(';').next())
        .unwrap_or_else(|| panic!("no session cookie in {answer}"));
    let (status, answer) = ask(request(
        "GET",
        "/stats",
        &host,
        &format!("Cookie: {cookie}\r\n"),
    ))
    .await;
    assert_eq!(status, 200, "{answer}");
    let bearer = format!("Authorization: Bearer {TOKEN}\r\n");
    let (status, _) = ask(request(
        "GET",
        "/ws",
        &host,
        &(upgrade_headers(&origin) + &bearer),
    ))
    .await;
    assert_eq!(status, 101);

    // A browser (which does not know the self-signed certificate) is asked for the token once,
    // and then draws the scene over HTTPS and a secure WebSocket.
    let browser = Browser::start(640, 480).await;
    browser
        .cdp(
            "Security.setIgnoreCertificateErrors",
            json!({ "ignore": true }),
        )
        .await;
    browser
        .client
        .goto(&viewer.url())
        .await
        .expect("open the page");
    let field = browser
        .client
        .find(Locator::Id("token"))
        .await
        .expect("the token's field");
    field.send_keys(TOKEN).await.expect("type the token");
    let enter = browser
        .client
        .find(Locator::Id("enter"))
        .await
        .expect("the button");
    enter.click().await.expect("enter");
    browser
        .wait_for(
            "window.vasViewer?.scene?.name === 'peg insert' && window.vasViewer.received.frames > 0",
        )
        .await;
    assert_eq!(browser.eval::<String>("location.protocol").await, "https:");
    browser.close().await;

    let (_, answer) = ask(request("GET", "/stats", &host, &bearer)).await;
    let stats: serde_json::Value =
        serde_json::from_str(answer.split_once("\r\n\r\n").expect("a body").1).expect("JSON");
    assert_eq!(stats["pages_served"], 2, "{stats}");
    // Each request above without the token, the wrong token, and the browser's first visit.
    let refused = stats["refused_requests"]["token"]
        .as_u64()
        .expect("a count");
    assert!(refused > without.len() as u64 + 1, "{stats}");
}
