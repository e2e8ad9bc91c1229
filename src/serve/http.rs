//! Just enough HTTP/1.1 for one local page: one request per connection (`Connection: close`), bodies only
//! with `Content-Length`, and every size bounded before it is read. The request head is parsed by
//! `httparse` (no allocation, a fixed header array, so too many headers is an error, not a growing
//! buffer); everything else here is reading, limits and writing.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::Duration;

/// Largest request body, bytes (a scene with [`MAX_EDIT_WALL_POINTS`] points is about 100 KiB).
///
/// [`MAX_EDIT_WALL_POINTS`]: crate::scene::edit::MAX_EDIT_WALL_POINTS
pub const MAX_BODY_BYTES: usize = 1 << 20;
/// Largest request line plus headers, bytes.
pub const MAX_HEAD_BYTES: usize = 16 * 1024;
/// Most headers a request may carry.
pub const MAX_HEADERS: usize = 48;
/// How long a connection may take to send its request or read its answer.
pub const IO_TIMEOUT: Duration = Duration::from_secs(10);

/// A request as the handlers see it.
#[derive(Clone, Debug, PartialEq)]
pub struct Request {
    /// `GET`, `POST`, ...
    pub method: String,
    /// The path without the query (`/api/solve`).
    pub path: String,
    /// The `Host` header, if given.
    pub host: Option<String>,
    /// The `Content-Type` header, if given.
    pub content_type: Option<String>,
    /// The body (empty without `Content-Length`).
    pub body: Vec<u8>,
}

/// An answer: status, type, body and any extra headers.
#[derive(Clone, Debug, PartialEq)]
pub struct Response {
    /// HTTP status code.
    pub status: u16,
    /// `Content-Type`.
    pub content_type: &'static str,
    /// The body.
    pub body: Vec<u8>,
    /// Extra headers (`Content-Disposition`, ...).
    pub headers: Vec<(&'static str, String)>,
}

impl Response {
    /// A JSON answer.
    pub fn json(status: u16, value: &serde_json::Value) -> Response {
        Response {
            status,
            content_type: "application/json",
            body: value.to_string().into_bytes(),
            headers: Vec::new(),
        }
    }

    /// A JSON error answer: `{"status": kind, "error": message}`.
    pub fn error(status: u16, kind: &str, message: &str) -> Response {
        Response::json(
            status,
            &serde_json::json!({ "status": kind, "error": message }),
        )
    }

    /// A file to download as `filename`.
    pub fn download(content_type: &'static str, filename: &str, body: Vec<u8>) -> Response {
        Response {
            status: 200,
            content_type,
            body,
            headers: vec![(
                "Content-Disposition",
                format!("attachment; filename=\"{filename}\""),
            )],
        }
    }
}

/// Why a request could not be read: an answer to send, or nothing (the peer left).
#[derive(Debug)]
pub enum ReadError {
    /// The connection closed or timed out before a whole request came.
    Gone,
    /// A request the server refuses; send this and close.
    Refuse(Response),
}

fn refuse(status: u16, message: &str) -> ReadError {
    ReadError::Refuse(Response::error(status, "bad-request", message))
}

/// Reads one request, enforcing [`MAX_HEAD_BYTES`], [`MAX_HEADERS`] and [`MAX_BODY_BYTES`].
pub fn read_request(stream: &mut TcpStream) -> Result<Request, ReadError> {
    let mut buf = Vec::with_capacity(4096);
    let mut chunk = [0u8; 4096];
    let (head_len, mut request) = loop {
        let n = stream.read(&mut chunk).map_err(|_| ReadError::Gone)?;
        if n == 0 {
            return Err(ReadError::Gone);
        }
        buf.extend_from_slice(&chunk[..n]);
        let mut headers = [httparse::EMPTY_HEADER; MAX_HEADERS];
        let mut parsed = httparse::Request::new(&mut headers);
        match parsed.parse(&buf) {
            Ok(httparse::Status::Complete(len)) => break (len, head_of(&parsed)?),
            Ok(httparse::Status::Partial) if buf.len() < MAX_HEAD_BYTES => continue,
            Ok(httparse::Status::Partial) => {
                return Err(refuse(
                    431,
                    &format!("the request head is over {MAX_HEAD_BYTES} bytes"),
                ))
            }
            Err(httparse::Error::TooManyHeaders) => {
                return Err(refuse(431, &format!("more than {MAX_HEADERS} headers")))
            }
            Err(e) => return Err(refuse(400, &format!("malformed request: {e}"))),
        }
    };
    if buf.len() - head_len > request.body_len {
        return Err(refuse(400, "more bytes than the Content-Length"));
    }
    if request.expects_continue && request.body_len > buf.len() - head_len {
        let _ = stream.write_all(b"HTTP/1.1 100 Continue\r\n\r\n");
    }
    let mut body = buf.split_off(head_len);
    body.reserve_exact(request.body_len - body.len());
    let mut rest = (&mut *stream).take((request.body_len - body.len()) as u64);
    rest.read_to_end(&mut body).map_err(|_| ReadError::Gone)?;
    if body.len() < request.body_len {
        return Err(ReadError::Gone);
    }
    request.request.body = body;
    Ok(request.request)
}

/// A parsed head: the request without its body, the body's length, and `Expect: 100-continue`.
struct Head {
    request: Request,
    body_len: usize,
    expects_continue: bool,
}

fn head_of(parsed: &httparse::Request<'_, '_>) -> Result<Head, ReadError> {
    let header = |name: &str| {
        parsed
            .headers
            .iter()
            .find(|h| h.name.eq_ignore_ascii_case(name))
            .map(|h| String::from_utf8_lossy(h.value).trim().to_string())
    };
    if header("transfer-encoding").is_some() {
        return Err(refuse(
            411,
            "chunked bodies are not accepted; send a Content-Length",
        ));
    }
    let body_len = match header("content-length") {
        None => 0,
        Some(v) => v
            .parse::<usize>()
            .map_err(|_| refuse(400, "Content-Length is not a whole number"))?,
    };
    if body_len > MAX_BODY_BYTES {
        return Err(ReadError::Refuse(Response::error(
            413,
            "too-large",
            &format!("a request body of {body_len} bytes; at most {MAX_BODY_BYTES}"),
        )));
    }
    let target = parsed.path.unwrap_or("/");
    let path = target.split(['?', '#']).next().unwrap_or("/").to_string();
    Ok(Head {
        request: Request {
            method: parsed.method.unwrap_or("GET").to_string(),
            path,
            host: header("host"),
            content_type: header("content-type"),
            body: Vec::new(),
        },
        body_len,
        expects_continue: header("expect").is_some_and(|v| v.eq_ignore_ascii_case("100-continue")),
    })
}

/// Reason phrases of the statuses the server sends.
fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        409 => "Conflict",
        411 => "Length Required",
        413 => "Payload Too Large",
        415 => "Unsupported Media Type",
        422 => "Unprocessable Content",
        431 => "Request Header Fields Too Large",
        500 => "Internal Server Error",
        503 => "Service Unavailable",
        _ => "Status",
    }
}

/// Writes `response` and closes the write side. Nothing from elsewhere may be loaded by what is served
/// (the content security policy), and nothing is cached.
pub fn write_response(stream: &mut TcpStream, response: &Response) -> std::io::Result<()> {
    let mut head = format!(
        "HTTP/1.1 {} {}\r\nContent-Type: {}\r\nContent-Length: {}\r\nConnection: close\r\n\
         Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\n\
         Content-Security-Policy: default-src 'none'; script-src 'unsafe-inline'; \
         style-src 'unsafe-inline'; connect-src 'self'; img-src data:; form-action 'none'\r\n",
        response.status,
        reason(response.status),
        response.content_type,
        response.body.len()
    );
    for (name, value) in &response.headers {
        head.push_str(&format!("{name}: {value}\r\n"));
    }
    head.push_str("\r\n");
    stream.write_all(head.as_bytes())?;
    stream.write_all(&response.body)?;
    stream.flush()
}

/// After refusing a request whose body is still coming, reads (and drops) a bounded amount of it so the
/// peer sees the answer instead of a reset connection.
pub fn drain(stream: &mut TcpStream) {
    let _ = stream.set_read_timeout(Some(Duration::from_millis(500)));
    let _ = std::io::copy(
        &mut (&mut *stream).take(4 * MAX_BODY_BYTES as u64),
        &mut std::io::sink(),
    );
}
