//! `lampshade render --turntable N`: the APNG holds N frames, each the image `render` gives for
//! that frame's camera written into the scene; numbered frames; shards that together write
//! every frame once; and the arguments it refuses.

use std::path::Path;
use std::process::Output;

use crate::process::{everything, lampshade};
use glam::DVec3;
use lampshade::scene::{Camera, Projection};
use lampshade::turntable::orbit_camera;

const EYE: DVec3 = DVec3::new(1.5, 1.2, 4.0);
const TARGET: DVec3 = DVec3::new(0.2, 0.0, 0.0);

/// A small scene that looks different from every side (a cube and a sphere off the axis),
/// seen from `eye` (printed with every bit, as Rust's `{:?}` round-trips an `f64`).
fn scene(eye: DVec3, up: DVec3) -> String {
    format!(
        "(image: (width: 48, height: 36), \
         camera: Perspective(eye: ({:?}, {:?}, {:?}), target: ({:?}, {:?}, {:?}), up: ({:?}, {:?}, {:?}), fov: 40), \
         lights: [Point(position: (2, 3, 2))], \
         objects: [(mesh: Cube, material: (color: (0.9, 0.4, 0.1))), \
                   (mesh: Sphere(segments: 24), translate: (1.4, 0, 0.5), scale: 0.5, material: (color: (0.1, 0.5, 0.9)))])",
        eye.x, eye.y, eye.z, TARGET.x, TARGET.y, TARGET.z, up.x, up.y, up.z
    )
}

fn scene_camera() -> Camera {
    Camera {
        eye: EYE,
        target: TARGET,
        up: DVec3::Y,
        // Not used by the orbit, which keeps the projection as it is.
        projection: Projection::Perspective {
            fov_y_degrees: 40.0,
            near: 0.1,
            far: 100.0,
        },
    }
}

/// `lampshade render scene.ron --turntable FRAMES --axis y -o OUTPUT EXTRA…` in `folder`.
fn turntable(folder: &Path, frames: &str, output: &str, extra: &[&str]) -> Output {
    let mut args = vec![
        "render",
        "scene.ron",
        "--turntable",
        frames,
        "--axis",
        "y",
        "-o",
        output,
    ];
    args.extend_from_slice(extra);
    lampshade(&args, folder)
}

/// The names of the files in `folder`, sorted.
fn file_names(folder: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(folder)
        .unwrap()
        .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Every frame of an APNG, as RGB bytes.
fn apng_frames(bytes: &[u8]) -> (u32, Vec<Vec<u8>>) {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().expect("a PNG");
    let announced = reader
        .info()
        .animation_control
        .expect("an animated PNG")
        .num_frames;
    let mut frames = Vec::new();
    let mut buffer = vec![0; reader.output_buffer_size().expect("a frame size")];
    while let Ok(info) = reader.next_frame(&mut buffer) {
        frames.push(buffer[..info.buffer_size()].to_vec());
    }
    (announced, frames)
}

/// The image `render` writes for `scene_text`, as RGB bytes.
fn rendered(folder: &Path, scene_text: &str) -> Vec<u8> {
    std::fs::write(folder.join("single.ron"), scene_text).unwrap();
    let output = lampshade(&["render", "single.ron", "-o", "single.png"], folder);
    assert!(output.status.success(), "{}", everything(&output));
    image::open(folder.join("single.png"))
        .unwrap()
        .to_rgb8()
        .into_raw()
}

#[test]
fn an_apng_holds_every_frame_as_render_draws_its_camera() {
    let folder = tempfile::tempdir().unwrap();
    std::fs::write(folder.path().join("scene.ron"), scene(EYE, DVec3::Y)).unwrap();
    let output = turntable(folder.path(), "6", "spin.png", &[]);
    assert!(output.status.success(), "{}", everything(&output));
    assert!(
        String::from_utf8_lossy(&output.stdout).contains("6 frames"),
        "{}",
        everything(&output)
    );
    let (announced, frames) = apng_frames(&std::fs::read(folder.path().join("spin.png")).unwrap());
    assert_eq!(announced, 6);
    assert_eq!(frames.len(), 6);
    for (number, frame) in frames.iter().enumerate() {
        let camera = orbit_camera(&scene_camera(), DVec3::Y, number as u32, 6);
        let expected = rendered(folder.path(), &scene(camera.eye, camera.up));
        assert!(
            *frame == expected,
            "frame {number} differs from `render` of its camera"
        );
    }
    assert_ne!(frames[0], frames[3], "the camera moved");
    // Nothing but the outputs: no temporary file left behind.
    assert_eq!(
        file_names(folder.path()),
        ["scene.ron", "single.png", "single.ron", "spin.png"]
    );
}

#[test]
fn numbered_frames_and_shards_cover_every_frame_once() {
    let folder = tempfile::tempdir().unwrap();
    std::fs::write(folder.path().join("scene.ron"), scene(EYE, DVec3::Y)).unwrap();
    let output = turntable(folder.path(), "5", "all/f-%03d.png", &[]);
    // The folder must exist, as for any output.
    assert!(!output.status.success(), "{}", everything(&output));
    std::fs::create_dir(folder.path().join("all")).unwrap();
    std::fs::create_dir(folder.path().join("shards")).unwrap();
    let output = turntable(folder.path(), "5", "all/f-%03d.png", &[]);
    assert!(output.status.success(), "{}", everything(&output));
    let listing = |sub: &str| file_names(&folder.path().join(sub));
    let expected: Vec<String> = (0..5).map(|frame| format!("f-{frame:03}.png")).collect();
    assert_eq!(listing("all"), expected);
    let mut written_by_shards = Vec::new();
    for shard in ["1/2", "2/2"] {
        let before = listing("shards");
        let output = turntable(folder.path(), "5", "shards/f-%03d.png", &["--shard", shard]);
        assert!(output.status.success(), "{}", everything(&output));
        let new: Vec<String> = listing("shards")
            .into_iter()
            .filter(|name| !before.contains(name))
            .collect();
        assert!(!new.is_empty(), "shard {shard} wrote nothing");
        written_by_shards.extend(new);
    }
    written_by_shards.sort();
    assert_eq!(written_by_shards, expected, "each frame exactly once");
    for name in &expected {
        let whole = std::fs::read(folder.path().join("all").join(name)).unwrap();
        let sharded = std::fs::read(folder.path().join("shards").join(name)).unwrap();
        assert!(
            whole == sharded,
            "{name} differs between the whole run and its shard"
        );
    }
}

#[test]
fn bad_turntable_arguments_are_refused_before_rendering() {
    let folder = tempfile::tempdir().unwrap();
    std::fs::write(folder.path().join("scene.ron"), scene(EYE, DVec3::Y)).unwrap();
    let refused = |args: &[&str], says: &str| {
        let mut all = vec!["render", "scene.ron"];
        all.extend_from_slice(args);
        let output = lampshade(&all, folder.path());
        let text = everything(&output);
        assert_eq!(output.status.code(), Some(2), "{args:?}\n{text}");
        assert!(text.contains(says), "{args:?}: expected `{says}` in\n{text}");
    };
    refused(&["--turntable", "0"], "invalid value '0'");
    refused(&["--turntable", "many"], "invalid value 'many'");
    refused(&["--turntable", "4", "-o", "f-%s.png"], "is not a frame pattern");
    refused(
        &["--turntable", "4", "-o", "f-%03d-%d.png"],
        "is not a frame pattern",
    );
    refused(&["--turntable", "4", "-o", "spin.exr"], "give a pattern");
    refused(
        &["--turntable", "4", "-o", "spin.png", "--shard", "1/2"],
        "cannot be split",
    );
    refused(
        &["--turntable", "4", "-o", "f-%d.png", "--shard", "3/2"],
        "is not a shard",
    );
    refused(&["--turntable", "4", "-o", "-"], "not standard output");
    refused(&["--shard", "1/2"], "--turntable");
    // Looking straight down the axis, the eye cannot orbit.
    std::fs::write(
        folder.path().join("scene.ron"),
        scene(DVec3::new(0.2, 5.0, 0.0), DVec3::Z),
    )
    .unwrap();
    refused(
        &["--turntable", "4", "--axis", "y"],
        "looks along the turntable axis",
    );
    let names: Vec<_> = std::fs::read_dir(folder.path()).unwrap().collect();
    assert_eq!(names.len(), 1, "nothing written");
}
