//! Plain HTTP/1.1 requests to a local server, each on its own connection and sent as written
//! (no client normalises the path), for tests of what a server answers to exactly that.

use std::net::SocketAddr;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;

/// A `GET path` sent as written (no client normalises it): the status and the body.
pub async fn http_get(address: SocketAddr, path: &str) -> (u16, Vec<u8>) {
    http_request(address, "GET", path, None).await
}

/// One HTTP/1.1 request with an optional JSON body, on its own connection: the status and the
/// body of the answer.
pub async fn http_request(
    address: SocketAddr,
    method: &str,
    path: &str,
    json_body: Option<&str>,
) -> (u16, Vec<u8>) {
    let mut stream = TcpStream::connect(address).await.expect("connect");
    let mut request = format!("{method} {path} HTTP/1.1\r\nHost: {address}\r\n");
    if let Some(body) = json_body {
        request += &format!(
            "Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
            body.len()
        );
    } else {
        request += "\r\n";
    }
    stream
        .write_all(request.as_bytes())
        .await
        .expect("send the request");
    let mut response = Vec::new();
    let head_end = loop {
        if let Some(end) = response.windows(4).position(|window| window == b"\r\n\r\n") {
            break end + 4;
        }
        read_more(&mut stream, &mut response).await;
    };
    let head = String::from_utf8_lossy(&response[..head_end]).to_ascii_lowercase();
    let status = head
        .split(' ')
        .nth(1)
        .and_then(|code| code.parse().ok())
        .unwrap_or_else(|| panic!("no status in {head:?}"));
    let mut body = response.split_off(head_end);
    if head.contains("transfer-encoding: chunked") {
        while !body.ends_with(b"0\r\n\r\n") {
            read_more(&mut stream, &mut body).await;
        }
        return (status, dechunk(&body));
    }
    let length = head
        .lines()
        .find_map(|line| line.strip_prefix("content-length:"))
        .and_then(|length| length.trim().parse().ok())
        .unwrap_or_else(|| panic!("no length in {head:?}"));
    while body.len() < length {
        read_more(&mut stream, &mut body).await;
    }
    (status, body)
}

/// Appends what `stream` has next to `buffer`; panics at its end.
async fn read_more(stream: &mut TcpStream, buffer: &mut Vec<u8>) {
    let mut chunk = [0; 16 * 1024];
    let read = stream.read(&mut chunk).await.expect("read the response");
    assert!(read > 0, "the response ended early");
    buffer.extend_from_slice(&chunk[..read]);
}

/// The body of a chunked transfer.
fn dechunk(mut chunked: &[u8]) -> Vec<u8> {
    let mut body = Vec::new();
    loop {
        let line_end = chunked
            .windows(2)
            .position(|window| window == b"\r\n")
            .expect("a chunk size line");
        let size = usize::from_str_radix(String::from_utf8_lossy(&chunked[..line_end]).trim(), 16)
            .expect("a hexadecimal chunk size");
        if size == 0 {
            return body;
        }
        let start = line_end + 2;
        body.extend_from_slice(&chunked[start..start + size]);
        chunked = &chunked[start + size + 2..];
    }
}
