//! The browser preview of `lampshade watch --serve`: a page that shows the latest image, the
//! render time, and the diagnostics over the last good image when a save breaks the scene.
//!
//! Design:
//! - [tiny_http](https://docs.rs/tiny_http) on `127.0.0.1` only, never `0.0.0.0`: the preview is
//!   for the person at this machine, and scene files, paths and diagnostics are theirs. The
//!   `Host` header must name `127.0.0.1` or `localhost` at our port, so a web page elsewhere
//!   cannot reach the server through DNS rebinding.
//! - Routes: `/` (a static page, `preview.html`, and its scripts under `/page/`), `/image.png`
//!   (the last good image), `/events` (server-sent events), `/api/state` (the state the page
//!   was last sent, for a script loaded after the first event), `/turntable.png` (the scene
//!   orbiting, made on request: `super::turntable`), the inspector's (`watch::pick`):
//!   `/api/pick`, `/api/object-mask`, and the POST routes of the view (`watch::view`:
//!   `/api/view`, `/api/camera`, `/api/buffer`), which a page of another site may not call (its
//!   `Origin` is refused). Each build publishes one small JSON state, the same shape the
//!   page receives on connecting; the page swaps the image in only once the new one has loaded
//!   (no flicker) and shows or hides the diagnostics overlay.
//! - The last good image is kept in memory as the PNG bytes just written, so the page can never
//!   read a file that is being replaced, and an image URL carries a version unique to this run
//!   (`<start time>-<generation>`) so no cache, even across restarts, serves an old one.
//! - One thread accepts and answers requests; each `/events` stream gets a thread of its own
//!   that sleeps on a channel, sends a comment every [`KEEP_ALIVE`] to notice closed pages, and
//!   ends when the page goes away or the server stops.
//!
//! Rejected: WebSocket (two-way, needs a handshake implementation or another crate, and the
//! browser's `EventSource` already reconnects by itself); polling the image (latency, and
//! needless requests while nothing changes); reloading the page (flicker, loses scroll).

use std::io::{self, Write};
use std::net::{Ipv4Addr, TcpListener};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use serde::Serialize;
use tiny_http::{Header, Method, Request, Response, Server};

use super::turntable::TurntableSource;
use super::view::{Inbox, ViewSummary};
use crate::inspect::ImageOrigin;

/// The page, served as is.
const PAGE: &str = include_str!("preview.html");

/// The compare views (swipe, onion skin, difference), shared with `check --report`'s page.
const COMPARE_SCRIPT: &str = include_str!("page/compare.js");

/// The page's scripts, served under `/page/`.
const PAGE_FILES: &[(&str, &str)] = &[("view.js", include_str!("page/view.js"))];

/// How often an idle event stream sends a comment, so a closed page is noticed and its thread
/// ends.
const KEEP_ALIVE: Duration = Duration::from_secs(15);

/// What the page shows; sent as JSON on every build.
#[derive(Debug, Clone, Serialize)]
struct PreviewState {
    /// The scene's file name, for the page title.
    scene: String,
    /// Builds so far (a failed build counts).
    build: u64,
    /// Version of the last good image (for the URL), if there is one.
    image: Option<String>,
    /// One line: what was rendered, how long it took.
    summary: String,
    /// The diagnostics of the last build, plain text, if it failed.
    error: Option<String>,
    /// The URL template source links open (`watch --editor`).
    editor: String,
    /// The camera, overrides and size of the image (`watch::view`).
    view: Option<ViewSummary>,
}

/// What the server threads share with the watch loop.
struct Hub {
    inner: Mutex<HubInner>,
    /// Distinguishes this run's image versions from an earlier run's.
    run_id: u128,
}

struct HubInner {
    state: PreviewState,
    image_bytes: Option<Arc<Vec<u8>>>,
    /// What made the image shown, for `/api/pick` (none for an earlier run's image).
    image_origin: Option<Arc<ImageOrigin>>,
    generation: u64,
    /// One sender per open `/events` stream.
    subscribers: Vec<Sender<String>>,
    /// What `/turntable.png` renders, once the watch has said.
    turntable: Option<Arc<TurntableSource>>,
}

impl Hub {
    /// The lock; a panic while holding it cannot leave the state half-updated (each update is
    /// a few assignments), so a poisoned lock is simply taken over.
    fn lock(&self) -> MutexGuard<'_, HubInner> {
        self.inner.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Registers a new stream and returns the state to send it first (under one lock, so no
    /// update can fall between the two).
    fn subscribe(&self, subscriber: Sender<String>) -> String {
        let mut inner = self.lock();
        inner.subscribers.push(subscriber);
        to_json(&inner.state)
    }

    fn update(&self, change: impl FnOnce(&mut HubInner)) {
        let mut inner = self.lock();
        change(&mut inner);
        inner.state.build += 1;
        let message = to_json(&inner.state);
        // A send fails once a stream's thread has ended (its page closed): forget it.
        inner
            .subscribers
            .retain(|subscriber| subscriber.send(message.clone()).is_ok());
    }
}

fn to_json(state: &PreviewState) -> String {
    // Serialising strings, numbers and options cannot fail.
    serde_json::to_string(state).unwrap_or_else(|_| String::from("{}"))
}

/// The running preview server; stops when dropped.
pub struct PreviewServer {
    url: String,
    hub: Arc<Hub>,
    server: Arc<Server>,
    stopping: Arc<AtomicBool>,
    acceptor: Option<JoinHandle<()>>,
}

/// A server that started, and why it is not on the port asked for, if it is not.
pub struct StartedPreview {
    pub server: PreviewServer,
    pub port_note: Option<String>,
}

impl PreviewServer {
    /// Serves on `127.0.0.1:port`, or on a free port if that one cannot be had (port 0 always
    /// picks a free one). `initial_image` is shown until the first build (an earlier run's image).
    /// POST requests go to `inbox` (`watch::view`).
    pub fn start(
        port: u16,
        scene_name: &str,
        initial_image: Option<Vec<u8>>,
        inbox: Arc<Inbox>,
    ) -> io::Result<StartedPreview> {
        let (listener, port_note) = match TcpListener::bind((Ipv4Addr::LOCALHOST, port)) {
            Ok(listener) => (listener, None),
            Err(error) if port != 0 => {
                let listener = TcpListener::bind((Ipv4Addr::LOCALHOST, 0))?;
                let note = format!(
                    "port {port} is not available ({error}); using port {} instead",
                    listener.local_addr()?.port()
                );
                (listener, Some(note))
            }
            Err(error) => return Err(error),
        };
        let address = listener.local_addr()?;
        let server = Arc::new(Server::from_listener(listener, None).map_err(io::Error::other)?);
        let run_id = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |since| since.as_millis());
        let has_image = initial_image.is_some();
        let hub = Arc::new(Hub {
            inner: Mutex::new(HubInner {
                state: PreviewState {
                    scene: scene_name.to_owned(),
                    build: 0,
                    image: has_image.then(|| format!("{run_id}-0")),
                    summary: String::from("rendering…"),
                    error: None,
                    editor: String::from(crate::watch::DEFAULT_EDITOR_LINK),
                    view: None,
                },
                image_bytes: initial_image.map(Arc::new),
                image_origin: None,
                generation: 0,
                subscribers: Vec::new(),
                turntable: None,
            }),
            run_id,
        });
        let stopping = Arc::new(AtomicBool::new(false));
        let acceptor = {
            let (server, hub, stopping) = (server.clone(), hub.clone(), stopping.clone());
            std::thread::Builder::new()
                .name("preview server".into())
                .spawn(move || answer_requests(&server, &hub, &inbox, &stopping, address.port()))?
        };
        Ok(StartedPreview {
            server: PreviewServer {
                url: format!("http://{address}/"),
                hub,
                server,
                stopping,
                acceptor: Some(acceptor),
            },
            port_note,
        })
    }

    /// The page's address, `http://127.0.0.1:PORT/`.
    pub fn url(&self) -> &str {
        &self.url
    }

    /// What `/turntable.png` renders: the watched scene with the watch's options.
    pub fn set_turntable(&self, source: TurntableSource) {
        self.hub.lock().turntable = Some(Arc::new(source));
    }

    /// The URL template the page's source links follow (`watch --editor`).
    /// Set before the first page connects; pages get it with the state.
    pub fn set_editor_link(&self, template: &str) {
        self.hub.lock().state.editor = template.to_owned();
    }

    /// The port served on.
    pub fn port(&self) -> u16 {
        self.server
            .server_addr()
            .to_ip()
            .map_or(0, |address| address.port())
    }

    /// The state the page was last sent, as JSON (the answer to a view request).
    pub fn state_json(&self) -> String {
        to_json(&self.hub.lock().state)
    }

    /// A build wrote `png`, or the preview rendered it with its `view`, made as `origin` says:
    /// show it, and answer `/api/pick` about it.
    pub fn publish_image(&self, png: Vec<u8>, summary: String, view: ViewSummary, origin: Arc<ImageOrigin>) {
        let run_id = self.hub.run_id;
        self.hub.update(|inner| {
            inner.generation += 1;
            inner.image_bytes = Some(Arc::new(png));
            inner.image_origin = Some(origin);
            inner.state.image = Some(format!("{run_id}-{}", inner.generation));
            inner.state.summary = summary;
            inner.state.error = None;
            inner.state.view = Some(view);
        });
    }

    /// A build failed: show `report` over the last good image, if there is one. `problem`
    /// begins the status line, which goes on to say what image is shown under the report.
    pub fn publish_error(&self, report: String, problem: &str) {
        self.hub.update(|inner| {
            let shown = match (&inner.image_bytes, inner.generation) {
                (None, _) => "no image yet",
                (Some(_), 0) => "showing the image from before this watch started",
                (Some(_), _) => "showing the last good image",
            };
            inner.state.summary = format!("{problem}; {shown}");
            inner.state.error = Some(report);
        });
    }
}

impl Drop for PreviewServer {
    fn drop(&mut self) {
        self.stopping.store(true, Ordering::SeqCst);
        self.server.unblock();
        if let Some(acceptor) = self.acceptor.take() {
            let _ = acceptor.join();
        }
        // Dropping the senders ends every event stream's thread.
        self.hub.lock().subscribers.clear();
    }
}

fn answer_requests(server: &Server, hub: &Arc<Hub>, inbox: &Inbox, stopping: &AtomicBool, port: u16) {
    loop {
        match server.recv() {
            Ok(request) => answer(request, hub, inbox, port),
            Err(_) if stopping.load(Ordering::SeqCst) => return,
            // A failed accept (e.g. out of file descriptors) is transient: wait a little.
            Err(_) => std::thread::sleep(Duration::from_millis(50)),
        }
    }
}

fn answer(request: Request, hub: &Arc<Hub>, inbox: &Inbox, port: u16) {
    if !names_us(&request, port) {
        respond(
            request,
            text(
                403,
                "forbidden: this server only answers to 127.0.0.1 and localhost",
            ),
        );
        return;
    }
    if *request.method() == Method::Post {
        if from_another_site(&request, port) {
            respond(
                request,
                text(
                    403,
                    "forbidden: requests from other sites may not change the view",
                ),
            );
        } else {
            inbox.answer_post(request);
        }
        return;
    }
    if !matches!(request.method(), Method::Get | Method::Head) {
        respond(request, text(405, "only GET, HEAD and POST are supported"));
        return;
    }
    let path = request.url().split('?').next().unwrap_or_default();
    match path {
        "/" | "/index.html" => {
            let page = with_headers(
                Response::from_string(PAGE),
                &[
                    ("Content-Type", "text/html; charset=utf-8"),
                    ("Cache-Control", "no-store"),
                ],
            );
            respond(request, page);
        }
        "/page/compare.js" => respond(
            request,
            with_headers(
                Response::from_string(COMPARE_SCRIPT),
                &[
                    ("Content-Type", "text/javascript; charset=utf-8"),
                    ("Cache-Control", "no-store"),
                ],
            ),
        ),
        "/turntable.png" => super::turntable::answer(request, hub.lock().turntable.clone()),
        "/image.png" => {
            let image = hub.lock().image_bytes.clone();
            match image {
                // The URL's version makes each image's address unique, so it may be cached.
                Some(png) => respond(
                    request,
                    with_headers(
                        Response::from_data(png.as_slice().to_vec()),
                        &[
                            ("Content-Type", "image/png"),
                            ("Cache-Control", "private, max-age=86400"),
                        ],
                    ),
                ),
                None => respond(request, text(404, "no image yet")),
            }
        }
        "/api/pick" | "/api/object-mask" => {
            let origin = hub.lock().image_origin.clone();
            let (status, content_type, body) = super::pick::answer(request.url(), origin.as_deref());
            let response = Response::from_data(body).with_status_code(status);
            respond(
                request,
                with_headers(
                    response,
                    &[("Content-Type", content_type), ("Cache-Control", "no-store")],
                ),
            );
        }
        script
            if PAGE_FILES
                .iter()
                .any(|(name, _)| script.strip_prefix("/page/") == Some(*name)) =>
        {
            match PAGE_FILES
                .iter()
                .find(|(name, _)| script["/page/".len()..] == **name)
            {
                Some((_, code)) => respond(
                    request,
                    with_headers(
                        Response::from_string(*code),
                        &[
                            ("Content-Type", "text/javascript; charset=utf-8"),
                            ("Cache-Control", "no-store"),
                        ],
                    ),
                ),
                None => respond(request, text(404, "not found")),
            }
        }
        path if path.starts_with("/page/") => match super::pick::page_file(path) {
            Some((content_type, body)) => respond(
                request,
                with_headers(
                    Response::from_string(body),
                    &[("Content-Type", content_type), ("Cache-Control", "no-store")],
                ),
            ),
            None => respond(request, text(404, "not found")),
        },
        "/api/state" => respond(
            request,
            with_headers(
                Response::from_string(to_json(&hub.lock().state)),
                &[
                    ("Content-Type", "application/json"),
                    ("Cache-Control", "no-store"),
                ],
            ),
        ),
        "/events" => {
            let hub = hub.clone();
            let spawned = std::thread::Builder::new()
                .name("preview events".into())
                .spawn(move || stream_events(request, &hub));
            if let Err(error) = spawned {
                errln!("warning: preview: cannot start an event stream: {error}");
            }
        }
        _ => respond(request, text(404, "not found")),
    }
}

/// Whether the request's `Host` is us: `127.0.0.1:PORT` or `localhost:PORT`.
fn names_us(request: &Request, port: u16) -> bool {
    let Some(host) = request.headers().iter().find(|h| h.field.equiv("Host")) else {
        return false;
    };
    let host = host.value.as_str();
    let expected_port = port.to_string();
    match host.rsplit_once(':') {
        Some((name, host_port)) => {
            host_port == expected_port && (name == "127.0.0.1" || name.eq_ignore_ascii_case("localhost"))
        }
        None => false,
    }
}

/// Whether a browser sent `request` from a page that is not ours (its `Origin` names another
/// site): any web page may POST to 127.0.0.1, and the view routes write the scene file. Scripts
/// and editors send no `Origin`.
fn from_another_site(request: &Request, port: u16) -> bool {
    let Some(origin) = request.headers().iter().find(|h| h.field.equiv("Origin")) else {
        return false;
    };
    let origin = origin.value.as_str();
    origin != format!("http://127.0.0.1:{port}") && origin != format!("http://localhost:{port}")
}

fn stream_events(request: Request, hub: &Hub) {
    let (sender, messages) = mpsc::channel();
    let mut next = Some(hub.subscribe(sender));
    let mut writer = request.into_writer();
    // `retry` makes a page reconnect within a second when the watch is restarted.
    let head = "HTTP/1.1 200 OK\r\n\
                Content-Type: text/event-stream; charset=utf-8\r\n\
                Cache-Control: no-store\r\n\
                Connection: close\r\n\r\n\
                retry: 1000\n\n";
    if send(&mut writer, head).is_err() {
        return;
    }
    loop {
        let chunk = match next.take() {
            // JSON from serde_json holds no raw newline, so one `data:` line carries it.
            Some(json) => format!("data: {json}\n\n"),
            None => match messages.recv_timeout(KEEP_ALIVE) {
                Ok(json) => format!("data: {json}\n\n"),
                Err(RecvTimeoutError::Timeout) => String::from(": keep-alive\n\n"),
                Err(RecvTimeoutError::Disconnected) => return,
            },
        };
        if send(&mut writer, &chunk).is_err() {
            return; // the page went away
        }
    }
}

fn send(writer: &mut dyn Write, text: &str) -> io::Result<()> {
    writer.write_all(text.as_bytes())?;
    writer.flush()
}

pub(super) fn text(status: u16, message: &str) -> Response<io::Cursor<Vec<u8>>> {
    with_headers(
        Response::from_string(format!("{message}\n")).with_status_code(status),
        &[("Content-Type", "text/plain; charset=utf-8")],
    )
}

pub(super) fn with_headers<R: io::Read>(mut response: Response<R>, headers: &[(&str, &str)]) -> Response<R> {
    for (name, value) in headers {
        // Our header names and values are constant ASCII, which `from_bytes` always accepts.
        if let Ok(header) = Header::from_bytes(name.as_bytes(), value.as_bytes()) {
            response.add_header(header);
        }
    }
    response
}

pub(super) fn respond<R: io::Read>(request: Request, response: Response<R>) {
    // A page that went away mid-answer is not our problem.
    let _ = request.respond(response);
}
