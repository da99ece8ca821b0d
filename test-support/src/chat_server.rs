//! A loopback OpenAI-compatible chat-completions server for the tests of the
//! LLM context policy: std `TcpListener` on `127.0.0.1:0` (never another
//! address), one thread per connection, `POST /v1/chat/completions` and,
//! when given a model list ([`serve_with_models`]), `GET /v1/models`
//! (anything else gets a 404).
//!
//! # Example
//! ```
//! use std::sync::Arc;
//! use std::time::Duration;
//! use sornav_test_support::chat_server::{completion, serve};
//!
//! let server = serve(Arc::new(|_request| {
//!     (200, completion(r#"{"action":"continue_explore"}"#), Duration::ZERO)
//! }));
//! assert!(server.base_url.starts_with("http://127.0.0.1:"));
//! assert!(server.base_url.ends_with("/v1"));
//! ```

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::Duration;

use serde_json::{Value, json};

/// What the server answers to a request body: HTTP status, response body
/// and a delay before answering.
pub type Handler = dyn Fn(&Value) -> (u16, String, Duration) + Send + Sync;

/// A running server (it lives until the test process ends).
pub struct ChatServer {
    /// `http://127.0.0.1:PORT/v1`, the client's base URL.
    pub base_url: String,
    /// Every request body received, in arrival order.
    pub requests: Arc<Mutex<Vec<Value>>>,
    /// Chat-completion requests received.
    pub hits: Arc<AtomicUsize>,
    /// Chat-completion answers written (after their delay).
    pub answered: Arc<AtomicUsize>,
}

impl ChatServer {
    /// Chat-completion requests received so far.
    pub fn hits(&self) -> usize {
        self.hits.load(Ordering::SeqCst)
    }

    /// Chat-completion answers written so far.
    pub fn answered(&self) -> usize {
        self.answered.load(Ordering::SeqCst)
    }
}

/// A request the server understands.
enum Request {
    /// `POST /v1/chat/completions` with its JSON body.
    Chat(Value),
    /// `GET /v1/models`.
    Models,
}

/// The request read from `stream`; `None` for any other request or a
/// malformed one.
fn read_request(stream: &mut TcpStream) -> Option<Request> {
    let mut reader = BufReader::new(stream.try_clone().ok()?);
    let mut line = String::new();
    reader.read_line(&mut line).ok()?;
    if line.starts_with("GET /v1/models ") {
        return Some(Request::Models);
    }
    if !line.starts_with("POST /v1/chat/completions ") {
        return None;
    }
    let mut length = 0usize;
    loop {
        line.clear();
        reader.read_line(&mut line).ok()?;
        let l = line.trim_end();
        if l.is_empty() {
            break;
        }
        if let Some((k, v)) = l.split_once(':')
            && k.eq_ignore_ascii_case("content-length")
        {
            length = v.trim().parse().ok()?;
        }
    }
    let mut body = vec![0; length];
    reader.read_exact(&mut body).ok()?;
    serde_json::from_slice(&body).ok().map(Request::Chat)
}

fn respond(stream: &mut TcpStream, status: u16, body: &str) -> bool {
    let text = format!(
        "HTTP/1.1 {status} X\r\ncontent-type: application/json\r\ncontent-length: {}\r\nconnection: close\r\n\r\n{body}",
        body.len()
    );
    stream.write_all(text.as_bytes()).is_ok()
}

/// Starts a server on a free loopback port answering chat completions with
/// `handler` (`GET /v1/models` gets a 404).
///
/// # Panics
/// When no loopback port can be bound (the test cannot run then).
pub fn serve(handler: Arc<Handler>) -> ChatServer {
    serve_with_models(handler, None)
}

/// [`serve`], and `GET /v1/models` lists `models` when given (an OpenAI
/// model list: `{"object":"list","data":[{"id":...}]}`).
///
/// # Panics
/// When no loopback port can be bound (the test cannot run then).
pub fn serve_with_models(handler: Arc<Handler>, models: Option<Vec<String>>) -> ChatServer {
    let listener = TcpListener::bind("127.0.0.1:0").expect("bind loopback");
    let base_url = format!(
        "http://{}/v1",
        listener.local_addr().expect("bound address")
    );
    let requests = Arc::new(Mutex::new(Vec::new()));
    let hits = Arc::new(AtomicUsize::new(0));
    let answered = Arc::new(AtomicUsize::new(0));
    let (req2, hits2, answered2) = (
        Arc::clone(&requests),
        Arc::clone(&hits),
        Arc::clone(&answered),
    );
    let models: Option<Arc<str>> = models.map(|m| {
        let data: Vec<Value> = m
            .iter()
            .map(|id| json!({"id": id, "object": "model"}))
            .collect();
        json!({"object": "list", "data": data}).to_string().into()
    });
    thread::spawn(move || {
        for stream in listener.incoming() {
            let Ok(mut stream) = stream else { continue };
            let handler = Arc::clone(&handler);
            let models = models.clone();
            let (req3, hits3, answered3) = (
                Arc::clone(&req2),
                Arc::clone(&hits2),
                Arc::clone(&answered2),
            );
            thread::spawn(move || {
                let body = match (read_request(&mut stream), models) {
                    (Some(Request::Chat(body)), _) => body,
                    (Some(Request::Models), Some(list)) => {
                        respond(&mut stream, 200, &list);
                        return;
                    }
                    _ => {
                        let _ = stream.write_all(
                            b"HTTP/1.1 404 Not Found\r\ncontent-length: 0\r\nconnection: close\r\n\r\n",
                        );
                        return;
                    }
                };
                hits3.fetch_add(1, Ordering::SeqCst);
                let (status, reply, delay) = handler(&body);
                if let Ok(mut requests) = req3.lock() {
                    requests.push(body);
                }
                thread::sleep(delay);
                if respond(&mut stream, status, &reply) {
                    answered3.fetch_add(1, Ordering::SeqCst);
                }
            });
        }
    });
    ChatServer {
        base_url,
        requests,
        hits,
        answered,
    }
}

/// A chat-completion response body whose message content is `content`.
pub fn completion(content: &str) -> String {
    json!({
        "id": "chatcmpl-1", "object": "chat.completion", "created": 0, "model": "test",
        "choices": [{"index": 0, "finish_reason": "stop", "message": {"role": "assistant", "content": content}}],
        "usage": {"prompt_tokens": 1, "completion_tokens": 1, "total_tokens": 2}
    })
    .to_string()
}
