//! Running a suite: each scene loaded, rendered and compared on its own ([`check_scene`]),
//! scenes in parallel ([`run_scenes`]).
//!
//! One scene: load and render through [`render_scene_file`] (the build `render` and `watch`
//! use), quantise with [`to_rgb8`] (the bytes `render` would write), decode the reference,
//! compare; then, when asked, bless the reference or write the report's pictures. Every
//! phase is timed for `--timings`.
//!
//! Parallelism: one rayon pool of `--jobs` threads runs scenes with `par_iter`, and each
//! render's own tile and vertex loops run in the same pool, so a thread that finishes a small
//! scene steals tiles from a big one instead of idling. Results reach the caller's
//! [`RunObserver`] twice: in completion order (for a progress bar) and in suite order (for
//! everything printed), so the output is the same whatever the scheduling.
//!
//! A panic while checking a scene (a bug in lampshade) is caught and becomes that scene's
//! [`SceneError::Internal`]; the other scenes still run.
//!
//! Interruption ([`RunOptions::interrupted`], set by Ctrl-C): no scene starts after it, and
//! [`run_scenes`] returns at once with the results it has, the rest [`SceneStatus::NotRun`],
//! without waiting for the scenes under way (a render cannot be cancelled, and a big one would
//! hold the report back for as long as it takes). So the scenes run on a detached thread that
//! owns what it needs; the caller exits soon after, through
//! [`crate::output::exit_when_no_write_is_in_progress`], so a picture being written is still
//! renamed into place.
//!
//! Rejected: one process per scene (cannot share the thread pool, and pays start-up per
//! scene); a pool of scene workers each rendering single-threaded (a suite with one big scene
//! and many small ones would leave cores idle at the end).

use std::io::Write as _;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, mpsc};
use std::time::{Duration, Instant};

use image::RgbImage;
use rayon::prelude::*;

use crate::check::compare::{self, Comparison, SizeMismatch};
use crate::check::suite::SuiteScene;
use crate::output::{self, OutputError, PngCompression, to_rgb8, write_png};
use crate::pipeline::{BuildCache, render_scene_file};
use crate::render::RenderOptions;
use crate::scene::load::{LoadError, LoadOptions};

/// What a run does besides comparing.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Write the reference of every scene that was run and differs from it at all.
    pub bless: bool,
    /// Compute FLIP as well (needs [`compare::FLIP_AVAILABLE`]).
    pub flip: bool,
    /// Write the pictures of every failing scene into this folder (the report's `images/`).
    pub pictures: Option<PathBuf>,
    /// Stop starting scenes after the first failure or error.
    pub fail_fast: bool,
    /// `--sandbox` and `--max-memory`.
    pub load_options: LoadOptions,
    /// Set by Ctrl-C: start no more scenes, and stop waiting for those under way.
    pub interrupted: Arc<AtomicBool>,
}

/// Where one scene's time went.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PhaseTimes {
    /// Reading, parsing and checking the scene, and loading its meshes.
    pub load: Duration,
    /// Geometry, rasterizing and shading.
    pub render: Duration,
    /// Linear light to 8-bit pixels.
    pub quantize: Duration,
    /// Reading and decoding the reference PNG.
    pub decode: Duration,
    /// The pixel test, and FLIP when asked.
    pub compare: Duration,
    /// Encoding and writing PNGs: blessed references and report pictures.
    pub encode: Duration,
}

impl PhaseTimes {
    /// The phases by name, in pipeline order.
    pub fn phases(&self) -> [(&'static str, Duration); 6] {
        [
            ("load", self.load),
            ("render", self.render),
            ("quantize", self.quantize),
            ("decode", self.decode),
            ("compare", self.compare),
            ("encode", self.encode),
        ]
    }

    pub fn total(&self) -> Duration {
        self.phases().iter().map(|(_, time)| *time).sum()
    }
}

/// The outcome of one scene.
#[derive(Debug)]
pub struct SceneResult {
    pub status: SceneStatus,
    pub times: PhaseTimes,
    /// The pictures written for the report, by file name in [`RunOptions::pictures`].
    pub pictures: Pictures,
    /// A report picture that could not be written (the run then exits with 2).
    pub picture_error: Option<String>,
    /// Every file the scene's build read (empty when it did not load): nothing the run writes
    /// may replace one of them.
    pub inputs: Vec<PathBuf>,
}

#[derive(Debug)]
pub enum SceneStatus {
    /// Within tolerance (with `--bless`: identical, so the reference was left alone).
    Passed(Comparison),
    Failed(Failure),
    /// `--bless` wrote the reference; the text says why (new, or what changed).
    Blessed(String),
    /// The scene could not be checked.
    Errored(SceneError),
    /// Not run, or not finished when the run was interrupted.
    NotRun(StopReason),
}

/// Why a scene was not run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// `--fail-fast`, after an earlier failure.
    FailFast,
    /// Ctrl-C (or SIGTERM) before the scene finished.
    Interrupted,
}

impl StopReason {
    /// "--fail-fast stopped the run", for a sentence starting "not run: ".
    pub fn describe(self) -> &'static str {
        match self {
            StopReason::FailFast => "--fail-fast stopped the run",
            StopReason::Interrupted => "the run was interrupted (Ctrl-C)",
        }
    }
}

/// Why a scene that rendered does not pass.
#[derive(Debug, Clone)]
pub enum Failure {
    MissingReference,
    UnreadableReference(String),
    SizeMismatch(SizeMismatch),
    /// Beyond tolerance; one text per limit broken.
    Mismatch {
        comparison: Comparison,
        violations: Vec<String>,
    },
}

/// Why a scene could not be checked.
#[derive(Debug)]
pub enum SceneError {
    /// The scene file or a file it uses has errors.
    Load(Box<LoadError>),
    /// `--bless` could not write the reference.
    WriteReference(String),
    /// A bug in lampshade: a panic while checking this scene.
    Internal(String),
}

/// Report pictures, as file names inside [`RunOptions::pictures`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Pictures {
    pub expected: Option<String>,
    pub actual: Option<String>,
    pub difference: Option<String>,
    pub flip: Option<String>,
}

/// How many scenes ended which way.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Tally {
    pub passed: usize,
    pub failed: usize,
    pub errored: usize,
    pub blessed: usize,
    pub not_run: usize,
}

impl Tally {
    pub fn of<'a>(results: impl IntoIterator<Item = &'a SceneResult>) -> Self {
        let mut tally = Tally::default();
        for result in results {
            match result.status {
                SceneStatus::Passed(_) => tally.passed += 1,
                SceneStatus::Failed(_) => tally.failed += 1,
                SceneStatus::Errored(_) => tally.errored += 1,
                SceneStatus::Blessed(_) => tally.blessed += 1,
                SceneStatus::NotRun(_) => tally.not_run += 1,
            }
        }
        tally
    }
}

impl SceneResult {
    fn new(status: SceneStatus, times: PhaseTimes) -> Self {
        SceneResult {
            status,
            times,
            pictures: Pictures::default(),
            picture_error: None,
            inputs: Vec::new(),
        }
    }

    /// Whether this scene stops a `--fail-fast` run.
    pub fn is_problem(&self) -> bool {
        matches!(self.status, SceneStatus::Failed(_) | SceneStatus::Errored(_))
    }

    /// The comparison, when one was made.
    pub fn comparison(&self) -> Option<&Comparison> {
        match &self.status {
            SceneStatus::Passed(comparison) | SceneStatus::Failed(Failure::Mismatch { comparison, .. }) => {
                Some(comparison)
            }
            _ => None,
        }
    }
}

impl Failure {
    /// One line for a person: what is wrong, and what to do when it says so.
    pub fn describe(&self, scene: &SuiteScene) -> String {
        match self {
            Failure::MissingReference => format!(
                "no reference image `{}`: look at the render, then run with --bless to make it the reference",
                scene.reference.display()
            ),
            Failure::UnreadableReference(error) => {
                format!(
                    "cannot read the reference `{}`: {error}",
                    scene.reference.display()
                )
            }
            Failure::SizeMismatch(mismatch) => mismatch.to_string(),
            Failure::Mismatch { violations, .. } => violations.join("; "),
        }
    }
}

impl SceneError {
    /// One line for a person; a load error's diagnostics are printed separately.
    pub fn describe(&self) -> String {
        match self {
            SceneError::Load(error) => {
                let count = error.diagnostics.iter().filter(|d| d.is_error()).count();
                match count {
                    1 => "the scene could not be rendered (1 error)".to_owned(),
                    n => format!("the scene could not be rendered ({n} errors)"),
                }
            }
            SceneError::WriteReference(error) => format!("cannot bless: {error}"),
            SceneError::Internal(message) => {
                format!("internal error (a bug in lampshade, please report it): {message}")
            }
        }
    }
}

/// Loads, renders and compares one scene, and blesses it or writes its report pictures as
/// `options` ask. `index` numbers the pictures' file names.
pub fn check_scene(scene: &SuiteScene, index: usize, options: &RunOptions) -> SceneResult {
    let mut times = PhaseTimes::default();
    let started = Instant::now();
    let rendered = match render_scene_file(
        &scene.path,
        &options.load_options,
        &RenderOptions::default(),
        &mut BuildCache::default(),
    ) {
        Ok(rendered) => rendered,
        Err(error) => {
            times.load = started.elapsed();
            return SceneResult::new(SceneStatus::Errored(SceneError::Load(Box::new(error))), times);
        }
    };
    times.load = rendered.load_time;
    times.render = started.elapsed().saturating_sub(rendered.load_time);
    let inputs = rendered.files_read.clone();

    let phase = Instant::now();
    let actual = to_rgb8(&rendered.framebuffer);
    drop(rendered);
    times.quantize = phase.elapsed();

    let phase = Instant::now();
    let reference = read_reference(&scene.reference);
    times.decode = phase.elapsed();

    let phase = Instant::now();
    let (compared, flip_map) = match &reference {
        Ok((_, expected)) => match compare::compare_pixels(expected, &actual, &scene.tolerance) {
            Ok(mut comparison) => {
                let flip = if options.flip {
                    compare::flip(expected, &actual)
                } else {
                    None
                };
                comparison.flip = flip.as_ref().map(|(score, _)| *score);
                (Ok(comparison), flip.map(|(_, map)| map))
            }
            Err(mismatch) => (Err(Failure::SizeMismatch(mismatch)), None),
        },
        Err(failure) => (Err(failure.clone()), None),
    };
    times.compare = phase.elapsed();

    let phase = Instant::now();
    if options.bless {
        let mut result = bless(scene, &actual, compared, times, &inputs);
        result.times.encode = phase.elapsed();
        result.inputs = inputs;
        return result;
    }
    let status = match compared {
        Ok(comparison) => {
            let violations = comparison.violations(&scene.tolerance);
            if violations.is_empty() {
                SceneStatus::Passed(comparison)
            } else {
                SceneStatus::Failed(Failure::Mismatch {
                    comparison,
                    violations,
                })
            }
        }
        Err(failure) => SceneStatus::Failed(failure),
    };
    let mut result = SceneResult::new(status, times);
    result.inputs = inputs;
    if let (Some(folder), SceneStatus::Failed(_)) = (&options.pictures, &result.status) {
        let expected = reference.as_ref().ok();
        let difference = expected
            .filter(|(_, expected)| expected.dimensions() == actual.dimensions())
            .map(|(_, expected)| {
                compare::heat_map(expected, &actual, scene.tolerance.max_channel_difference)
            });
        let pictures = PicturesToWrite {
            expected: expected.map(|(bytes, _)| bytes),
            actual: &actual,
            difference: difference.as_ref(),
            flip: flip_map.as_ref(),
        };
        write_pictures(&mut result, folder, index, &scene.name, pictures);
    }
    result.times.encode = phase.elapsed();
    result
}

/// `--bless`: writes the reference unless it holds exactly these pixels already.
fn bless(
    scene: &SuiteScene,
    actual: &RgbImage,
    compared: Result<Comparison, Failure>,
    times: PhaseTimes,
    inputs: &[PathBuf],
) -> SceneResult {
    // A scene that reads its own reference (as a texture, say) must not have it replaced.
    if let Some(input) = output::overwritten_input(&scene.reference, inputs.iter().map(PathBuf::as_path)) {
        let error = OutputError::WouldReplaceInput {
            path: scene.reference.clone(),
            input: input.to_path_buf(),
        };
        return SceneResult::new(
            SceneStatus::Errored(SceneError::WriteReference(error.to_string())),
            times,
        );
    }
    let reason = match compared {
        Ok(comparison) if comparison.is_identical() => {
            return SceneResult::new(SceneStatus::Passed(comparison), times);
        }
        Ok(comparison) => {
            let violations = comparison.violations(&scene.tolerance);
            if violations.is_empty() {
                format!(
                    "replaced: within tolerance, but up to {} levels off",
                    comparison.largest_difference
                )
            } else {
                format!("replaced: {}", violations.join("; "))
            }
        }
        Err(Failure::MissingReference) => "new reference".to_owned(),
        Err(failure) => format!("replaced: {}", failure.describe(scene)),
    };
    let written = scene
        .reference
        .parent()
        .filter(|folder| !folder.as_os_str().is_empty())
        .map_or(Ok(()), std::fs::create_dir_all)
        .map_err(|source| OutputError::Io {
            path: scene.reference.clone(),
            source,
        })
        .and_then(|()| write_png(&scene.reference, actual, PngCompression::Best));
    let status = match written {
        Ok(()) => SceneStatus::Blessed(reason),
        Err(error) => SceneStatus::Errored(SceneError::WriteReference(error.to_string())),
    };
    SceneResult::new(status, times)
}

/// The reference's file bytes (copied as they are into reports) and its pixels.
fn read_reference(path: &Path) -> Result<(Vec<u8>, RgbImage), Failure> {
    let bytes = match std::fs::read(path) {
        Ok(bytes) => bytes,
        Err(error) if error.kind() == std::io::ErrorKind::NotFound => return Err(Failure::MissingReference),
        Err(error) => return Err(Failure::UnreadableReference(error.to_string())),
    };
    match image::load_from_memory_with_format(&bytes, image::ImageFormat::Png) {
        Ok(decoded) => Ok((bytes, decoded.to_rgb8())),
        Err(error) => Err(Failure::UnreadableReference(error.to_string())),
    }
}

struct PicturesToWrite<'a> {
    /// The reference PNG's bytes, copied unchanged.
    expected: Option<&'a Vec<u8>>,
    actual: &'a RgbImage,
    difference: Option<&'a RgbImage>,
    flip: Option<&'a RgbImage>,
}

/// Writes the report pictures of a failing scene as `NNNN-NAME-KIND.png`: the number keeps
/// names unique when two scenes' names differ only in characters a file name cannot hold.
fn write_pictures(
    result: &mut SceneResult,
    folder: &Path,
    index: usize,
    name: &str,
    pictures: PicturesToWrite,
) {
    let safe_name: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '-'
            }
        })
        .collect();
    let file_name = |kind: &str| format!("{index:04}-{safe_name}-{kind}.png");
    let mut errors = Vec::new();
    let mut write = |kind: &str, write_one: &dyn Fn(&Path) -> Result<(), OutputError>| {
        let name = file_name(kind);
        match write_one(&folder.join(&name)) {
            Ok(()) => Some(name),
            Err(error) => {
                errors.push(error.to_string());
                None
            }
        }
    };
    if let Some(bytes) = pictures.expected {
        result.pictures.expected = write("expected", &|path| {
            output::write_atomically(path, |writer| {
                writer.write_all(bytes).map_err(|source| OutputError::Io {
                    path: path.to_path_buf(),
                    source,
                })
            })
        });
    }
    result.pictures.actual = write("actual", &|path| {
        write_png(path, pictures.actual, PngCompression::Fast)
    });
    if let Some(difference) = pictures.difference {
        result.pictures.difference = write("difference", &|path| {
            write_png(path, difference, PngCompression::Fast)
        });
    }
    if let Some(flip) = pictures.flip {
        result.pictures.flip = write("flip", &|path| write_png(path, flip, PngCompression::Fast));
    }
    if !errors.is_empty() {
        result.picture_error = Some(errors.join("; "));
    }
}

/// Told about each scene's result as a run goes.
pub trait RunObserver {
    /// A scene finished (in completion order, which depends on scheduling).
    fn scene_finished(&mut self, scene: &SuiteScene, result: &SceneResult);
    /// The next scene in suite order has a result: calls come in `scenes` order.
    fn scene_in_order(&mut self, scene: &SuiteScene, result: &SceneResult);
}

/// Checks every scene in `pool`, in parallel, and returns the results in `scenes` order.
/// Returns early, without the scenes under way, once [`RunOptions::interrupted`] is set.
pub fn run_scenes(
    scenes: &[SuiteScene],
    options: &RunOptions,
    pool: &Arc<rayon::ThreadPool>,
    observer: &mut dyn RunObserver,
) -> Vec<SceneResult> {
    let interrupted = Arc::clone(&options.interrupted);
    let (sender, receiver) = mpsc::channel::<(usize, SceneResult)>();
    // The workers own their inputs, so that an interrupted run can return while they finish.
    let worker = {
        let scenes: Arc<[SuiteScene]> = scenes.into();
        let options = options.clone();
        let pool = Arc::clone(pool);
        std::thread::spawn(move || pool.install(|| run_in_pool(&scenes, &options, sender)))
    };
    let mut slots: Vec<Option<SceneResult>> = scenes.iter().map(|_| None).collect();
    let mut next_in_order = 0;
    loop {
        // A short timeout, so that Ctrl-C is noticed while a long scene runs.
        let (index, result) = match receiver.recv_timeout(Duration::from_millis(50)) {
            Ok(received) => received,
            Err(mpsc::RecvTimeoutError::Timeout) if interrupted.load(Ordering::Relaxed) => break,
            Err(mpsc::RecvTimeoutError::Timeout) => continue,
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                // Every result is in; the thread is ending, and a panic in it is reported as
                // missing results below.
                let _ = worker.join();
                break;
            }
        };
        observer.scene_finished(&scenes[index], &result);
        slots[index] = Some(result);
        while let Some(Some(result)) = slots.get(next_in_order) {
            observer.scene_in_order(&scenes[next_in_order], result);
            next_in_order += 1;
        }
    }
    let was_interrupted = interrupted.load(Ordering::Relaxed);
    let results: Vec<SceneResult> = slots
        .into_iter()
        .map(|slot| match slot {
            Some(result) => result,
            None if was_interrupted => SceneResult::new(
                SceneStatus::NotRun(StopReason::Interrupted),
                PhaseTimes::default(),
            ),
            // Every index is sent exactly once unless the worker thread itself died.
            None => SceneResult::new(
                SceneStatus::Errored(SceneError::Internal("the scene's worker stopped".to_owned())),
                PhaseTimes::default(),
            ),
        })
        .collect();
    // Scenes that finished out of order behind one still under way are printed now.
    for (scene, result) in scenes.iter().zip(&results).skip(next_in_order) {
        observer.scene_in_order(scene, result);
    }
    results
}

/// The workers' side of [`run_scenes`]: every scene, in parallel, each result sent as it comes.
fn run_in_pool(scenes: &[SuiteScene], options: &RunOptions, sender: mpsc::Sender<(usize, SceneResult)>) {
    let failed = AtomicBool::new(false);
    scenes
        .par_iter()
        .enumerate()
        .for_each_with(sender, |sender, (index, scene)| {
            let result = if options.interrupted.load(Ordering::Relaxed) {
                SceneResult::new(
                    SceneStatus::NotRun(StopReason::Interrupted),
                    PhaseTimes::default(),
                )
            } else if failed.load(Ordering::Relaxed) {
                SceneResult::new(SceneStatus::NotRun(StopReason::FailFast), PhaseTimes::default())
            } else {
                let result = check_scene_catching_panics(scene, index, options);
                if options.fail_fast && result.is_problem() {
                    failed.store(true, Ordering::Relaxed);
                }
                result
            };
            // After an interruption the receiver may be gone; the result is then not wanted.
            let _ = sender.send((index, result));
        });
}

fn check_scene_catching_panics(scene: &SuiteScene, index: usize, options: &RunOptions) -> SceneResult {
    catch_unwind(AssertUnwindSafe(|| check_scene(scene, index, options))).unwrap_or_else(|payload| {
        let message = payload
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "panic".to_owned());
        SceneResult::new(
            SceneStatus::Errored(SceneError::Internal(message)),
            PhaseTimes::default(),
        )
    })
}
