//! The memory estimate (`scene::limits`) against the real peak: for each kind of scene that
//! needs much memory, a fresh process renders it as `lampshade render` does (load, render,
//! quantise, encode and write the PNG) and reports its peak resident memory (`VmHWM`), which
//! must stay at or below the estimate the loader makes (docs/limits.md: it errs on the high
//! side).
//!
//! Its own test binary, and one process per scene: the peak of a process is only meaningful
//! when nothing else runs in it, and a process's peak cannot be lowered again (the allocator
//! keeps freed memory), so scenes cannot share one. The probe is this binary itself, run again
//! with [`PROBE`] naming the scene; it uses mimalloc like `lampshade`, so the peak includes the
//! same allocator's overhead. Linux only (`/proc/self/status`); elsewhere the test says so and
//! passes.

use std::path::Path;
use std::process::Command;

use lampshade::output::{PngCompression, to_rgb8, write_png};
use lampshade::render::{RenderOptions, render};
use lampshade::scene::limits::{human_bytes, scene_memory};
use lampshade::scene::{LoadOptions, load_scene};

#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Set in a probe process: the scene to render, then print `estimate PEAK` and exit.
const PROBE: &str = "LAMPSHADE_MEMORY_PROBE";

/// The process's peak resident memory in bytes (`VmHWM`), on Linux.
fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|line| line.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The probe: what `lampshade render SCENE -o OUT.png` does, then the two numbers.
fn probe(scene: &Path) {
    let loaded = load_scene(scene, &LoadOptions::default())
        .unwrap_or_else(|error| panic!("{}: {:?}", scene.display(), error.diagnostics));
    let estimate = scene_memory(&loaded.scene.image, &loaded.scene.lights, &loaded.scene.objects).total();
    let (framebuffer, _) = render(&loaded.scene, &RenderOptions::default());
    let image = to_rgb8(&framebuffer);
    drop(framebuffer);
    write_png(&scene.with_extension("png"), &image, PngCompression::Fast).expect("the PNG is written");
    let peak = peak_resident_bytes().expect("VmHWM in /proc/self/status");
    // One line the parent looks for among the test harness's own.
    lampshade::outln!("memory-probe {estimate} {peak}");
}

/// An OBJ grid of `n`×`n` quads (split into triangles by the loader), without normals.
fn obj_grid(n: usize) -> String {
    let mut text = String::new();
    for y in 0..=n {
        for x in 0..=n {
            let height = ((x * 7 + y * 13) % 17) as f32 / 170.0;
            text.push_str(&format!(
                "v {} {} {height}\n",
                x as f32 / n as f32,
                y as f32 / n as f32
            ));
        }
    }
    for y in 0..n {
        for x in 0..n {
            let corner = y * (n + 1) + x + 1;
            text.push_str(&format!(
                "f {} {} {} {}\n",
                corner,
                corner + 1,
                corner + n + 2,
                corner + n + 1
            ));
        }
    }
    text
}

#[test]
fn the_memory_estimate_is_at_least_the_peak_resident_memory() {
    if let Some(scene) = std::env::var_os(PROBE) {
        probe(Path::new(&scene));
        return;
    }
    if peak_resident_bytes().is_none() {
        lampshade::outln!("skipped: no /proc/self/status VmHWM on this system");
        return;
    }
    let work = tempfile::tempdir().expect("a temporary folder");
    std::fs::write(work.path().join("grid.obj"), obj_grid(700)).expect("the mesh file");
    let scenes = [
        // The case the estimate once fell short on: 4.5 million triangles.
        ("dense-sphere", "(objects: [(mesh: Sphere(segments: 1500))])"),
        (
            "large-image",
            "(image: (width: 6000, height: 4000), objects: [(mesh: Sphere(segments: 200))])",
        ),
        (
            "msaa",
            "(image: (width: 1600, height: 1200, samples: 16), objects: [(mesh: Sphere(segments: 600))])",
        ),
        (
            "shadows",
            "(lights: [
                Point(position: (2, 3, 2), shadows: true, shadow_map: (resolution: 4096)),
                Spot(position: (-2, 3, 2), direction: (1, -1.5, -1), cutoff: 40, shadows: true,
                     shadow_map: (resolution: 8192)),
                Directional(direction: (0, 1, 0.5), shadows: true, shadow_map: (resolution: 4096)),
             ],
             objects: [
                (mesh: Sphere(segments: 700)),
                (mesh: Plane, translate: (0, -1, 0), scale: 6),
             ])",
        ),
        (
            "mesh-file",
            "(image: (width: 1024, height: 768), objects: [(mesh: Obj(\"grid.obj\"))])",
        ),
    ];
    let mut failures = Vec::new();
    for (name, text) in scenes {
        let scene = work.path().join(format!("{name}.ron"));
        std::fs::write(&scene, text).expect("the scene file");
        let output = Command::new(std::env::current_exe().expect("this test binary"))
            .args([
                "the_memory_estimate_is_at_least_the_peak_resident_memory",
                "--exact",
                "--nocapture",
            ])
            .env(PROBE, &scene)
            .output()
            .expect("the probe runs");
        let stdout = String::from_utf8_lossy(&output.stdout);
        let numbers: Option<Vec<u64>> = stdout
            .lines()
            .find_map(|line| line.strip_prefix("memory-probe "))
            .map(|rest| rest.split(' ').filter_map(|n| n.parse().ok()).collect());
        let Some([estimate, peak]) = numbers.as_deref() else {
            panic!(
                "{name}: the probe failed\n{stdout}\n{}",
                String::from_utf8_lossy(&output.stderr)
            );
        };
        let line = format!(
            "{name}: estimate {}, peak {} ({:+.1}%)",
            human_bytes(*estimate),
            human_bytes(*peak),
            (*estimate as f64 / *peak as f64 - 1.0) * 100.0
        );
        lampshade::outln!("{line}");
        if estimate < peak {
            failures.push(line);
        }
    }
    assert!(
        failures.is_empty(),
        "the estimate is below the peak:\n{}",
        failures.join("\n")
    );
}
