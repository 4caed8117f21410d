//! `lampshade check`: render a suite of scenes and compare each with its reference image, the
//! way CI runs image regression tests.
//!
//! ```text
//! arguments ─► suite::discover ─► select (--filter, --shard) ─► runner::run_scenes ─► console
//!  (a plan)    scenes, references,                                 (rayon, per scene:       lines, bar
//!              tolerances (configs)                                 load, render, compare,  junit, report
//!                                                                   bless or pictures)      exit code
//! ```
//!
//! The stages, one module each:
//! - [`suite`]: which files are scenes, where their references are (`DIR/refs/NAME.png`), and
//!   what tolerance each gets ([`config`]: `lampshade-check.ron`).
//! - [`select`]: `--filter` and `--shard K/N` (a fixed hash of the scene's name).
//! - [`runner`]: one scene through the same load+render build as `render`
//!   ([`crate::pipeline`]), then [`compare`]; scenes in parallel on one rayon pool.
//! - [`console`], [`junit`], [`report`]: what people and CI systems see.
//!
//! Exit codes (2 wins over 1, 101 over both):
//! - `0`: every scene selected rendered and matched its reference (or was blessed).
//! - `1`: a scene differs beyond its tolerance, has no reference, or its reference cannot be
//!   read or has another size.
//! - `2`: the suite could not be checked as asked: a scene could not be rendered (its
//!   diagnostics are printed; the other scenes still run), bad arguments, a path that does not
//!   exist, a bad `lampshade-check.ron`, no scenes found, or a reference, report or JUnit file
//!   that could not be written.
//! - `101`: a bug in lampshade (a panic), after the other scenes ran.
//! - `130`: interrupted by Ctrl-C (or SIGTERM). No scene starts after the first Ctrl-C; the
//!   scenes that finished are reported as usual (lines, summary, JUnit file, HTML report),
//!   those not run or still under way as not run, and one line says what was kept. A second
//!   Ctrl-C exits at once. Either way a file being written is finished and renamed first.
//!
//! Architecture invariants:
//! - A reference is only ever written by `--bless`, and only for a scene that was run (after
//!   `--filter` and `--shard`) and rendered: a missing reference is a failure, never filled in.
//! - Output does not depend on scheduling: scenes are sorted by path and reported in that
//!   order whatever order they finish in; rendering itself is bit-identical for any thread
//!   count.
//! - `check` never writes next to the scenes except references under `--bless`; report
//!   pictures go to the `--report` folder only.
//! - A report holds one run: the pictures an earlier report wrote into `DIR/images/` are
//!   removed before the scenes run (only files named the way reports name them, so a person's
//!   own files there stay).
//!
//! Rejected: running the suite as `cargo test` cases (users of lampshade have no Cargo
//! project); writing a missing reference on first run (an unreviewed image would become the
//! truth); stopping at the first bad scene by default (one typo would hide every other
//! result).

pub mod compare;
pub mod config;
pub mod console;
pub mod escape;
pub mod junit;
pub mod report;
pub mod runner;
pub mod select;
pub mod suite;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use crate::check::compare::FLIP_AVAILABLE;
use crate::check::console::Console;
use crate::check::runner::{RunOptions, SceneResult, SceneStatus, StopReason, Tally, run_scenes};
use crate::check::select::{NameFilter, Shard};
use crate::check::suite::{SuiteScene, discover};
use crate::cli::{EXIT_BAD_INPUT, EXIT_INTERNAL_ERROR, EXIT_OK, use_color};
use crate::diag::render_diagnostics;

/// Some scene differs from its reference (or has none).
pub const EXIT_MISMATCH: i32 = 1;

/// Interrupted by Ctrl-C (128 + SIGINT, the shell's convention).
pub const EXIT_INTERRUPTED: i32 = 130;

/// The suite checked when no path is given.
pub const DEFAULT_SUITE: &str = "scenes";

/// Arguments of `lampshade check`.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct CheckArgs {
    /// Scene files, or folders searched recursively for `*.ron` scenes (skipping `refs/`
    /// folders, hidden files and material libraries). Default: `scenes/`.
    #[arg(value_name = "PATH")]
    pub paths: Vec<PathBuf>,
    /// Write the reference image (`DIR/refs/NAME.png`) of every scene that was run and
    /// renders differently from it, or has none. Look at the images first.
    #[arg(long, visible_alias = "update")]
    pub bless: bool,
    /// Only scenes whose name or path contains PATTERN; with `*` (not crossing `/`), `**` or
    /// `?`, a glob matching the whole name or path. Repeat to take scenes matching any.
    #[arg(long, value_name = "PATTERN")]
    pub filter: Vec<String>,
    /// Only the K-th of N parts of the suite (1 ≤ K ≤ N), chosen by a fixed hash of each
    /// scene's name: N jobs with K = 1..N check every scene exactly once.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<Shard>,
    /// Worker threads, shared by scenes and by the tiles within a scene (default: one per core).
    #[arg(short, long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    pub jobs: Option<u16>,
    /// Start no more scenes after the first failure or error.
    #[arg(long)]
    pub fail_fast: bool,
    /// Write an HTML report into DIR: `index.html`, failures first with the expected, actual
    /// and difference images side by side (in `DIR/images/`).
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Write the results as JUnit XML to FILE, for CI systems.
    #[arg(long, value_name = "FILE")]
    pub junit: Option<PathBuf>,
    /// Also compare with FLIP, NVIDIA's perceptual metric: its mean and 99th percentile must
    /// stay within the tolerance too.
    #[arg(long)]
    pub flip: bool,
    /// Print where the time went: load, render, quantize, decode, compare, encode.
    #[arg(long)]
    pub timings: bool,
    /// Print only failures, errors and the final counts.
    #[arg(short, long)]
    pub quiet: bool,
    #[command(flatten)]
    pub limits: crate::cli::InputLimits,
}

/// Runs `lampshade check`; returns the exit code.
pub fn run(args: &CheckArgs) -> i32 {
    let started = Instant::now();
    if args.flip && !FLIP_AVAILABLE {
        errln!(
            "error: --flip needs FLIP, and this lampshade was built without it \
             (rebuild with the `flip` feature, which needs a C++ compiler)"
        );
        return EXIT_BAD_INPUT;
    }
    let paths = if args.paths.is_empty() {
        if !Path::new(DEFAULT_SUITE).is_dir() {
            errln!("error: no PATH given, and there is no `{DEFAULT_SUITE}/` folder here to check");
            return EXIT_BAD_INPUT;
        }
        vec![PathBuf::from(DEFAULT_SUITE)]
    } else {
        args.paths.clone()
    };

    let all_scenes = match discover(&paths) {
        Ok(scenes) => scenes,
        Err(problems) => {
            errout!(
                "{}",
                render_diagnostics(&problems.diagnostics, &problems.sources, use_color())
            );
            errln!("error: the suite could not be read; no scene was checked");
            return EXIT_BAD_INPUT;
        }
    };
    let discovery_time = started.elapsed();
    let shown_paths: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    if all_scenes.is_empty() {
        errln!("error: no scene files (*.ron) in {}", shown_paths.join(", "));
        return EXIT_BAD_INPUT;
    }
    let filter = NameFilter::new(&args.filter);
    let filtered: Vec<SuiteScene> = all_scenes
        .iter()
        .filter(|scene| filter.matches(&scene.name, &scene.path.display().to_string()))
        .cloned()
        .collect();
    if filtered.is_empty() {
        errln!(
            "error: no scene matches --filter {} (of {} scenes found)",
            args.filter.join(", "),
            all_scenes.len()
        );
        return EXIT_BAD_INPUT;
    }
    let scenes: Vec<SuiteScene> = match args.shard {
        Some(shard) => filtered
            .into_iter()
            .filter(|scene| shard.contains(&scene.name))
            .collect(),
        None => filtered,
    };

    let pictures = args
        .report
        .as_ref()
        .map(|folder| folder.join(report::PICTURE_FOLDER));
    if let Some(folder) = &pictures {
        if let Err(error) = report::remove_old_pictures(folder) {
            errln!("error: {error}");
            return EXIT_BAD_INPUT;
        }
        if let Err(error) = std::fs::create_dir_all(folder) {
            errln!(
                "error: cannot create the report folder `{}`: {error}",
                folder.display()
            );
            return EXIT_BAD_INPUT;
        }
    }
    let interrupted = Arc::new(AtomicBool::new(false));
    let options = RunOptions {
        interrupted: Arc::clone(&interrupted),
        bless: args.bless,
        flip: args.flip,
        pictures,
        fail_fast: args.fail_fast,
        load_options: match args.limits.load_options() {
            Ok(options) => options,
            Err(message) => {
                errln!("error: {message}");
                return EXIT_BAD_INPUT;
            }
        },
    };
    let pool = match rayon::ThreadPoolBuilder::new()
        .num_threads(args.jobs.map_or(0, usize::from))
        .build()
    {
        Ok(pool) => pool,
        Err(error) => {
            errln!("error: cannot start worker threads: {error}");
            return EXIT_BAD_INPUT;
        }
    };
    let pool = Arc::new(pool);
    let workers = pool.current_num_threads();

    if let Err(error) = stop_on_ctrl_c(Arc::clone(&interrupted)) {
        errln!("warning: cannot catch Ctrl-C ({error}); it will end the run without a summary");
    }
    let mut console = Console::new(scenes.len(), args.quiet);
    let results = run_scenes(&scenes, &options, &pool, &mut console);
    console.finish();
    let elapsed = started.elapsed();
    let was_interrupted = interrupted.load(Ordering::Relaxed);

    let tally = Tally::of(&results);
    let stopped_by = if was_interrupted {
        StopReason::Interrupted
    } else {
        StopReason::FailFast
    };
    let summary = summary_line(
        &tally,
        stopped_by,
        scenes.len(),
        all_scenes.len(),
        args.shard,
        elapsed,
    );
    let mut exit_code = exit_code(&results);
    let mut kept = Vec::new();
    // The JUnit file and the report never replace a scene or a file a scene read.
    let inputs: Vec<&Path> = scenes
        .iter()
        .map(|scene| scene.path.as_path())
        .chain(
            results
                .iter()
                .flat_map(|result| result.inputs.iter().map(PathBuf::as_path)),
        )
        .collect();
    let refuse_input = |output: &Path| -> bool {
        match crate::output::overwritten_input(output, inputs.iter().copied()) {
            Some(input) => {
                errln!(
                    "error: not writing `{}`: it is `{}`, a file the suite reads\n  = help: choose another path",
                    output.display(),
                    input.display()
                );
                true
            }
            None => false,
        }
    };
    let junit_file = args.junit.as_ref().filter(|file| !refuse_input(file));
    let report_folder = args
        .report
        .as_ref()
        .filter(|folder| !refuse_input(&folder.join("index.html")));
    if (args.junit.is_some() && junit_file.is_none()) || (args.report.is_some() && report_folder.is_none()) {
        exit_code = exit_code.max(EXIT_BAD_INPUT);
    }
    if let Some(file) = junit_file {
        let title = match args.shard {
            Some(shard) => format!("lampshade check {} (shard {shard})", shown_paths.join(" ")),
            None => format!("lampshade check {}", shown_paths.join(" ")),
        };
        let xml = junit::junit_xml(&scenes, &results, &title, elapsed);
        match write_text(file, &xml) {
            Ok(()) => kept.push(format!("the JUnit file `{}`", file.display())),
            Err(error) => {
                errln!("error: {error}");
                exit_code = exit_code.max(EXIT_BAD_INPUT);
            }
        }
    }
    if let Some(folder) = report_folder {
        let images = folder.join(report::PICTURE_FOLDER);
        let html = report::report_html(&scenes, &results, &summary, &|file| {
            std::fs::read(images.join(file)).ok()
        });
        let index = folder.join("index.html");
        match report::write_report(folder, &html) {
            Ok(()) => {
                outln!("report: {}", index.display());
                kept.push(format!("the report `{}`", index.display()));
            }
            Err(error) => {
                errln!("error: {error}");
                exit_code = exit_code.max(EXIT_BAD_INPUT);
            }
        }
    }
    if results.iter().any(|result| result.picture_error.is_some()) {
        exit_code = exit_code.max(EXIT_BAD_INPUT);
    }
    if args.timings {
        out!(
            "{}",
            timings_table(&scenes, &results, discovery_time, elapsed, workers)
        );
    }
    if tally.failed > 0 && !args.bless {
        let report_hint = if args.report.is_none() {
            "see the differences with --report DIR; "
        } else {
            ""
        };
        outln!("hint: {report_hint}if the new images are right, make them the references with --bless");
    }
    outln!("{summary}");
    if was_interrupted {
        let finished = scenes.len() - tally.not_run;
        let mut line = format!(
            "interrupted: kept the results of the {finished} {} that finished",
            if finished == 1 { "scene" } else { "scenes" }
        );
        if !kept.is_empty() {
            line.push_str(&format!(" in {}", kept.join(" and ")));
        }
        errln!("{line}");
        // Scenes still under way may be writing report pictures: let those finish, then end
        // here, without waiting for their renders.
        crate::output::exit_when_no_write_is_in_progress(EXIT_INTERRUPTED);
    }
    exit_code
}

/// On the first Ctrl-C (or SIGTERM) sets `interrupted`: the run starts no more scenes and
/// reports those that finished. A second one exits at once.
fn stop_on_ctrl_c(interrupted: Arc<AtomicBool>) -> Result<(), ctrlc::Error> {
    ctrlc::set_handler(move || {
        if interrupted.swap(true, Ordering::Relaxed) {
            crate::output::exit_when_no_write_is_in_progress(EXIT_INTERRUPTED);
        }
    })
}

/// 101 for a bug, else 2 for a scene that could not be checked, else 1 for a mismatch, else 0.
fn exit_code(results: &[SceneResult]) -> i32 {
    use crate::check::runner::SceneError;
    results
        .iter()
        .map(|result| match &result.status {
            SceneStatus::Errored(SceneError::Internal(_)) => EXIT_INTERNAL_ERROR,
            SceneStatus::Errored(_) => EXIT_BAD_INPUT,
            SceneStatus::Failed(_) => EXIT_MISMATCH,
            SceneStatus::Passed(_) | SceneStatus::Blessed(_) | SceneStatus::NotRun(_) => EXIT_OK,
        })
        .max()
        .unwrap_or(EXIT_OK)
}

/// `check: 11 passed, 1 failed, 0 errored — 12 scenes in 0.41 s`, with blessed, not-run and
/// shard counts when there are any.
fn summary_line(
    tally: &Tally,
    stopped_by: StopReason,
    selected: usize,
    found: usize,
    shard: Option<Shard>,
    elapsed: Duration,
) -> String {
    let mut line = format!(
        "check: {} passed, {} failed, {} errored",
        tally.passed, tally.failed, tally.errored
    );
    if tally.blessed > 0 {
        line.push_str(&format!(", {} blessed", tally.blessed));
    }
    if tally.not_run > 0 {
        let why = match stopped_by {
            StopReason::FailFast => "--fail-fast",
            StopReason::Interrupted => "interrupted",
        };
        line.push_str(&format!(", {} not run ({why})", tally.not_run));
    }
    let scenes = if selected == 1 { "scene" } else { "scenes" };
    line.push_str(&format!(" — {selected} {scenes}"));
    if let Some(shard) = shard {
        line.push_str(&format!(" in shard {shard}"));
    }
    if selected != found {
        line.push_str(&format!(" of {found} found"));
    }
    line.push_str(&format!(" in {:.2} s", elapsed.as_secs_f64()));
    line
}

/// `--timings`: throughput, the time per phase summed over scenes, and the slowest scenes.
fn timings_table(
    scenes: &[SuiteScene],
    results: &[SceneResult],
    discovery: Duration,
    elapsed: Duration,
    workers: usize,
) -> String {
    let ran: Vec<(&SuiteScene, &SceneResult)> = scenes
        .iter()
        .zip(results)
        .filter(|(_, result)| !matches!(result.status, SceneStatus::NotRun(_)))
        .collect();
    let mut out = format!(
        "timings: {} scenes in {:.3} s wall ({:.1} scenes/s) on {workers} worker {}; \
         finding the suite took {:.1} ms\n",
        ran.len(),
        elapsed.as_secs_f64(),
        ran.len() as f64 / elapsed.as_secs_f64().max(1e-9),
        if workers == 1 { "thread" } else { "threads" },
        discovery.as_secs_f64() * 1000.0
    );
    let mut totals = runner::PhaseTimes::default();
    for (_, result) in &ran {
        let t = &result.times;
        totals.load += t.load;
        totals.render += t.render;
        totals.quantize += t.quantize;
        totals.decode += t.decode;
        totals.compare += t.compare;
        totals.encode += t.encode;
    }
    let sum = totals.total().as_secs_f64().max(1e-9);
    out.push_str("  phase      summed over scenes   share\n");
    for (name, time) in totals.phases() {
        out.push_str(&format!(
            "  {name:<9} {:>12.1} ms {:>12.1}%\n",
            time.as_secs_f64() * 1000.0,
            time.as_secs_f64() / sum * 100.0
        ));
    }
    if workers > 1 {
        // While a scene's render waits for its tiles, its thread may run another scene's work
        // (rayon steals it), and that time counts in the waiting scene's phase too.
        out.push_str(&format!(
            "  (summed over scenes in parallel, {:.1} ms in all, more than the wall time; a thread \
             waiting for tiles may run other scenes' work meanwhile, so use --jobs 1 for exact \
             shares)\n",
            sum * 1000.0
        ));
    }
    let mut slowest = ran.clone();
    slowest.sort_by_key(|(_, result)| std::cmp::Reverse(result.times.total()));
    let names: Vec<String> = slowest
        .iter()
        .take(5)
        .map(|(scene, result)| {
            format!(
                "{} {:.1} ms",
                scene.name,
                result.times.total().as_secs_f64() * 1000.0
            )
        })
        .collect();
    out.push_str(&format!("  slowest: {}\n", names.join(", ")));
    out
}

/// Writes `text` to `path` atomically, creating its folder.
fn write_text(path: &Path, text: &str) -> Result<(), crate::output::OutputError> {
    use std::io::Write as _;
    let io_error = |source| crate::output::OutputError::Io {
        path: path.to_path_buf(),
        source,
    };
    if let Some(folder) = path.parent().filter(|folder| !folder.as_os_str().is_empty()) {
        std::fs::create_dir_all(folder).map_err(io_error)?;
    }
    crate::output::write_atomically(path, |writer| writer.write_all(text.as_bytes()).map_err(io_error))
}
