//! `lampshade report speed-error`: what each way of approximating a sphere costs in time and
//! gains in accuracy, measured against the exact reference ([`crate::reference`]).
//!
//! The sweep takes a scene (by default the seed's MATLAB demo, `scenes/matlab-shiny.ron`) and
//! varies, on every object that is a `Sphere`:
//! - the shading mode: Flat, Gouraud, Phong with Nlerp and with Slerp normal interpolation;
//! - the tessellation, `Sphere(8)` to `Sphere(512)`;
//! - the material's shininess (5, 50, 500);
//! - the samples per pixel (1 and 4).
//!
//! Each point is rendered `runs` times with [`crate::render::render`] (the median wall time is
//! kept; the mesh is built before timing, as the loader would have) and compared with the
//! reference of the same scene, shininess and samples by [`crate::metrics`]. Two more rows per
//! reference measure the reference itself: its own time, and the error of the same ray caster
//! with the renderer's `f32` lighting (`LightingPrecision::F32`), which isolates what `f32`
//! arithmetic costs from what tessellation and interpolation cost.
//!
//! Outputs, in the folder named by `--out`: `speed-error.csv` (every point), `speed-error.md`
//! (the table, Pareto-optimal points marked) and one plot per shininess and sample count,
//! `speed-error-sSHININESS-xSAMPLES.svg`: mean absolute error against time, both logarithmic,
//! one colour per shading mode, the Pareto front (no other point is both faster and more
//! accurate) drawn as a line.
//!
//! For any other scene (`--knobs`, or a scene without spheres), [`knobs`] sweeps the knobs the
//! scene uses one at a time instead.

pub mod knobs;
pub mod maps;
pub mod plot;

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use clap::Subcommand;

use crate::cli::{EXIT_BAD_INPUT, EXIT_OK, EXIT_OUTPUT_FAILED, print_load_error};
use crate::mesh::{Mesh, primitives};
use crate::metrics::{Compared, ErrorMetrics, compare, compare_over};
use crate::reference::{
    LightingPrecision, ReferenceOptions, Shape, recognize_shape, render_reference, render_reference_with,
};
use crate::render::{RenderOptions, render};
use crate::scene::load::{LoadOptions, load_scene};
use crate::scene::{LightingModel, NormalInterpolation, Scene, Shading, presets};

#[derive(Debug, clap::Args)]
pub struct ReportArgs {
    #[command(subcommand)]
    pub report: ReportKind,
}

#[derive(Debug, Subcommand)]
pub enum ReportKind {
    /// Sweep shading mode, tessellation, shininess and samples on a sphere scene; time each
    /// point and measure its error against the exact reference. Writes a CSV and a Markdown
    /// table and SVG plots with the Pareto front.
    SpeedError(SpeedErrorArgs),
    /// The llvmpipe anchor's accuracy table for a scene (by default seed 002's MATLAB demo at
    /// 1920×1080): flat, Gouraud and Blinn with the half vector, Phong with R·V, each against
    /// the exact reference of the same model, over the pixels both images cover. Prints
    /// Markdown.
    Accuracy(AccuracyArgs),
}

#[derive(Debug, clap::Args)]
pub struct AccuracyArgs {
    /// The scene; every object is shaded in each mode in turn.
    #[arg(long, value_name = "SCENE", default_value = "scenes/matlab-shiny.ron")]
    pub scene: PathBuf,
    #[arg(long, default_value_t = 1920)]
    pub width: u32,
    #[arg(long, default_value_t = 1080)]
    pub height: u32,
}

#[derive(Debug, clap::Args)]
pub struct SpeedErrorArgs {
    /// Folder for the table and plots (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// The scene to sweep; its `Sphere` objects are varied, everything else is kept.
    #[arg(long, value_name = "SCENE", default_value = "scenes/matlab-shiny.ron")]
    pub scene: PathBuf,
    /// Renders per point; the median time is reported.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    pub runs: u32,
    /// A small sweep on a 160×120 image, one run per point (seconds, for tests).
    #[arg(long)]
    pub quick: bool,
    /// Worker threads for rendering (default: one per core).
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..))]
    pub threads: Option<u16>,
    /// Sweep the approximation knobs the scene uses instead, one at a time around its own
    /// settings (shading of all objects and of each, Nlerp/Slerp, sphere tessellation,
    /// shadow-map resolution, PCF and bias, mip bias, samples), against one reference with
    /// 4×4 samples per pixel, over the image and on shadow edges, highlight peaks and texture
    /// detail; writes `knobs.md` (with a recommendation per knob), `knobs.csv` and
    /// `knobs-*.svg` plots. The default for a scene without `Sphere` objects.
    #[arg(long)]
    pub knobs: bool,
    /// With the knob sweep: write a heat map of each point's error (FLIP, with its colour
    /// scale) into DIR as `KNOB-VALUE.png`, linked from `knobs.md`.
    #[arg(long, value_name = "DIR")]
    pub maps: Option<PathBuf>,
}

/// How a sphere is shaded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    Flat,
    Gouraud,
    PhongNlerp,
    PhongSlerp,
}

impl Mode {
    pub const ALL: [Mode; 4] = [Mode::Flat, Mode::Gouraud, Mode::PhongNlerp, Mode::PhongSlerp];

    pub fn name(self) -> &'static str {
        match self {
            Mode::Flat => "Flat",
            Mode::Gouraud => "Gouraud",
            Mode::PhongNlerp => "Phong (Nlerp)",
            Mode::PhongSlerp => "Phong (Slerp)",
        }
    }

    fn shading(self) -> (Shading, NormalInterpolation) {
        match self {
            Mode::Flat => (Shading::Flat, NormalInterpolation::Nlerp),
            Mode::Gouraud => (Shading::Gouraud, NormalInterpolation::Nlerp),
            Mode::PhongNlerp => (Shading::Phong, NormalInterpolation::Nlerp),
            Mode::PhongSlerp => (Shading::Phong, NormalInterpolation::Slerp),
        }
    }
}

/// The values each axis of the sweep takes.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepPlan {
    pub modes: Vec<Mode>,
    pub segments: Vec<u32>,
    pub shininess: Vec<f32>,
    pub samples: Vec<u32>,
    pub runs: u32,
    /// Overrides the scene's image size.
    pub size: Option<(u32, u32)>,
}

impl SweepPlan {
    pub fn full(runs: u32) -> Self {
        SweepPlan {
            modes: Mode::ALL.to_vec(),
            segments: vec![8, 16, 32, 64, 128, 256, 512],
            shininess: vec![5.0, 50.0, 500.0],
            samples: vec![1, 4],
            runs,
            size: None,
        }
    }

    pub fn quick() -> Self {
        SweepPlan {
            modes: Mode::ALL.to_vec(),
            segments: vec![8, 32],
            shininess: vec![5.0, 50.0],
            samples: vec![1],
            runs: 1,
            size: Some((160, 120)),
        }
    }
}

/// What one point of the sweep measured.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepPoint {
    /// A shading mode's name, or `reference (f64)` / `reference, f32 lighting`.
    pub method: String,
    /// `Sphere(N)`'s N; 0 for the reference rows.
    pub segments: u32,
    pub triangles: usize,
    pub shininess: f32,
    pub samples: u32,
    /// Median wall time of a render.
    pub time: Duration,
    pub error: ErrorMetrics,
    /// No other point of the same shininess and samples is both faster and more accurate.
    pub pareto: bool,
}

/// Runs the sweep on `scene` (whose `Sphere` objects are varied). Fails with a message when
/// the scene has no sphere or its reference cannot be rendered.
pub fn sweep(
    scene: &Scene,
    plan: &SweepPlan,
    threads: Option<usize>,
    mut progress: impl FnMut(&SweepPoint),
) -> Result<Vec<SweepPoint>, String> {
    let spheres: Vec<usize> = (0..scene.objects.len())
        .filter(|&i| recognize_shape(&scene.objects[i].mesh) == Some(Shape::Sphere))
        .collect();
    if spheres.is_empty() {
        return Err("the scene has no `Sphere` object to sweep".to_string());
    }
    let mut base = scene.clone();
    if let Some((width, height)) = plan.size {
        (base.image.width, base.image.height) = (width, height);
    }
    let meshes: Vec<Arc<Mesh>> = plan
        .segments
        .iter()
        .map(|&n| Arc::new(primitives::sphere(n)))
        .collect();
    let options = RenderOptions {
        threads,
        debug_view: None,
    };
    let mut points = Vec::new();
    for &shininess in &plan.shininess {
        for &samples in &plan.samples {
            let mut variant = base.clone();
            variant.image.samples = samples;
            for &i in &spheres {
                let object = &mut variant.objects[i];
                let mut material = object.material.unwrap_or_else(presets::default_material);
                material.shininess = shininess;
                object.material = Some(material);
            }
            let started = Instant::now();
            let reference = render_reference(&variant, threads);
            let reference_time = started.elapsed();
            let started = Instant::now();
            let with_f32 = render_reference_with(
                &variant,
                &ReferenceOptions {
                    threads,
                    precision: LightingPrecision::F32,
                    ..ReferenceOptions::default()
                },
            )
            .framebuffer;
            let f32_time = started.elapsed();
            let first = points.len();
            for (method, time, image) in [
                ("reference (f64)", reference_time, &reference),
                ("reference, f32 lighting", f32_time, &with_f32),
            ] {
                points.push(SweepPoint {
                    method: method.to_string(),
                    segments: 0,
                    triangles: 0,
                    shininess,
                    samples,
                    time,
                    error: compare(&reference, image).expect("same size"),
                    pareto: false,
                });
                progress(points.last().expect("just pushed"));
            }
            for &mode in &plan.modes {
                for (mesh, &segments) in meshes.iter().zip(&plan.segments) {
                    let mut point_scene = variant.clone();
                    let (shading, interpolation) = mode.shading();
                    for &i in &spheres {
                        let object = &mut point_scene.objects[i];
                        object.mesh = Arc::clone(mesh);
                        object.shading = shading;
                        object.normal_interpolation = interpolation;
                    }
                    let mut times = Vec::new();
                    let mut image = None;
                    for _ in 0..plan.runs {
                        let started = Instant::now();
                        let (frame, _) = render(&point_scene, &options);
                        times.push(started.elapsed());
                        image = Some(frame);
                    }
                    times.sort();
                    let image = image.expect("at least one run");
                    points.push(SweepPoint {
                        method: mode.name().to_string(),
                        segments,
                        triangles: point_scene.triangle_count(),
                        shininess,
                        samples,
                        time: times[times.len() / 2],
                        error: compare(&reference, &image).expect("same size"),
                        pareto: false,
                    });
                    progress(points.last().expect("just pushed"));
                }
            }
            mark_pareto_front(&mut points[first + 2..]);
        }
    }
    Ok(points)
}

/// Marks the points no other point beats on both time and mean error.
pub fn mark_pareto_front(points: &mut [SweepPoint]) {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        (points[a].time, points[a].error.mean_abs_all())
            .partial_cmp(&(points[b].time, points[b].error.mean_abs_all()))
            .expect("finite")
    });
    let mut best = f64::INFINITY;
    for index in order {
        let error = points[index].error.mean_abs_all();
        points[index].pareto = error < best;
        best = best.min(error);
    }
}

fn milliseconds(duration: Duration) -> f64 {
    duration.as_secs_f64() * 1000.0
}

fn flip_fields(error: &ErrorMetrics) -> (String, String) {
    match error.flip {
        Some(flip) => (format!("{:.4}", flip.mean), format!("{:.4}", flip.percentile_99)),
        None => (String::new(), String::new()),
    }
}

/// Every point as CSV, one line each, with a header.
pub fn csv(points: &[SweepPoint]) -> String {
    let mut out = String::from(
        "method,segments,triangles,shininess,samples,time_ms,mean_abs,mean_abs_r,mean_abs_g,mean_abs_b,max_abs,rmse,psnr_db,share_over_2,share_over_8,peak_loss,flip_mean,flip_p99,pareto,pixels\n",
    );
    for p in points {
        let e = &p.error;
        let (flip_mean, flip_p99) = flip_fields(e);
        let _ = writeln!(
            out,
            "{},{},{},{},{},{:.3},{:.4},{:.4},{:.4},{:.4},{},{:.4},{:.2},{:.6},{:.6},{:.2},{},{},{},{}",
            p.method,
            p.segments,
            p.triangles,
            p.shininess,
            p.samples,
            milliseconds(p.time),
            e.mean_abs_all(),
            e.mean_abs[0],
            e.mean_abs[1],
            e.mean_abs[2],
            e.max_abs_all(),
            e.rmse,
            e.psnr_db,
            e.share_over_2,
            e.share_over_8,
            e.peak_loss,
            flip_mean,
            flip_p99,
            p.pareto,
            e.pixels,
        );
    }
    out
}

/// The table in Markdown, one section per shininess and sample count.
pub fn markdown(
    points: &[SweepPoint],
    scene: &Path,
    plan: &SweepPlan,
    threads: usize,
    width: u32,
    height: u32,
) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# Speed against error: `{}`\n", scene.display());
    let _ = writeln!(
        out,
        "{width}×{height} px, {threads} threads, median of {} runs per point. Errors on the 0..255 scale \
         against the exact reference (`lampshade render --reference`), over the pixels covered in either \
         image; *peak loss* is how many levels dimmer the brightest pixel (the highlight) is than the \
         reference's; FLIP mean and 99th percentile over the same pixels. **P** marks the Pareto front (no other \
         point is both faster and more accurate, by mean absolute error). Reproduce with \
         `cargo run --release -- report speed-error --out docs/speed-error`.\n",
        plan.runs
    );
    for &shininess in &plan.shininess {
        for &samples in &plan.samples {
            let _ = writeln!(out, "## Shininess {shininess}, {samples} sample(s) per pixel\n");
            let _ = writeln!(
                out,
                "| method | sphere(N) | triangles | ms | mean abs | max abs | PSNR dB | > 2 | > 8 | peak loss | FLIP mean | FLIP p99 | P |"
            );
            let _ = writeln!(
                out,
                "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|:-:|"
            );
            for p in points
                .iter()
                .filter(|p| p.shininess == shininess && p.samples == samples)
            {
                let e = &p.error;
                let (flip_mean, flip_p99) = flip_fields(e);
                let _ = writeln!(
                    out,
                    "| {} | {} | {} | {:.1} | {:.3} | {} | {:.1} | {:.2}% | {:.2}% | {:.1} | {} | {} | {} |",
                    p.method,
                    if p.segments == 0 {
                        "exact".to_string()
                    } else {
                        p.segments.to_string()
                    },
                    p.triangles,
                    milliseconds(p.time),
                    e.mean_abs_all(),
                    e.max_abs_all(),
                    e.psnr_db,
                    100.0 * e.share_over_2,
                    100.0 * e.share_over_8,
                    e.peak_loss,
                    flip_mean,
                    flip_p99,
                    if p.pareto { "P" } else { "" },
                );
            }
            out.push('\n');
        }
    }
    out
}

/// The plot of one shininess and sample count as SVG text: one colour per shading mode, each
/// point labelled with its tessellation, the sweep's Pareto front as a line.
pub fn plot_svg(points: &[SweepPoint], title: &str) -> Result<String, String> {
    use plotters::style::RGBColor;
    let shown: Vec<&SweepPoint> = points.iter().filter(|p| p.segments > 0).collect();
    // Zero errors cannot sit on a log axis: floor them at a thousandth of a level.
    let at = |p: &SweepPoint| (milliseconds(p.time), p.error.mean_abs_all().max(0.001));
    let colours = [
        RGBColor(90, 90, 90),
        RGBColor(230, 120, 0),
        RGBColor(0, 110, 200),
        RGBColor(0, 160, 80),
    ];
    let series = Mode::ALL
        .iter()
        .zip(colours)
        .map(|(mode, colour)| plot::Series {
            name: mode.name().to_string(),
            colour,
            points: shown
                .iter()
                .filter(|p| p.method == mode.name())
                .map(|p| {
                    let (time_ms, error) = at(p);
                    plot::PlotPoint {
                        time_ms,
                        error,
                        ringed: false,
                        label: Some(p.segments.to_string()),
                    }
                })
                .collect(),
        })
        .collect();
    let mut front: Vec<(f64, f64)> = shown.iter().filter(|p| p.pareto).map(|p| at(p)).collect();
    front.sort_by(|a, b| a.partial_cmp(b).expect("finite"));
    plot::TimeErrorChart {
        title,
        size: (900, 600),
        error_axis: "mean absolute error, levels of 255",
        series,
        front,
        front_legend: "Pareto front",
    }
    .to_svg()
}

/// `lampshade report ...`: returns the exit code.
pub fn run(args: &ReportArgs) -> i32 {
    match &args.report {
        ReportKind::SpeedError(args) => run_speed_error(args),
        ReportKind::Accuracy(args) => run_accuracy(args),
    }
}

/// The anchor table's rows: (name, shading, lighting model). As in the anchor, flat, Gouraud
/// and "blinn" use the half vector and "phong" uses R·V; note that lampshade's flat lights the
/// face normal at the centroid where OpenGL's lights the provoking vertex.
const ACCURACY_ROWS: [(&str, Shading, LightingModel); 4] = [
    ("phong (per pixel, R·V)", Shading::Phong, LightingModel::Phong),
    (
        "blinn (per pixel, N·H)",
        Shading::Phong,
        LightingModel::BlinnPhong,
    ),
    (
        "gouraud (per vertex, N·H)",
        Shading::Gouraud,
        LightingModel::BlinnPhong,
    ),
    ("flat (per face, N·H)", Shading::Flat, LightingModel::BlinnPhong),
];

fn run_accuracy(args: &AccuracyArgs) -> i32 {
    let options = LoadOptions {
        width: Some(args.width),
        height: Some(args.height),
        ..LoadOptions::default()
    };
    let loaded = match load_scene(&args.scene, &options) {
        Ok(loaded) => loaded,
        Err(error) => {
            print_load_error(&error);
            return EXIT_BAD_INPUT;
        }
    };
    outln!(
        "| {} {}×{} | mean abs | max abs | PSNR dB | pixels off by > 2 | pixels off by > 8 |",
        args.scene.display(),
        args.width,
        args.height
    );
    outln!("|---|---:|---:|---:|---:|---:|");
    for (name, shading, model) in ACCURACY_ROWS {
        let mut scene = loaded.scene.clone();
        for object in &mut scene.objects {
            let mut material = object.material.unwrap_or_else(presets::default_material);
            material.model = model;
            object.material = Some(material);
            object.shading = shading;
        }
        let reference = render_reference(&scene, None);
        let (image, _) = render(&scene, &RenderOptions::default());
        let e = compare_over(&reference, &image, Compared::BothCovered).expect("same size");
        outln!(
            "| {name} | {:.4} | {} | {:.1} | {:.3}% | {:.3}% |",
            e.mean_abs_all(),
            e.max_abs_all(),
            e.psnr_db,
            100.0 * e.share_over_2,
            100.0 * e.share_over_8
        );
    }
    EXIT_OK
}

/// Writes the report's files into `--out` (created if missing), or returns the exit code after
/// saying why not. Nothing is written if any file would replace the scene; each file is written
/// whole or not at all.
fn write_report_files(args: &SpeedErrorArgs, files: &[(PathBuf, Vec<u8>)]) -> Result<(), i32> {
    let mut folders: Vec<&Path> = files.iter().filter_map(|(path, _)| path.parent()).collect();
    folders.dedup();
    for folder in folders {
        if let Err(error) = std::fs::create_dir_all(folder) {
            errln!("error: cannot create {}: {error}", folder.display());
            return Err(EXIT_OUTPUT_FAILED);
        }
    }
    if let Some((path, _)) = files
        .iter()
        .find(|(path, _)| crate::output::overwritten_input(path, [args.scene.as_path()]).is_some())
    {
        errln!(
            "error: `{}` would replace the scene `{}`; nothing was written\n  = help: choose another --out folder",
            path.display(),
            args.scene.display()
        );
        return Err(EXIT_BAD_INPUT);
    }
    for (path, bytes) in files {
        let written = crate::output::write_atomically(path, |writer| {
            writer
                .write_all(bytes)
                .map_err(|source| crate::output::OutputError::Io {
                    path: path.clone(),
                    source,
                })
        });
        if let Err(error) = written {
            errln!("error: {error}");
            return Err(EXIT_OUTPUT_FAILED);
        }
    }
    Ok(())
}

/// `report speed-error --knobs`: the knob sweep of [`knobs`], written to `--out`.
fn run_knob_sweep(args: &SpeedErrorArgs, mut scene: Scene) -> i32 {
    if args.quick {
        (scene.image.width, scene.image.height) = (160, 120);
    }
    let plan = knobs::KnobPlan {
        runs: if args.quick { 1 } else { args.runs },
        quick: args.quick,
        maps: args.maps.is_some(),
    };
    let threads = args.threads.map(usize::from);
    let started = Instant::now();
    let (points, reference_time) = knobs::sweep_knobs(&scene, plan, threads, |p| {
        errln!(
            "  {:<22} {:<12} {:>8.1} ms, FLIP p99 {}",
            p.knob,
            p.value,
            milliseconds(p.time),
            p.error
                .flip
                .map_or("-".to_string(), |f| format!("{:.4}", f.percentile_99))
        )
    });
    let header = format!(
        "{}×{} px, {} threads, median of {} runs per point; the reference ({:.1} s) has 4×4 stratified \
         samples per pixel, shadow rays and level-0 textures over each sample. Errors on the 0..255 scale \
         over the pixels covered in either image; FLIP over the same pixels. **P** marks the Pareto front \
         by FLIP p99. Reproduce with `lampshade report speed-error --knobs --scene {}`.",
        scene.image.width,
        scene.image.height,
        threads.unwrap_or_else(rayon::current_num_threads),
        plan.runs,
        reference_time.as_secs_f64(),
        args.scene.display()
    );
    // The maps' folder as the Markdown file links it: relative when it is inside `--out`.
    let maps_link = args.maps.as_ref().map(|maps| {
        maps.strip_prefix(&args.out)
            .unwrap_or(maps)
            .display()
            .to_string()
            .replace('\\', "/")
    });
    let mut files = vec![
        (args.out.join("knobs.csv"), knobs::knobs_csv(&points).into_bytes()),
        (
            args.out.join("knobs.md"),
            knobs::knobs_markdown(
                &points,
                &args.scene.display().to_string(),
                &header,
                maps_link.as_deref(),
            )
            .into_bytes(),
        ),
    ];
    let stem = args.scene.file_stem().unwrap_or_default().to_string_lossy();
    for axis in knobs::PlotError::ALL {
        let title = format!("{stem}: {}×{}", scene.image.width, scene.image.height);
        match knobs::knobs_plot_svg(&points, axis, &title) {
            Some(Ok(svg)) => files.push((args.out.join(axis.file_name()), svg.into_bytes())),
            Some(Err(message)) => errln!("warning: {message}"),
            None => {}
        }
    }
    if let Some(maps) = &args.maps {
        for point in &points {
            if let Some(map) = &point.heat_map {
                files.push((maps.join(point.map_file_name()), maps::png_bytes(map)));
            }
        }
    }
    if let Err(code) = write_report_files(args, &files) {
        return code;
    }
    for line in knobs::recommendations(&points) {
        outln!("{line}");
    }
    errln!(
        "{} points in {:.1} s → {}",
        points.len(),
        started.elapsed().as_secs_f64(),
        args.out.display()
    );
    EXIT_OK
}

fn run_speed_error(args: &SpeedErrorArgs) -> i32 {
    let loaded = match load_scene(&args.scene, &LoadOptions::default()) {
        Ok(loaded) => loaded,
        Err(error) => {
            print_load_error(&error);
            return EXIT_BAD_INPUT;
        }
    };
    let has_sphere = loaded
        .scene
        .objects
        .iter()
        .any(|object| recognize_shape(&object.mesh) == Some(Shape::Sphere));
    if args.knobs || !has_sphere {
        return run_knob_sweep(args, loaded.scene);
    }
    let plan = if args.quick {
        SweepPlan::quick()
    } else {
        SweepPlan::full(args.runs)
    };
    let threads = args.threads.map(usize::from);
    let started = Instant::now();
    let points = sweep(&loaded.scene, &plan, threads, |p| {
        errln!(
            "  shininess {:>3}, {:>2} spp, {:<24} {:>4}: {:>8.1} ms, mean abs {:.3}",
            p.shininess,
            p.samples,
            p.method,
            if p.segments == 0 {
                "-".to_string()
            } else {
                p.segments.to_string()
            },
            milliseconds(p.time),
            p.error.mean_abs_all()
        )
    });
    let points = match points {
        Ok(points) => points,
        Err(message) => {
            errln!("error: {}: {message}", args.scene.display());
            return EXIT_BAD_INPUT;
        }
    };
    let (width, height) = plan
        .size
        .unwrap_or((loaded.scene.image.width, loaded.scene.image.height));
    let thread_count = threads.unwrap_or_else(rayon::current_num_threads);
    let mut files = vec![
        (args.out.join("speed-error.csv"), csv(&points).into_bytes()),
        (
            args.out.join("speed-error.md"),
            markdown(&points, &args.scene, &plan, thread_count, width, height).into_bytes(),
        ),
    ];
    for &shininess in &plan.shininess {
        for &samples in &plan.samples {
            let group: Vec<SweepPoint> = points
                .iter()
                .filter(|p| p.shininess == shininess && p.samples == samples)
                .cloned()
                .collect();
            let title = format!(
                "{}: shininess {shininess}, {samples} spp, {width}×{height}",
                args.scene.file_stem().unwrap_or_default().to_string_lossy()
            );
            match plot_svg(&group, &title) {
                Ok(svg) => files.push((
                    args.out.join(format!("speed-error-s{shininess}-x{samples}.svg")),
                    svg.into_bytes(),
                )),
                Err(message) => errln!("warning: {message}"),
            }
        }
    }
    if let Err(code) = write_report_files(args, &files) {
        return code;
    }
    outln!(
        "speed-error: {} points in {:.1} s → {}",
        points.len(),
        started.elapsed().as_secs_f64(),
        args.out.display()
    );
    EXIT_OK
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::ErrorMetrics;

    fn point(ms: u64, error: f64) -> SweepPoint {
        SweepPoint {
            method: "Flat".to_string(),
            segments: 8,
            triangles: 128,
            shininess: 5.0,
            samples: 1,
            time: Duration::from_millis(ms),
            error: ErrorMetrics {
                pixels: 1,
                mean_abs: [error; 3],
                max_abs: [0; 3],
                rmse: 0.0,
                psnr_db: 0.0,
                share_over_2: 0.0,
                share_over_8: 0.0,
                peak_loss: 0.0,
                flip: None,
            },
            pareto: false,
        }
    }

    #[test]
    fn the_pareto_front_keeps_exactly_the_undominated_points() {
        let mut points = vec![
            point(10, 5.0), // fastest: on the front
            point(20, 6.0), // slower and worse than the first
            point(30, 1.0), // on the front
            point(30, 2.0), // as slow as the third, worse
            point(40, 1.0), // slower, not better
            point(50, 0.5), // on the front
        ];
        mark_pareto_front(&mut points);
        let front: Vec<bool> = points.iter().map(|p| p.pareto).collect();
        assert_eq!(front, [true, false, true, false, false, true]);
    }

    /// The quick sweep on the MATLAB demo: every point is measured, errors fall as the
    /// tessellation grows for the smooth modes, f32 lighting is within a level of f64, and the
    /// outputs are written.
    #[test]
    fn a_quick_sweep_measures_every_point_and_writes_its_outputs() {
        let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/matlab-shiny.ron");
        let scene = load_scene(&scene_path, &LoadOptions::default()).unwrap().scene;
        let plan = SweepPlan::quick();
        let points = sweep(&scene, &plan, Some(2), |_| {}).unwrap();
        // Per shininess: two reference rows and 4 modes × 2 tessellations.
        assert_eq!(points.len(), plan.shininess.len() * (2 + 4 * 2));
        let error = |method: &str, segments: u32, shininess: f32| {
            points
                .iter()
                .find(|p| p.method == method && p.segments == segments && p.shininess == shininess)
                .unwrap()
                .error
                .mean_abs_all()
        };
        for mode in ["Gouraud", "Phong (Nlerp)", "Phong (Slerp)", "Flat"] {
            assert!(error(mode, 32, 50.0) < error(mode, 8, 50.0), "{mode}");
        }
        assert!(error("Phong (Nlerp)", 32, 50.0) < error("Gouraud", 32, 50.0));
        assert_eq!(error("reference (f64)", 0, 5.0), 0.0);
        assert!(error("reference, f32 lighting", 0, 5.0) < 0.01);
        assert!(points.iter().any(|p| p.pareto));

        let csv_text = csv(&points);
        assert_eq!(csv_text.lines().count(), points.len() + 1);
        let svg = plot_svg(&points[..10], "test").unwrap();
        assert!(
            svg.starts_with("<svg") && svg.contains("Pareto front"),
            "{}",
            &svg[..100]
        );
        let table = markdown(&points, &scene_path, &plan, 2, 160, 120);
        assert!(table.contains("| P |\n"), "{table}");
    }
}
