//! The command line: arguments are parsed into a plan, the plan is run, and every outcome maps
//! to a documented exit code.
//!
//! Exit codes:
//! - `0`: everything asked for was done.
//! - `1`: the inputs were fine but an output could not be written (disk full, no permission).
//! - `2`: bad input: a scene (or a file it uses) has errors, or the arguments are wrong. The
//!   diagnostics are printed to stderr; no output file is created or replaced for that scene.
//! - `101`: an internal error (a bug in lampshade), reported by `main`.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant, SystemTime};

use clap::{Parser, Subcommand, ValueEnum};

use crate::diag::render_diagnostics;
use crate::output::{self, Destination, Encoding, OutputFormat, PngCompression};
use crate::pipeline::{BuildCache, RenderedScene, render_scene_file};
use crate::progress::{BarClearer, RenderBar};
use crate::render::{DebugView, RenderOptions, RenderStats};
use crate::scene::access::FileAccess;
use crate::scene::limits::parse_memory_size;
use crate::scene::load::{LoadError, LoadOptions};
use crate::scene::{LightingModel, Shading};

pub const EXIT_OK: i32 = 0;
pub const EXIT_OUTPUT_FAILED: i32 = 1;
pub const EXIT_BAD_INPUT: i32 = 2;
pub const EXIT_INTERNAL_ERROR: i32 = 101;

#[derive(Debug, Parser)]
#[command(
    name = "lampshade",
    version,
    about = "Render hand-written RON scene files with a tiled CPU rasterizer"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render scene files to images (PNG, OpenEXR or Radiance HDR).
    #[command(after_help = RENDER_EXAMPLES)]
    Render(RenderArgs),
    /// Render a suite of scenes and compare each with its reference image.
    #[command(after_help = CHECK_EXAMPLES)]
    Check(crate::check::CheckArgs),
    /// Re-render a scene whenever it, or any file it uses, changes.
    #[command(after_help = WATCH_EXAMPLES)]
    Watch(crate::watch::WatchArgs),
    /// Time frames of scenes per shading mode (loaded once, rendered many times).
    #[command(after_help = BENCH_EXAMPLES)]
    Bench(crate::bench::BenchArgs),
    /// Measurements of the renderer: `report speed-error` (time against error), `report accuracy`.
    #[command(after_help = REPORT_EXAMPLES)]
    Report(crate::report::ReportArgs),
    /// A language server for scene files (diagnostics as you type, completion, hover, go to
    /// definition, outline) over standard input and output, for any editor's LSP client.
    #[command(after_help = LSP_EXAMPLES)]
    Lsp(crate::lsp::LspArgs),
}

const LSP_EXAMPLES: &str = "\
Editors start it themselves; see README.md (VS Code, Neovim, Helix):
  lampshade lsp                                            JSON-RPC on standard input and output";

const RENDER_EXAMPLES: &str = "\
Examples:
  lampshade render scenes/matlab-shiny.ron                 writes scenes/matlab-shiny.png
  lampshade render scene.ron -o out.exr                    linear, unclamped OpenEXR
  lampshade render scene.ron --width 3840 --height 2160 --samples 4
  lampshade render scene.ron --shading gouraud --model blinn-phong -o gouraud.png
  lampshade render scene.ron --debug normals -o normals.png
  lampshade render scene.ron --reference -o exact.exr      the f64 ray-cast image it converges to
  lampshade render scene.ron --reference=mesh --reference-samples 4
  lampshade render scene.ron -o - | display               PNG on standard output
  lampshade render scene.ron --turntable 36                an animated PNG, scene-turntable.png
  lampshade render scene.ron --turntable 120 -o spin-%03d.png --shard 1/4
  lampshade render scenes/*.ron                            each beside its scene";

const CHECK_EXAMPLES: &str = "\
Examples:
  lampshade check scenes/                                  every scene against scenes/refs/
  lampshade check scenes/ --report report --junit junit.xml
  lampshade check scenes/ --bless                          accept the new images as references";

const WATCH_EXAMPLES: &str = "\
Examples:
  lampshade watch scene.ron                                re-renders scene.png on every save
  lampshade watch scene.ron --serve                        and shows it on http://127.0.0.1:7800
  lampshade watch scene.ron -o /tmp/preview.png --width 640 --height 360";

const BENCH_EXAMPLES: &str = "\
Examples:
  lampshade bench scenes/bench/two-spheres.ron
  lampshade bench scenes/bench/two-spheres.ron --modes phong --threads 1 --frames 20";

const REPORT_EXAMPLES: &str = "\
Examples:
  lampshade report speed-error --out docs/speed-error
  lampshade report speed-error --out /tmp/se --scene scene.ron --quick
  lampshade report accuracy --scene scenes/matlab-shiny.ron";

#[derive(Debug, clap::Args)]
pub struct RenderArgs {
    /// Scene files (.ron). Each is rendered in turn; a bad one is reported and the rest still render.
    #[arg(required = true, value_name = "SCENE")]
    pub scenes: Vec<PathBuf>,
    /// Output image (only with a single scene): `.png`, `.exr` or `.hdr`, the format following
    /// the extension; `-` writes to standard output. Default: the scene's path with the
    /// format's extension.
    #[arg(short, long, value_name = "OUT.png")]
    pub output: Option<PathBuf>,
    /// Output format: png (8-bit), exr or hdr (linear float, not clamped). Must agree with the
    /// output's extension; needed only without -o, or with `-o -`. Default: png.
    #[arg(long, value_enum)]
    pub format: Option<FormatArg>,
    /// How 8-bit PNG stores light: linear (as OpenGL writes a framebuffer) or srgb.
    #[arg(long, value_enum, default_value = "linear")]
    pub encoding: EncodingArg,
    /// Image width in pixels, overriding the scene's.
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels, overriding the scene's.
    #[arg(long)]
    pub height: Option<u32>,
    /// Samples per pixel (anti-aliasing: 1, 2, 4, 8 or 16), overriding the scene's.
    #[arg(long, value_parser = parse_samples)]
    pub samples: Option<u32>,
    /// Worker threads (default: one per core). The image is identical for any count.
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..))]
    pub threads: Option<u16>,
    /// Shade every object this way, overriding the scene.
    #[arg(long, value_enum)]
    pub shading: Option<ShadingArg>,
    /// Light every material with this model, overriding the scene.
    #[arg(long, value_enum)]
    pub model: Option<ModelArg>,
    /// Render one ingredient of the lighting instead of the lit image.
    #[arg(long, value_enum, value_name = "VIEW")]
    pub debug: Option<DebugArg>,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
    /// Render the exact reference instead: the scene ray-cast and lit in f64, shadows by
    /// shadow rays, textures at level 0 integrated over the pixel (see `reference`).
    /// `--reference=mesh` ray-casts the primitives' tessellation instead of their exact shapes.
    #[arg(
        long,
        value_enum,
        value_name = "GEOMETRY",
        num_args = 0..=1,
        require_equals = true,
        default_missing_value = "exact",
        conflicts_with = "debug"
    )]
    pub reference: Option<ReferenceArg>,
    /// With --reference: N×N stratified samples per pixel (the ideal box filter) instead of the
    /// scene's sample pattern.
    #[arg(long, value_name = "N", requires = "reference", value_parser = clap::value_parser!(u32).range(1..=i64::from(crate::reference::MAX_REFERENCE_SAMPLES)))]
    pub reference_samples: Option<u32>,
    /// Print what the frame drew at image pixel X,Y (from the top-left corner) as JSON on
    /// standard output, with the lighting per light and term and where each thing is defined
    /// (docs/pick.md). No image is written unless -o is given too.
    #[arg(long, value_name = "X,Y", value_parser = parse_pixel, conflicts_with_all = ["reference", "turntable"])]
    pub pick: Option<(u32, u32)>,
    /// Render N frames of the camera orbiting its target (a full turn, frame 0 the scene's
    /// camera) as an animated PNG, or as numbered images when -o has a `%03d`-style pattern
    /// (`-o spin-%03d.png`). Default output: SCENE-turntable.png.
    #[arg(long, value_name = "N", conflicts_with = "reference", value_parser = clap::value_parser!(u32).range(1..))]
    pub turntable: Option<u32>,
    /// The axis the turntable turns about, through the camera's target (default: the camera's
    /// up direction).
    #[arg(long, value_enum, requires = "turntable")]
    pub axis: Option<crate::turntable::TurntableAxis>,
    /// With --turntable and numbered frames: render only frames K−1, K−1+N, K−1+2N, … (every
    /// N-th frame), as `check --shard` splits a suite over N CI jobs.
    #[arg(long, value_name = "K/N", requires = "turntable")]
    pub shard: Option<crate::check::select::Shard>,
    #[command(flatten)]
    pub limits: InputLimits,
}

/// `--pick X,Y`: two pixel coordinates.
fn parse_pixel(text: &str) -> Result<(u32, u32), String> {
    let parsed = text
        .split_once(',')
        .and_then(|(x, y)| Some((x.trim().parse().ok()?, y.trim().parse().ok()?)));
    parsed.ok_or_else(|| format!("expected two pixel coordinates X,Y (whole numbers from 0), not `{text}`"))
}

/// What scenes may read and how much memory they may take: `--sandbox` and `--max-memory`,
/// shared by `render`, `check` and `watch`.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct InputLimits {
    /// Read nothing outside DIR: every file a scene names (includes, meshes, MTL libraries,
    /// textures, glTF buffers and images) must resolve inside it, after symlinks and `..`.
    #[arg(long, value_name = "DIR")]
    pub sandbox: Option<PathBuf>,
    /// Refuse scenes whose render would need more memory than this (e.g. 512M, 16G;
    /// default 12G).
    #[arg(long, value_name = "SIZE", value_parser = parse_memory_size)]
    pub max_memory: Option<u64>,
}

impl InputLimits {
    /// The file access `--sandbox` asks for.
    pub fn file_access(&self) -> Result<FileAccess, String> {
        match &self.sandbox {
            Some(folder) => FileAccess::sandboxed(folder),
            None => Ok(FileAccess::unrestricted()),
        }
    }

    /// Load options with these limits and nothing overridden.
    pub fn load_options(&self) -> Result<LoadOptions, String> {
        Ok(LoadOptions {
            access: self.file_access()?,
            max_memory: self.max_memory,
            ..LoadOptions::default()
        })
    }
}

/// `--samples`: the counts the rasterizer's sample patterns exist for.
fn parse_samples(text: &str) -> Result<u32, String> {
    match text.parse::<u32>() {
        Ok(samples) if crate::render::raster::SamplePattern::new(samples).is_some() => Ok(samples),
        _ => Err(format!("must be 1, 2, 4, 8 or 16, not `{text}`")),
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FormatArg {
    Png,
    Exr,
    Hdr,
}

impl FormatArg {
    pub fn format(self) -> OutputFormat {
        match self {
            FormatArg::Png => OutputFormat::Png,
            FormatArg::Exr => OutputFormat::Exr,
            FormatArg::Hdr => OutputFormat::Hdr,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum EncodingArg {
    Linear,
    Srgb,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ReferenceArg {
    /// Sphere, Plane and Cube as their exact shapes, every other mesh as its triangles.
    Exact,
    /// Every object as its triangles, primitives as their tessellation.
    Mesh,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ShadingArg {
    /// One colour per object, lit at the centre of its bounds.
    Constant,
    /// One colour per triangle, lit with its face normal.
    Flat,
    /// Lit at the vertices, colours interpolated.
    Gouraud,
    /// Normals interpolated, lit at every pixel.
    Phong,
}

impl ShadingArg {
    pub fn shading(self) -> Shading {
        match self {
            ShadingArg::Constant => Shading::Constant,
            ShadingArg::Flat => Shading::Flat,
            ShadingArg::Gouraud => Shading::Gouraud,
            ShadingArg::Phong => Shading::Phong,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ModelArg {
    /// Specular `max(R·V, 0)^n`.
    Phong,
    /// Specular `max(N·H, 0)^n` with the half vector.
    BlinnPhong,
    /// Ambient and diffuse only.
    Lambert,
    /// The microfacet model (Beckmann or GGX). Cook-Torrance materials keep their roughness,
    /// Fresnel and distribution; others get the format's defaults (roughness 0.3, F0 0.04,
    /// Beckmann).
    CookTorrance,
    /// No lighting: the diffuse colour plus emission.
    Unlit,
}

impl ModelArg {
    pub fn model(self) -> LightingModel {
        match self {
            ModelArg::Phong => LightingModel::Phong,
            ModelArg::BlinnPhong => LightingModel::BlinnPhong,
            ModelArg::Lambert => LightingModel::Lambert,
            ModelArg::CookTorrance => {
                LightingModel::CookTorrance(crate::scene::presets::default_microfacet())
            }
            ModelArg::Unlit => LightingModel::Unlit,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DebugArg {
    /// Ambient term only (k_a·I_a).
    Ambient,
    /// Diffuse term only.
    Diffuse,
    /// Specular term only.
    Specular,
    /// Shading normals as colours.
    Normals,
    /// Depth, near white to far black.
    Depth,
}

impl DebugArg {
    pub fn debug_view(self) -> DebugView {
        match self {
            DebugArg::Ambient => DebugView::Ambient,
            DebugArg::Diffuse => DebugView::Diffuse,
            DebugArg::Specular => DebugView::Specular,
            DebugArg::Normals => DebugView::Normals,
            DebugArg::Depth => DebugView::Depth,
        }
    }
}

/// Parses `args` and runs the command; returns the exit code.
pub fn run(args: impl IntoIterator<Item = std::ffi::OsString>) -> i32 {
    RUN_STARTED.get_or_init(Instant::now);
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(error) => {
            let _ = error.print();
            return if error.use_stderr() {
                EXIT_BAD_INPUT
            } else {
                EXIT_OK
            };
        }
    };
    match cli.command {
        Command::Render(args) => {
            exit_on_ctrl_c_after_render_line();
            run_render(&args)
        }
        Command::Check(args) => crate::check::run(&args),
        Command::Watch(args) => crate::watch::run(&args),
        Command::Bench(args) => crate::bench::run(&args),
        Command::Report(args) => crate::report::run(&args),
        Command::Lsp(args) => crate::lsp::run(&args),
    }
}

/// `render`'s Ctrl-C (or SIGTERM): exit 130 at once, except that an output being written is
/// finished and renamed first (no truncated image, no stray temporary file); then one line says
/// which images were written and which was left as it was. (`watch` and `check` have their own
/// handlers: the current render, the finished scenes' report.)
fn exit_on_ctrl_c_after_render_line() {
    let handler = || {
        output::exit_after_writes(130, || {
            let record = render_record();
            if let Some(bar) = &record.bar {
                bar.clear();
            }
            errln!("\n{}", interrupted_render_line(&record));
        })
    };
    if let Err(error) = ctrlc::set_handler(handler) {
        errln!("warning: cannot catch Ctrl-C ({error}); an interrupted write may leave a temporary file");
    }
}

/// Prints the diagnostics of a scene that failed to load, on stderr.
pub fn print_load_error(error: &LoadError) {
    errout!(
        "{}",
        render_diagnostics(&error.diagnostics, &error.sources, use_color())
    );
}

/// Whether diagnostics on stderr should be coloured.
pub fn use_color() -> bool {
    std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none()
}

fn run_render(args: &RenderArgs) -> i32 {
    if args.output.is_some() && args.scenes.len() > 1 {
        errln!(
            "error: --output names one image, but {} scenes were given",
            args.scenes.len()
        );
        return EXIT_BAD_INPUT;
    }
    let (destination, format) =
        match output::choose_format(args.output.as_deref(), args.format.map(FormatArg::format)) {
            Ok(chosen) => chosen,
            Err(message) => {
                errln!("error: {message}");
                return EXIT_BAD_INPUT;
            }
        };
    if destination == Destination::Stdout && std::io::stdout().is_terminal() {
        errln!(
            "error: `-o -` writes the image to standard output, which is a terminal\n  \
             = help: redirect it (`> out.{}`) or pipe it into another program",
            format.extension()
        );
        return EXIT_BAD_INPUT;
    }
    let access = match args.limits.file_access() {
        Ok(access) => access,
        Err(message) => {
            errln!("error: {message}");
            return EXIT_BAD_INPUT;
        }
    };
    let load_options = LoadOptions {
        access,
        max_memory: args.limits.max_memory,
        width: args.width,
        height: args.height,
        samples: args.samples,
        shading: args.shading.map(ShadingArg::shading),
        model: args.model.map(ModelArg::model),
    };
    let render_options = RenderOptions {
        threads: args.threads.map(usize::from),
        debug_view: args.debug.map(DebugArg::debug_view),
    };
    let output_settings = OutputSettings {
        format,
        encoding: match args.encoding {
            EncodingArg::Linear => Encoding::Linear,
            EncodingArg::Srgb => Encoding::Srgb,
        },
    };
    if let Some(pixel) = args.pick {
        return run_pick(args, pixel, &load_options, &render_options, output_settings);
    }
    if let Some(frames) = args.turntable {
        let turntable = TurntableRun {
            frames,
            axis: args.axis.unwrap_or_default(),
            shard: args.shard,
        };
        return run_turntable(
            args,
            &turntable,
            &load_options,
            &render_options,
            output_settings.encoding,
        );
    }
    let mut bad_inputs = Vec::new();
    let mut failed_outputs = 0;
    // Scenes rendered in turn share meshes (a mesh several scenes use is read once) and the
    // renderer's arrays.
    let mut cache = BuildCache::default();
    let mut last_rendered = None;
    let run = RenderRun {
        load_options: &load_options,
        render_options: &render_options,
        output_settings,
        quiet: args.quiet,
        reference: args.reference.map(|geometry| crate::reference::ReferenceOptions {
            threads: render_options.threads,
            geometry: match geometry {
                ReferenceArg::Exact => crate::reference::ReferenceGeometry::Exact,
                ReferenceArg::Mesh => crate::reference::ReferenceGeometry::Mesh,
            },
            samples: args.reference_samples,
            ..crate::reference::ReferenceOptions::default()
        }),
        progress_bar: !args.quiet && crate::progress::progress_allowed(),
    };
    for scene_path in &args.scenes {
        let target = match &destination {
            Destination::Stdout => Target::Stdout,
            Destination::File(Some(path)) => Target::File(path.clone()),
            Destination::File(None) => Target::File(scene_path.with_extension(format.extension())),
        };
        match render_one(scene_path, &target, &run, &mut cache, &mut last_rendered) {
            Ok(()) => {}
            Err(RenderFailure::BadInput) => bad_inputs.push(scene_path),
            Err(RenderFailure::Output) => failed_outputs += 1,
        }
    }
    // The process ends after this command: handing the meshes, the renderer's arrays and the
    // last frame back to the allocator makes mimalloc return them to the kernel page range by
    // page range (about 35 MB for the koala scene, in `madvise` calls) before the exit would
    // free them at once.
    std::mem::forget((cache, last_rendered));
    if args.scenes.len() > 1 && !bad_inputs.is_empty() {
        let names: Vec<String> = bad_inputs.iter().map(|p| p.display().to_string()).collect();
        errln!(
            "error: {} of {} scenes could not be rendered: {}",
            names.len(),
            args.scenes.len(),
            names.join(", ")
        );
    }
    if !bad_inputs.is_empty() {
        EXIT_BAD_INPUT
    } else if failed_outputs > 0 {
        EXIT_OUTPUT_FAILED
    } else {
        EXIT_OK
    }
}

/// `render --pick X,Y SCENE`: the pick JSON on standard output, and the image too when `-o`
/// names one (its summary line is not printed: standard output carries the JSON).
fn run_pick(
    args: &RenderArgs,
    (x, y): (u32, u32),
    load_options: &LoadOptions,
    render_options: &RenderOptions,
    output_settings: OutputSettings,
) -> i32 {
    let [scene_path] = args.scenes.as_slice() else {
        errln!(
            "error: --pick inspects one scene, but {} were given",
            args.scenes.len()
        );
        return EXIT_BAD_INPUT;
    };
    if let Some(output) = &args.output {
        let target = if output.as_os_str() == "-" {
            Target::Stdout
        } else {
            Target::File(output.clone())
        };
        if matches!(target, Target::Stdout) {
            errln!("error: --pick prints JSON on standard output, so the image cannot go there too (`-o -`)");
            return EXIT_BAD_INPUT;
        }
        let run = RenderRun {
            load_options,
            render_options,
            output_settings,
            quiet: true,
            reference: None,
            progress_bar: false,
        };
        match render_one(scene_path, &target, &run, &mut BuildCache::default(), &mut None) {
            Ok(()) => {}
            Err(RenderFailure::BadInput) => return EXIT_BAD_INPUT,
            Err(RenderFailure::Output) => return EXIT_OUTPUT_FAILED,
        }
    }
    let loaded = match crate::scene::load_scene(scene_path, load_options) {
        Ok(loaded) => loaded,
        Err(error) => {
            print_load_error(&error);
            return EXIT_BAD_INPUT;
        }
    };
    // The render for -o is quiet (its summary line would go into the JSON): warnings are said here.
    if !loaded.warnings.is_empty() && !args.quiet {
        errout!(
            "{}",
            render_diagnostics(&loaded.warnings, &loaded.sources, use_color())
        );
    }
    let origin = crate::inspect::ImageOrigin {
        scene: std::sync::Arc::new(loaded.scene),
        sources: std::sync::Arc::new(loaded.sources),
        load_options: load_options.clone(),
        render_options: *render_options,
        encoding: output_settings.encoding,
    };
    match origin.pick(x, y) {
        Ok(report) => {
            outln!("{}", report.to_json_pretty());
            EXIT_OK
        }
        Err(error) => {
            errln!("error: --pick {x},{y}: {error}");
            EXIT_BAD_INPUT
        }
    }
}

enum RenderFailure {
    BadInput,
    Output,
}

/// Where one scene's image goes.
#[derive(Debug, Clone)]
enum Target {
    File(PathBuf),
    Stdout,
}

impl Target {
    fn name(&self) -> String {
        match self {
            Target::File(path) => path.display().to_string(),
            Target::Stdout => "standard output".to_string(),
        }
    }
}

#[derive(Debug, Clone, Copy)]
struct OutputSettings {
    format: OutputFormat,
    encoding: Encoding,
}

/// What `render` does to every scene it is given.
struct RenderRun<'a> {
    load_options: &'a LoadOptions,
    render_options: &'a RenderOptions,
    output_settings: OutputSettings,
    quiet: bool,
    /// `Some` for `--reference`.
    reference: Option<crate::reference::ReferenceOptions>,
    progress_bar: bool,
}

/// What `render` has written so far, for the one line Ctrl-C prints.
#[derive(Default)]
struct RenderRecord {
    written: Vec<String>,
    /// The image being made, and when its scene started (a file modified since was written
    /// whole: Ctrl-C waits for a write under way to be renamed into place).
    current: Option<(PathBuf, SystemTime)>,
    bar: Option<BarClearer>,
}

/// When `run` began: the start of `render`'s timings (`LAMPSHADE_TIMINGS`).
static RUN_STARTED: OnceLock<Instant> = OnceLock::new();

static RENDER_RECORD: Mutex<RenderRecord> = Mutex::new(RenderRecord {
    written: Vec::new(),
    current: None,
    bar: None,
});

fn render_record() -> std::sync::MutexGuard<'static, RenderRecord> {
    RENDER_RECORD
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The line Ctrl-C prints during `render`: what was written and what was left as it was.
fn interrupted_render_line(record: &RenderRecord) -> String {
    let mut written = record.written.clone();
    let mut unfinished = None;
    if let Some((path, started)) = &record.current {
        let modified = std::fs::metadata(path).and_then(|m| m.modified());
        match modified {
            Ok(modified) if modified >= *started => written.push(path.display().to_string()),
            _ => unfinished = Some(path.display().to_string()),
        }
    }
    let written = match written.len() {
        0 => "nothing was written".to_string(),
        1 => format!("`{}` was written", written[0]),
        n => format!("{n} images were written ({})", written.join(", ")),
    };
    match unfinished {
        Some(path) => format!("interrupted: {written}; `{path}` was not written and is left as it was"),
        None => format!("interrupted: {written}"),
    }
}

/// Renders one scene and writes its image; the scene and its frame are left in `last_rendered`
/// (whose previous content is dropped first, so scenes rendered in turn never hold two frames).
fn render_one(
    scene_path: &Path,
    target: &Target,
    run: &RenderRun,
    cache: &mut BuildCache,
    last_rendered: &mut Option<RenderedScene>,
) -> Result<(), RenderFailure> {
    *last_rendered = None;
    let RenderRun {
        load_options,
        render_options,
        output_settings,
        quiet,
        ref reference,
        progress_bar,
    } = *run;
    let timings = timings_requested().then(PhaseClock::now);
    // The scene itself is refused before it is read; the files it reads, once they are known.
    if let Target::File(output_path) = target
        && output::overwritten_input(output_path, [scene_path]).is_some()
    {
        report_overwritten_input(output_path, scene_path, scene_path);
        return Err(RenderFailure::BadInput);
    }
    if let Target::File(output_path) = target {
        render_record().current = Some((output_path.clone(), SystemTime::now()));
    }
    let bar = RenderBar::start(
        scene_path.display().to_string(),
        cache.renderer.progress(),
        progress_bar,
    );
    render_record().bar = Some(bar.clearer());
    let rendered = if let Some(reference) = reference {
        let options = crate::reference::ReferenceOptions {
            progress: Some(cache.renderer.progress()),
            ..reference.clone()
        };
        crate::reference::render_reference_file(scene_path, load_options, &options)
    } else {
        render_scene_file(scene_path, load_options, render_options, cache)
    };
    bar.finish();
    let rendered = match rendered {
        Ok(rendered) => rendered,
        Err(error) => {
            render_record().current = None;
            print_load_error(&error);
            return Err(RenderFailure::BadInput);
        }
    };
    if let Target::File(output_path) = target
        && let Some(input) =
            output::overwritten_input(output_path, rendered.files_read.iter().map(PathBuf::as_path))
    {
        render_record().current = None;
        report_overwritten_input(output_path, input, scene_path);
        return Err(RenderFailure::BadInput);
    }
    if !rendered.warnings.is_empty() && !quiet {
        errout!(
            "{}",
            render_diagnostics(&rendered.warnings, &rendered.sources, use_color())
        );
    }
    let RenderedScene {
        framebuffer,
        stats,
        load_time,
        ..
    } = &rendered;
    let load_time = *load_time;

    let rendered_clock = timings.as_ref().map(|_| PhaseClock::now());
    let started = Instant::now();
    let (format, encoding) = (output_settings.format, output_settings.encoding);
    let written = match target {
        Target::File(path) => {
            output::write_image_timed(path, framebuffer, format, encoding, PngCompression::Fast)
        }
        Target::Stdout => output::write_image_to_stdout(framebuffer, format, encoding, PngCompression::Fast)
            .map(|()| output::WriteTimings::default()),
    };
    {
        let mut record = render_record();
        record.current = None;
        if written.is_ok() {
            record.written.push(target.name());
        }
    }
    let write_timings = match written {
        Ok(write_timings) => write_timings,
        // A reader that went away (`render -o - | head -c 100`) wants no more: not an error.
        Err(output::OutputError::Io { source, .. })
            if matches!(target, Target::Stdout) && source.kind() == std::io::ErrorKind::BrokenPipe =>
        {
            output::WriteTimings::default()
        }
        Err(error) => {
            errln!("error: {error}");
            return Err(RenderFailure::Output);
        }
    };
    let encode_time = started.elapsed();
    if let (Some(start), Some(rendered)) = (timings, rendered_clock) {
        let phases = RenderPhases {
            start,
            rendered,
            written: PhaseClock::now(),
            load: load_time,
            stats,
            write: write_timings,
        };
        errln!("{}", phases.line());
    }
    if !quiet {
        let summary = format!(
            "{} → {}: {} triangles, {}×{} px | load {}, {}geometry {}, raster+shade {}, encode {} ({} threads)",
            scene_path.display(),
            target.name(),
            thousands(stats.triangles),
            framebuffer.width(),
            framebuffer.height(),
            milliseconds(load_time),
            shadow_maps_part(stats),
            milliseconds(stats.geometry),
            milliseconds(stats.raster_shade),
            milliseconds(encode_time),
            stats.threads,
        );
        // Standard output carries the image itself with `-o -`.
        match target {
            Target::File(_) => outln!("{summary}"),
            Target::Stdout => errln!("{summary}"),
        }
    }
    *last_rendered = Some(rendered);
    Ok(())
}

/// `LAMPSHADE_TIMINGS=1` (any value but 0): `render` prints to standard error where each
/// scene's time went, wall clock and CPU time.
fn timings_requested() -> bool {
    std::env::var_os("LAMPSHADE_TIMINGS").is_some_and(|value| value != "0")
}

/// A point in time, by the wall clock and by the CPU time the process has used.
struct PhaseClock {
    wall: Instant,
    cpu: Option<Duration>,
}

impl PhaseClock {
    fn now() -> PhaseClock {
        PhaseClock {
            wall: Instant::now(),
            cpu: crate::cpu_time::process_cpu_time(),
        }
    }
}

/// One scene's render, phase by phase, for `LAMPSHADE_TIMINGS`.
struct RenderPhases<'a> {
    /// When the scene's render began, when its frame was ready, when its image was in place.
    start: PhaseClock,
    rendered: PhaseClock,
    written: PhaseClock,
    load: Duration,
    stats: &'a RenderStats,
    write: output::WriteTimings,
}

impl RenderPhases<'_> {
    /// `timings: before 1.2 ms | load 33.0 ms | shadow maps … | … | CPU load+frame 80.1 ms, output 4.2 ms, process 90.3 ms`.
    fn line(&self) -> String {
        let run_started = *RUN_STARTED.get_or_init(Instant::now);
        let cpu = |from: &PhaseClock, to: &PhaseClock| match (from.cpu, to.cpu) {
            (Some(from), Some(to)) => milliseconds(to.saturating_sub(from)),
            _ => "unknown".to_string(),
        };
        let process_cpu = self.written.cpu.map_or("unknown".to_string(), milliseconds);
        format!(
            "timings: before the scene {} | load {} | {}geometry {}, raster+shade {} | \
             encode {}, write {}, sync {}, rename {} | total {} | \
             CPU: load+frame {}, output {}, process {}",
            milliseconds(self.start.wall - run_started),
            milliseconds(self.load),
            shadow_maps_part(self.stats),
            milliseconds(self.stats.geometry),
            milliseconds(self.stats.raster_shade),
            milliseconds(self.write.encode),
            milliseconds(self.write.write),
            milliseconds(self.write.sync),
            milliseconds(self.write.rename),
            milliseconds(self.written.wall - run_started),
            cpu(&self.start, &self.rendered),
            cpu(&self.rendered, &self.written),
            process_cpu,
        )
    }
}

/// What `render --turntable` was asked for.
struct TurntableRun {
    frames: u32,
    axis: crate::turntable::TurntableAxis,
    shard: Option<crate::check::select::Shard>,
}

/// `render --turntable N`: one scene, its frames to an APNG or to numbered files.
fn run_turntable(
    args: &RenderArgs,
    turntable: &TurntableRun,
    load_options: &LoadOptions,
    render_options: &RenderOptions,
    encoding: Encoding,
) -> i32 {
    use crate::turntable::TurntableOutput;
    let [scene_path] = args.scenes.as_slice() else {
        errln!(
            "error: --turntable renders one scene, but {} were given",
            args.scenes.len()
        );
        return EXIT_BAD_INPUT;
    };
    let destination = match turntable_output(args, scene_path) {
        Ok(destination) => destination,
        Err(message) => {
            errln!("error: {message}");
            return EXIT_BAD_INPUT;
        }
    };
    let outputs: Vec<PathBuf> = match &destination {
        TurntableOutput::Animation(path) => vec![path.clone()],
        TurntableOutput::Numbered(pattern, _) => {
            crate::turntable::frames_to_render(turntable.frames, turntable.shard)
                .into_iter()
                .map(|frame| pattern.path(frame))
                .collect()
        }
    };
    if let TurntableOutput::Animation(_) = destination
        && turntable.shard.is_some()
    {
        errln!(
            "error: --shard splits a turntable into numbered frames; one animated PNG cannot be split\n  \
             = help: give -o a frame pattern, e.g. `-o spin-%03d.png`"
        );
        return EXIT_BAD_INPUT;
    }
    if let Some(output) = outputs
        .iter()
        .find(|output| output::overwritten_input(output, [scene_path.as_path()]).is_some())
    {
        report_overwritten_input(output, scene_path, scene_path);
        return EXIT_BAD_INPUT;
    }
    let started = Instant::now();
    let loaded = match crate::scene::load::load_scene(scene_path, load_options) {
        Ok(loaded) => loaded,
        Err(error) => {
            print_load_error(&error);
            return EXIT_BAD_INPUT;
        }
    };
    let load_time = started.elapsed();
    for output in &outputs {
        if let Some(input) = output::overwritten_input(output, loaded.files_read.iter().map(PathBuf::as_path))
        {
            report_overwritten_input(output, input, scene_path);
            return EXIT_BAD_INPUT;
        }
    }
    if !loaded.warnings.is_empty() && !args.quiet {
        errout!(
            "{}",
            render_diagnostics(&loaded.warnings, &loaded.sources, use_color())
        );
    }
    let axis = turntable.axis.direction(&loaded.scene.camera);
    if let Some(problem) = crate::turntable::orbit_problem(&loaded.scene.camera, axis) {
        errln!("error: {problem}");
        return EXIT_BAD_INPUT;
    }
    let frames = crate::turntable::frames_to_render(turntable.frames, turntable.shard);
    if let TurntableOutput::Animation(path) = &destination {
        render_record().current = Some((path.clone(), SystemTime::now()));
    }
    let orbit = crate::turntable::Orbit {
        axis,
        frame_count: turntable.frames,
        frames: &frames,
    };
    let rendered = crate::turntable::render_turntable(
        &loaded.scene,
        &orbit,
        render_options,
        &destination,
        encoding,
        |path| {
            let mut record = render_record();
            record.current = None;
            record.written.push(path.display().to_string());
        },
    );
    let stats = match rendered {
        Ok(stats) => stats,
        Err(error) => {
            render_record().current = None;
            errln!("error: {error}");
            return EXIT_OUTPUT_FAILED;
        }
    };
    if !args.quiet {
        let target = match &destination {
            TurntableOutput::Animation(path) => format!("{} (animated PNG)", path.display()),
            TurntableOutput::Numbered(..) => match (outputs.first(), outputs.last()) {
                (Some(first), Some(last)) if outputs.len() > 1 => {
                    format!("{} … {}", first.display(), last.display())
                }
                (Some(only), _) => only.display().to_string(),
                _ => String::from("no frames"),
            },
        };
        let of_all = match turntable.shard {
            Some(shard) => format!(" of {} (shard {shard})", turntable.frames),
            None => String::new(),
        };
        outln!(
            "{} → {target}: {} frames{of_all}, {} triangles, {}×{} px | load {}, render {}, encode {} ({} threads)",
            scene_path.display(),
            stats.frames,
            thousands(stats.triangles),
            loaded.scene.image.width,
            loaded.scene.image.height,
            milliseconds(load_time),
            milliseconds(stats.render),
            milliseconds(stats.encode),
            stats.threads,
        );
    }
    EXIT_OK
}

/// Where a turntable goes: an APNG (`-o spin.png`, default `SCENE-turntable.png`) or numbered
/// frames in the pattern's format (`-o spin-%03d.png`, `.exr`, `.hdr`).
fn turntable_output(
    args: &RenderArgs,
    scene_path: &Path,
) -> Result<crate::turntable::TurntableOutput, String> {
    use crate::turntable::{FramePattern, TurntableOutput};
    let Some(output) = &args.output else {
        if args.format.is_some_and(|format| format != FormatArg::Png) {
            return Err(String::from(
                "a turntable is one animated PNG, or numbered frames in any format with -o (e.g. `-o spin-%03d.exr`)",
            ));
        }
        let stem = scene_path.file_stem().unwrap_or_default().to_string_lossy();
        return Ok(TurntableOutput::Animation(
            scene_path.with_file_name(format!("{stem}-turntable.png")),
        ));
    };
    if output.as_os_str() == output::STDOUT_NAME {
        return Err(String::from(
            "--turntable writes files, not standard output: give -o a file (`spin.png`) or a frame pattern (`spin-%03d.png`)",
        ));
    }
    let pattern = FramePattern::parse(output)?;
    let (_, format) = output::choose_format(Some(output), args.format.map(FormatArg::format))?;
    match pattern {
        Some(pattern) => Ok(TurntableOutput::Numbered(pattern, format)),
        None if format == OutputFormat::Png => Ok(TurntableOutput::Animation(output.clone())),
        None => Err(format!(
            "`{}`: a turntable is one animated PNG or numbered frames; for {} frames give a pattern, e.g. `-o spin-%03d.{}`",
            output.display(),
            format.name(),
            format.extension(),
        )),
    }
}

/// Says that `output` is `input`, a file the scene reads, and that nothing was written.
fn report_overwritten_input(output: &Path, input: &Path, scene: &Path) {
    let what = if output::overwritten_input(input, [scene]).is_some() {
        "the scene file itself".to_string()
    } else if input == output {
        format!("a file the scene `{}` reads", scene.display())
    } else {
        format!(
            "`{}`, a file the scene `{}` reads",
            input.display(),
            scene.display()
        )
    };
    errln!(
        "error: the output `{}` is {what}; writing the image there would destroy it, so nothing was written\n  \
         = help: choose another output with -o (e.g. `-o {}`)",
        output.display(),
        suggested_output(scene).display(),
    );
}

/// An output name beside `scene` that is not an input: `NAME.render.png`.
fn suggested_output(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().unwrap_or_default().to_string_lossy();
    scene.with_file_name(format!("{stem}.render.png"))
}

fn milliseconds(duration: Duration) -> String {
    format!("{:.1} ms", duration.as_secs_f64() * 1000.0)
}

/// `shadow maps 12.3 ms, ` when the frame rendered any, for the summary lines.
pub fn shadow_maps_part(stats: &RenderStats) -> String {
    if stats.shadow_faces == 0 {
        String::new()
    } else {
        format!("shadow maps {}, ", milliseconds(stats.shadow_maps))
    }
}

/// `129600` → `129,600`.
pub fn thousands(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thousands_separators() {
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(999), "999");
        assert_eq!(thousands(1000), "1,000");
        assert_eq!(thousands(1_002_528), "1,002,528");
    }
}
