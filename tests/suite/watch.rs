//! `lampshade watch`, run as a real process on a temporary folder: every way editors save, an
//! edited include and mesh, errors that keep the last good image, recovery, missing files that
//! appear later, Ctrl-C, and the preview server (without a browser; `watch_browser` has one).
//!
//! Each check waits for a condition with a deadline (the image on disk equal to a one-shot
//! `lampshade render` of the same files, a diagnostic on stderr, a numbered status line); no
//! test sleeps and then asserts. The watch process is killed when its guard is dropped, also
//! when an assertion fails.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Upper bound for anything to happen. Generous because the machine may be busy compiling;
/// a passing run waits for the event, never for the deadline.
pub const DEADLINE: Duration = Duration::from_secs(20);

/// Polls `condition` every few milliseconds until it gives a value or `DEADLINE` passes; then
/// panics with `what` and `context()` (the watcher's output, say).
pub fn wait_for<T>(what: &str, context: impl Fn() -> String, mut condition: impl FnMut() -> Option<T>) -> T {
    let started = Instant::now();
    loop {
        if let Some(value) = condition() {
            return value;
        }
        if started.elapsed() > DEADLINE {
            panic!("timed out after {DEADLINE:?} waiting for {what}\n{}", context());
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// A running `lampshade watch`; killed when dropped.
pub struct WatchProcess {
    child: Child,
    stdout: Arc<Mutex<String>>,
    stderr: Arc<Mutex<String>>,
}

impl WatchProcess {
    /// Starts `lampshade watch ARGS` in `folder` and waits for its first status line.
    pub fn start(folder: &Path, args: &[&str]) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_lampshade"))
            .arg("watch")
            .args(args)
            .current_dir(folder)
            .env("NO_COLOR", "1")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("the lampshade binary starts");
        let stdout = collect(child.stdout.take().expect("piped stdout"));
        let stderr = collect(child.stderr.take().expect("piped stderr"));
        let process = WatchProcess {
            child,
            stdout,
            stderr,
        };
        process.wait_for_status_line(1);
        process
    }

    pub fn stdout(&self) -> String {
        self.stdout.lock().unwrap().clone()
    }

    pub fn stderr(&self) -> String {
        self.stderr.lock().unwrap().clone()
    }

    /// Both outputs, for failure messages.
    pub fn output(&self) -> String {
        format!("--- stdout\n{}--- stderr\n{}", self.stdout(), self.stderr())
    }

    /// The numbered status lines printed so far, one per build.
    pub fn status_lines(&self) -> Vec<String> {
        self.stdout()
            .lines()
            .filter(|line| line.starts_with('#'))
            .map(str::to_owned)
            .collect()
    }

    /// Waits for build `number`'s status line and returns it.
    pub fn wait_for_status_line(&self, number: usize) -> String {
        let prefix = format!("#{number} ");
        wait_for(
            &format!("status line {prefix}"),
            || self.output(),
            || {
                self.status_lines()
                    .into_iter()
                    .find(|line| line.starts_with(&prefix))
            },
        )
    }

    /// Waits until stdout contains `text` and returns the line holding it.
    pub fn wait_for_stdout(&self, text: &str) -> String {
        wait_for(
            &format!("`{text}` on stdout"),
            || self.output(),
            || {
                self.stdout()
                    .lines()
                    .find(|line| line.contains(text))
                    .map(str::to_owned)
            },
        )
    }

    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Waits for the process to exit by itself and returns its exit code.
    pub fn wait_for_exit(&mut self) -> Option<i32> {
        let child = &mut self.child;
        let status = wait_for("the watcher to exit", String::new, || {
            child.try_wait().expect("the watcher can be waited for")
        });
        status.code()
    }
}

impl Drop for WatchProcess {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Collects everything `stream` says, on a thread of its own.
fn collect(stream: impl Read + Send + 'static) -> Arc<Mutex<String>> {
    let text = Arc::new(Mutex::new(String::new()));
    let sink = text.clone();
    std::thread::spawn(move || {
        for line in BufReader::new(stream).lines() {
            let Ok(line) = line else { break };
            let mut text = sink.lock().unwrap();
            text.push_str(&line);
            text.push('\n');
        }
    });
    text
}

/// What `lampshade render SCENE` writes for the files as they are now (byte for byte what a
/// watch build of the same files writes: same encoder, same settings).
pub fn render_once(scene: &Path) -> Vec<u8> {
    let scratch = tempfile::tempdir().unwrap();
    let image = scratch.path().join("expected.png");
    let output = Command::new(env!("CARGO_BIN_EXE_lampshade"))
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(&image)
        .env("NO_COLOR", "1")
        .output()
        .expect("the lampshade binary runs");
    assert!(
        output.status.success(),
        "one-shot render of {} failed:\n{}",
        scene.display(),
        String::from_utf8_lossy(&output.stderr)
    );
    std::fs::read(&image).unwrap()
}

/// A scene folder: `scene.ron` including `mats.ron`, a sphere and an OBJ triangle, 32×24 px.
pub struct SceneFolder {
    _temporary: tempfile::TempDir,
    pub path: PathBuf,
}

pub const TRIANGLE_OBJ: &str = "v -0.6 -0.6 0\nv 0.6 -0.6 0\nv 0 0.6 0\nf 1 2 3\n";

impl SceneFolder {
    pub fn new() -> Self {
        let temporary = tempfile::tempdir().unwrap();
        let path = temporary.path().to_path_buf();
        let folder = SceneFolder {
            _temporary: temporary,
            path,
        };
        folder.write("scene.ron", &scene_text((1.0, 1.0, 1.0)));
        folder.write("mats.ron", &materials_text((0.9, 0.2, 0.1)));
        folder.write("tri.obj", TRIANGLE_OBJ);
        folder
    }

    pub fn file(&self, name: &str) -> PathBuf {
        self.path.join(name)
    }

    pub fn write(&self, name: &str, text: &str) {
        std::fs::write(self.file(name), text).unwrap();
    }

    pub fn image(&self) -> Option<Vec<u8>> {
        std::fs::read(self.file("out.png")).ok()
    }
}

/// The scene with its light's colour; everything else fixed.
pub fn scene_text(light: (f32, f32, f32)) -> String {
    let (r, g, b) = light;
    format!(
        r#"Scene(
    image: (width: 32, height: 24),
    camera: Perspective(eye: (0, 0, 4), target: (0, 0, 0), fov: 40),
    include: ["mats.ron"],
    lights: [Directional(direction: (0.3, -0.2, -1), color: ({r}, {g}, {b}))],
    objects: [
        (mesh: Sphere(segments: 8), translate: (-0.8, 0, 0), material: "paint"),
        (mesh: Obj("tri.obj"), translate: (0.8, 0, 0), material: "paint"),
    ],
)
"#
    )
}

pub fn materials_text(color: (f32, f32, f32)) -> String {
    let (r, g, b) = color;
    format!("Materials(materials: {{ \"paint\": (color: ({r}, {g}, {b})) }})\n")
}

/// Waits until the watcher's image is exactly what `lampshade render` gives for the files now,
/// after checking that this differs from `previous` (so the test really asks for a new image).
fn expect_new_image(watch: &WatchProcess, folder: &SceneFolder, previous: &[u8]) -> Vec<u8> {
    let expected = render_once(&folder.file("scene.ron"));
    assert_ne!(expected, previous, "the edit must change the image");
    wait_for(
        "the watcher's image to match the edited files",
        || watch.output(),
        || (folder.image().as_deref() == Some(expected.as_slice())).then_some(()),
    );
    assert_no_build_caused_by_our_output(watch);
    expected
}

/// Writing the image (and its temporary file) must never count as a change.
fn assert_no_build_caused_by_our_output(watch: &WatchProcess) {
    for line in watch.status_lines() {
        // "#3 scene.ron, mats.ron changed → ..." or "#3 scene.ron changed: 1 error ..."
        let Some((cause, _)) = line.split_once(" changed") else {
            continue;
        };
        assert!(
            !cause.contains("out.png") && !cause.contains(".lampshade-"),
            "a build was triggered by our own output: {line}"
        );
    }
}

/// Starts a watch of `folder` writing `out.png` and returns it with its first image.
fn start_watch(folder: &SceneFolder) -> (WatchProcess, Vec<u8>) {
    let watch = WatchProcess::start(&folder.path, &["scene.ron", "-o", "out.png"]);
    let first = expect_new_image(&watch, folder, &[]);
    (watch, first)
}

#[test]
fn an_in_place_write_gives_a_new_image() {
    let folder = SceneFolder::new();
    let (watch, first) = start_watch(&folder);
    folder.write("scene.ron", &scene_text((1.0, 0.4, 0.4)));
    let second = expect_new_image(&watch, &folder, &first);
    // And again: the watch goes on after a change.
    folder.write("scene.ron", &scene_text((0.4, 1.0, 0.4)));
    expect_new_image(&watch, &folder, &second);
    // The status line follows the image by a moment: wait for it too.
    let line = watch.wait_for_stdout("scene.ron changed → out.png");
    assert!(line.contains("change to image"), "{line}");
}

#[test]
fn a_write_to_a_temporary_file_renamed_over_the_scene_gives_a_new_image() {
    // vim (`backupcopy=no`), JetBrains "safe write", Sublime: the scene's inode is replaced.
    let folder = SceneFolder::new();
    let (watch, first) = start_watch(&folder);
    let mut previous = first;
    for (step, light) in [(0.3, 0.6, 1.0), (1.0, 1.0, 0.2)].into_iter().enumerate() {
        let temporary = folder.file(&format!(".scene.ron.{step}.swp"));
        std::fs::write(&temporary, scene_text(light)).unwrap();
        std::fs::rename(&temporary, folder.file("scene.ron")).unwrap();
        previous = expect_new_image(&watch, &folder, &previous);
    }
}

#[test]
fn deleting_and_recreating_the_scene_gives_a_new_image() {
    let folder = SceneFolder::new();
    let (watch, first) = start_watch(&folder);
    std::fs::remove_file(folder.file("scene.ron")).unwrap();
    folder.write("scene.ron", &scene_text((0.2, 0.9, 0.9)));
    expect_new_image(&watch, &folder, &first);
}

#[test]
fn a_burst_of_writes_ends_in_the_image_of_the_last_one() {
    let folder = SceneFolder::new();
    let (watch, first) = start_watch(&folder);
    let builds_before = watch.status_lines().len();
    // An editor that truncates, then writes in pieces, then touches up: five writes in a row.
    let final_text = scene_text((0.5, 0.5, 1.0));
    let (head, tail) = final_text.split_at(final_text.len() / 2);
    let scene = folder.file("scene.ron");
    std::fs::write(&scene, "").unwrap();
    std::fs::write(&scene, head).unwrap();
    let mut file = std::fs::OpenOptions::new().append(true).open(&scene).unwrap();
    file.write_all(tail.as_bytes()).unwrap();
    drop(file);
    std::fs::write(&scene, &final_text).unwrap();
    std::fs::write(&scene, &final_text).unwrap();
    expect_new_image(&watch, &folder, &first);
    // The image is renamed into place just before its status line is printed: wait for the line.
    watch.wait_for_stdout(&format!("#{} ", builds_before + 1));
    let builds = watch.status_lines().len() - builds_before;
    assert!(
        (1..=5).contains(&builds),
        "{builds} builds for 5 writes\n{}",
        watch.output()
    );
}

#[test]
fn saves_made_during_a_long_render_are_rendered_together() {
    // A render far longer than the debounce's maximum delay (0.5 s): 2 million triangles,
    // 8 samples, one thread. Four saves made while it runs must give one more render, not one per
    // file-system event they queued.
    let folder = SceneFolder::new();
    let watch = WatchProcess::start(&folder.path, &["scene.ron", "-o", "out.png", "--threads", "1"]);
    let slow = |light: f32| {
        scene_text((light, 1.0, 1.0))
            .replace("width: 32, height: 24", "width: 1600, height: 1200, samples: 8")
            .replace("Sphere(segments: 8)", "Sphere(segments: 1000)")
    };
    let before = watch.status_lines().len();
    folder.write("scene.ron", &slow(1.0));
    // The slow build starts 15–50 ms after that save; give it time to be under way (if it is
    // not, the saves below only join it, and the count below still holds).
    std::thread::sleep(Duration::from_millis(300));
    for light in [0.9, 0.8, 0.7, 0.6] {
        folder.write("scene.ron", &slow(light));
        std::thread::sleep(Duration::from_millis(20));
    }
    // A save of another file after them: its event is queued behind theirs, so once its build
    // is reported, every build their events caused has been reported before it.
    folder.write("mats.ron", &materials_text((0.2, 0.8, 0.2)));
    let caused_by = |line: &String, name: &str| {
        line.split_once(" changed")
            .is_some_and(|(cause, _)| cause.contains(name))
    };
    let lines = wait_for(
        "the build of mats.ron",
        || watch.output(),
        || {
            let lines = watch.status_lines();
            lines
                .iter()
                .any(|line| caused_by(line, "mats.ron"))
                .then_some(lines)
        },
    );
    let scene_builds = lines[before..]
        .iter()
        .filter(|line| caused_by(line, "scene.ron"))
        .count();
    assert!(
        (1..=2).contains(&scene_builds),
        "{scene_builds} builds for the slow save and the four made during its render\n{}",
        watch.output()
    );
}

#[test]
fn editing_an_included_material_file_gives_a_new_image() {
    let folder = SceneFolder::new();
    let (watch, first) = start_watch(&folder);
    folder.write("mats.ron", &materials_text((0.1, 0.3, 0.9)));
    expect_new_image(&watch, &folder, &first);
    watch.wait_for_stdout("mats.ron changed → out.png");
}

#[test]
fn editing_an_obj_mesh_gives_a_new_image() {
    let folder = SceneFolder::new();
    let (watch, first) = start_watch(&folder);
    folder.write("tri.obj", "v -0.6 0.6 0\nv 0 -0.6 0\nv 0.6 0.6 0\nf 1 2 3\n");
    expect_new_image(&watch, &folder, &first);
    watch.wait_for_stdout("tri.obj changed → out.png");
}

#[test]
fn an_unchanged_mesh_is_not_read_again() {
    // The mesh cache trusts a file whose modification time and size have not changed. Replace
    // the OBJ by garbage of the same size with its old time: if the next build read it again,
    // it would fail.
    let folder = SceneFolder::new();
    let (watch, first) = start_watch(&folder);
    let mesh = folder.file("tri.obj");
    let metadata = std::fs::metadata(&mesh).unwrap();
    let modified = metadata.modified().unwrap();
    // Written aside with the old time, then renamed into place: one step, so no build can see
    // the garbage with a new time in between.
    let garbage = folder.file("garbage.tmp");
    let mut junk = b"f 1 2 99\nthis is not an OBJ file\n".to_vec();
    junk.resize(metadata.len() as usize, b'#');
    std::fs::write(&garbage, &junk).unwrap();
    std::fs::File::options()
        .write(true)
        .open(&garbage)
        .unwrap()
        .set_modified(modified)
        .unwrap();
    std::fs::rename(&garbage, &mesh).unwrap();
    let builds = watch.status_lines().len();
    folder.write("scene.ron", &scene_text((1.0, 0.7, 0.2)));
    let expected_scene = scene_text((1.0, 0.7, 0.2));
    // The expected image is the new scene with the *old* mesh.
    let reference = SceneFolder::new();
    reference.write("scene.ron", &expected_scene);
    let expected = render_once(&reference.file("scene.ron"));
    assert_ne!(expected, first);
    wait_for(
        "the new scene rendered with the cached mesh",
        || watch.output(),
        || (folder.image().as_deref() == Some(expected.as_slice())).then_some(()),
    );
    // Wait for the successful build's line: any failed build's line comes before it.
    let lines = wait_for(
        "the successful build's status line",
        || watch.output(),
        || {
            let lines = watch.status_lines();
            lines[builds..].iter().any(|l| l.contains(" → ")).then_some(lines)
        },
    );
    assert!(
        lines[builds..].iter().all(|l| l.contains(" → ")),
        "a build read the garbage mesh\n{}",
        watch.output()
    );
}

#[test]
fn an_error_keeps_the_last_good_image_and_the_next_good_save_recovers() {
    let folder = SceneFolder::new();
    let (watch, first) = start_watch(&folder);
    let builds = watch.status_lines().len();

    // An unknown material on line 7 (the sphere's): the diagnostic names file, line and column.
    let broken = scene_text((1.0, 1.0, 1.0)).replacen("\"paint\"", "\"pant\"", 1);
    folder.write("scene.ron", &broken);
    wait_for(
        "the diagnostic",
        || watch.output(),
        || watch.stderr().contains("scene.ron:7:").then_some(()),
    );
    let line = watch.wait_for_status_line(builds + 1);
    assert!(line.contains("1 error"), "{line}");
    assert!(line.contains("out.png left as it was"), "{line}");
    assert_eq!(
        folder.image().unwrap(),
        first,
        "the last good image must stay, byte for byte"
    );

    // A syntax error next: still the same image, and still watching.
    folder.write("scene.ron", "Scene(objects: [(mesh: Sphere(]");
    watch.wait_for_status_line(builds + 2);
    assert_eq!(folder.image().unwrap(), first);

    folder.write("scene.ron", &scene_text((0.9, 0.9, 0.3)));
    expect_new_image(&watch, &folder, &first);
}

#[test]
fn an_error_in_an_include_is_fixed_by_editing_the_include() {
    let folder = SceneFolder::new();
    let (watch, first) = start_watch(&folder);
    folder.write(
        "mats.ron",
        "Materials(materials: { \"paint\": (color: (1, 0, ) })",
    );
    wait_for(
        "the diagnostic in mats.ron",
        || watch.output(),
        || watch.stderr().contains("mats.ron:1:").then_some(()),
    );
    assert_eq!(folder.image().unwrap(), first);
    folder.write("mats.ron", &materials_text((0.2, 0.8, 0.2)));
    expect_new_image(&watch, &folder, &first);
}

#[test]
fn a_missing_include_is_reported_then_picked_up_when_created() {
    let folder = SceneFolder::new();
    std::fs::remove_file(folder.file("mats.ron")).unwrap();
    let watch = WatchProcess::start(&folder.path, &["scene.ron", "-o", "out.png"]);
    watch.wait_for_stdout("waiting for mats.ron to be created");
    wait_for(
        "the diagnostic about mats.ron",
        || watch.output(),
        || watch.stderr().contains("mats.ron").then_some(()),
    );
    assert!(
        folder.image().is_none(),
        "no image from a scene that does not load"
    );

    folder.write("mats.ron", &materials_text((0.9, 0.5, 0.1)));
    expect_new_image(&watch, &folder, &[]);
}

#[test]
fn a_mesh_in_a_folder_that_does_not_exist_yet_is_picked_up() {
    let folder = SceneFolder::new();
    folder.write(
        "scene.ron",
        &scene_text((1.0, 1.0, 1.0)).replace("tri.obj", "meshes/tri.obj"),
    );
    let watch = WatchProcess::start(&folder.path, &["scene.ron", "-o", "out.png"]);
    watch.wait_for_stdout("waiting for meshes/tri.obj to be created");
    // The folder alone: a build, labelled with what changed (the folder), not with the file,
    // which still does not exist.
    std::fs::create_dir(folder.file("meshes")).unwrap();
    let line = watch.wait_for_status_line(2);
    assert!(line.starts_with("#2 meshes/ changed: 1 error"), "{line}");
    folder.write("meshes/tri.obj", TRIANGLE_OBJ);
    expect_new_image(&watch, &folder, &[]);
    let line = watch.wait_for_status_line(3);
    assert!(line.starts_with("#3 meshes/tri.obj changed → out.png"), "{line}");
}

/// Lines of stdout from line `from` on, once one satisfies `condition`; returns its index.
fn wait_for_line_from(
    watch: &WatchProcess,
    from: usize,
    what: &str,
    condition: impl Fn(&str) -> bool,
) -> usize {
    wait_for(
        what,
        || watch.output(),
        || {
            let stdout = watch.stdout();
            let found = stdout
                .lines()
                .enumerate()
                .skip(from)
                .find(|(_, line)| condition(line));
            found.map(|(index, _)| index)
        },
    )
}

#[test]
fn every_kind_of_file_a_build_reads_stays_followed_while_it_is_missing() {
    // One scene using every kind of dependency: an include, an OBJ mesh with its MTL library and
    // the library's texture, a texture of the scene's own, and a glTF with an external buffer
    // and image. Each is deleted in turn: the build fails (or warns), the watch says it waits
    // for the file, and restoring that file alone must bring the image back.
    let folder = SceneFolder::new();
    let gltf = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/gltf/BoxTextured/glTF");
    for name in ["BoxTextured.gltf", "BoxTextured0.bin", "CesiumLogoFlat.png"] {
        std::fs::copy(gltf.join(name), folder.file(name)).unwrap();
    }
    std::fs::copy(gltf.join("CesiumLogoFlat.png"), folder.file("logo.png")).unwrap();
    std::fs::copy(gltf.join("CesiumLogoFlat.png"), folder.file("wood.png")).unwrap();
    folder.write(
        "quad.obj",
        "mtllib quad.mtl\nv -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0.5 0.5 0\nv -0.5 0.5 0\n\
         vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl logo\nf 1/1 2/2 3/3 4/4\n",
    );
    folder.write("quad.mtl", "newmtl logo\nKd 1 0.8 0.6\nmap_Kd logo.png\n");
    folder.write(
        "mats.ron",
        "Materials(materials: { \"wood\": (color: (1, 1, 1), texture: \"wood.png\") })\n",
    );
    folder.write(
        "scene.ron",
        r#"Scene(
    image: (width: 48, height: 32),
    camera: Perspective(eye: (0, 0, 4), target: (0, 0, 0), fov: 45),
    include: ["mats.ron"],
    objects: [
        (mesh: Obj("quad.obj"), translate: (-1.1, 0, 0)),
        (mesh: Obj("quad.obj"), translate: (0, 0, 0), material: "wood"),
        (mesh: Gltf("BoxTextured.gltf"), translate: (1.1, 0, 0), rotate: (30, 30, 0), scale: 0.6),
    ],
)
"#,
    );
    let (watch, first) = start_watch(&folder);
    for name in [
        "mats.ron",
        "quad.obj",
        "quad.mtl",
        "logo.png",
        "wood.png",
        "BoxTextured.gltf",
        "BoxTextured0.bin",
        "CesiumLogoFlat.png",
        "scene.ron",
    ] {
        let bytes = std::fs::read(folder.file(name)).unwrap();
        let from = watch.stdout().lines().count();
        std::fs::remove_file(folder.file(name)).unwrap();
        let waiting = wait_for_line_from(&watch, from, &format!("waiting for {name}"), |line| {
            line.starts_with("waiting for ") && line.contains(name)
        });
        std::fs::write(folder.file(name), &bytes).unwrap();
        let rebuilt = format!("{name} changed → out.png");
        wait_for_line_from(&watch, waiting, &format!("`{rebuilt}`"), |line| {
            line.starts_with('#') && line.contains(&rebuilt)
        });
        assert_eq!(folder.image().unwrap(), first, "after restoring {name}");
    }
}

#[cfg(unix)]
#[test]
fn ctrl_c_stops_the_watch_cleanly() {
    let folder = SceneFolder::new();
    let (mut watch, _) = start_watch(&folder);
    let interrupted = Command::new("kill")
        .args(["-INT", &watch.pid().to_string()])
        .status()
        .expect("kill runs");
    assert!(interrupted.success());
    assert_eq!(watch.wait_for_exit(), Some(0), "{}", watch.output());
    // The output pipe may still be being read after the exit.
    watch.wait_for_stdout("stopped");
}

#[test]
fn a_closed_standard_output_ends_the_watch_quietly_at_the_next_build() {
    // `lampshade watch scene.ron | head -1`: the reader leaves after the first line.
    let folder = SceneFolder::new();
    struct KillOnDrop(Child);
    impl Drop for KillOnDrop {
        fn drop(&mut self) {
            let _ = self.0.kill();
            let _ = self.0.wait();
        }
    }
    let mut guard = KillOnDrop(
        Command::new(env!("CARGO_BIN_EXE_lampshade"))
            .args(["watch", "scene.ron", "-o", "out.png"])
            .current_dir(&folder.path)
            .env("NO_COLOR", "1")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("the lampshade binary starts"),
    );
    let child = &mut guard.0;
    let stderr = collect(child.stderr.take().expect("piped stderr"));
    let mut stdout = BufReader::new(child.stdout.take().expect("piped stdout"));
    let mut first_line = String::new();
    stdout.read_line(&mut first_line).unwrap();
    assert!(first_line.starts_with("#1 "), "{first_line}");
    drop(stdout);

    folder.write("scene.ron", &scene_text((0.6, 0.6, 1.0)));
    let status = wait_for(
        "the watch to end after its output was closed",
        || stderr.lock().unwrap().clone(),
        || child.try_wait().expect("the watcher can be waited for"),
    );
    let stderr = stderr.lock().unwrap().clone();
    assert_eq!(status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn an_image_that_cannot_be_written_is_reported_by_its_own_name() {
    let folder = SceneFolder::new();
    let watch = WatchProcess::start(&folder.path, &["scene.ron", "-o", "no-such-folder/out.png"]);
    let line = watch.wait_for_status_line(1);
    assert!(line.contains("the image could not be written"), "{line}");
    let stderr = wait_for(
        "the error",
        || watch.output(),
        || Some(watch.stderr()).filter(|e| e.contains("cannot write")),
    );
    assert!(
        stderr.contains("cannot write `no-such-folder/out.png`"),
        "{stderr}"
    );
    // The temporary file it is written through is ours, not a name the user knows.
    assert!(!stderr.contains(".lampshade-"), "{stderr}");
}

#[test]
fn an_output_that_would_replace_an_input_or_is_not_a_png_is_refused() {
    let folder = SceneFolder::new();
    std::fs::copy(folder.file("scene.ron"), folder.file("odd-name.png")).unwrap();
    // (arguments, what stderr must say): refused before anything is watched or written.
    let cases: &[(&[&str], &str)] = &[
        (&["scene.ron", "-o", "./scene.ron"], "not .ron"),
        (&["odd-name.png"], "would replace the scene"),
        (&["scene.ron", "-o", "out.exr"], "watch writes PNG images"),
        (&["scene.ron", "-o", "out.hdr"], "watch writes PNG images"),
        (&["scene.ron", "-o", "out.jpg"], "not .jpg"),
        (&["scene.ron", "-o", "-"], "needs a file"),
    ];
    for &(args, expected) in cases {
        let before = std::fs::read(folder.file("odd-name.png")).unwrap();
        let output = Command::new(env!("CARGO_BIN_EXE_lampshade"))
            .arg("watch")
            .args(args)
            .current_dir(&folder.path)
            .stdin(Stdio::null())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        assert_eq!(std::fs::read(folder.file("odd-name.png")).unwrap(), before);
    }

    // An input that only the build knows (a texture): reported each build, never written over.
    image::RgbImage::from_pixel(4, 4, image::Rgb([200, 30, 30]))
        .save(folder.file("red.png"))
        .unwrap();
    let texture = std::fs::read(folder.file("red.png")).unwrap();
    folder.write(
        "textured.ron",
        r#"(image: (width: 32, height: 32), materials: { "red": (texture: "red.png") },
            objects: [(mesh: Sphere(), material: "red")])"#,
    );
    let watch = WatchProcess::start(&folder.path, &["textured.ron", "-o", "red.png"]);
    wait_for(
        "the refusal",
        || watch.output(),
        || {
            watch
                .stderr()
                .contains("not writing `red.png`: the scene reads it")
                .then_some(())
        },
    );
    assert_eq!(
        std::fs::read(folder.file("red.png")).unwrap(),
        texture,
        "the texture was overwritten"
    );
}

// ----- the preview server, without a browser -----

/// The port in the watcher's "preview at http://127.0.0.1:PORT/" line.
pub fn preview_port(watch: &WatchProcess) -> u16 {
    let line = watch.wait_for_stdout("preview at http://127.0.0.1:");
    let after = line.split("http://127.0.0.1:").nth(1).unwrap();
    after.trim_end_matches('/').parse().unwrap()
}

/// A GET request to `127.0.0.1:port`, with `host` as the Host header; returns status and body.
/// The body is read up to its `Content-Length` (not to the end of the connection: some servers,
/// Chromium's DevTools among them, keep it open whatever the request says).
pub fn http_get(port: u16, path: &str, host: &str) -> (u16, Vec<u8>) {
    let mut stream = TcpStream::connect(("127.0.0.1", port)).unwrap();
    stream.set_read_timeout(Some(DEADLINE)).unwrap();
    write!(
        stream,
        "GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut response = Vec::new();
    let mut chunk = [0; 8192];
    let head_end = loop {
        if let Some(end) = response.windows(4).position(|w| w == b"\r\n\r\n") {
            break end;
        }
        let read = stream.read(&mut chunk).expect("an HTTP response head");
        assert!(read > 0, "the connection closed before the response head ended");
        response.extend_from_slice(&chunk[..read]);
    };
    let head = String::from_utf8_lossy(&response[..head_end]).into_owned();
    let status = head.split(' ').nth(1).unwrap().parse().unwrap();
    let content_length = head.lines().find_map(|line| {
        let (name, value) = line.split_once(':')?;
        name.eq_ignore_ascii_case("content-length")
            .then(|| value.trim().parse::<usize>().ok())?
    });
    let mut body = response.split_off(head_end + 4);
    match content_length {
        Some(length) => {
            while body.len() < length {
                let read = stream.read(&mut chunk).expect("the rest of the body");
                assert!(read > 0, "the connection closed before the body ended");
                body.extend_from_slice(&chunk[..read]);
            }
            body.truncate(length);
        }
        None => {
            stream.read_to_end(&mut body).unwrap();
        }
    }
    (status, body)
}

/// An open `/events` stream, read one message at a time.
struct EventStream {
    stream: TcpStream,
    buffer: Vec<u8>,
}

impl EventStream {
    fn open(port: u16) -> Self {
        let mut stream = TcpStream::connect(("127.0.0.1", port)).unwrap();
        stream.set_read_timeout(Some(DEADLINE)).unwrap();
        write!(stream, "GET /events HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n").unwrap();
        EventStream {
            stream,
            buffer: Vec::new(),
        }
    }

    /// The next `data:` message, parsed as JSON.
    fn next(&mut self) -> serde_json::Value {
        loop {
            let text = String::from_utf8_lossy(&self.buffer).into_owned();
            if let Some(end) = text.find("\n\n") {
                self.buffer.drain(..end + 2);
                if let Some(data) = text[..end].lines().find_map(|l| l.strip_prefix("data: ")) {
                    return serde_json::from_str(data).unwrap();
                }
                continue; // the response head, `retry:`, or a keep-alive comment
            }
            let mut chunk = [0; 4096];
            let read = self.stream.read(&mut chunk).expect("the event stream stays open");
            assert!(read > 0, "the event stream closed");
            self.buffer.extend_from_slice(&chunk[..read]);
        }
    }

    /// Skips messages until one satisfies `condition`.
    fn next_where(&mut self, condition: impl Fn(&serde_json::Value) -> bool) -> serde_json::Value {
        loop {
            let message = self.next();
            if condition(&message) {
                return message;
            }
        }
    }
}

#[test]
fn the_preview_serves_the_page_the_image_and_live_state_on_localhost_only() {
    let folder = SceneFolder::new();
    let watch = WatchProcess::start(
        &folder.path,
        &["scene.ron", "-o", "out.png", "--serve", "--port", "0"],
    );
    let port = preview_port(&watch);
    let host = format!("127.0.0.1:{port}");
    let first = expect_new_image(&watch, &folder, &[]);

    let (status, page) = http_get(port, "/", &host);
    assert_eq!(status, 200);
    assert!(String::from_utf8_lossy(&page).contains("new EventSource(\"/events\")"));
    let (status, image) = http_get(port, "/image.png?v=anything", &format!("localhost:{port}"));
    assert_eq!((status, image), (200, first.clone()));
    // DNS rebinding: a page elsewhere reaching us under its own name is refused.
    assert_eq!(http_get(port, "/", &format!("attacker.example:{port}")).0, 403);
    assert_eq!(http_get(port, "/nothing", &host).0, 404);

    let mut events = EventStream::open(port);
    let current = events.next();
    assert_eq!(current["scene"], "scene.ron");
    assert!(current["error"].is_null());
    let first_version = current["image"].as_str().unwrap().to_owned();

    folder.write("scene.ron", &scene_text((0.3, 0.3, 1.0)));
    let rendered = events.next_where(|m| m["image"].as_str() != Some(first_version.as_str()));
    assert!(rendered["error"].is_null());
    assert!(rendered["summary"].as_str().unwrap().contains("rendered in"));
    let second = expect_new_image(&watch, &folder, &first);
    assert_eq!(http_get(port, "/image.png", &host).1, second);

    folder.write("scene.ron", "Scene(objects: [(mesh: Sphere(]");
    let failed = events.next_where(|m| !m["error"].is_null());
    let report = failed["error"].as_str().unwrap();
    assert!(report.contains("scene.ron:1:"), "{report}");
    assert!(
        !report.contains('\u{1b}'),
        "no terminal colours in the page: {report:?}"
    );
    assert_eq!(failed["image"], rendered["image"], "the last good image stays");
    assert_eq!(http_get(port, "/image.png", &host).1, second);
}

#[test]
fn the_preview_status_says_which_image_is_under_the_errors() {
    let folder = SceneFolder::new();
    let broken = "Scene(objects: [(mesh: Sphere(]";
    let good = scene_text((1.0, 1.0, 1.0));
    folder.write("scene.ron", broken);
    let args = ["scene.ron", "-o", "out.png", "--serve", "--port", "0"];
    let summary = |watch: &WatchProcess, build: u64| -> String {
        let mut events = EventStream::open(preview_port(watch));
        let state = events.next_where(|m| m["build"] == build);
        assert!(!state["error"].is_null(), "{state}");
        state["summary"].as_str().unwrap().to_owned()
    };

    // Started on a broken scene with no image on disk: there is nothing under the errors.
    let mut watch = WatchProcess::start(&folder.path, &args);
    let status = summary(&watch, 1);
    assert!(status.ends_with("; no image yet"), "{status}");

    // A good save, then a broken one: the last good image is under the errors.
    folder.write("scene.ron", &good);
    let image = expect_new_image(&watch, &folder, &[]);
    folder.write("scene.ron", broken);
    watch.wait_for_status_line(3);
    let status = summary(&watch, 3);
    assert!(status.ends_with("; showing the last good image"), "{status}");
    drop(watch);

    // Restarted on the broken scene: the image on disk is from before this watch.
    watch = WatchProcess::start(&folder.path, &args);
    let status = summary(&watch, 1);
    assert!(
        status.ends_with("; showing the image from before this watch started"),
        "{status}"
    );
    assert_eq!(folder.image().unwrap(), image);
}

#[test]
fn a_busy_port_is_replaced_by_a_free_one_and_reported() {
    let taken = std::net::TcpListener::bind(("127.0.0.1", 0)).unwrap();
    let busy = taken.local_addr().unwrap().port();
    let folder = SceneFolder::new();
    let watch = WatchProcess::start(
        &folder.path,
        &[
            "scene.ron",
            "-o",
            "out.png",
            "--serve",
            "--port",
            &busy.to_string(),
        ],
    );
    let port = preview_port(&watch);
    assert_ne!(port, busy);
    let note = format!("port {busy} is not available");
    wait_for(
        "the note about the busy port",
        || watch.output(),
        || watch.stderr().contains(&note).then_some(()),
    );
    assert_eq!(http_get(port, "/", &format!("127.0.0.1:{port}")).0, 200);
}
