//! The preview of `lampshade watch --serve` in a real browser, end to end: headless Chromium
//! opens the page, the test edits the scene file, and the page must show the new image (checked
//! pixel by pixel against the PNG on disk), then, after a broken save, the diagnostics overlay
//! above the last good image, with a snippet wider than the page scrolled, never wrapped.
//!
//! Chromium is driven as `browser.rs` says; without it the test prints why it skipped and passes.

use serde_json::Value;

use crate::browser::{Browser, chromium_or_skip};
use crate::watch::{SceneFolder, WatchProcess, preview_port, scene_text, wait_for};

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
    let Some(chromium) = chromium_or_skip("watch_browser") else {
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
