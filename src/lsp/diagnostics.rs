//! Diagnostics as the user types: the loader's own, on the unsaved text, in two stages.
//!
//! 1. On every change, on the request thread: [`crate::scene::load::parse_scene_text`], the
//!    loader's first stage (ron's syntax and type checks, unknown fields and variants, with the
//!    loader's wording and hints). It reads no file and takes well under a millisecond on a
//!    300-line scene. When it fails, its diagnostics are the whole answer (the loader stops at a
//!    syntax error too) and are published at once.
//! 2. When the text parses: the full load ([`crate::scene::load::load_scene_from_str_cached`]:
//!    includes, materials, values, meshes, textures, the memory check) on the [`Checker`]'s
//!    thread, after 50 ms without a change, with a [`MeshCache`] kept for the session, so a mesh
//!    file is parsed once and later keystrokes only check that it has not changed. Its result is
//!    published only if no newer version of the document has been seen meanwhile.
//!
//! A diagnostic keeps the CLI's range (the same byte span, in LSP positions) and its text: the
//! message, then each hint as a `help:` line; the caret label becomes related information at
//! the same place. Diagnostics located in an included material library are published for
//! that library's file; those without a location (a mesh file's content, at a line when known)
//! for the file they are about.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

use lsp_server::{Message, Notification};
use lsp_types::notification::{Notification as _, PublishDiagnostics};
use lsp_types::{
    DiagnosticRelatedInformation, DiagnosticSeverity, Location, Position, PublishDiagnosticsParams, Range,
    Url,
};

use crate::diag::{Diagnostic, Severity, Sources};
use crate::lsp::documents::range_of;
use crate::scene::load::{LoadError, LoadOptions, MeshCache, load_scene_from_str_cached};

/// How long the text must stay unchanged before the full load runs: long enough to skip the
/// loads of a burst of keystrokes, short enough to feel immediate.
const QUIET_PERIOD: Duration = Duration::from_millis(50);

/// Sends a message to the editor.
pub type Outbox = Arc<dyn Fn(Message) + Send + Sync>;

/// What has been published, shared by the request thread and the checker.
#[derive(Default)]
struct Published {
    /// The newest version seen of each document.
    latest: HashMap<Url, i32>,
    /// The files each document has published diagnostics for (to clear those it no longer has).
    files: HashMap<Url, HashSet<Url>>,
}

/// Publishes a document's diagnostics, dropping results for versions that are no longer the
/// newest.
#[derive(Clone)]
pub struct Publisher {
    outbox: Outbox,
    published: Arc<Mutex<Published>>,
}

impl Publisher {
    pub fn new(outbox: Outbox) -> Self {
        Publisher {
            outbox,
            published: Arc::default(),
        }
    }

    fn lock(&self) -> MutexGuard<'_, Published> {
        self.published
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Records `version` as the newest of `document`; results for older ones are dropped.
    pub fn saw(&self, document: &Url, version: i32) {
        self.lock().latest.insert(document.clone(), version);
    }

    /// Publishes `diagnostics` (by file) for `document` at `version`, and clears the files it
    /// published for before and has nothing for now. Does nothing when `version` is stale.
    pub fn publish(
        &self,
        document: &Url,
        version: i32,
        diagnostics: HashMap<Url, Vec<lsp_types::Diagnostic>>,
    ) {
        let mut published = self.lock();
        if published
            .latest
            .get(document)
            .is_some_and(|&latest| latest != version)
        {
            return;
        }
        let mut files: HashSet<Url> = diagnostics.keys().cloned().collect();
        // The document itself always gets an answer, empty when it is clean.
        files.insert(document.clone());
        let before = published
            .files
            .insert(document.clone(), files.clone())
            .unwrap_or_default();
        let mut diagnostics = diagnostics;
        for file in files.iter().chain(before.difference(&files)) {
            let list = diagnostics.remove(file).unwrap_or_default();
            let file_version = (file == document).then_some(version);
            self.send(file.clone(), list, file_version);
        }
    }

    /// Clears everything `document` published (it was closed).
    pub fn clear(&self, document: &Url) {
        let mut published = self.lock();
        published.latest.remove(document);
        for file in published.files.remove(document).unwrap_or_default() {
            self.send(file, Vec::new(), None);
        }
    }

    fn send(&self, file: Url, diagnostics: Vec<lsp_types::Diagnostic>, version: Option<i32>) {
        let params = PublishDiagnosticsParams::new(file, diagnostics, version);
        (self.outbox)(Message::Notification(Notification::new(
            PublishDiagnostics::METHOD.to_owned(),
            params,
        )));
    }
}

/// The loader's diagnostics as LSP diagnostics, by the file each is about. `scene` is the
/// document's path; its text is the one in `sources`.
pub fn to_lsp(error: &LoadError) -> HashMap<Url, Vec<lsp_types::Diagnostic>> {
    by_file(&error.diagnostics, &error.sources)
}

/// See [`to_lsp`]; for warnings of a scene that loaded too.
pub fn by_file(diagnostics: &[Diagnostic], sources: &Sources) -> HashMap<Url, Vec<lsp_types::Diagnostic>> {
    let mut files: HashMap<Url, Vec<lsp_types::Diagnostic>> = HashMap::new();
    for diagnostic in diagnostics {
        let (path, converted) = convert(diagnostic, sources);
        if let Some(uri) = file_url(&path) {
            files.entry(uri).or_default().push(converted);
        }
    }
    files
}

/// The `file:` URI of `path` (made absolute first).
pub fn file_url(path: &Path) -> Option<Url> {
    let absolute = std::path::absolute(path).ok()?;
    Url::from_file_path(absolute).ok()
}

fn convert(diagnostic: &Diagnostic, sources: &Sources) -> (PathBuf, lsp_types::Diagnostic) {
    let (path, range) = match &diagnostic.location {
        Some((source, span)) => (
            sources.path(*source).to_path_buf(),
            range_of(sources.text(*source), span.clone()),
        ),
        None => {
            let line = diagnostic.line_in_file.map_or(0, |line| line.saturating_sub(1));
            let line = u32::try_from(line).unwrap_or(u32::MAX);
            (
                diagnostic.path.clone(),
                Range::new(Position::new(line, 0), Position::new(line, 0)),
            )
        }
    };
    let mut message = diagnostic.message.clone();
    for hint in &diagnostic.hints {
        message.push_str("\nhelp: ");
        message.push_str(hint);
    }
    let related_information = diagnostic.label.as_ref().and_then(|label| {
        Some(vec![DiagnosticRelatedInformation {
            location: Location::new(file_url(&path)?, range),
            message: label.clone(),
        }])
    });
    let severity = match diagnostic.severity {
        Severity::Error => DiagnosticSeverity::ERROR,
        Severity::Warning => DiagnosticSeverity::WARNING,
    };
    let converted = lsp_types::Diagnostic {
        range,
        severity: Some(severity),
        source: Some("lampshade".to_owned()),
        message,
        related_information,
        ..lsp_types::Diagnostic::default()
    };
    (path, converted)
}

/// One document version to load in full.
struct CheckRequest {
    uri: Url,
    path: PathBuf,
    version: i32,
    text: String,
}

/// The thread that runs full loads of documents that parse, newest version only.
pub struct Checker {
    requests: Option<Sender<CheckRequest>>,
    thread: Option<JoinHandle<()>>,
    /// Meshes loaded so far, for every document; hover reads them.
    pub meshes: Arc<Mutex<MeshCache>>,
}

impl Checker {
    pub fn start(publisher: Publisher, options: LoadOptions) -> Self {
        let (requests, inbox) = mpsc::channel();
        let meshes = Arc::new(Mutex::new(MeshCache::default()));
        let cache = Arc::clone(&meshes);
        let thread = std::thread::Builder::new()
            .name("lsp-checker".to_owned())
            .spawn(move || check_loop(&inbox, &publisher, &options, &cache))
            .ok();
        Checker {
            requests: Some(requests),
            thread,
            meshes,
        }
    }

    /// Asks for a full load of `text` as `uri`'s version `version`.
    pub fn check(&self, uri: Url, path: PathBuf, version: i32, text: String) {
        if let Some(requests) = &self.requests {
            // The thread ends only when this sender is dropped.
            let _ = requests.send(CheckRequest {
                uri,
                path,
                version,
                text,
            });
        }
    }
}

impl Drop for Checker {
    fn drop(&mut self) {
        self.requests = None;
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

fn check_loop(
    inbox: &Receiver<CheckRequest>,
    publisher: &Publisher,
    options: &LoadOptions,
    cache: &Mutex<MeshCache>,
) {
    while let Ok(first) = inbox.recv() {
        // The newest request per document, once the text has been quiet for a moment.
        let mut pending: HashMap<Url, CheckRequest> = HashMap::new();
        pending.insert(first.uri.clone(), first);
        loop {
            match inbox.recv_timeout(QUIET_PERIOD) {
                Ok(request) => {
                    pending.insert(request.uri.clone(), request);
                }
                Err(RecvTimeoutError::Timeout) => break,
                Err(RecvTimeoutError::Disconnected) => return,
            }
        }
        for request in pending.into_values() {
            let mut cache = cache.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
            let loaded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                load_scene_from_str_cached(&request.path, &request.text, options, &mut cache)
            }));
            drop(cache);
            let diagnostics = match loaded {
                Ok(Ok(scene)) => by_file(&scene.warnings, &scene.sources),
                Ok(Err(error)) => to_lsp(&error),
                // A bug in the loader: the CLI would exit 101; the editor keeps its server.
                Err(_) => HashMap::new(),
            };
            publisher.publish(&request.uri, request.version, diagnostics);
        }
    }
}
