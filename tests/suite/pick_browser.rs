//! The preview's pixel inspector in headless Chromium: a click on a pixel of the image opens the
//! panel with the object, its source link (`vscode://file/...:LINE:COL` pointing at the line the
//! object is written on), the lighting table, and the object's pixels highlighted; Escape closes
//! it. Skipped, with a message, without Chromium.

use serde_json::{Value, json};

use crate::browser::{Browser, chromium_or_skip};
use crate::watch::{SceneFolder, WatchProcess, preview_port, wait_for};

const SCENE: &str = r#"Scene(
    image: (width: 320, height: 240),
    camera: Perspective(eye: (0, 0, 6), target: (0, 0, 0), fov: 40),
    include: ["mats.ron"],
    lights: [Directional(direction: (0.3, -0.2, -1)), Point(position: (2, 2, 3))],
    objects: [
        (name: "ball", mesh: Sphere(segments: 32), translate: (-1, 0, 0), material: "paint"),
        (name: "box", mesh: Cube, translate: (1.2, 0, 0), scale: 0.6, rotate: (20, 30, 0), material: "brass"),
    ],
)
"#;

/// What the inspector shows.
const PROBE: &str = r#"(() => {
  const view = document.getElementById("view");
  const panel = document.getElementById("pick-panel");
  const mask = document.getElementById("pick-mask");
  if (view === null || panel === null || !view.complete || view.naturalWidth === 0) return { state: "loading" };
  const box = view.getBoundingClientRect();
  return {
    state: document.body.dataset.state,
    pick: document.body.dataset.pick ?? null,
    highlight: document.body.dataset.highlight ?? null,
    panelShown: !panel.hidden,
    object: panel.dataset.object ?? null,
    title: panel.querySelector("h3.object")?.textContent ?? null,
    links: Array.from(panel.querySelectorAll("a.source-link")).map((a) => a.getAttribute("href")),
    lightRows: panel.querySelectorAll("table.lighting tr").length,
    maskShown: mask !== null && !mask.hidden && mask.complete && mask.naturalWidth === view.naturalWidth,
    left: box.left, top: box.top, scale: box.width / view.naturalWidth,
  };
})()"#;

fn click(browser: &mut Browser, state: &Value, (x, y): (u32, u32)) {
    let scale = state["scale"].as_f64().unwrap();
    let at_x = state["left"].as_f64().unwrap() + (f64::from(x) + 0.5) * scale;
    let at_y = state["top"].as_f64().unwrap() + (f64::from(y) + 0.5) * scale;
    for kind in ["mousePressed", "mouseReleased"] {
        browser.call(
            "Input.dispatchMouseEvent",
            json!({ "type": kind, "x": at_x, "y": at_y, "button": "left", "clickCount": 1 }),
        );
    }
}

/// `watch --serve` on [`SCENE`] in a new folder, its first image written, and Chromium on its
/// preview page.
fn open_preview_of_the_scene(chromium: &std::path::Path) -> (SceneFolder, WatchProcess, Browser) {
    let folder = SceneFolder::new();
    folder.write("scene.ron", SCENE);
    let watch = WatchProcess::start(
        &folder.path,
        &["scene.ron", "-o", "out.png", "--serve", "--port", "0"],
    );
    let port = preview_port(&watch);
    wait_for("the first image", || watch.output(), || folder.image());
    let browser = Browser::open(chromium, &format!("http://127.0.0.1:{port}/"));
    (folder, watch, browser)
}

#[test]
fn clicking_a_pixel_shows_its_object_with_a_link_to_its_line_and_highlights_it() {
    let Some(chromium) = chromium_or_skip("pick_browser") else {
        return;
    };
    let (folder, watch, mut browser) = open_preview_of_the_scene(&chromium);
    let state = browser.wait_for_page(PROBE, "the image", &watch, |state| state["state"] == "ok");

    // The ball's centre: one unit left of the image's centre, 6 units away with a 40° field of view.
    click(&mut browser, &state, (105, 120));
    let shown = browser.wait_for_page(PROBE, "the inspector panel", &watch, |state| {
        state["pick"] == "shown" && state["maskShown"] == true
    });
    browser.save_screenshot("pick-panel.png");
    assert_eq!(shown["object"], "0", "{shown}");
    assert_eq!(shown["highlight"], "0", "{shown}");
    assert!(shown["title"].as_str().unwrap().contains("ball"), "{shown}");
    let scene_path = std::path::absolute(folder.file("scene.ron")).unwrap();
    let line = SCENE.lines().position(|l| l.contains("(name: \"ball\"")).unwrap() + 1;
    let column = SCENE.lines().nth(line - 1).unwrap().find('(').unwrap() + 1;
    let expected = format!("vscode://file{}:{line}:{column}", scene_path.display());
    let links: Vec<&str> = shown["links"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(Value::as_str)
        .collect();
    assert_eq!(links.first(), Some(&expected.as_str()), "{shown}");
    assert!(
        shown["lightRows"].as_u64().unwrap() >= 6,
        "header, emission, ambient, two lights, sum: {shown}"
    );

    // The box, then the background, then Escape.
    click(&mut browser, &shown, (230, 120));
    let boxed = browser.wait_for_page(PROBE, "the box", &watch, |state| {
        state["pick"] == "shown" && state["highlight"] == "1"
    });
    assert!(boxed["title"].as_str().unwrap().contains("box"), "{boxed}");
    click(&mut browser, &boxed, (5, 5));
    let background = browser.wait_for_page(PROBE, "the background", &watch, |state| {
        state["pick"] == "shown" && state["object"] == ""
    });
    assert_eq!(background["highlight"], Value::Null, "{background}");
    browser.call(
        "Input.dispatchKeyEvent",
        json!({ "type": "keyDown", "key": "Escape", "code": "Escape", "windowsVirtualKeyCode": 27 }),
    );
    browser.wait_for_page(PROBE, "the panel to close", &watch, |state| {
        state["panelShown"] == false
    });
}

/// Where the panel and the image are, and what the lighting table's last rows say.
const LAYOUT: &str = r#"(() => {
  const rect = (element) => { const r = element.getBoundingClientRect();
    return { left: r.left, top: r.top, right: r.right, bottom: r.bottom }; };
  const panel = document.getElementById("pick-panel");
  return {
    pick: document.body.dataset.pick ?? null,
    window: [window.innerWidth, window.innerHeight],
    page: document.documentElement.scrollWidth,
    image: rect(document.getElementById("view")),
    panel: rect(panel),
    clipped: panel.scrollWidth > panel.clientWidth,
    sumRow: panel.querySelector("tr.sum td")?.textContent ?? null,
    shownRow: panel.querySelector("tr.shown td")?.textContent ?? null,
    pixelSum: panel.querySelector("p.pixel-sum")?.textContent ?? null,
  };
})()"#;

#[test]
fn the_panel_fits_small_windows_beside_or_below_the_image_and_says_what_its_sums_are() {
    let Some(chromium) = chromium_or_skip("pick_browser") else {
        return;
    };
    let (_folder, watch, mut browser) = open_preview_of_the_scene(&chromium);
    for (width, height) in [(640, 420), (1024, 768)] {
        browser.call(
            "Emulation.setDeviceMetricsOverride",
            json!({ "width": width, "height": height, "deviceScaleFactor": 1, "mobile": false }),
        );
        let state = browser.wait_for_page(PROBE, "the image", &watch, |state| state["state"] == "ok");
        click(&mut browser, &state, (105, 120));
        browser.wait_for_page(PROBE, "the inspector panel", &watch, |state| {
            state["pick"] == "shown" && state["maskShown"] == true
        });
        browser.save_screenshot(&format!("pick-panel-{width}x{height}.png"));
        let layout = browser.evaluate(LAYOUT);
        let get = |path: &str| layout.pointer(path).and_then(Value::as_f64).unwrap();
        assert!(
            get("/panel/right") <= f64::from(width),
            "wider than the window: {layout}"
        );
        assert!(
            get("/page") <= f64::from(width),
            "the page scrolls sideways: {layout}"
        );
        let beside = get("/panel/left") >= get("/image/right");
        let below = get("/panel/top") >= get("/image/bottom");
        assert!(beside || below, "the panel covers the image: {layout}");
        assert!(
            get("/panel/bottom") - get("/panel/top") <= f64::from(height),
            "{layout}"
        );
        if width >= 1024 {
            // Room for the whole lighting table beside the image: none of it hidden.
            assert_eq!(layout["clipped"], false, "{layout}");
        }
        assert_eq!(layout["sumRow"], "sum of the lights", "{layout}");
        assert!(
            layout["pixelSum"].as_str().unwrap().contains("before clamping"),
            "{layout}"
        );
        browser.call(
            "Input.dispatchKeyEvent",
            json!({ "type": "keyDown", "key": "Escape", "code": "Escape", "windowsVirtualKeyCode": 27 }),
        );
        browser.wait_for_page(PROBE, "the panel to close", &watch, |state| {
            state["panelShown"] == false
        });
    }
}
