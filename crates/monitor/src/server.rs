//! The HTTP side: routes, the Host and method guard, server-sent events.

use std::collections::VecDeque;
use std::convert::Infallible;
use std::path::PathBuf;
use std::sync::{Arc, PoisonError, RwLock};
use std::time::Duration;

use axum::Router;
use axum::extract::{Path as UrlPath, Request, State};
use axum::http::{HeaderMap, HeaderValue, Method, StatusCode, header};
use axum::middleware::{self, Next};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use futures_util::Stream;
use serde::Serialize;
use tokio::sync::watch;

use crate::follow::{Follower, RunFiles, point_records};
use crate::state;
use crate::view::{PointView, View};

/// The page, with its script and style inline: nothing else is fetched but this server's API.
const PAGE: &str = include_str!("page.html");
/// Width of the maps on the page, px.
const MAP_WIDTH_PX: usize = 480;
/// How often the follower looks at the run directory (two `stat` calls when nothing changed): the page updates
/// within a second of a commit, with room for a loaded machine.
pub const POLL_INTERVAL: Duration = Duration::from_millis(100);
/// How often an idle event stream sends a comment, so that proxies and `ssh -L` tunnels keep it open.
pub const KEEP_ALIVE: Duration = Duration::from_secs(10);

/// What the handlers share: the follower's last reading (replaced whole after each change, so that a request never
/// waits for a poll reading a file from a slow disk) and a counter bumped at each change.
pub(crate) struct Shared {
    pub(crate) dir: PathBuf,
    pub(crate) files: RwLock<Arc<RunFiles>>,
    pub(crate) changes: watch::Sender<u64>,
}

impl Shared {
    fn files(&self) -> Arc<RunFiles> {
        Arc::clone(&self.files.read().unwrap_or_else(PoisonError::into_inner))
    }

    fn dir(&self) -> PathBuf {
        self.dir.clone()
    }
}

/// Polls the run directory with `follower` every [`POLL_INTERVAL`] and publishes each change in `shared`. Runs on
/// its own thread (file reads are blocking and must not hold up the server); ends once the server has dropped its
/// share.
pub(crate) fn follow(mut follower: Follower, shared: &Arc<Shared>) {
    while Arc::strong_count(shared) > 1 {
        if follower.poll() {
            *shared.files.write().unwrap_or_else(PoisonError::into_inner) = Arc::new(follower.files().clone());
            shared.changes.send_modify(|n| *n += 1);
        }
        std::thread::sleep(POLL_INTERVAL);
    }
}

/// The router of the monitor over `shared`.
pub(crate) fn router(shared: Arc<Shared>) -> Router {
    Router::new()
        .route("/", get(page))
        .route("/api/state", get(api_state))
        .route("/api/view", get(api_view))
        .route("/api/point/{n}", get(api_point))
        .route("/events", get(events))
        .fallback(not_found)
        .layer(middleware::from_fn(guard))
        .with_state(shared)
}

/// Whether `host` (a Host header's value) names this machine's loopback interface: `localhost` or a name under
/// `.localhost`, an address in 127.0.0.0/8, or `[::1]`, with or without a port. Anything else is refused: a page
/// on another site that resolves its own name to 127.0.0.1 (DNS rebinding) sends its own name.
pub fn is_loopback_host(host: &str) -> bool {
    let name = if let Some(rest) = host.strip_prefix('[') {
        match rest.split_once(']') {
            Some((addr, port)) if port.is_empty() || port.starts_with(':') => return addr == "::1",
            _ => return false,
        }
    } else {
        host.rsplit_once(':').map_or(host, |(name, _)| name)
    };
    let name = name.to_ascii_lowercase();
    name == "localhost"
        || name.ends_with(".localhost")
        || name.parse::<std::net::Ipv4Addr>().is_ok_and(|a| a.is_loopback())
}

/// Refuses a request whose Host is not a loopback name (403) and every method but GET and HEAD (405): nothing here
/// changes anything.
async fn guard(request: Request, next: Next) -> Response {
    let host = request.headers().get(header::HOST).and_then(|h| h.to_str().ok());
    if !host.is_some_and(is_loopback_host) {
        return (StatusCode::FORBIDDEN, "refused: the Host header does not name the loopback interface\n")
            .into_response();
    }
    if request.method() != Method::GET && request.method() != Method::HEAD {
        let mut response =
            (StatusCode::METHOD_NOT_ALLOWED, "read-only: only GET and HEAD are served\n").into_response();
        response.headers_mut().insert(header::ALLOW, HeaderValue::from_static("GET, HEAD"));
        return response;
    }
    next.run(request).await
}

async fn not_found() -> Response {
    (StatusCode::NOT_FOUND, "not found\n").into_response()
}

fn json_response(value: &impl Serialize) -> Response {
    let mut headers = HeaderMap::new();
    headers.insert(header::CONTENT_TYPE, HeaderValue::from_static("application/json"));
    headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    (headers, to_json(value)).into_response()
}

/// `value` as JSON text (our types always serialize; `null` if one ever did not).
fn to_json(value: &impl Serialize) -> String {
    serde_json::to_string(value).unwrap_or_else(|_| "null".into())
}

/// Where the page takes the view as it was when it was served, so that its first paint shows the run without waiting
/// for a fetch.
const INITIAL_VIEW: &str = "/*INITIAL_VIEW*/null";

async fn page(State(shared): State<Arc<Shared>>) -> Response {
    let mut headers = HeaderMap::new();
    headers.insert(header::CONTENT_TYPE, HeaderValue::from_static("text/html; charset=utf-8"));
    headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    // Belt and braces for "self-contained": the browser itself refuses anything but this origin.
    headers.insert(
        header::CONTENT_SECURITY_POLICY,
        HeaderValue::from_static(
            "default-src 'none'; connect-src 'self'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src data:",
        ),
    );
    // Inside a script element, `</` would end it: JSON allows `<\/` for it.
    let view = to_json(&view(&shared)).replace("</", "<\\/");
    (headers, PAGE.replacen(INITIAL_VIEW, &view, 1)).into_response()
}

async fn api_state(State(shared): State<Arc<Shared>>) -> Response {
    json_response(&state::snapshot(&shared.files(), &shared.dir(), chrono::Utc::now()))
}

/// What the page draws: the snapshot, the maps, the last point's spectra and the log's tail.
fn view(shared: &Shared) -> View {
    let (files, dir) = (shared.files(), shared.dir());
    View::new(&files, state::snapshot(&files, &dir, chrono::Utc::now()), MAP_WIDTH_PX)
}

async fn api_view(State(shared): State<Arc<Shared>>) -> Response {
    json_response(&view(&shared))
}

/// One point's rows: status, SNR, retries, time and the impulse response of each actuator.
async fn api_point(State(shared): State<Arc<Shared>>, UrlPath(n): UrlPath<String>) -> Response {
    let Ok(point) = n.parse::<u32>() else {
        return (StatusCode::BAD_REQUEST, "the point is a grid index: a whole number\n").into_response();
    };
    let (files, dir) = (shared.files(), shared.dir());
    let read = tokio::task::spawn_blocking(move || point_records(&dir, &files.journal, point)).await;
    match read {
        Ok(Ok(Some(records))) => json_response(&PointView::new(point, records)),
        Ok(Ok(None)) => (StatusCode::NOT_FOUND, format!("point {point} is not committed\n")).into_response(),
        Ok(Err(e)) => (StatusCode::SERVICE_UNAVAILABLE, format!("{e}\n")).into_response(),
        Err(e) => (StatusCode::INTERNAL_SERVER_ERROR, format!("{e}\n")).into_response(),
    }
}

/// Which dataset `files` shows (its creation time), `None` before there is one.
fn dataset_of(files: &RunFiles) -> Option<String> {
    files.manifest.as_ref().map(|m| m.created_at.clone())
}

/// Server-sent events: one `commit` event per journal commit, its `id` the commit's sequence number. A client that
/// reconnects with `Last-Event-ID: N` gets every commit after N first; a new client starts at the next commit.
async fn events(
    State(shared): State<Arc<Shared>>,
    headers: HeaderMap,
) -> Sse<impl Stream<Item = Result<Event, Infallible>>> {
    let resume_after: Option<u64> =
        headers.get("last-event-id").and_then(|v| v.to_str().ok()).and_then(|v| v.trim().parse().ok());
    let after = match resume_after {
        Some(seq) => Some(seq),
        None => shared.files().journal.commits.last().map(|c| c.seq),
    };
    let changes = shared.changes.subscribe();
    // Sequence numbers count within one dataset: when another one replaces it in the directory, the stream starts
    // again at its first commit.
    let dataset = dataset_of(&shared.files());
    let stream = futures_util::stream::unfold(
        (shared, changes, after, dataset, VecDeque::<Event>::new()),
        |(shared, mut changes, mut after, mut dataset, mut queue)| async move {
            loop {
                if let Some(event) = queue.pop_front() {
                    return Some((Ok(event), (shared, changes, after, dataset, queue)));
                }
                let files = shared.files();
                let current = dataset_of(&files);
                if current != dataset {
                    (dataset, after) = (current, None);
                }
                let since = after;
                for commit in files.journal.commits.iter().filter(|c| since.is_none_or(|a| c.seq > a)) {
                    let data = to_json(&state::commit_event(&files, commit));
                    queue.push_back(Event::default().id(commit.seq.to_string()).event("commit").data(data));
                    after = Some(commit.seq);
                }
                if queue.is_empty() && changes.changed().await.is_err() {
                    return None;
                }
            }
        },
    );
    Sse::new(stream).keep_alive(KeepAlive::new().interval(KEEP_ALIVE))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_loopback_names_pass_the_host_check() {
        for host in [
            "localhost",
            "localhost:8765",
            "LocalHost",
            "a.localhost:1",
            "127.0.0.1",
            "127.1.2.3:80",
            "[::1]",
            "[::1]:8765",
        ] {
            assert!(is_loopback_host(host), "{host}");
        }
        for host in [
            "",
            "evil.example",
            "localhost.evil.example",
            "127.0.0.1.nip.io",
            "10.0.0.1:8765",
            "[::2]",
            "[::1",
            "[::1]x",
            "0.0.0.0",
        ] {
            assert!(!is_loopback_host(host), "{host}");
        }
    }
}
