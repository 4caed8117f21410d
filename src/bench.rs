//! `lampshade bench`: frame times of scenes per shading mode, for comparing with llvmpipe.
//!
//! Each scene is loaded once; then for every mode and thread count it is rendered `warmup`
//! times untimed and `frames` times timed, in one process, as a GL benchmark times frames in a
//! warm context. A frame is `render::render`: shadow maps, geometry, binning, rasterizing,
//! shading and the resolve into a linear-light frame buffer; loading and encoding are not part of it (the
//! one-shot `render` command reports those). Binning is part of the geometry stage (each chunk
//! of triangles bins its own). Times are medians and minimums over the frames;
//! the stage times are medians too, with rasterizing and shading given as thread time summed
//! over tiles (they run interleaved on every core, so they have no wall time of their own).
//!
//! The modes are the anchor harness's (`shared/anchors/llvmpipe`): `flat` and `gouraud` light
//! per vertex with the half vector as fixed-function OpenGL does, `phong` lights per pixel with
//! `R·V`, `blinn` per pixel with `N·H`. `scene` leaves the file's own modes alone.
//!
//! `cores` is the process's CPU time over the wall time of the same timed frames: how many cores
//! the frames kept busy on average (at most the thread count, give or take the clocks' grain).
//! Over the median frame instead, one slow frame among short ones read above the core count.
//!
//! Before the frames, each scene is also loaded `loads` times per thread count, from scratch
//! (no mesh cache: what a one-shot `render` does), and the `load` row gives the median time and
//! the rate over the bytes of every file the scene read (scene, includes, meshes, materials,
//! textures), in MB/s of 10⁶ bytes.
//!
//! This is a benchmark, not a test: it asserts nothing about time.

use std::path::{Path, PathBuf};
use std::time::Duration;

use image::RgbImage;
use serde_json::json;

use crate::check::compare::{Tolerance, compare_pixels};
use crate::cli::{EXIT_BAD_INPUT, EXIT_OK, EXIT_OUTPUT_FAILED, print_load_error, thousands};
use crate::output::{self, PngCompression};
use crate::render::{RenderOptions, RenderStats, Renderer};
use crate::scene::load::{LoadOptions, load_scene};
use crate::scene::{LightingModel, Scene, Shading};

#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Scene files (.ron).
    #[arg(required = true, value_name = "SCENE")]
    pub scenes: Vec<PathBuf>,
    /// Timed frames per scene, mode and thread count.
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: u32,
    /// Untimed frames before the timed ones (caches, page faults, thread pool start-up).
    #[arg(long, default_value_t = 3)]
    pub warmup: u32,
    /// Shading modes to measure, comma-separated.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "flat,gouraud,phong,blinn"
    )]
    pub modes: Vec<BenchMode>,
    /// Worker thread counts to measure, comma-separated (default: one per core).
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u16).range(1..))]
    pub threads: Vec<u16>,
    /// Image width, overriding the scene's.
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height, overriding the scene's.
    #[arg(long)]
    pub height: Option<u32>,
    /// A folder of llvmpipe frames named `sN_SCENE__MODE.png` (as in `shared/anchors/llvmpipe/out`):
    /// each of our frames is compared with the one of the same scene (the file name with `-` as
    /// `_`) and mode.
    #[arg(long, value_name = "DIR")]
    pub anchors: Option<PathBuf>,
    /// Write the last frame of each scene and mode to DIR/SCENE__MODE.png.
    #[arg(long, value_name = "DIR")]
    pub save: Option<PathBuf>,
    /// Timed loads of each scene per thread count (reading, parsing and checking the scene and
    /// every file it names, from scratch); 0 skips them.
    #[arg(long, default_value_t = 3)]
    pub loads: u32,
    /// One JSON object per line and per scene × mode × thread count, instead of the table (then
    /// one per scene × thread count for the loads, with `"stage": "load"`).
    #[arg(long)]
    pub json: bool,
}

/// A shading mode of the anchor harness.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum BenchMode {
    /// Per-vertex Blinn-Phong, one colour per triangle.
    Flat,
    /// Per-vertex Blinn-Phong, colours interpolated.
    Gouraud,
    /// Per-pixel Phong (`R·V`), normals interpolated.
    Phong,
    /// Per-pixel Blinn-Phong (`N·H`), normals interpolated.
    Blinn,
    /// The scene's own shading modes and lighting models.
    Scene,
}

impl BenchMode {
    fn name(self) -> &'static str {
        match self {
            BenchMode::Flat => "flat",
            BenchMode::Gouraud => "gouraud",
            BenchMode::Phong => "phong",
            BenchMode::Blinn => "blinn",
            BenchMode::Scene => "scene",
        }
    }

    /// The scene as this mode renders it.
    fn apply(self, scene: &Scene) -> Scene {
        let mut scene = scene.clone();
        let (shading, model) = match self {
            BenchMode::Flat => (Shading::Flat, LightingModel::BlinnPhong),
            BenchMode::Gouraud => (Shading::Gouraud, LightingModel::BlinnPhong),
            BenchMode::Phong => (Shading::Phong, LightingModel::Phong),
            BenchMode::Blinn => (Shading::Phong, LightingModel::BlinnPhong),
            BenchMode::Scene => return scene,
        };
        scene.override_shading(shading);
        scene.override_lighting_model(model);
        scene
    }
}

/// What the timed frames of one scene, mode and thread count measured.
struct Measurement {
    frames: Vec<Duration>,
    stats: Vec<RenderStats>,
    peak_memory: Option<u64>,
    /// Process CPU time (all threads) over the timed frames.
    cpu_time: Option<Duration>,
}

impl Measurement {
    fn median(&self) -> Duration {
        median(self.frames.iter().copied())
    }

    /// How many cores the timed frames kept busy on average: their CPU time over their wall
    /// time.
    fn cores(&self) -> Option<f64> {
        let wall: Duration = self.frames.iter().sum();
        Some(self.cpu_time?.as_secs_f64() / wall.as_secs_f64().max(1e-9))
    }

    /// The timed frames' CPU time, per frame.
    fn cpu_per_frame(&self) -> Option<Duration> {
        Some(self.cpu_time? / (self.frames.len() as u32).max(1))
    }

    fn min(&self) -> Duration {
        self.frames.iter().copied().min().unwrap_or_default()
    }

    fn stage(&self, stage: impl Fn(&RenderStats) -> Duration) -> Duration {
        median(self.stats.iter().map(stage))
    }
}

fn median(values: impl Iterator<Item = Duration>) -> Duration {
    let mut values: Vec<Duration> = values.collect();
    values.sort();
    match values.len() {
        0 => Duration::ZERO,
        n if n % 2 == 1 => values[n / 2],
        n => (values[n / 2 - 1] + values[n / 2]) / 2,
    }
}

/// Our frame against llvmpipe's, on the 0..255 scale.
struct AnchorDifference {
    mean: f64,
    max: u8,
    /// Share of pixels with a channel more than 2 levels off.
    share_over_2: f64,
}

pub fn run(args: &BenchArgs) -> i32 {
    let load_options = LoadOptions {
        width: args.width,
        height: args.height,
        ..LoadOptions::default()
    };
    let thread_counts: Vec<Option<usize>> = if args.threads.is_empty() {
        vec![None]
    } else {
        args.threads.iter().map(|&n| Some(usize::from(n))).collect()
    };
    if let Some(folder) = &args.save
        && let Err(error) = std::fs::create_dir_all(folder)
    {
        errln!("error: cannot create {}: {error}", folder.display());
        return EXIT_OUTPUT_FAILED;
    }
    let mut exit = EXIT_OK;
    for path in &args.scenes {
        let loaded = match load_scene(path, &load_options) {
            Ok(loaded) => loaded,
            Err(error) => {
                print_load_error(&error);
                exit = EXIT_BAD_INPUT;
                continue;
            }
        };
        let scene_name = path
            .file_stem()
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
        let base = &loaded.scene;
        if !args.json {
            outln!(
                "{} ({}×{} px, {} triangles), median of {} frames after {} warm-up",
                path.display(),
                base.image.width,
                base.image.height,
                thousands(base.triangle_count()),
                args.frames,
                args.warmup,
            );
            outln!(
                "  {:<8} {:>3} {:>9} {:>9} | {:>7} {:>8} {:>8} {:>8} {:>8} | {:>7} {:>8} {:>8} {:>5}{}",
                "mode",
                "thr",
                "median",
                "min",
                "shadows",
                "geometry",
                "raster*",
                "shade*",
                "resolve",
                "Mtri/s",
                "Mpix/s",
                "peak MiB",
                "cores",
                if args.anchors.is_some() {
                    "  | vs llvmpipe: mean   max  >2/255"
                } else {
                    ""
                },
            );
        }
        let bytes_read = bytes_of_files(&loaded.files_read);
        if args.loads > 0 {
            for &threads in &thread_counts {
                let times = measure_loads(path, &load_options, threads, args.loads);
                report_loads(args.json, &scene_name, threads, &times, bytes_read);
            }
        }
        for &mode in &args.modes {
            let scene = mode.apply(base);
            for &threads in &thread_counts {
                let options = RenderOptions {
                    threads,
                    debug_view: None,
                };
                let (measurement, last_frame) = measure(&scene, &options, args.warmup, args.frames);
                let image = output::to_rgb8(&last_frame);
                let anchor = args
                    .anchors
                    .as_deref()
                    .and_then(|folder| anchor_difference(folder, &scene_name, mode, &image));
                report(
                    args.json,
                    &scene_name,
                    &scene,
                    mode,
                    &measurement,
                    anchor.as_ref(),
                );
                if let Some(folder) = &args.save {
                    let file = folder.join(format!("{scene_name}__{}.png", mode.name()));
                    if let Some(input) =
                        output::overwritten_input(&file, args.scenes.iter().map(PathBuf::as_path))
                    {
                        errln!(
                            "error: `{}` would replace the scene `{}`; not saved\n  = help: choose another --save folder",
                            file.display(),
                            input.display()
                        );
                        exit = exit.max(crate::cli::EXIT_BAD_INPUT);
                    } else if let Err(error) = output::write_png(&file, &image, PngCompression::Fast) {
                        errln!("error: {error}");
                        exit = exit.max(EXIT_OUTPUT_FAILED);
                    }
                }
            }
        }
    }
    exit
}

/// The total size of `files` (each counted once).
fn bytes_of_files(files: &[PathBuf]) -> u64 {
    let mut unique: Vec<&PathBuf> = files.iter().collect();
    unique.sort();
    unique.dedup();
    unique
        .iter()
        .filter_map(|file| std::fs::metadata(file).ok())
        .map(|metadata| metadata.len())
        .sum()
}

/// Times `count` loads of the scene at `path` from scratch, on a pool of `threads` (the
/// global pool when `None`).
fn measure_loads(path: &Path, options: &LoadOptions, threads: Option<usize>, count: u32) -> Vec<Duration> {
    let run = || {
        (0..count)
            .map(|_| {
                let started = std::time::Instant::now();
                let loaded = load_scene(path, options);
                let elapsed = started.elapsed();
                drop(loaded);
                elapsed
            })
            .collect()
    };
    match threads.and_then(|threads| rayon::ThreadPoolBuilder::new().num_threads(threads).build().ok()) {
        Some(pool) => pool.install(run),
        None => run(),
    }
}

fn report_loads(json: bool, scene_name: &str, threads: Option<usize>, times: &[Duration], bytes: u64) {
    let ms = |d: Duration| d.as_secs_f64() * 1000.0;
    let median = median(times.iter().copied());
    let min = times.iter().copied().min().unwrap_or_default();
    let threads = threads.unwrap_or_else(rayon::current_num_threads);
    let megabytes_per_second = bytes as f64 / 1e6 / median.as_secs_f64().max(1e-9);
    if json {
        let line = json!({
            "scene": scene_name,
            "stage": "load",
            "threads": threads,
            "loads": times.len(),
            "median_ms": ms(median),
            "min_ms": ms(min),
            "bytes_read": bytes,
            "mb_per_s": megabytes_per_second,
        });
        outln!("{line}");
    } else {
        outln!(
            "  {:<8} {:>3} {:>6.2} ms {:>6.2} ms | {:.2} MB read, {:.0} MB/s",
            "load",
            threads,
            ms(median),
            ms(min),
            bytes as f64 / 1e6,
            megabytes_per_second,
        );
    }
}

/// Renders `warmup` frames, then times `frames` more.
fn measure(
    scene: &Scene,
    options: &RenderOptions,
    warmup: u32,
    frames: u32,
) -> (Measurement, crate::render::FrameBuffer) {
    // One pool for every frame, as a GL context keeps its threads: building a pool per frame
    // would time thread start-up.
    let pool = options
        .threads
        .and_then(|threads| rayon::ThreadPoolBuilder::new().num_threads(threads).build().ok());
    let pooled = RenderOptions {
        threads: None,
        ..*options
    };
    let run = || {
        reset_peak_memory();
        // Frames reuse the last frame's buffers, as a GL context keeps its framebuffer.
        let mut renderer = Renderer::default();
        for _ in 0..warmup {
            renderer.render(scene, &pooled);
        }
        let mut measurement = Measurement {
            frames: Vec::new(),
            stats: Vec::new(),
            peak_memory: None,
            cpu_time: None,
        };
        let cpu_before = crate::cpu_time::process_cpu_time();
        for _ in 0..frames {
            let started = std::time::Instant::now();
            let stats = renderer.render(scene, &pooled);
            measurement.frames.push(started.elapsed());
            measurement.stats.push(stats);
        }
        measurement.peak_memory = peak_memory();
        if let (Some(before), Some(after)) = (cpu_before, crate::cpu_time::process_cpu_time()) {
            measurement.cpu_time = Some(after.saturating_sub(before));
        }
        if warmup + frames == 0 {
            renderer.render(scene, &pooled);
        }
        (measurement, renderer.framebuffer().clone())
    };
    match &pool {
        Some(pool) => pool.install(run),
        None => run(),
    }
}

fn report(
    json: bool,
    scene_name: &str,
    scene: &Scene,
    mode: BenchMode,
    measurement: &Measurement,
    anchor: Option<&AnchorDifference>,
) {
    let ms = |d: Duration| d.as_secs_f64() * 1000.0;
    let median = measurement.median();
    let stats = measurement.stats.last().copied().unwrap_or_default();
    let per_second = |count: usize| count as f64 / median.as_secs_f64().max(1e-9);
    let shaded = median_count(measurement.stats.iter().map(|s| s.shaded_pixels));
    let mib = measurement
        .peak_memory
        .map(|bytes| bytes as f64 / (1024.0 * 1024.0));
    if json {
        let mut line = json!({
            "scene": scene_name,
            "shading": mode.name(),
            "threads": stats.threads,
            "width": scene.image.width,
            "height": scene.image.height,
            "triangles": stats.triangles,
            "raster_triangles": stats.raster_triangles,
            "frames": measurement.frames.len(),
            "median_ms": ms(median),
            "min_ms": ms(measurement.min()),
            "shadow_maps_ms": ms(measurement.stage(|s| s.shadow_maps)),
            "shadow_faces": stats.shadow_faces,
            "geometry_ms": ms(measurement.stage(|s| s.geometry)),
            "raster_thread_ms": ms(measurement.stage(|s| s.raster_thread_time)),
            "shade_thread_ms": ms(measurement.stage(|s| s.shade_thread_time)),
            "resolve_ms": ms(measurement.stage(|s| s.resolve)),
            "triangles_per_s": per_second(stats.triangles),
            "shaded_pixels": shaded,
            "shaded_pixels_per_s": per_second(shaded),
            "peak_memory_mib": mib,
            "cpu_ms_per_frame": measurement.cpu_per_frame().map(ms),
            "cores_busy": measurement.cores(),
        });
        if let Some(anchor) = anchor {
            line["llvmpipe_mean_abs"] = json!(anchor.mean);
            line["llvmpipe_max_abs"] = json!(anchor.max);
            line["llvmpipe_share_over_2"] = json!(anchor.share_over_2);
        }
        outln!("{line}");
    } else {
        let mut row = format!(
            "  {:<8} {:>3} {:>6.2} ms {:>6.2} ms | {:>7.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} | {:>7.1} {:>8.1} {:>8} {:>5}",
            mode.name(),
            stats.threads,
            ms(median),
            ms(measurement.min()),
            ms(measurement.stage(|s| s.shadow_maps)),
            ms(measurement.stage(|s| s.geometry)),
            ms(measurement.stage(|s| s.raster_thread_time)),
            ms(measurement.stage(|s| s.shade_thread_time)),
            ms(measurement.stage(|s| s.resolve)),
            per_second(stats.triangles) / 1e6,
            per_second(shaded) / 1e6,
            mib.map_or_else(|| "?".to_string(), |mib| format!("{mib:.0}")),
            measurement
                .cores()
                .map_or_else(|| "?".to_string(), |cores| format!("{cores:.2}")),
        );
        if let Some(anchor) = anchor {
            row += &format!(
                "  | {:>17.3} {:>5} {:>6.2}%",
                anchor.mean,
                anchor.max,
                anchor.share_over_2 * 100.0
            );
        }
        outln!("{row}");
    }
}

fn median_count(counts: impl Iterator<Item = usize>) -> usize {
    let mut counts: Vec<usize> = counts.collect();
    counts.sort_unstable();
    counts.get(counts.len() / 2).copied().unwrap_or(0)
}

/// The anchor frame of `scene_name` in `mode`: `sN_<scene_name with - as _>__<mode>.png`.
fn anchor_path(folder: &Path, scene_name: &str, mode: BenchMode) -> Option<PathBuf> {
    let wanted = format!("{}__{}.png", scene_name.replace('-', "_"), mode.name());
    let entries = std::fs::read_dir(folder).ok()?;
    let mut matches: Vec<PathBuf> = entries
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|path| {
            path.file_name().and_then(|n| n.to_str()).is_some_and(|name| {
                // Strip the harness's `sN_` prefix.
                let unprefixed = name
                    .strip_prefix('s')
                    .map(|rest| rest.trim_start_matches(|c: char| c.is_ascii_digit()))
                    .and_then(|rest| rest.strip_prefix('_'));
                unprefixed == Some(wanted.as_str())
            })
        })
        .collect();
    matches.sort();
    matches.into_iter().next()
}

fn anchor_difference(
    folder: &Path,
    scene_name: &str,
    mode: BenchMode,
    ours: &RgbImage,
) -> Option<AnchorDifference> {
    let path = anchor_path(folder, scene_name, mode)?;
    let theirs = match image::open(&path) {
        Ok(image) => image.to_rgb8(),
        Err(error) => {
            errln!("warning: cannot read {}: {error}", path.display());
            return None;
        }
    };
    let tolerance = Tolerance {
        max_channel_difference: 2,
        ..Tolerance::default()
    };
    let comparison = match compare_pixels(&theirs, ours, &tolerance) {
        Ok(comparison) => comparison,
        Err(mismatch) => {
            errln!("warning: {}: {mismatch}", path.display());
            return None;
        }
    };
    let channel_sum: u64 = theirs
        .as_raw()
        .iter()
        .zip(ours.as_raw())
        .map(|(a, b)| u64::from(a.abs_diff(*b)))
        .sum();
    Some(AnchorDifference {
        mean: channel_sum as f64 / theirs.as_raw().len().max(1) as f64,
        max: comparison.largest_difference,
        share_over_2: comparison.differing_share(),
    })
}

/// Linux: resets the process's peak resident memory to its current size (`clear_refs` 5), so
/// each measurement reports its own peak.
fn reset_peak_memory() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// Linux: the process's peak resident memory (`VmHWM`) in bytes.
fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|line| line.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_of_odd_and_even_counts() {
        let ms = Duration::from_millis;
        assert_eq!(median([ms(3), ms(1), ms(2)].into_iter()), ms(2));
        assert_eq!(
            median([ms(4), ms(1), ms(2), ms(3)].into_iter()),
            Duration::from_micros(2500)
        );
        assert_eq!(median(std::iter::empty()), Duration::ZERO);
    }

    #[test]
    fn bytes_read_count_each_file_once() {
        let folder = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        let a = folder.path().join("a.obj");
        let b = folder.path().join("b.mtl");
        std::fs::write(&a, [0u8; 1000]).unwrap_or_else(|e| panic!("{e}"));
        std::fs::write(&b, [0u8; 24]).unwrap_or_else(|e| panic!("{e}"));
        let missing = folder.path().join("missing.png");
        assert_eq!(bytes_of_files(&[a.clone(), b, a, missing]), 1024);
    }

    /// Cores are CPU time over the frames' wall time: one slow frame among short ones does not
    /// lift them above the cores there are (over the median frame this read 8).
    #[test]
    fn cores_are_cpu_time_over_the_frames_wall_time() {
        let ms = Duration::from_millis;
        let measurement = Measurement {
            frames: vec![ms(1), ms(1), ms(10)],
            stats: Vec::new(),
            peak_memory: None,
            cpu_time: Some(ms(24)),
        };
        assert_eq!(measurement.cores(), Some(2.0));
        assert_eq!(measurement.cpu_per_frame(), Some(ms(8)));
        let unmeasured = Measurement {
            cpu_time: None,
            ..measurement
        };
        assert_eq!(unmeasured.cores(), None);
    }

    #[test]
    fn anchor_files_are_found_by_scene_and_mode() {
        let folder = tempfile::tempdir().expect("a temporary folder");
        for name in [
            "s1_two_spheres__phong.png",
            "s1_two_spheres_800x600__phong.png",
            "s3_overdraw__flat.png",
        ] {
            std::fs::write(folder.path().join(name), b"").expect("writable");
        }
        let found = |scene: &str, mode| {
            anchor_path(folder.path(), scene, mode)
                .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        };
        assert_eq!(
            found("two-spheres", BenchMode::Phong).as_deref(),
            Some("s1_two_spheres__phong.png")
        );
        assert_eq!(
            found("two-spheres-800x600", BenchMode::Phong).as_deref(),
            Some("s1_two_spheres_800x600__phong.png")
        );
        assert_eq!(
            found("overdraw", BenchMode::Flat).as_deref(),
            Some("s3_overdraw__flat.png")
        );
        assert_eq!(found("overdraw", BenchMode::Phong), None);
    }

    #[test]
    fn modes_set_shading_and_model_of_every_object() {
        let loaded = load_scene(Path::new("scenes/bench/two-spheres.ron"), &LoadOptions::default())
            .expect("the bench scene loads");
        for (mode, shading, model) in [
            (BenchMode::Flat, Shading::Flat, LightingModel::BlinnPhong),
            (BenchMode::Gouraud, Shading::Gouraud, LightingModel::BlinnPhong),
            (BenchMode::Phong, Shading::Phong, LightingModel::Phong),
            (BenchMode::Blinn, Shading::Phong, LightingModel::BlinnPhong),
        ] {
            let scene = mode.apply(&loaded.scene);
            for object in &scene.objects {
                assert_eq!(object.shading, shading);
                assert_eq!(object.material.map(|m| m.model), Some(model));
            }
        }
    }
}
