//! The preview follows the unsaved buffer: when a `lampshade watch --serve` runs for a scene the
//! editor has open, its unsaved text is sent to that watch (`POST /api/buffer`), which renders it
//! in the page without touching the file; on save or close the editor's file wins again
//! (`text: null`). The watch is found through its registry file (`watch::registry`).
//!
//! Texts go through a thread of their own, newest per document only, once typing has paused for
//! [`QUIET_PERIOD`]: a render per keystroke would only queue behind itself, and a slow or absent
//! watch never delays an answer to the editor. A document with no watch costs one file lookup.

use std::collections::HashMap;
use std::io::{self, Read, Write};
use std::net::{Ipv4Addr, SocketAddr, TcpStream};
use std::path::PathBuf;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::thread::JoinHandle;
use std::time::Duration;

use crate::watch::registry;

/// How long the text must stay unchanged before the preview is sent it.
const QUIET_PERIOD: Duration = Duration::from_millis(100);

/// How long a watch may take to accept a text.
const TIMEOUT: Duration = Duration::from_secs(1);

/// A document's text to show, or `None` to show the file again.
struct Update {
    path: PathBuf,
    text: Option<String>,
}

/// The thread that sends texts to the previews.
pub struct PreviewLink {
    updates: Option<Sender<Update>>,
    thread: Option<JoinHandle<()>>,
}

impl PreviewLink {
    pub fn start() -> Self {
        let (updates, inbox) = mpsc::channel();
        let thread = std::thread::Builder::new()
            .name("lsp-preview".to_owned())
            .spawn(move || send_loop(&inbox))
            .ok();
        PreviewLink {
            updates: Some(updates),
            thread,
        }
    }

    /// `path`'s unsaved text changed.
    pub fn text(&self, path: PathBuf, text: String) {
        self.send(Update {
            path,
            text: Some(text),
        });
    }

    /// `path` was saved or closed: its preview shows the file again.
    pub fn file_wins(&self, path: PathBuf) {
        self.send(Update { path, text: None });
    }

    fn send(&self, update: Update) {
        if let Some(updates) = &self.updates {
            // The thread ends only when this sender is dropped.
            let _ = updates.send(update);
        }
    }
}

impl Drop for PreviewLink {
    fn drop(&mut self) {
        self.updates = None;
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

fn send_loop(inbox: &Receiver<Update>) {
    while let Ok(first) = inbox.recv() {
        let mut pending: HashMap<PathBuf, Option<String>> = HashMap::new();
        pending.insert(first.path, first.text);
        loop {
            match inbox.recv_timeout(QUIET_PERIOD) {
                Ok(update) => {
                    pending.insert(update.path, update.text);
                }
                Err(RecvTimeoutError::Timeout) => break,
                Err(RecvTimeoutError::Disconnected) => return,
            }
        }
        for (path, text) in pending {
            if let Some(port) = registry::lookup(&path) {
                let body = serde_json::json!({ "path": path, "text": text }).to_string();
                // A watch that went away, or answers slowly, is not the editor's problem.
                let _ = post(port, "/api/buffer", &body);
            }
        }
    }
}

/// POSTs `body` (JSON) to `path` on `127.0.0.1:port` and returns the status.
fn post(port: u16, path: &str, body: &str) -> io::Result<u16> {
    let address = SocketAddr::from((Ipv4Addr::LOCALHOST, port));
    let mut stream = TcpStream::connect_timeout(&address, TIMEOUT)?;
    stream.set_read_timeout(Some(TIMEOUT))?;
    stream.set_write_timeout(Some(TIMEOUT))?;
    write!(
        stream,
        "POST {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nContent-Type: application/json\r\n\
         Content-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    )?;
    let mut head = [0; 32];
    let read = stream.read(&mut head)?;
    let status = std::str::from_utf8(&head[..read])
        .ok()
        .and_then(|line| line.split(' ').nth(1))
        .and_then(|code| code.parse().ok())
        .ok_or_else(|| io::Error::other("not an HTTP answer"))?;
    Ok(status)
}
