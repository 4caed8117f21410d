//! Headless Chromium for the browser tests, driven through the DevTools protocol (a WebSocket
//! on 127.0.0.1; `Runtime.evaluate` reads and drives the page). `.ci/run` installs Debian's
//! `chromium`; `LAMPSHADE_CHROMIUM` names another binary. Without one, a test calls
//! [`chromium_or_skip`] and passes with a line saying why it skipped.

use std::io::Write;
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use serde_json::{Value, json};
use tungstenite::{Message, WebSocket};

use crate::watch::{DEADLINE, WatchProcess, http_get, wait_for};

/// The Chromium binary, or `None` after saying on stderr (past the test harness's capture, so
/// the skip is seen in every run) that `test` was skipped.
pub fn chromium_or_skip(test: &str) -> Option<PathBuf> {
    let found = find_chromium();
    if found.is_none() {
        let _ = writeln!(
            std::io::stderr(),
            "{test}: skipped: chromium not installed (apt-get install chromium)"
        );
    }
    found
}

/// The Chromium binary: `LAMPSHADE_CHROMIUM`, else the usual names on `PATH`.
pub fn find_chromium() -> Option<PathBuf> {
    if let Some(path) = std::env::var_os("LAMPSHADE_CHROMIUM") {
        return Some(PathBuf::from(path));
    }
    let path = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .flat_map(|name| std::env::split_paths(&path).map(move |dir| dir.join(name)))
        .find(|candidate| candidate.is_file())
}

/// A child process killed when dropped: Chromium must not outlive a failed test.
struct KillOnDrop(Child);

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A headless Chromium with one page open, driven over the DevTools protocol; killed on drop.
pub struct Browser {
    _process: KillOnDrop,
    socket: WebSocket<TcpStream>,
    last_id: u64,
    _profile: tempfile::TempDir,
}

impl Browser {
    pub fn open(chromium: &Path, url: &str) -> Browser {
        let profile = tempfile::tempdir().unwrap();
        // Guarded at once: every step below may panic.
        let process = Command::new(chromium)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                // Containers often have a tiny /dev/shm, which makes Chromium's renderer crash.
                "--disable-dev-shm-usage",
                "--remote-debugging-address=127.0.0.1",
                "--remote-debugging-port=0",
                "--window-size=1024,768",
            ])
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .arg(url)
            // Chromium leaves a singleton-socket folder in TMPDIR when killed: keep it in the
            // profile, which is removed after the test.
            .env("TMPDIR", profile.path())
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .map(KillOnDrop)
            .unwrap_or_else(|e| panic!("cannot start {}: {e}", chromium.display()));
        // Chromium writes the DevTools port it chose into the profile once it listens.
        let port_file = profile.path().join("DevToolsActivePort");
        let devtools_port: u16 = wait_for(
            "Chromium's DevTools port",
            || String::from("(Chromium did not write DevToolsActivePort)"),
            || {
                std::fs::read_to_string(&port_file)
                    .ok()?
                    .lines()
                    .next()?
                    .parse()
                    .ok()
            },
        );
        // The page target showing our URL.
        let page_socket = wait_for("the preview page in Chromium's target list", String::new, || {
            let (status, body) = http_get(devtools_port, "/json/list", &format!("127.0.0.1:{devtools_port}"));
            if status != 200 {
                return None;
            }
            let targets: Value = serde_json::from_slice(&body).ok()?;
            targets.as_array()?.iter().find_map(|target| {
                let is_ours = target["type"] == "page" && target["url"].as_str()?.starts_with(url);
                is_ours.then(|| target["webSocketDebuggerUrl"].as_str().map(str::to_owned))?
            })
        });
        assert!(
            page_socket.starts_with(&format!("ws://127.0.0.1:{devtools_port}/")),
            "{page_socket}"
        );
        let stream = TcpStream::connect(("127.0.0.1", devtools_port)).unwrap();
        stream.set_read_timeout(Some(DEADLINE)).unwrap();
        let (socket, _) =
            tungstenite::client(page_socket.as_str(), stream).expect("the DevTools WebSocket opens");
        Browser {
            _process: process,
            socket,
            last_id: 0,
            _profile: profile,
        }
    }

    /// Calls DevTools method `method` and returns its result.
    pub fn call(&mut self, method: &str, params: Value) -> Value {
        self.last_id += 1;
        let id = self.last_id;
        let call = json!({ "id": id, "method": method, "params": params });
        self.socket.send(Message::text(call.to_string())).unwrap();
        loop {
            let message = self.socket.read().expect("a DevTools reply");
            let Message::Text(text) = message else { continue };
            let reply: Value = serde_json::from_str(text.as_str()).unwrap();
            if reply["id"] == id {
                assert!(reply["error"].is_null(), "{method}: {reply}");
                return reply["result"].clone();
            }
        }
    }

    /// Evaluates `expression` in the page and returns its value.
    pub fn evaluate(&mut self, expression: &str) -> Value {
        let result = self.call(
            "Runtime.evaluate",
            json!({ "expression": expression, "returnByValue": true }),
        );
        assert!(result["exceptionDetails"].is_null(), "{result}");
        result["result"]["value"].clone()
    }

    /// Saves a screenshot of the page as `name` in the test's scratch folder under `target/`,
    /// for a person to look at what the test saw.
    pub fn save_screenshot(&mut self, name: &str) {
        let result = self.call("Page.captureScreenshot", json!({ "format": "png" }));
        let Some(png) = result["data"].as_str().and_then(decode_base64) else {
            panic!("no screenshot in {result}");
        };
        let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
        std::fs::write(&path, png).unwrap();
    }
}

impl Browser {
    /// Evaluates `probe` until `condition` holds for its value, which is returned.
    pub fn wait_for_page(
        &mut self,
        probe: &str,
        what: &str,
        watch: &WatchProcess,
        condition: impl Fn(&Value) -> bool,
    ) -> Value {
        let started = std::time::Instant::now();
        loop {
            let state = self.evaluate(probe);
            if condition(&state) {
                return state;
            }
            if started.elapsed() > DEADLINE {
                panic!(
                    "timed out waiting for the page to show {what}
page state: {state}
{}",
                    watch.output()
                );
            }
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
    }
}

/// Standard base64 (as DevTools sends screenshots); `None` on anything else.
pub fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let mut bytes = Vec::with_capacity(text.len() / 4 * 3);
    let (mut accumulator, mut bits) = (0u32, 0);
    for c in text.bytes().filter(|&c| c != b'=') {
        let value = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        };
        accumulator = (accumulator << 6) | u32::from(value);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            bytes.push((accumulator >> bits) as u8);
        }
    }
    Some(bytes)
}
