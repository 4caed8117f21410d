//! The preview of `lampshade watch --serve` in a real browser, end to end: headless Chromium
//! opens the page, the test edits the scene file, and the page must show the new image (checked
//! pixel by pixel against the PNG on disk), then, after a broken save, the diagnostics overlay
//! above the last good image, with a snippet wider than the page scrolled, never wrapped.
//!
//! Chromium is driven through the DevTools protocol (a WebSocket on 127.0.0.1, `Runtime.evaluate`
//! to read the page's state). Without Chromium the test prints why it skipped and passes:
//! `.ci/run` installs Debian's `chromium` where it can; `LAMPSHADE_CHROMIUM` names another
//! binary.

use std::io::Write;
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use serde_json::{Value, json};
use tungstenite::{Message, WebSocket};

use crate::watch::{DEADLINE, SceneFolder, WatchProcess, http_get, preview_port, scene_text, wait_for};

/// The Chromium binary: `LAMPSHADE_CHROMIUM`, else the usual names on `PATH`.
fn find_chromium() -> Option<PathBuf> {
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
struct Browser {
    _process: KillOnDrop,
    socket: WebSocket<TcpStream>,
    last_id: u64,
    _profile: tempfile::TempDir,
}

impl Browser {
    fn open(chromium: &Path, url: &str) -> Browser {
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
                "--window-size=640,420",
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
    fn call(&mut self, method: &str, params: Value) -> Value {
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
    fn evaluate(&mut self, expression: &str) -> Value {
        let result = self.call(
            "Runtime.evaluate",
            json!({ "expression": expression, "returnByValue": true }),
        );
        assert!(result["exceptionDetails"].is_null(), "{result}");
        result["result"]["value"].clone()
    }

    /// Saves a screenshot of the page as `name` in the test's scratch folder under `target/`,
    /// for a person to look at what the test saw.
    fn save_screenshot(&mut self, name: &str) {
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
    fn wait_for_page(
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
fn decode_base64(text: &str) -> Option<Vec<u8>> {
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

/// What the page shows: its state, image version, overlay text, and the colour of pixel (PIXEL_X, PIXEL_Y)
/// of the image as displayed (read back through a canvas).
const PROBE: &str = r#"(() => {
  const view = document.getElementById("view");
  const overlay = document.getElementById("overlay");
  if (view === null || overlay === null) return { state: "loading" };
  let pixel = null;
  if (view.complete && view.naturalWidth > 0) {
    const canvas = document.createElement("canvas");
    canvas.width = view.naturalWidth;
    canvas.height = view.naturalHeight;
    const context = canvas.getContext("2d");
    context.drawImage(view, 0, 0);
    pixel = Array.from(context.getImageData(PIXEL_X, PIXEL_Y, 1, 1).data.slice(0, 3));
  }
  return {
    state: document.body.dataset.state,
    image: document.body.dataset.image,
    overlay: overlay.hidden ? null : overlay.textContent,
    pixel,
  };
})()"#;

/// The pixel where two images differ most, and its colour in each.
fn most_different_pixel(a: &[u8], b: &[u8]) -> ((u32, u32), [u8; 3], [u8; 3]) {
    let a = image::load_from_memory(a).unwrap().to_rgb8();
    let b = image::load_from_memory(b).unwrap().to_rgb8();
    let distance = |p: &image::Rgb<u8>, q: &image::Rgb<u8>| -> u32 {
        p.0.iter().zip(q.0).map(|(x, y)| x.abs_diff(y) as u32).sum()
    };
    let (x, y, _) = a
        .enumerate_pixels()
        .map(|(x, y, p)| (x, y, distance(p, b.get_pixel(x, y))))
        .max_by_key(|&(_, _, d)| d)
        .unwrap();
    ((x, y), a.get_pixel(x, y).0, b.get_pixel(x, y).0)
}

fn shows_colour(state: &Value, colour: [u8; 3]) -> bool {
    let Some(pixel) = state["pixel"].as_array() else {
        return false;
    };
    // Colour management may move an untagged PNG's values by a step or two.
    pixel.len() == 3
        && pixel
            .iter()
            .zip(colour)
            .all(|(p, c)| p.as_u64().is_some_and(|p| p.abs_diff(c as u64) <= 2))
}

#[test]
fn the_preview_page_follows_edits_and_shows_errors_over_the_last_good_image() {
    let Some(chromium) = find_chromium() else {
        // Straight to stderr, past the test harness's capture, so the skip is seen in every run.
        let _ = writeln!(
            std::io::stderr(),
            "watch_browser: skipped: chromium not installed (apt-get install chromium)"
        );
        return;
    };
    let folder = SceneFolder::new();
    let watch = WatchProcess::start(
        &folder.path,
        &["scene.ron", "-o", "out.png", "--serve", "--port", "0"],
    );
    let port = preview_port(&watch);
    let url = format!("http://127.0.0.1:{port}/");
    let first = wait_for("the first image", || watch.output(), || folder.image());

    // What the second image will be, so the test knows which pixel to look at.
    let second_scene = scene_text((0.2, 0.4, 1.0));
    let reference = SceneFolder::new();
    reference.write("scene.ron", &second_scene);
    let second = crate::watch::render_once(&reference.file("scene.ron"));
    let ((x, y), before, after) = most_different_pixel(&first, &second);
    assert_ne!(before, after);
    let probe = PROBE
        .replace("PIXEL_X", &x.to_string())
        .replace("PIXEL_Y", &y.to_string());

    let mut browser = Browser::open(&chromium, &url);
    let state = browser.wait_for_page(&probe, "the first image", &watch, |state| {
        state["state"] == "ok" && shows_colour(state, before)
    });
    let first_version = state["image"].clone();

    folder.write("scene.ron", &second_scene);
    let state = browser.wait_for_page(&probe, "the edited image", &watch, |state| {
        state["image"] != first_version && shows_colour(state, after)
    });
    assert_eq!(folder.image().unwrap(), second);
    browser.save_screenshot("watch-preview-image.png");
    let second_version = state["image"].clone();

    folder.write("scene.ron", "Scene(objects: [(mesh: Sphere(]");
    let last_state = browser.wait_for_page(&probe, "the error overlay", &watch, |state| {
        state["state"] == "error"
    });
    browser.save_screenshot("watch-preview-error.png");
    let overlay = last_state["overlay"].as_str().unwrap_or_default();
    assert!(overlay.contains("scene.ron:1:"), "overlay: {overlay:?}");
    assert!(
        !overlay.contains('\u{1b}'),
        "terminal colours in the overlay: {overlay:?}"
    );
    assert_eq!(
        last_state["image"], second_version,
        "the last good image stays under the overlay"
    );
    assert!(shows_colour(&last_state, after), "page state: {last_state}");

    // A mistake at the end of a line far wider than the page: the snippet must not wrap, or the
    // `^` lands under another column (or at column 0). It scrolls instead.
    let long_line = format!(
        "(objects: [{}(mesh: Sphere(segments: 8), translate: (0, 0, oops))])\n",
        "(mesh: Sphere(segments: 8)), ".repeat(12)
    );
    folder.write("scene.ron", &long_line);
    let caret = browser.wait_for_page(CARET_PROBE, "the caret under the long line", &watch, |state| {
        state["column"].as_u64().is_some_and(|column| column > 300)
    });
    browser.save_screenshot("watch-preview-long-line.png");
    assert_eq!(caret["sourceRows"], 1, "the snippet line wrapped: {caret}");
    let (marked, under) = (
        caret["markedLeft"].as_f64().unwrap(),
        caret["caretLeft"].as_f64().unwrap(),
    );
    assert!(
        (marked - under).abs() < 1.0,
        "the caret is not under its column: {caret}"
    );
    assert!(
        caret["caretTop"].as_f64() > caret["markedTop"].as_f64(),
        "{caret}"
    );
    assert_eq!(caret["scrolls"], true, "{caret}");
}

/// Where the overlay draws the first `^` of its snippet and the character of the line above it
/// in the same column: the snippet's line and the caret's line are each one text line, the caret
/// directly below the marked character (`column` is the caret's index within its line).
const CARET_PROBE: &str = r#"(() => {
  const overlay = document.getElementById("overlay");
  if (overlay === null || overlay.hidden || overlay.firstChild === null) return {};
  const lines = overlay.textContent.split("\n");
  const caretLine = lines.findIndex(line => /│\s*\^/.test(line));
  if (caretLine < 1) return {};
  let sourceStart = 0;
  for (let i = 0; i < caretLine - 1; i++) sourceStart += lines[i].length + 1;
  const sourceLength = lines[caretLine - 1].length;
  const caretStart = sourceStart + sourceLength + 1;
  const column = lines[caretLine].indexOf("^");
  const range = (start, end) => {
    const r = document.createRange();
    r.setStart(overlay.firstChild, start);
    r.setEnd(overlay.firstChild, end);
    return r;
  };
  const marked = range(sourceStart + column, sourceStart + column + 1).getBoundingClientRect();
  const caret = range(caretStart + column, caretStart + column + 1).getBoundingClientRect();
  return {
    column,
    sourceRows: range(sourceStart, sourceStart + sourceLength).getClientRects().length,
    markedLeft: marked.left,
    caretLeft: caret.left,
    markedTop: marked.top,
    caretTop: caret.top,
    scrolls: overlay.scrollWidth > overlay.clientWidth,
  };
})()"#;
