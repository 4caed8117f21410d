//! The preview's view controls in headless Chromium (`watch::view`, `src/watch/page/view.js`):
//! a drag orbits the camera (reduced frames while moving, the full image after), the copied
//! camera put in the file renders the preview's full image bit for bit, writing it changes the
//! file only in the camera's span, the toggles change the image and reset restores it; the
//! page's camera math at the poles; and the drag benchmark on `matlab-shiny` (ignored: run it
//! with `cargo test --release --test suite preview_orbit_speed -- --ignored --nocapture`).

use std::time::{Duration, Instant};

use serde_json::{Value, json};

use crate::browser::{Browser, chromium_or_skip};
use crate::watch::{WatchProcess, http_get, preview_port, render_once, wait_for};

/// The file's camera, which the page replaces (this exact text is the span that may change).
const FILE_CAMERA: &str = "Perspective(eye: (0.5, 1.5, 4), target: (0, 0, 0), fov: 40)";

fn scene_text() -> String {
    format!(
        "// A test scene: writing the camera changes only the camera's value.\n\
         Scene(\n    image: (width: 160, height: 120), // small\n    \
         camera: {FILE_CAMERA}, // the file's camera\n    \
         lights: [Point()], /* at the eye: it follows the camera */\n    objects: [\n        \
         (mesh: Sphere(segments: 24), material: (base: \"shiny\", color: (0.8, 0.3, 0.2))),\n        \
         (mesh: Cube, translate: (1.5, 0, 0)),\n    ],\n)\n"
    )
}

/// What the page shows: the image version, whether it is busy, and the last state's view.
const PROBE: &str = r#"(() => {
  const v = window.lampshadeView;
  if (!v || !v.state()) return { ready: false };
  return {
    ready: v.camera() !== null,
    image: document.body.dataset.image,
    busy: v.busy(),
    previewCamera: document.body.dataset.previewCamera,
    view: v.state().view,
    frames: v.frames.length,
    movingFrames: v.frames.filter(f => f.moving).length,
    pick: document.body.dataset.pick ?? null,
  };
})()"#;

fn image_pixels(png: &[u8]) -> image::RgbImage {
    image::load_from_memory(png).unwrap().to_rgb8()
}

/// The image the server shows now.
fn shown_image(port: u16) -> Vec<u8> {
    let (status, body) = http_get(port, "/image.png", &format!("127.0.0.1:{port}"));
    assert_eq!(status, 200);
    body
}

/// Drags from the middle of the image's top part (inside a small window) by `(dx, dy)` pixels in `steps` moves, `pause` apart.
fn drag(browser: &mut Browser, dx: f64, dy: f64, steps: u32, pause: Duration, shift: bool) {
    let rect = browser.evaluate(
        r#"(() => { const r = document.getElementById("view").getBoundingClientRect();
           return [r.left + r.width / 2, r.top + Math.min(r.height / 2, 60)]; })()"#,
    );
    let (x, y) = (rect[0].as_f64().unwrap(), rect[1].as_f64().unwrap());
    let modifiers = if shift { 8 } else { 0 };
    let mouse = |kind: &str, x: f64, y: f64, buttons: u32| {
        json!({ "type": kind, "x": x, "y": y, "button": "left", "buttons": buttons,
                "clickCount": 1, "modifiers": modifiers })
    };
    browser.call("Input.dispatchMouseEvent", mouse("mousePressed", x, y, 1));
    for step in 1..=steps {
        let t = f64::from(step) / f64::from(steps);
        browser.call(
            "Input.dispatchMouseEvent",
            mouse("mouseMoved", x + dx * t, y + dy * t, 1),
        );
        std::thread::sleep(pause);
    }
    browser.call(
        "Input.dispatchMouseEvent",
        mouse("mouseReleased", x + dx, y + dy, 0),
    );
}

/// Waits until the page is idle on a full-size image other than `not`.
fn wait_for_still_image(browser: &mut Browser, watch: &WatchProcess, not: &Value) -> Value {
    browser.wait_for_page(PROBE, "a still full-size image", watch, |state| {
        state["ready"] == true
            && state["busy"] == false
            && state["image"] != *not
            && state["view"]["moving"] == false
    })
}

fn open_preview(folder: &std::path::Path, args: &[&str]) -> Option<(WatchProcess, Browser, u16)> {
    let chromium = chromium_or_skip("view_browser")?;
    let watch = WatchProcess::start(folder, args);
    let port = preview_port(&watch);
    let mut browser = Browser::open(&chromium, &format!("http://127.0.0.1:{port}/"));
    browser.wait_for_page(PROBE, "the page with a camera", &watch, |state| {
        state["ready"] == true && state["image"].as_str().is_some_and(|image| !image.is_empty())
    });
    Some((watch, browser, port))
}

#[test]
fn orbiting_copying_writing_the_camera_toggles_and_reset() {
    let folder = tempfile::tempdir().unwrap();
    let scene = folder.path().join("scene.ron");
    let original = scene_text();
    std::fs::write(&scene, &original).unwrap();
    let Some((watch, mut browser, port)) = open_preview(
        folder.path(),
        &["scene.ron", "-o", "out.png", "--serve", "--port", "0"],
    ) else {
        return;
    };
    let first = browser.evaluate(PROBE);
    let file_image = shown_image(port);
    assert_eq!(first["previewCamera"], "false");

    // Orbit: reduced frames while moving, then the full image from elsewhere. The drag ends
    // inside the image, where its release must not also count as a click on a pixel.
    drag(&mut browser, 60.0, -20.0, 12, Duration::from_millis(30), false);
    let orbited = wait_for_still_image(&mut browser, &watch, &first["image"]);
    assert_eq!(orbited["previewCamera"], "true", "{orbited}");
    assert!(
        orbited["movingFrames"].as_u64() > Some(0),
        "no reduced frame painted: {orbited}"
    );
    // Each painted frame says where its time went: the server's parts and the page's.
    let frames = browser.evaluate("window.lampshadeView.frames");
    for frame in frames.as_array().unwrap() {
        for part in [
            "/request",
            "/image",
            "/server/load_ms",
            "/server/render_ms",
            "/server/encode_ms",
        ] {
            assert!(
                frame
                    .pointer(part)
                    .and_then(Value::as_f64)
                    .is_some_and(|ms| ms >= 0.0),
                "{part} of {frame}"
            );
        }
    }
    assert_eq!(
        orbited["pick"],
        Value::Null,
        "the release that ended the drag also picked a pixel: {orbited}"
    );
    browser.save_screenshot("view-orbited.png");
    let preview_image = shown_image(port);
    assert_eq!(image_pixels(&preview_image).dimensions(), (160, 120));
    assert_ne!(
        image_pixels(&preview_image),
        image_pixels(&file_image),
        "the orbit changed nothing"
    );
    assert_eq!(
        std::fs::read_to_string(&scene).unwrap(),
        original,
        "the preview wrote the scene"
    );

    // Copy: the copied camera, put into the file by hand, renders the preview's image exactly.
    browser.evaluate(r#"document.getElementById("view-copy").click()"#);
    let copied = wait_for(
        "the copied camera",
        || watch.output(),
        || {
            browser
                .evaluate("window.lampshadeView.lastCopied()")
                .as_str()
                .map(str::to_owned)
        },
    );
    assert!(copied.starts_with("camera: Perspective(eye: ("), "{copied}");
    let by_hand = tempfile::tempdir().unwrap();
    let by_hand_scene = by_hand.path().join("scene.ron");
    std::fs::write(
        &by_hand_scene,
        original.replace(&format!("camera: {FILE_CAMERA},"), &copied),
    )
    .unwrap();
    assert_eq!(
        image_pixels(&render_once(&by_hand_scene)),
        image_pixels(&preview_image),
        "the copied camera renders another image"
    );

    // Write: only the camera's span changes, and the watch renders the file as the preview was.
    browser.evaluate(r#"document.getElementById("view-write").click()"#);
    let written = wait_for(
        "the camera written",
        || watch.output(),
        || {
            let text = std::fs::read_to_string(&scene).ok()?;
            (text != original).then_some(text)
        },
    );
    let span = original.find(FILE_CAMERA).unwrap();
    let tail = &original[span + FILE_CAMERA.len()..];
    assert!(written.starts_with(&original[..span]), "{written}");
    assert!(written.ends_with(tail), "{written}");
    let new_value = &written[span..written.len() - tail.len()];
    assert_eq!(format!("camera: {new_value},"), copied);
    let after_write = browser.wait_for_page(PROBE, "the file's new camera", &watch, |state| {
        state["previewCamera"] == "false" && state["busy"] == false && state["image"] != orbited["image"]
    });
    wait_for(
        "the image file of the written camera",
        || watch.output(),
        || {
            let out = std::fs::read(folder.path().join("out.png")).ok()?;
            (image_pixels(&out) == image_pixels(&preview_image)).then_some(())
        },
    );
    assert_eq!(image_pixels(&shown_image(port)), image_pixels(&preview_image));

    // Toggles: the debug view changes the image; reset brings the file's image back.
    browser.evaluate(
        r#"(() => { const s = document.getElementById("view-debug"); s.value = "normals";
           s.dispatchEvent(new Event("change")); })()"#,
    );
    let normals = wait_for_still_image(&mut browser, &watch, &after_write["image"]);
    assert_eq!(normals["view"]["debug"], "normals", "{normals}");
    browser.save_screenshot("view-normals.png");
    assert_ne!(image_pixels(&shown_image(port)), image_pixels(&preview_image));
    browser.evaluate(
        r#"(() => { const s = document.getElementById("view-shading"); s.value = "flat";
           s.dispatchEvent(new Event("change")); })()"#,
    );
    let flat = wait_for_still_image(&mut browser, &watch, &normals["image"]);
    assert_eq!(flat["view"]["shading"], "flat", "{flat}");
    browser.evaluate(r#"document.getElementById("view-reset").click()"#);
    let reset = wait_for_still_image(&mut browser, &watch, &flat["image"]);
    assert!(
        reset["view"]["debug"].is_null() && reset["view"]["shading"].is_null(),
        "{reset}"
    );
    assert_eq!(image_pixels(&shown_image(port)), image_pixels(&preview_image));
    // The file was written once, by the write button.
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), written);
}

#[test]
fn the_page_s_camera_math_keeps_the_up_vector_and_never_reaches_the_poles() {
    let folder = tempfile::tempdir().unwrap();
    std::fs::write(folder.path().join("scene.ron"), scene_text()).unwrap();
    let Some((_watch, mut browser, _port)) = open_preview(
        folder.path(),
        &["scene.ron", "-o", "out.png", "--serve", "--port", "0"],
    ) else {
        return;
    };
    let result = browser.evaluate(
        r#"(() => {
  const v = window.lampshadeView;
  const length = (a) => Math.hypot(a[0], a[1], a[2]);
  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const finite = (c) => [...c.eye, ...c.target, ...c.up, c.fov].every(Number.isFinite);
  const start = { eye: [0, 0, 5], target: [0, 0, 0], up: [0, 0, 1], fov: 30 };
  const straightDown = { eye: [0, 0, 5], target: [0, 0, 0], up: [0, 1, 0], fov: 30 };
  const results = [];
  for (const camera of [start, straightDown, { ...start, eye: [3, -4, 0.5] }]) {
    for (const [yaw, pitch] of [[0, 10], [0, -10], [1.3, 3.2], [-2, -3.2], [0.5, 0]]) {
      const moved = v.orbit(camera, yaw, pitch);
      const offset = sub(moved.eye, moved.target);
      const r = length(offset);
      const cosine = (offset[0] * moved.up[0] + offset[1] * moved.up[1] + offset[2] * moved.up[2]) / r / length(moved.up);
      results.push({
        finite: finite(moved),
        radius: Math.abs(r - length(sub(camera.eye, camera.target))) < 1e-9 * r,
        offPole: Math.abs(cosine) < Math.cos(1e-3) + 1e-12,
        upKept: moved.up === camera.up,
      });
    }
  }
  const side = { ...start, eye: [3, -4, 0.5] };
  const panned = v.pan(side, 30, -20, 120);
  const dollied = v.dolly(start, 5);
  const far = v.dolly(start, -5);
  const tooClose = v.dolly(start, 1e6);
  return {
    orbit: results,
    panKeepsOffset: length(sub(sub(panned.eye, panned.target), sub(side.eye, side.target))) < 1e-12,
    panMoves: length(sub(panned.target, side.target)) > 0,
    dollyCloser: length(dollied.eye) < 5 && length(far.eye) > 5,
    dollyNeverReaches: length(tooClose.eye) > 0 && finite(tooClose),
  };
})()"#,
    );
    for (index, case) in result["orbit"].as_array().unwrap().iter().enumerate() {
        assert_eq!(
            case,
            &json!({ "finite": true, "radius": true, "offPole": true, "upKept": true }),
            "orbit case {index}"
        );
    }
    assert_eq!(result["panKeepsOffset"], true, "{result}");
    assert_eq!(result["panMoves"], true, "{result}");
    assert_eq!(result["dollyCloser"], true, "{result}");
    assert_eq!(result["dollyNeverReaches"], true, "{result}");
}

/// Updates painted per second while dragging `scenes/matlab-shiny.ron` at 800×600 on two
/// threads, and the time from each input event to the image that answers it being painted.
#[test]
#[ignore = "a benchmark: run it in release, alone on the machine"]
fn preview_orbit_speed() {
    let Some(chromium) = chromium_or_skip("preview_orbit_speed") else {
        return;
    };
    let folder = tempfile::tempdir().unwrap();
    let scene = crate::repo().join("scenes/matlab-shiny.ron");
    std::fs::copy(&scene, folder.path().join("scene.ron")).unwrap();
    let args = [
        "scene.ron",
        "-o",
        "out.png",
        "--width",
        "800",
        "--height",
        "600",
        "--threads",
        "2",
        "--serve",
        "--port",
        "0",
    ];
    let watch = WatchProcess::start(folder.path(), &args);
    let port = preview_port(&watch);
    let mut browser = Browser::open(&chromium, &format!("http://127.0.0.1:{port}/"));
    browser.wait_for_page(PROBE, "the page with a camera", &watch, |state| {
        state["ready"] == true && state["image"].as_str().is_some_and(|image| !image.is_empty())
    });
    let runs: u32 = std::env::var("LAMPSHADE_ORBIT_RUNS")
        .ok()
        .and_then(|runs| runs.parse().ok())
        .unwrap_or(5);
    let mut rates = Vec::new();
    let mut latencies = Vec::new();
    for run in 0..runs {
        browser.evaluate("window.lampshadeView.frames.length = 0");
        // Three seconds of a 60 Hz mouse.
        let started = Instant::now();
        drag(
            &mut browser,
            if run % 2 == 0 { 300.0 } else { -300.0 },
            30.0,
            180,
            Duration::from_millis(16),
            false,
        );
        let dragged = started.elapsed().as_secs_f64();
        let before = browser.evaluate(PROBE);
        let state = wait_for_still_image(&mut browser, &watch, &before["image"]);
        let frames = browser.evaluate("window.lampshadeView.frames.filter(f => f.moving)");
        let frames = frames.as_array().unwrap();
        let mut run_latencies: Vec<f64> = frames.iter().map(|f| f["latency"].as_f64().unwrap()).collect();
        run_latencies.sort_by(f64::total_cmp);
        let rate = frames.len() as f64 / dragged;
        let median = run_latencies
            .get(run_latencies.len() / 2)
            .copied()
            .unwrap_or(f64::NAN);
        let width = frames.last().map_or(0, |f| f["width"].as_u64().unwrap_or(0));
        // The median of each part of a moving frame's time (see `paint` in view.js).
        let part = |pointer: &str| {
            let mut values: Vec<f64> = frames
                .iter()
                .filter_map(|f| f.pointer(pointer)?.as_f64())
                .collect();
            values.sort_by(f64::total_cmp);
            values.get(values.len() / 2).copied().unwrap_or(f64::NAN)
        };
        let _ = writeln_stderr(&format!(
            "run {run}: {rate:.1} updates/s over {dragged:.2} s, input to paint median {median:.1} ms \
             (waited {:.1}, request {:.1} = load {:.1} + render {:.1} + encode {:.1} + the rest, \
             image fetch and decode {:.1}), moving frames {width} px wide; still frame {}×{}",
            part("/waited"),
            part("/request"),
            part("/server/load_ms"),
            part("/server/render_ms"),
            part("/server/encode_ms"),
            part("/image"),
            state["view"]["width"],
            state["view"]["height"]
        ));
        rates.push(rate);
        latencies.push(median);
    }
    rates.sort_by(f64::total_cmp);
    latencies.sort_by(f64::total_cmp);
    let _ = writeln_stderr(&format!(
        "preview orbit, matlab-shiny 800×600, 2 threads: median {:.1} updates/s (runs {:.1}–{:.1}), \
         input to paint median {:.1} ms",
        rates[rates.len() / 2],
        rates[0],
        rates[rates.len() - 1],
        latencies[latencies.len() / 2]
    ));
}

/// Prints past the test harness's capture.
fn writeln_stderr(line: &str) -> std::io::Result<()> {
    use std::io::Write;
    writeln!(std::io::stderr(), "{line}")
}

/// POSTs `body` to the preview with extra `headers`; returns the status and the body.
fn http_post(port: u16, path: &str, headers: &str, body: &str) -> (u16, String) {
    use std::io::{Read, Write};
    let mut stream = std::net::TcpStream::connect(("127.0.0.1", port)).unwrap();
    stream.set_read_timeout(Some(crate::watch::DEADLINE)).unwrap();
    write!(
        stream,
        "POST {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n{headers}Content-Type: application/json\r\n\
         Content-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    )
    .unwrap();
    let mut response = String::new();
    let _ = stream.read_to_string(&mut response);
    let status = response.split(' ').nth(1).unwrap().parse().unwrap();
    let body = response
        .split_once("\r\n\r\n")
        .map_or("", |(_, body)| body)
        .to_owned();
    (status, body)
}

#[test]
fn the_view_routes_answer_scripts_and_refuse_other_sites() {
    let folder = tempfile::tempdir().unwrap();
    let scene = folder.path().join("scene.ron");
    let original = scene_text();
    std::fs::write(&scene, &original).unwrap();
    let watch = WatchProcess::start(
        folder.path(),
        &["scene.ron", "-o", "out.png", "--serve", "--port", "0"],
    );
    let port = preview_port(&watch);
    let camera = r#"{"eye": [3, 1, 2], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 35}"#;

    let (status, _) = http_post(
        port,
        "/api/camera",
        "Origin: http://elsewhere.example\r\n",
        camera,
    );
    assert_eq!(status, 403);
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), original);

    let (status, body) = http_post(port, "/api/view", "", r#"{"debug": "wireframe"}"#);
    assert_eq!(
        (status, body.contains("unknown debug view")),
        (400, true),
        "{body}"
    );
    let degenerate = r#"{"camera": {"eye": [0, 0, 0], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 35}}"#;
    assert_eq!(http_post(port, "/api/view", "", degenerate).0, 400);

    let (status, body) = http_post(
        port,
        "/api/view",
        "",
        &format!(r#"{{"camera": {camera}, "moving": true}}"#),
    );
    assert_eq!(status, 200, "{body}");
    let state: Value = serde_json::from_str(&body).unwrap();
    assert_eq!(state["view"]["moving"], true, "{state}");
    assert_eq!(state["view"]["preview_camera"], true, "{state}");
    assert_eq!(
        (state["view"]["width"].as_u64(), state["view"]["height"].as_u64()),
        (Some(160), Some(120))
    );
    let shown = image_pixels(&shown_image(port));
    assert_eq!(shown.dimensions(), (80, 60), "a reduced frame while moving");

    let (status, body) = http_post(
        port,
        "/api/camera",
        &format!("Origin: http://127.0.0.1:{port}\r\n"),
        camera,
    );
    assert_eq!(status, 200, "{body}");
    let written = std::fs::read_to_string(&scene).unwrap();
    assert_eq!(
        written,
        original.replace(
            FILE_CAMERA,
            "Perspective(eye: (3, 1, 2), target: (0, 0, 0), up: (0, 1, 0), fov: 35)"
        )
    );
    let (status, _) = http_post(
        port,
        "/api/buffer",
        "",
        r#"{"path": "/elsewhere/other.ron", "text": "()"}"#,
    );
    assert_eq!(status, 404);
}
