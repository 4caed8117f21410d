//! Edit-to-image latency of `lampshade watch`: the time from writing the scene file to the new
//! PNG being in place on disk, as a user waiting for the picture would measure it.
//!
//! The bundled two-sphere scene (`scenes/matlab-shiny.ron`, 129,600 triangles) is copied to a
//! temporary folder and watched at 800×600; the benchmark then changes a light's colour, one
//! edit at a time, and times each edit from just before the write until the output file has been
//! replaced (the watcher renames a complete new file over it, so a new inode means a new image).
//! The goal (issue 4) is a median under 100 ms on a 2-core machine. The debounce (50 ms of quiet
//! after the last event) is part of what is measured: it is part of what the user waits for.
//!
//! Run with `cargo bench --bench watch_latency` (optimised build), optionally followed by
//! `-- --edits N` (default 25).

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

const DEFAULT_EDITS: usize = 25;
/// Longest any single step may take before the benchmark gives up.
const TIMEOUT: Duration = Duration::from_secs(30);
/// Time left between edits, so that each is a separate save (not part of the measurement).
const PAUSE_BETWEEN_EDITS: Duration = Duration::from_millis(150);

/// The watcher, killed when the benchmark ends (or fails).
struct Watcher(Child);

impl Drop for Watcher {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Which file is at `path`: a rename over it changes the inode even within one mtime tick.
fn identity(path: &Path) -> Option<(u64, std::time::SystemTime)> {
    let metadata = std::fs::metadata(path).ok()?;
    #[cfg(unix)]
    let inode = std::os::unix::fs::MetadataExt::ino(&metadata);
    #[cfg(not(unix))]
    let inode = metadata.len();
    Some((inode, metadata.modified().ok()?))
}

fn wait_until(what: &str, mut condition: impl FnMut() -> bool) {
    let started = Instant::now();
    while !condition() {
        if started.elapsed() > TIMEOUT {
            eprintln!("watch_latency: timed out waiting for {what}");
            std::process::exit(1);
        }
        std::thread::sleep(Duration::from_micros(500));
    }
}

fn milliseconds(duration: Duration) -> String {
    format!("{:.1} ms", duration.as_secs_f64() * 1000.0)
}

fn main() {
    let arguments: Vec<String> = std::env::args().collect();
    let edits = arguments
        .windows(2)
        .find(|pair| pair[0] == "--edits")
        .and_then(|pair| pair[1].parse().ok())
        .unwrap_or(DEFAULT_EDITS)
        .max(1);

    let original_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/matlab-shiny.ron");
    let original = std::fs::read_to_string(&original_path).expect("the bundled scene is readable");
    const LIGHT: &str = "Directional(direction: (-1, 1, -1))";
    assert!(
        original.contains(LIGHT),
        "the scene's first light has changed; update the benchmark"
    );

    let folder = tempfile::tempdir().expect("a temporary folder");
    let scene = folder.path().join("scene.ron");
    let output = folder.path().join("out.png");
    std::fs::write(&scene, &original).expect("the scene copy is writable");

    let mut child = Command::new(env!("CARGO_BIN_EXE_lampshade"))
        .args([
            "watch",
            "scene.ron",
            "-o",
            "out.png",
            "--width",
            "800",
            "--height",
            "600",
        ])
        .current_dir(folder.path())
        .env("NO_COLOR", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("the lampshade binary starts");
    let status_lines = Arc::new(Mutex::new(Vec::<String>::new()));
    if let Some(stdout) = child.stdout.take() {
        let lines = status_lines.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if let Ok(mut lines) = lines.lock() {
                    lines.push(line);
                }
            }
        });
    }
    let _watcher = Watcher(child);
    wait_until("the first image", || output.exists());

    let mut latencies = Vec::with_capacity(edits);
    for edit in 0..edits {
        std::thread::sleep(PAUSE_BETWEEN_EDITS);
        let level = 0.5 + 0.5 * (edit as f32 + 1.0) / edits as f32;
        let edited = original.replace(
            LIGHT,
            &format!("Directional(direction: (-1, 1, -1), color: ({level}, {level}, 1))"),
        );
        let before = identity(&output);
        let written = Instant::now();
        std::fs::write(&scene, edited).expect("the scene copy is writable");
        wait_until("the new image", || identity(&output) != before);
        latencies.push(written.elapsed());
    }

    latencies.sort();
    let median = latencies[latencies.len() / 2];
    let worst = latencies[latencies.len() - 1];
    let best = latencies[0];
    println!(
        "watch latency, matlab-shiny at 800×600 (129,600 triangles), {edits} edits, scene written → new PNG on disk:"
    );
    println!(
        "  median {}, worst {}, best {}",
        milliseconds(median),
        milliseconds(worst),
        milliseconds(best)
    );
    // Where the time goes, from the watcher's own status lines (the edits' builds, not the first).
    let lines = status_lines.lock().map(|lines| lines.clone()).unwrap_or_default();
    let mut work: Vec<Duration> = lines
        .iter()
        .skip_while(|l| !l.starts_with("#2 "))
        .filter_map(|l| stage_total(l))
        .collect();
    if !work.is_empty() {
        work.sort();
        let median_work = work[work.len() / 2];
        println!(
            "  of which load + render + encode (median of the watcher's status lines): {}; \
             the rest is the debounce, event delivery and scheduling",
            milliseconds(median_work)
        );
    }
    if let Some(last) = lines.last() {
        println!("  the watcher's last status line: {last}");
    }
}

/// The sum of the stage times in a status line (`load 2.0 ms, geometry 23.4 ms, ...`).
fn stage_total(line: &str) -> Option<Duration> {
    let stages = line.split(" | ").nth(1)?;
    let mut total = 0.0;
    for stage in stages.split(", ") {
        let milliseconds: f64 = stage.rsplit(' ').nth(1)?.parse().ok()?;
        total += milliseconds;
    }
    Some(Duration::from_secs_f64(total / 1000.0))
}
