//! The compare views in headless Chromium: in the watch preview (swipe shows the previous image
//! left of the divider and the new one right of it, the difference of two known images, the
//! pinned image as the base, the mode kept across a reload) and in the `check --report` page
//! (failures first, the filters, swipe, onion skin and difference against the reference).
//! Pixels are read back from the viewer's canvas and compared with the PNGs `lampshade`
//! wrote. Chromium is driven as `browser.rs` says; without it the tests skip.

use serde_json::{Value, json};

use crate::browser::{Browser, chromium_or_skip};
use crate::check::{GREEN, three_spheres};
use crate::process::everything;
use crate::watch::{SceneFolder, WatchProcess, http_get, preview_port, render_once, scene_text, wait_for};

/// Colour management may move an untagged PNG's values by a step or two.
const TOLERANCE: i64 = 2;

/// The colour of the viewer canvas `CANVAS` at the points `POINTS` (`[[x, y], …]`), with the
/// page's compare state.
const CANVAS_PROBE: &str = r#"(() => {
  const canvas = CANVAS;
  if (!canvas || canvas.width === 0) return { ready: false };
  const data = canvas.getContext("2d").getImageData(0, 0, canvas.width, canvas.height).data;
  const at = ([x, y]) => Array.from(data.slice((y * canvas.width + x) * 4, (y * canvas.width + x) * 4 + 3));
  return {
    ready: true,
    width: canvas.width,
    mode: document.body.dataset.compare ?? null,
    base: document.body.dataset.compareBase ?? null,
    pixels: POINTS.map(at),
  };
})()"#;

fn probe(canvas: &str, points: &[(u32, u32)]) -> String {
    let points: Vec<[u32; 2]> = points.iter().map(|&(x, y)| [x, y]).collect();
    CANVAS_PROBE
        .replace("CANVAS", canvas)
        .replace("POINTS", &json!(points).to_string())
}

fn rgb(png: &[u8]) -> image::RgbImage {
    image::load_from_memory(png).unwrap().to_rgb8()
}

/// The pixel of `x_range` where `a` and `b` differ most.
fn most_different_in(a: &image::RgbImage, b: &image::RgbImage, x_range: std::ops::Range<u32>) -> (u32, u32) {
    let distance = |x, y| -> u32 {
        let (p, q) = (a.get_pixel(x, y).0, b.get_pixel(x, y).0);
        p.iter().zip(q).map(|(p, q)| u32::from(p.abs_diff(q))).sum()
    };
    let best = x_range
        .flat_map(|x| (0..a.height()).map(move |y| (x, y)))
        .max_by_key(|&(x, y)| distance(x, y))
        .unwrap();
    assert!(distance(best.0, best.1) > 30, "the images must differ there");
    best
}

/// Whether `state`'s pixel `index` is `expected` within `tolerance` per channel.
fn pixel_is(state: &Value, index: usize, expected: [i64; 3], tolerance: i64) -> bool {
    let Some(pixel) = state["pixels"].get(index).and_then(Value::as_array) else {
        return false;
    };
    pixel.len() == 3
        && pixel
            .iter()
            .zip(expected)
            .all(|(p, e)| p.as_i64().is_some_and(|p| (p - e).abs() <= tolerance))
}

fn colour(image: &image::RgbImage, (x, y): (u32, u32)) -> [i64; 3] {
    image.get_pixel(x, y).0.map(i64::from)
}

/// Waits until `condition` holds for `probe`'s value, with `context` on a timeout.
fn wait_for_page(
    browser: &mut Browser,
    probe: &str,
    what: &str,
    context: impl Fn() -> String,
    condition: impl Fn(&Value) -> bool,
) -> Value {
    let started = std::time::Instant::now();
    loop {
        let state = browser.evaluate(probe);
        if condition(&state) {
            return state;
        }
        assert!(
            started.elapsed() < crate::watch::DEADLINE,
            "timed out waiting for {what}\npage state: {state}\n{}",
            context()
        );
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
}

#[test]
fn the_preview_compares_the_new_image_with_the_previous_or_the_pinned_one() {
    let Some(chromium) = chromium_or_skip("compare_browser") else {
        return;
    };
    let lights = [(1.0, 1.0, 1.0), (1.0, 0.2, 0.2), (0.2, 0.3, 1.0)];
    // What each light gives, rendered on the side, so the test knows every pixel.
    let images: Vec<image::RgbImage> = lights
        .iter()
        .map(|&light| {
            let reference = SceneFolder::new();
            reference.write("scene.ron", &scene_text(light));
            rgb(&render_once(&reference.file("scene.ron")))
        })
        .collect();
    let (white, red, blue) = (&images[0], &images[1], &images[2]);
    // Left of the middle divider and right of it; the images are 32 pixels wide.
    let left = most_different_in(white, red, 0..12);
    let right = most_different_in(white, red, 20..32);
    let points = [left, right];
    let canvas = r##"document.querySelector("#compare canvas")"##;
    let probe = probe(canvas, &points);

    let folder = SceneFolder::new();
    let watch = WatchProcess::start(
        &folder.path,
        &["scene.ron", "-o", "out.png", "--serve", "--port", "0"],
    );
    let port = preview_port(&watch);
    let url = format!("http://127.0.0.1:{port}/");
    wait_for("the first image", || watch.output(), || folder.image());
    let mut browser = Browser::open(&chromium, &url);
    let context = || watch.output();

    // The plain view is the default: the canvas is hidden, the <img> shows.
    let state = wait_for_page(
        &mut browser,
        &probe,
        "the first image in the viewer",
        context,
        |state| state["ready"] == true && state["base"] == "none",
    );
    assert_eq!(state["mode"], "plain", "{state}");
    assert_eq!(
        browser.evaluate(r#"getComputedStyle(document.getElementById("compare")).display"#),
        "none"
    );

    // Swipe, chosen by its button, the divider in the middle: the previous (white) image left
    // of it, the new (red) one right of it.
    browser.evaluate(r##"document.querySelector('#compare-bar [data-mode="swipe"]').click()"##);
    browser.evaluate("window.lampshadeCompare.change({ split: 0.5 })");
    folder.write("scene.ron", &scene_text(lights[1]));
    let state = wait_for_page(
        &mut browser,
        &probe,
        "swipe: white left, red right",
        context,
        |state| {
            state["base"] == "previous"
                && pixel_is(state, 0, colour(white, left), TOLERANCE)
                && pixel_is(state, 1, colour(red, right), TOLERANCE)
        },
    );
    assert_eq!(state["mode"], "swipe");
    assert_eq!(state["width"], 32);
    assert_eq!(
        browser.evaluate(r#"getComputedStyle(document.getElementById("view")).display"#),
        "none",
        "the canvas takes the image's place"
    );
    browser.save_screenshot("compare-preview-swipe.png");

    // Dragging on the canvas moves the divider: pressed just right of the right-hand point,
    // that point shows the previous image too.
    let bounds = browser.evaluate(
        r##"(() => { const r = document.querySelector("#compare canvas").getBoundingClientRect();
                    return [r.left, r.top, r.width, r.height]; })()"##,
    );
    let bound = |i: usize| bounds[i].as_f64().unwrap();
    let past_right = (f64::from(right.0) + 1.5).min(32.0) / 32.0;
    let (x, y) = (bound(0) + past_right * bound(2), bound(1) + 0.5 * bound(3));
    for kind in ["mousePressed", "mouseReleased"] {
        browser.call(
            "Input.dispatchMouseEvent",
            json!({ "type": kind, "x": x, "y": y, "button": "left", "clickCount": 1 }),
        );
    }
    wait_for_page(
        &mut browser,
        &probe,
        "the divider dragged right",
        context,
        |state| pixel_is(state, 1, colour(white, right), TOLERANCE),
    );

    // Difference, not amplified: |red − white| per channel.
    browser.evaluate("window.lampshadeCompare.change({ mode: 'difference', gain: 1 })");
    let difference = |a: &image::RgbImage, b: &image::RgbImage, point| {
        let (a, b) = (colour(a, point), colour(b, point));
        [0, 1, 2].map(|c| (a[c] - b[c]).abs())
    };
    wait_for_page(
        &mut browser,
        &probe,
        "the difference of white and red",
        context,
        |state| {
            state["mode"] == "difference"
                && pixel_is(state, 0, difference(red, white, left), 2 * TOLERANCE)
                && pixel_is(state, 1, difference(red, white, right), 2 * TOLERANCE)
        },
    );
    browser.evaluate("window.lampshadeCompare.change({ gain: 4 })");
    wait_for_page(
        &mut browser,
        &probe,
        "the difference amplified ×4",
        context,
        |state| {
            pixel_is(
                state,
                0,
                difference(red, white, left).map(|c| (4 * c).min(255)),
                8 * TOLERANCE,
            )
        },
    );
    browser.save_screenshot("compare-preview-difference.png");

    // Pin the red image; after blue and then white again, swipe still compares with red
    // (the previous image would be blue).
    browser.evaluate("document.getElementById('pin').click()");
    browser.evaluate("window.lampshadeCompare.change({ mode: 'swipe', split: 0.5 })");
    folder.write("scene.ron", &scene_text(lights[2]));
    wait_for_page(
        &mut browser,
        &probe,
        "blue against the pinned red",
        context,
        |state| {
            state["base"] == "pinned"
                && pixel_is(state, 0, colour(red, left), TOLERANCE)
                && pixel_is(state, 1, colour(blue, right), TOLERANCE)
        },
    );
    folder.write("scene.ron", &scene_text(lights[0]));
    wait_for_page(
        &mut browser,
        &probe,
        "white against the pinned red",
        context,
        |state| {
            pixel_is(state, 0, colour(red, left), TOLERANCE)
                && pixel_is(state, 1, colour(white, right), TOLERANCE)
        },
    );
    // Unpinned, the base is the previous image again: blue.
    browser.evaluate("document.getElementById('pin').click()");
    wait_for_page(
        &mut browser,
        &probe,
        "white against the previous blue",
        context,
        |state| state["base"] == "previous" && pixel_is(state, 0, colour(blue, left), TOLERANCE),
    );

    // The mode is remembered across a reload.
    // `Page.navigate` answers once the new document has committed, so no evaluation below
    // lands in the page being torn down.
    browser.evaluate("window.beforeReload = true");
    browser.call("Page.navigate", json!({ "url": url }));
    let mode = wait_for_page(
        &mut browser,
        "window.beforeReload === undefined && document.body !== null ? document.body.dataset.compare ?? null : null",
        "the reloaded page's compare mode",
        context,
        |mode| !mode.is_null(),
    );
    assert_eq!(mode, "swipe", "the mode is remembered across a reload");

    // The turntable button plays the watch's APNG of the scene orbiting.
    browser.evaluate("document.getElementById('turntable-button').click()");
    let player = r#"(() => { const img = document.getElementById("turntable");
        return img && !img.hidden && img.complete ? img.naturalWidth : 0; })()"#;
    wait_for_page(&mut browser, player, "the turntable playing", context, |width| {
        width.as_u64() == Some(32)
    });
    browser.save_screenshot("compare-preview-turntable.png");
    let host = format!("127.0.0.1:{port}");
    let (status, body) = http_get(port, "/turntable.png?frames=4", &host);
    assert_eq!(status, 200);
    let reader = png::Decoder::new(std::io::Cursor::new(body))
        .read_info()
        .expect("a PNG");
    assert_eq!(reader.info().animation_control.map(|a| a.num_frames), Some(4));
    let (status, _) = http_get(port, "/turntable.png?frames=0", &host);
    assert_eq!(status, 400);
}

#[test]
fn the_report_viewer_shows_failures_first_filters_and_compares_with_the_reference() {
    let Some(chromium) = chromium_or_skip("compare_browser") else {
        return;
    };
    let suite = three_spheres();
    suite.bless_all();
    suite.write("c.ron", &crate::check::sphere(GREEN));
    let output = suite.check(&["--report", "report"]);
    assert_eq!(output.status.code(), Some(1), "{}", everything(&output));
    let expected = rgb(&std::fs::read(suite.reference("c")).unwrap());
    let actual_file = std::fs::read_dir(suite.dir().join("report/images"))
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .find(|path| path.to_string_lossy().ends_with("-actual.png"))
        .expect("the actual picture");
    let actual = rgb(&std::fs::read(actual_file).unwrap());
    let left = most_different_in(&expected, &actual, 0..15);
    let right = most_different_in(&expected, &actual, 17..32);
    let index = suite.dir().join("report/index.html");
    let url = format!("file://{}", index.display());
    let mut browser = Browser::open(&chromium, &url);
    let context = || String::new();

    let table = r##"(() => {
      const rows = [...document.querySelectorAll("#scenes tbody tr")];
      return {
        verdicts: rows.map((row) => row.dataset.verdict),
        visible: rows.filter((row) => !row.hidden).map((row) => row.dataset.name),
        sections: [...document.querySelectorAll("section.scene")].filter((s) => !s.hidden).length,
      };
    })()"##;
    let state = wait_for_page(&mut browser, table, "the summary table", context, |state| {
        state["visible"].as_array().is_some_and(|rows| rows.len() == 3)
    });
    assert_eq!(
        state["verdicts"],
        json!(["failed", "passed", "passed"]),
        "failures first"
    );
    assert_eq!(state["sections"], 1);
    // Unticking `passed` hides the passes; the name filter narrows further.
    browser.evaluate(r##"document.querySelector('#filters input[value="passed"]').click()"##);
    let state = browser.evaluate(table);
    assert_eq!(state["visible"].as_array().unwrap().len(), 1, "{state}");
    assert!(
        state["visible"][0].as_str().unwrap().ends_with("c.ron"),
        "{state}"
    );
    browser.evaluate(
        r##"(() => { const box = document.querySelector('#filters input[value="passed"]'); box.click();
                    const name = document.getElementById("name-filter"); name.value = "a.ron";
                    name.dispatchEvent(new Event("input")); })()"##,
    );
    let state = browser.evaluate(table);
    assert_eq!(state["visible"].as_array().unwrap().len(), 1, "{state}");
    assert!(
        state["visible"][0].as_str().unwrap().ends_with("a.ron"),
        "{state}"
    );
    assert_eq!(
        state["sections"], 0,
        "the failure does not match `a.ron`: {state}"
    );
    browser.evaluate(
        r#"(() => { const name = document.getElementById("name-filter"); name.value = "";
                    name.dispatchEvent(new Event("input")); })()"#,
    );

    let viewer = r#"document.querySelector("[data-compare]").compareView"#;
    let canvas = format!("{viewer}.canvas");
    let probe = probe(&canvas, &[left, right]);
    // Side by side by default: expected, a gap, actual.
    let state = wait_for_page(
        &mut browser,
        &probe,
        "the viewer side by side",
        context,
        |state| state["ready"] == true,
    );
    assert_eq!(state["width"], 2 * 32 + 8, "{state}");
    browser.evaluate(&format!("{viewer}.bar.scrollIntoView()"));
    browser.save_screenshot("compare-report-side.png");

    browser.evaluate(&format!("{viewer}.change({{ mode: 'swipe', split: 0.5 }})"));
    wait_for_page(
        &mut browser,
        &probe,
        "swipe: expected left, actual right",
        context,
        |state| {
            state["width"] == 32
                && pixel_is(state, 0, colour(&expected, left), TOLERANCE)
                && pixel_is(state, 1, colour(&actual, right), TOLERANCE)
        },
    );
    browser.save_screenshot("compare-report-swipe.png");

    browser.evaluate(&format!("{viewer}.change({{ mode: 'onion', opacity: 0.5 }})"));
    let halfway = [0, 1, 2].map(|c| (colour(&expected, left)[c] + colour(&actual, left)[c]) / 2);
    wait_for_page(&mut browser, &probe, "onion skin at one half", context, |state| {
        pixel_is(state, 0, halfway, TOLERANCE + 1)
    });

    browser.evaluate(&format!("{viewer}.change({{ mode: 'difference', gain: 4 }})"));
    let amplified =
        [0, 1, 2].map(|c| ((colour(&expected, right)[c] - colour(&actual, right)[c]).abs() * 4).min(255));
    wait_for_page(&mut browser, &probe, "the difference ×4", context, |state| {
        pixel_is(state, 1, amplified, 8 * TOLERANCE)
    });
    browser.save_screenshot("compare-report-difference.png");

    // The heat map the run wrote is a mode of its own.
    browser.evaluate(&format!("{viewer}.setMode('layer:heat map')"));
    let state = browser.evaluate(&probe);
    assert_eq!(state["width"], 32, "{state}");
}
