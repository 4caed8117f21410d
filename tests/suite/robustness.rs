//! Nothing lost and nothing read that should not be: Ctrl-C during `render`, `--sandbox` on
//! `check` and `watch` (the `render` side is in the `tests/bad-scenes/sandbox` corpus), and the
//! replay of the inputs the fuzzers found bugs with.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use crate::repo;

fn lampshade(dir: &Path) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_lampshade"));
    command.current_dir(dir).env("NO_COLOR", "1");
    command
}

/// Files in `dir` that `output::write_atomically` would have left behind.
fn temporary_files(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.starts_with(".lampshade-"))
        .collect()
}

#[cfg(unix)]
#[test]
fn ctrl_c_during_a_render_keeps_the_previous_image_and_leaves_no_temporary_file() {
    let work = tempfile::tempdir().unwrap();
    // Large enough to take well over the moment the signal arrives, even in release builds.
    std::fs::write(
        work.path().join("slow.ron"),
        "(image: (width: 4000, height: 3000, samples: 16),
          lights: [Point(position: (2, 3, 4), shadows: true, shadow_map: (resolution: 8192))],
          objects: [(mesh: Sphere(segments: 1500), shading: Phong)])",
    )
    .unwrap();
    std::fs::write(work.path().join("slow.png"), b"previous good image").unwrap();
    let mut child = lampshade(work.path())
        .args(["render", "slow.ron"])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(700));
    let interrupted = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(interrupted.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "interrupted: 128 + SIGINT");
    assert_eq!(
        std::fs::read(work.path().join("slow.png")).unwrap(),
        b"previous good image"
    );
    assert_eq!(temporary_files(work.path()), Vec::<String>::new());
}

#[cfg(unix)]
#[test]
fn an_unreadable_include_is_a_located_error() {
    use std::os::unix::fs::PermissionsExt;
    let work = tempfile::tempdir().unwrap();
    let locked = work.path().join("locked.ron");
    std::fs::write(&locked, "Materials(materials: {})").unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o000)).unwrap();
    // Root (CI containers) reads a file of mode 000; Linux's `/proc/self/mem` is a regular file
    // that nobody can read from its start (EIO), so it stands in.
    let (include, reason) = if std::fs::read(&locked).is_err() {
        ("locked.ron", "permission denied")
    } else if cfg!(target_os = "linux") {
        ("/proc/self/mem", "Input/output error")
    } else {
        eprintln!("skipped: this user reads a file of mode 000 and there is no /proc/self/mem");
        return;
    };
    std::fs::write(
        work.path().join("s.ron"),
        format!("(include: [\"{include}\"], objects: [(mesh: Cube)])"),
    )
    .unwrap();
    let output = lampshade(work.path()).args(["render", "s.ron"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("s.ron:1:12"), "{stderr}");
    assert!(
        stderr.contains(&format!("cannot read the file: {reason}")),
        "{stderr}"
    );
    assert!(!work.path().join("s.png").exists());
}

/// A bug's panic, here on the renderer's worker threads, is an internal error: exit code 101,
/// a request to report it, and the previous image untouched. The panic comes from the
/// debug-only seam `LAMPSHADE_SIMULATE_PANIC` (`render::render`); release builds have none,
/// so the test runs only where the binary was built with debug assertions, as `cargo test` does.
#[cfg(debug_assertions)]
#[test]
fn a_panic_is_an_internal_error_with_exit_code_101_and_nothing_written() {
    let work = tempfile::tempdir().unwrap();
    std::fs::write(work.path().join("a.ron"), "(objects: [(mesh: Cube)])").unwrap();
    std::fs::write(work.path().join("a.png"), b"previous good image").unwrap();
    let output = lampshade(work.path())
        .args(["render", "a.ron"])
        .env("LAMPSHADE_SIMULATE_PANIC", "1")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(101), "{stderr}");
    assert!(
        stderr.contains("simulated bug"),
        "the panic message comes first: {stderr}"
    );
    assert!(stderr.contains("internal error in lampshade"), "{stderr}");
    assert!(stderr.contains("Please report it"), "{stderr}");
    assert_eq!(
        std::fs::read(work.path().join("a.png")).unwrap(),
        b"previous good image"
    );
    assert_eq!(temporary_files(work.path()), Vec::<String>::new());
    // Without the seam the same command renders: the panic came from the seam alone.
    let output = lampshade(work.path()).args(["render", "a.ron"]).output().unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

/// A suite folder with a good scene and one that reads a mesh outside the sandbox.
fn escaping_suite() -> tempfile::TempDir {
    let work = tempfile::tempdir().unwrap();
    let suite = work.path().join("suite");
    std::fs::create_dir_all(suite.join("refs")).unwrap();
    std::fs::write(
        work.path().join("secret.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(
        suite.join("escape.ron"),
        "(image: (width: 8, height: 8),\n objects: [(mesh: Obj(\"../secret.obj\"))])",
    )
    .unwrap();
    work
}

#[test]
fn check_with_a_sandbox_refuses_a_scene_that_reads_outside_it() {
    let work = escaping_suite();
    let output = lampshade(work.path())
        .args(["check", "suite", "--sandbox", "suite"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("escape.ron:2:23"), "{stderr}");
    assert!(stderr.contains("outside the sandbox"), "{stderr}");
    // Without the sandbox the same suite reads the mesh (and fails only for lack of a reference).
    let output = lampshade(work.path()).args(["check", "suite"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(!stderr.contains("sandbox"), "{stderr}");
}

#[test]
fn watch_with_a_sandbox_refuses_a_scene_that_reads_outside_it_and_keeps_watching() {
    let work = escaping_suite();
    let mut child = lampshade(work.path())
        .args(["watch", "suite/escape.ron", "--sandbox", "suite"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let (lines, received) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines() {
            if lines.send(line.unwrap_or_default()).is_err() {
                break;
            }
        }
    });
    let deadline = Instant::now() + Duration::from_secs(10);
    let mut seen = String::new();
    while Instant::now() < deadline && !seen.contains("outside the sandbox") {
        if let Ok(line) = received.recv_timeout(Duration::from_millis(100)) {
            seen.push_str(&line);
            seen.push('\n');
        }
    }
    let still_running = child.try_wait().unwrap().is_none();
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(seen.contains("outside the sandbox"), "{seen}");
    assert!(
        still_running,
        "a refused read is a scene error: the watch goes on"
    );
    assert!(!work.path().join("suite/escape.png").exists());
}

#[test]
fn a_sandbox_that_is_not_a_folder_is_a_usage_error() {
    let work = escaping_suite();
    for command in ["render", "check"] {
        let output = lampshade(work.path())
            .args([command, "suite/escape.ron", "--sandbox", "no-such-folder"])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{command}: {stderr}");
        assert!(stderr.contains("--sandbox no-such-folder"), "{command}: {stderr}");
    }
}

#[test]
fn max_memory_takes_sizes_and_refuses_nonsense() {
    let work = escaping_suite();
    std::fs::write(
        work.path().join("big.ron"),
        "(image: (width: 2000, height: 2000), objects: [(mesh: Cube)])",
    )
    .unwrap();
    let run = |budget: &str| {
        lampshade(work.path())
            .args(["render", "big.ron", "-o", "big.png", "--max-memory", budget])
            .output()
            .unwrap()
    };
    // 2000 × 2000 pixels need about 130 MiB.
    let refused = run("100M");
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("more than the memory budget of 100.0 MiB"));
    assert!(!work.path().join("big.png").exists());
    assert_eq!(run("lots").status.code(), Some(2));
    let accepted = run("1G");
    assert!(
        accepted.status.success(),
        "{}",
        String::from_utf8_lossy(&accepted.stderr)
    );
    assert!(work.path().join("big.png").exists());
}

#[test]
fn fuzz_regressions_replay_through_the_fuzz_harness() {
    let folder = repo().join("tests/fuzz-regressions");
    let mut replayed = 0;
    for (target, run) in [
        ("scene", harness::scene as fn(&[u8])),
        ("obj", harness::obj),
        ("gltf", harness::gltf),
        ("render", harness::render_scene),
    ] {
        let Ok(entries) = std::fs::read_dir(folder.join(target)) else {
            continue;
        };
        for entry in entries {
            let path = entry.unwrap().path();
            let input = std::fs::read(&path).unwrap();
            let outcome = std::panic::catch_unwind(|| run(&input));
            assert!(outcome.is_ok(), "{target}: {} fails again", path.display());
            replayed += 1;
        }
    }
    // The seeds run too: they are the fuzzers' starting points and must pass as well.
    for target in ["scene", "obj", "gltf", "render"] {
        for entry in std::fs::read_dir(repo().join("fuzz/seeds").join(target)).unwrap() {
            let input = std::fs::read(entry.unwrap().path()).unwrap();
            match target {
                "scene" => harness::scene(&input),
                "obj" => harness::obj(&input),
                "gltf" => harness::gltf(&input),
                _ => harness::render_scene(&input),
            }
            replayed += 1;
        }
    }
    assert!(replayed >= 10, "only {replayed} inputs replayed");
}

#[path = "../../fuzz/harness.rs"]
mod harness;
