//! What the commands write and where: an output never replaces an input, the format follows
//! the extension, `-o -` is standard output, a closed stdout or stderr never panics, Ctrl-C says
//! what was kept, and the command-line overrides reach the renderer.

use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::process::{lampshade, stderr};
use crate::repo;

/// Every file in `folder` (recursively) with its bytes, to show that nothing changed.
fn snapshot(folder: &Path) -> Vec<(std::path::PathBuf, Vec<u8>)> {
    let mut files = Vec::new();
    let mut pending = vec![folder.to_path_buf()];
    while let Some(dir) = pending.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let metadata = std::fs::symlink_metadata(&path).unwrap();
            if metadata.is_dir() {
                pending.push(path);
            } else if metadata.is_file() {
                files.push((path.clone(), std::fs::read(&path).unwrap()));
            } else {
                files.push((
                    path.clone(),
                    std::fs::read_link(&path)
                        .unwrap()
                        .into_os_string()
                        .into_encoded_bytes(),
                ));
            }
        }
    }
    files.sort();
    files
}

/// A folder with a scene that reads a texture, an OBJ mesh with its MTL, and an include.
fn scene_with_inputs() -> tempfile::TempDir {
    let folder = tempfile::tempdir().unwrap();
    let dir = folder.path();
    std::fs::create_dir(dir.join("textures")).unwrap();
    image::RgbImage::from_fn(8, 8, |x, y| image::Rgb([(x * 30) as u8, (y * 30) as u8, 90]))
        .save(dir.join("textures/checker.png"))
        .unwrap();
    std::fs::write(
        dir.join("tri.obj"),
        "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n",
    )
    .unwrap();
    std::fs::write(dir.join("tri.mtl"), "newmtl m\nKd 0.8 0.2 0.2\n").unwrap();
    std::fs::write(
        dir.join("materials.ron"),
        r#"(materials: { "shiny": (color: (0.2, 0.4, 0.9), ks: 0.9, shininess: 60) })"#,
    )
    .unwrap();
    std::fs::write(
        dir.join("scene.ron"),
        r#"(
    image: (width: 64, height: 48),
    include: ["materials.ron"],
    materials: { "checker": (texture: "textures/checker.png") },
    objects: [
        (mesh: Sphere(), material: "checker", translate: (-1.2, 0, 0)),
        (mesh: Obj("tri.obj"), translate: (0.5, 0, 0)),
        (mesh: Sphere(), material: "shiny", translate: (1.2, 0, 0), scale: 0.5),
    ],
)"#,
    )
    .unwrap();
    folder
}

#[test]
fn an_output_that_is_an_input_of_the_scene_is_refused_and_nothing_is_written() {
    let folder = scene_with_inputs();
    let dir = folder.path();
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("textures/checker.png", dir.join("link.png")).unwrap();
        std::fs::hard_link(dir.join("textures/checker.png"), dir.join("hard.png")).unwrap();
    }
    let before = snapshot(dir);
    // Every way of naming an input: plainly, through `..`, `./`, a symlink, a hard link, and
    // with a `--format` that agrees; and every kind of input an image name can take.
    let mut outputs = vec![
        "textures/checker.png",
        "./textures/../textures/checker.png",
        "textures/checker.png --format png",
    ];
    if cfg!(unix) {
        outputs.extend(["link.png", "hard.png"]);
    }
    for output in outputs {
        let mut args = vec!["render", "scene.ron", "-o"];
        args.extend(output.split(' '));
        let result = lampshade(&args, dir);
        let message = stderr(&result);
        assert_eq!(result.status.code(), Some(2), "-o {output}: {message}");
        assert!(
            message.contains("a file the scene") && message.contains("nothing was written"),
            "-o {output}: {message}"
        );
        assert!(message.contains("help: choose another output"), "{message}");
        assert_eq!(snapshot(dir), before, "-o {output} changed a file");
    }

    // A scene whose default output is itself (a scene file named like an image) or one of its
    // textures (`checker.ron` beside the `checker.png` it uses).
    std::fs::copy(dir.join("scene.ron"), dir.join("odd-name.png")).unwrap();
    std::fs::write(
        dir.join("textures/checker.ron"),
        r#"(image: (width: 32, height: 32), materials: { "t": (texture: "checker.png") }, objects: [(mesh: Sphere(), material: "t")])"#,
    )
    .unwrap();
    let before = snapshot(dir);
    for scene in ["odd-name.png", "textures/checker.ron"] {
        let result = lampshade(&["render", scene], dir);
        assert_eq!(result.status.code(), Some(2), "{scene}: {}", stderr(&result));
        assert_eq!(snapshot(dir), before, "rendering {scene} changed a file");
    }
    // Another output is fine.
    let result = lampshade(&["render", "scene.ron", "-o", "render.png"], dir);
    assert_eq!(result.status.code(), Some(0), "{}", stderr(&result));
}

#[test]
fn the_format_follows_the_extension_and_contradictions_are_errors() {
    let folder = scene_with_inputs();
    let dir = folder.path();
    // (arguments, exit code, the file written and its first bytes)
    type Case<'a> = (&'a str, i32, Option<(&'a str, &'a [u8])>);
    let png_magic: &[u8] = b"\x89PNG";
    let exr_magic: &[u8] = b"\x76\x2f\x31\x01";
    let hdr_magic: &[u8] = b"#?RADIANCE";
    let cases: &[Case] = &[
        ("-o a.png", 0, Some(("a.png", png_magic))),
        ("-o b.EXR", 0, Some(("b.EXR", exr_magic))),
        ("-o c.hdr", 0, Some(("c.hdr", hdr_magic))),
        ("-o d.exr --format exr", 0, Some(("d.exr", exr_magic))),
        ("--format hdr", 0, Some(("scene.hdr", hdr_magic))),
        ("-o noextension --format exr", 0, Some(("noextension", exr_magic))),
        ("-o e.png --format exr", 2, None),
        ("-o f.exr --format png", 2, None),
        ("-o g.jpg", 2, None),
        ("-o h.jpg --format png", 2, None),
        ("-o noextension2", 2, None),
        ("-o scene.ron --format png", 2, None),
    ];
    for &(args, code, written) in cases {
        let before = snapshot(dir);
        let mut full = vec!["render", "scene.ron"];
        full.extend(args.split(' '));
        let result = lampshade(&full, dir);
        assert_eq!(result.status.code(), Some(code), "{args}: {}", stderr(&result));
        match written {
            Some((name, magic)) => {
                let bytes = std::fs::read(dir.join(name)).unwrap();
                assert!(
                    bytes.starts_with(magic),
                    "{args}: {name} is not the format asked for"
                );
            }
            None => {
                assert!(
                    stderr(&result).starts_with("error: "),
                    "{args}: {}",
                    stderr(&result)
                );
                assert_eq!(snapshot(dir), before, "{args} wrote something");
            }
        }
    }
}

#[test]
fn dash_writes_the_image_to_standard_output() {
    let folder = scene_with_inputs();
    let dir = folder.path();
    let before = snapshot(dir);
    let result = lampshade(&["render", "scene.ron", "-o", "-"], dir);
    assert_eq!(result.status.code(), Some(0), "{}", stderr(&result));
    let image = image::load_from_memory(&result.stdout).expect("standard output holds a PNG");
    assert_eq!((image.width(), image.height()), (64, 48));
    // The summary line goes to stderr, so the image stays clean, and no file named `-` appears.
    assert!(
        stderr(&result).contains("→ standard output"),
        "{}",
        stderr(&result)
    );
    assert_eq!(snapshot(dir), before);
    // The same pixels as a file.
    lampshade(&["render", "scene.ron", "-o", "file.png"], dir);
    let file = image::open(dir.join("file.png")).unwrap();
    assert_eq!(file.to_rgb8().as_raw(), image.to_rgb8().as_raw());

    let result = lampshade(&["render", "scene.ron", "-o", "-", "--format", "exr"], dir);
    assert_eq!(result.status.code(), Some(0), "{}", stderr(&result));
    assert!(
        result.stdout.starts_with(b"\x76\x2f\x31\x01"),
        "OpenEXR on standard output"
    );
}

/// Runs `args` with stdout (or stderr) a pipe whose reader has gone away.
fn run_with_closed_stream(args: &[&str], dir: &Path, close_stderr: bool) -> (Option<i32>, String) {
    let mut command = Command::new(env!("CARGO_BIN_EXE_lampshade"));
    command
        .args(args)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .stdin(Stdio::null());
    if close_stderr {
        command.stdout(Stdio::null()).stderr(Stdio::piped());
    } else {
        command.stdout(Stdio::piped()).stderr(Stdio::piped());
    }
    let mut child = command.spawn().unwrap();
    let mut messages = String::new();
    if close_stderr {
        drop(child.stderr.take());
    } else {
        drop(child.stdout.take());
        child
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut messages)
            .unwrap();
    }
    let status = child.wait().unwrap();
    (status.code(), messages)
}

#[test]
fn a_closed_stdout_or_stderr_ends_quietly_with_the_usual_exit_code() {
    let folder = scene_with_inputs();
    let dir = folder.path();
    std::fs::write(
        dir.join("broken.ron"),
        "(objects: [(mesh: Sphere(segments: -1))])",
    )
    .unwrap();
    let scenes = repo().join("scenes");
    let scenes = scenes.to_str().unwrap();
    let cases: &[&[&str]] = &[
        &["render", "scene.ron", "-o", "out.png"],
        &["render", "scene.ron", "-o", "-"],
        &["render", "broken.ron"],
        &["render", "scene.ron", "broken.ron"],
        &["check", scenes],
        &["--help"],
        &["render", "--help"],
        &["render", "--no-such-flag"],
    ];
    for &args in cases {
        // The exit code the command has with both streams open.
        let code = lampshade(args, dir).status.code().unwrap();
        for close_stderr in [false, true] {
            let (status, messages) = run_with_closed_stream(args, dir, close_stderr);
            let which = if close_stderr { "stderr" } else { "stdout" };
            assert!(
                !messages.contains("panicked"),
                "{args:?} with {which} closed: {messages}"
            );
            assert_eq!(status, Some(code), "{args:?} with {which} closed: {messages}");
        }
    }
}

#[test]
fn bad_samples_are_blamed_on_the_argument_not_the_scene() {
    let folder = scene_with_inputs();
    let result = lampshade(&["render", "scene.ron", "--samples", "3"], folder.path());
    assert_eq!(result.status.code(), Some(2));
    let message = stderr(&result);
    assert!(
        message.contains("--samples") && message.contains("1, 2, 4, 8 or 16"),
        "{message}"
    );
    assert!(
        !message.contains("scene.ron"),
        "the scene is not at fault: {message}"
    );
}

#[test]
fn every_shading_mode_and_lighting_model_can_be_chosen_on_the_command_line() {
    let folder = tempfile::tempdir().unwrap();
    let dir = folder.path();
    std::fs::write(
        dir.join("scene.ron"),
        r#"(image: (width: 48, height: 48),
            camera: Perspective(eye: (0, 0, 4), target: (0, 0, 0), fov: 40),
            lights: [Directional(direction: (-0.3, -0.4, -1))],
            objects: [(mesh: Sphere(segments: 12), material: (color: (0.2, 0.5, 0.8), ks: 0.8, shininess: 20))])"#,
    )
    .unwrap();
    let render = |extra: &[&str]| -> Vec<u8> {
        let mut args = vec!["render", "scene.ron", "-o", "out.png"];
        args.extend(extra);
        let result = lampshade(&args, dir);
        assert_eq!(result.status.code(), Some(0), "{extra:?}: {}", stderr(&result));
        image::open(dir.join("out.png")).unwrap().to_rgb8().into_raw()
    };
    let mut images = Vec::new();
    for shading in ["constant", "flat", "gouraud", "phong"] {
        images.push((shading, render(&["--shading", shading])));
    }
    for model in ["phong", "blinn-phong", "lambert", "cook-torrance", "unlit"] {
        images.push((model, render(&["--model", model])));
    }
    for (i, (a, image_a)) in images.iter().enumerate() {
        for (b, image_b) in &images[i + 1..] {
            // `--shading phong` is the scene as written, so it equals `--model phong`.
            if (*a, *b) != ("phong", "phong") {
                assert_ne!(image_a, image_b, "--{a} and --{b} render the same image");
            }
        }
    }
    // Constant shading is one colour per object; unlit is the diffuse colour everywhere.
    let colours = |image: &[u8]| {
        let mut colours: Vec<&[u8]> = image.chunks(3).collect();
        colours.sort();
        colours.dedup();
        colours.len()
    };
    assert_eq!(
        colours(&images[0].1),
        2,
        "constant: the object's one colour and the background"
    );
    assert_eq!(
        colours(&images[8].1),
        2,
        "unlit: the diffuse colour and the background"
    );
}

#[test]
fn ctrl_c_during_a_render_says_what_was_kept() {
    let folder = scene_with_inputs();
    let dir = folder.path();
    std::fs::write(dir.join("big.png"), b"the previous image").unwrap();
    // A render long enough to be interrupted (seconds, even in an optimised build).
    let child = Command::new(env!("CARGO_BIN_EXE_lampshade"))
        .args([
            "render",
            "scene.ron",
            "-o",
            "big.png",
            "--width",
            "8000",
            "--height",
            "8000",
        ])
        .args(["--samples", "16", "--threads", "1"])
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(700));
    let started = Instant::now();
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let output = child.wait_with_output().unwrap();
    let message = stderr(&output);
    assert_eq!(output.status.code(), Some(130), "{message}");
    assert!(
        started.elapsed() < Duration::from_secs(20),
        "Ctrl-C must end the render promptly"
    );
    assert!(
        message.contains("interrupted: nothing was written; `big.png` was not written and is left as it was"),
        "{message}"
    );
    assert_eq!(std::fs::read(dir.join("big.png")).unwrap(), b"the previous image");
    let leftovers: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

#[test]
fn help_shows_examples_and_every_output_format() {
    for command in ["render", "check", "watch", "bench", "report"] {
        let result = lampshade(&[command, "--help"], repo());
        let help = String::from_utf8_lossy(&result.stdout);
        assert!(
            help.contains("Examples:\n  lampshade "),
            "{command} --help has no examples:\n{help}"
        );
    }
    let help = String::from_utf8_lossy(&lampshade(&["--help"], repo()).stdout).into_owned();
    assert!(help.contains("PNG, OpenEXR or Radiance HDR"), "{help}");
}

#[test]
fn check_never_writes_its_junit_report_or_references_over_an_input() {
    let folder = scene_with_inputs();
    let dir = folder.path();
    // A scene textured with its own reference image: `--bless` must not replace it.
    std::fs::create_dir(dir.join("refs")).unwrap();
    std::fs::copy(dir.join("textures/checker.png"), dir.join("refs/mirror.png")).unwrap();
    std::fs::write(
        dir.join("mirror.ron"),
        r#"(image: (width: 32, height: 32), materials: { "m": (texture: "refs/mirror.png") },
            objects: [(mesh: Sphere(), material: "m")])"#,
    )
    .unwrap();
    let before = snapshot(dir);
    let cases: &[&[&str]] = &[
        &["check", ".", "--junit", "scene.ron"],
        &["check", ".", "--junit", "textures/checker.png"],
        &["check", ".", "--filter", "mirror", "--bless"],
    ];
    for &args in cases {
        let result = lampshade(args, dir);
        // The summary lines (a scene's error among them) go to stdout, other errors to stderr.
        let message = stderr(&result) + &String::from_utf8_lossy(&result.stdout);
        assert_eq!(result.status.code(), Some(2), "{args:?}: {message}");
        assert!(
            message.contains("a file the") || message.contains("the scene reads it"),
            "{args:?}: {message}"
        );
        for (path, bytes) in &before {
            assert_eq!(
                &std::fs::read(path).unwrap(),
                bytes,
                "{args:?} changed {}",
                path.display()
            );
        }
    }
}
