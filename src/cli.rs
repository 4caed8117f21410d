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
use std::time::{Duration, Instant};

use clap::{Parser, Subcommand, ValueEnum};

use crate::diag::render_diagnostics;
use crate::output::{self, Encoding, OutputFormat, PngCompression};
use crate::pipeline::{BuildCache, RenderedScene, render_scene_file};
use crate::render::{DebugView, RenderOptions};
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
    /// Render scene files to PNG images.
    Render(RenderArgs),
    /// Render a suite of scenes and compare each with its reference image.
    Check(crate::check::CheckArgs),
    /// Re-render a scene whenever it, or any file it uses, changes.
    Watch(crate::watch::WatchArgs),
    /// Time frames of scenes per shading mode (loaded once, rendered many times).
    Bench(crate::bench::BenchArgs),
    /// Measurements of the renderer: `report speed-error` (time against error).
    Report(crate::report::ReportArgs),
}

#[derive(Debug, clap::Args)]
pub struct RenderArgs {
    /// Scene files (.ron). Each is rendered in turn; a bad one is reported and the rest still render.
    #[arg(required = true, value_name = "SCENE")]
    pub scenes: Vec<PathBuf>,
    /// Output image (only with a single scene). Default: the scene's path with the format's
    /// extension (`.png` unless --format says otherwise).
    #[arg(short, long, value_name = "OUT.png")]
    pub output: Option<PathBuf>,
    /// Output format: png (8-bit), exr or hdr (linear float, not clamped). Default: from the
    /// output's extension, else png.
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
    #[arg(long)]
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
    /// Render the exact reference instead: analytic shapes ray-cast and lit in f64 (see
    /// `reference`). Mesh files and textures are errors; shadows are ignored.
    #[arg(long, conflicts_with = "debug")]
    pub reference: bool,
    #[command(flatten)]
    pub limits: InputLimits,
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

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FormatArg {
    Png,
    Exr,
    Hdr,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum EncodingArg {
    Linear,
    Srgb,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ShadingArg {
    Flat,
    Gouraud,
    Phong,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ModelArg {
    /// Specular `max(R·V, 0)^n`.
    Phong,
    /// Specular `max(N·H, 0)^n` with the half vector.
    BlinnPhong,
    /// Ambient and diffuse only.
    Lambert,
}

impl ModelArg {
    pub fn model(self) -> LightingModel {
        match self {
            ModelArg::Phong => LightingModel::Phong,
            ModelArg::BlinnPhong => LightingModel::BlinnPhong,
            ModelArg::Lambert => LightingModel::Lambert,
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

/// Parses `args` and runs the command; returns the exit code.
pub fn run(args: impl IntoIterator<Item = std::ffi::OsString>) -> i32 {
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
            exit_on_ctrl_c();
            run_render(&args)
        }
        Command::Check(args) => crate::check::run(&args),
        Command::Watch(args) => crate::watch::run(&args),
        Command::Bench(args) => crate::bench::run(&args),
        Command::Report(args) => crate::report::run(&args),
    }
}

/// Ctrl-C (or SIGTERM) ends `render` with 130 at once, except that an output being written is
/// finished and renamed first: no truncated image and no stray temporary file. (`watch` and
/// `check` have their own handlers: the current render, the finished scenes' report.)
fn exit_on_ctrl_c() {
    if let Err(error) = ctrlc::set_handler(|| output::exit_when_no_write_is_in_progress(130)) {
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
        shading: args.shading.map(|s| match s {
            ShadingArg::Flat => Shading::Flat,
            ShadingArg::Gouraud => Shading::Gouraud,
            ShadingArg::Phong => Shading::Phong,
        }),
        model: args.model.map(ModelArg::model),
    };
    let render_options = RenderOptions {
        threads: args.threads.map(usize::from),
        debug_view: args.debug.map(|d| match d {
            DebugArg::Ambient => DebugView::Ambient,
            DebugArg::Diffuse => DebugView::Diffuse,
            DebugArg::Specular => DebugView::Specular,
            DebugArg::Normals => DebugView::Normals,
            DebugArg::Depth => DebugView::Depth,
        }),
    };
    let format = match (args.format, args.output.as_deref()) {
        (Some(format), _) => match format {
            FormatArg::Png => OutputFormat::Png,
            FormatArg::Exr => OutputFormat::Exr,
            FormatArg::Hdr => OutputFormat::Hdr,
        },
        (None, Some(output)) => match OutputFormat::from_path(output) {
            Some(format) => format,
            None => {
                errln!(
                    "error: cannot tell the format of `{}` from its extension; use .png, .exr or .hdr, or --format",
                    output.display()
                );
                return EXIT_BAD_INPUT;
            }
        },
        (None, None) => OutputFormat::Png,
    };
    let output_settings = OutputSettings {
        format,
        encoding: match args.encoding {
            EncodingArg::Linear => Encoding::Linear,
            EncodingArg::Srgb => Encoding::Srgb,
        },
    };
    let mut bad_inputs = Vec::new();
    let mut failed_outputs = 0;
    // Scenes rendered in turn share meshes (a mesh several scenes use is read once) and the
    // renderer's arrays.
    let mut cache = BuildCache::default();
    let run = RenderRun {
        load_options: &load_options,
        render_options: &render_options,
        output_settings,
        quiet: args.quiet,
        reference: args.reference,
    };
    for scene_path in &args.scenes {
        let output = args
            .output
            .clone()
            .unwrap_or_else(|| scene_path.with_extension(format.extension()));
        match render_one(scene_path, &output, &run, &mut cache) {
            Ok(()) => {}
            Err(RenderFailure::BadInput) => bad_inputs.push(scene_path),
            Err(RenderFailure::Output) => failed_outputs += 1,
        }
    }
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

enum RenderFailure {
    BadInput,
    Output,
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
    reference: bool,
}

fn render_one(
    scene_path: &Path,
    output_path: &Path,
    run: &RenderRun,
    cache: &mut BuildCache,
) -> Result<(), RenderFailure> {
    let RenderRun {
        load_options,
        render_options,
        output_settings,
        quiet,
        reference,
    } = *run;
    let rendered = if reference {
        crate::reference::render_reference_file(scene_path, load_options, render_options.threads)
    } else {
        render_scene_file(scene_path, load_options, render_options, cache)
    };
    let rendered = match rendered {
        Ok(rendered) => rendered,
        Err(error) => {
            print_load_error(&error);
            return Err(RenderFailure::BadInput);
        }
    };
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
    } = rendered;

    let started = Instant::now();
    let written = output::write_image(
        output_path,
        &framebuffer,
        output_settings.format,
        output_settings.encoding,
        PngCompression::Fast,
    );
    if let Err(error) = written {
        errln!("error: {error}");
        return Err(RenderFailure::Output);
    }
    let encode_time = started.elapsed();
    if !quiet {
        outln!(
            "{} → {}: {} triangles, {}×{} px | load {}, geometry {}, raster+shade {}, encode {} ({} threads)",
            scene_path.display(),
            output_path.display(),
            thousands(stats.triangles),
            framebuffer.width,
            framebuffer.height,
            milliseconds(load_time),
            milliseconds(stats.geometry),
            milliseconds(stats.raster_shade),
            milliseconds(encode_time),
            stats.threads,
        );
    }
    Ok(())
}

fn milliseconds(duration: Duration) -> String {
    format!("{:.1} ms", duration.as_secs_f64() * 1000.0)
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
