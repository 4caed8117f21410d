//! The pixel inspector from outside: `lampshade render --pick X,Y` (the JSON, a background
//! pixel, coordinates outside the image, the overrides, `-o`) and `GET /api/pick` on
//! `watch --serve` (the same JSON for the image shown; errors as JSON with 4xx statuses).

use std::process::Output;

use serde_json::Value;

use crate::process::lampshade;
use crate::repo;
use crate::watch::{SceneFolder, WatchProcess, http_get, preview_port, wait_for};

fn json(output: &Output) -> Value {
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).expect("standard output is JSON")
}

#[test]
fn render_pick_prints_the_pixels_json_and_writes_no_image() {
    let work = tempfile::tempdir().unwrap();
    let scene = repo().join("scenes/matlab-shiny.ron");
    let output = lampshade(
        &["render", "--pick", "380,200", scene.to_str().unwrap()],
        work.path(),
    );
    let pick = json(&output);
    assert_eq!((pick["x"].as_u64(), pick["y"].as_u64()), (Some(380), Some(200)));
    assert_eq!(
        (pick["width"].as_u64(), pick["height"].as_u64()),
        (Some(640), Some(480))
    );
    assert_eq!(pick["background"], false);
    let surface = &pick["surfaces"][0];
    assert_eq!(surface["shading"], "Phong");
    assert_eq!(surface["lighting"]["at"], "pixel");
    let defined_at = &surface["object"]["defined_at"];
    assert!(
        defined_at["path"]
            .as_str()
            .unwrap()
            .ends_with("scenes/matlab-shiny.ron")
    );
    assert!(defined_at["line"].as_u64().unwrap() >= 17, "{defined_at}");
    assert_eq!(surface["material"]["origin"], "inline");
    let lights = surface["lighting"]["points"][0]["lights"].as_array().unwrap();
    assert_eq!(lights.len(), 2);
    // The pixel's 8-bit colour is the image's.
    let rgb8: Vec<u64> = pick["color"]["rgb8"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_u64().unwrap())
        .collect();
    let image = work.path().join("shiny.png");
    let rendered = lampshade(
        &["render", scene.to_str().unwrap(), "-o", image.to_str().unwrap()],
        work.path(),
    );
    assert!(rendered.status.success());
    let pixel = image::open(&image).unwrap().to_rgb8().get_pixel(380, 200).0;
    assert_eq!(rgb8, pixel.map(u64::from).to_vec());
    // Nothing but the image asked for was written.
    let written: Vec<_> = std::fs::read_dir(work.path()).unwrap().collect();
    assert_eq!(written.len(), 1);
}

#[test]
fn render_pick_honours_the_overrides_and_writes_the_image_with_o() {
    let work = tempfile::tempdir().unwrap();
    let scene = repo().join("scenes/matlab-shiny.ron");
    let image = work.path().join("flat.png");
    let output = lampshade(
        &[
            "render",
            "--pick",
            "20,12",
            "--shading",
            "flat",
            "--model",
            "blinn-phong",
            "--width",
            "32",
            "--height",
            "24",
            scene.to_str().unwrap(),
            "-o",
            image.to_str().unwrap(),
        ],
        work.path(),
    );
    let pick = json(&output);
    assert_eq!(pick["width"], 32);
    let surface = &pick["surfaces"][0];
    assert_eq!(surface["shading"], "Flat");
    assert_eq!(surface["lighting_model"], "BlinnPhong");
    assert_eq!(surface["lighting"]["at"], "centroid");
    let pixel = image::open(&image).unwrap().to_rgb8().get_pixel(20, 12).0;
    assert_eq!(pick["color"]["rgb8"], serde_json::json!(pixel));
}

#[test]
fn render_pick_of_the_background_and_outside_the_image() {
    let work = tempfile::tempdir().unwrap();
    let scene = repo().join("scenes/matlab-shiny.ron");
    let pick = json(&lampshade(
        &["render", "--pick", "0,0", scene.to_str().unwrap()],
        work.path(),
    ));
    assert_eq!(pick["background"], true);
    assert_eq!(pick["surfaces"], serde_json::json!([]));
    assert_eq!(pick["background_samples"], 1);

    let outside = lampshade(
        &["render", "--pick", "640,10", scene.to_str().unwrap()],
        work.path(),
    );
    assert_eq!(outside.status.code(), Some(2));
    let message = String::from_utf8_lossy(&outside.stderr);
    assert!(
        message.contains("(640, 10) is outside the 640×480 image"),
        "{message}"
    );
    assert!(outside.stdout.is_empty());

    let malformed = lampshade(&["render", "--pick", "12", scene.to_str().unwrap()], work.path());
    assert_eq!(malformed.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&malformed.stderr).contains("X,Y"));
}

#[test]
fn the_preview_server_answers_picks_about_the_image_shown() {
    let folder = SceneFolder::new();
    let watch = WatchProcess::start(
        &folder.path,
        &["scene.ron", "-o", "out.png", "--serve", "--port", "0"],
    );
    let port = preview_port(&watch);
    wait_for("the first image", || watch.output(), || folder.image());
    let host = format!("127.0.0.1:{port}");
    // The page's first image is published once it is written: wait for the server to have it.
    let (status, body) = wait_for(
        "a pick of the image",
        || watch.output(),
        || {
            let (status, body) = http_get(port, "/api/pick?x=8&y=12", &host);
            (status == 200).then_some((status, body))
        },
    );
    assert_eq!(status, 200);
    let served: Value = serde_json::from_slice(&body).unwrap();
    let cli = json(&lampshade(
        &["render", "--pick", "8,12", "scene.ron"],
        &folder.path,
    ));
    assert_eq!(served, cli, "the server and `render --pick` agree");
    assert_eq!(served["surfaces"][0]["object"]["index"], 0);

    let (status, body) = http_get(port, "/api/pick?x=32&y=0", &host);
    assert_eq!(status, 422);
    let error: Value = serde_json::from_slice(&body).unwrap();
    assert!(
        error["error"]
            .as_str()
            .unwrap()
            .contains("outside the 32×24 image"),
        "{error}"
    );
    let (status, _) = http_get(port, "/api/pick?x=one&y=2", &host);
    assert_eq!(status, 400);

    let (status, png) = http_get(port, "/api/object-mask?object=0", &host);
    assert_eq!(status, 200);
    let mask = image::load_from_memory(&png).unwrap().to_rgba8();
    assert_eq!(mask.dimensions(), (32, 24));
    assert!(mask.get_pixel(8, 12).0[3] > 0, "the picked pixel is highlighted");
    assert_eq!(mask.get_pixel(0, 0).0[3], 0, "the background is not");
    let (status, _) = http_get(port, "/api/object-mask?object=7", &host);
    assert_eq!(status, 422);
}
