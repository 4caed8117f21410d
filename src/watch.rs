//! `lampshade watch`: re-render a scene whenever it, or any file it uses, changes, and keep going
//! through mistakes.
//!
//! ```text
//!          ┌─────────────────────────────────────────────────────────────────────┐
//!          ▼                                                                     │
//! notify events ──► wait_for_changes ──► build: pipeline::render_scene_file ──► write PNG ──► status line
//! Ctrl-C            (debounce)                  (persistent MeshCache)          (atomic)      (+ preview)
//!                                                      │                                     │
//!                                                      └─► follow exactly the files read ───┘
//! ```
//!
//! Design:
//! - The build is the one `render` uses ([`render_scene_file`]), run in a loop with one
//!   [`MeshCache`] kept across builds, so a mesh whose files have not changed is not read again:
//!   editing a light in a scene with a million-triangle mesh costs the light, not the mesh.
//! - The files followed are exactly those the last build read, whether it succeeded or failed,
//!   missing ones included (`watch::files`): an error in an include is fixed by editing the include,
//!   and a file named before it exists is picked up when it is created.
//! - Bursts of events are debounced by a quiet period (`watch::debounce`); changes made during a render
//!   are collected into the next one, which starts as soon as the current one ends.
//! - A failed build prints its diagnostics, leaves the last good image untouched (the image is
//!   only ever replaced by a complete new one, atomically) and waits for the next save. A panic
//!   in a build is a bug, but it is caught here too: it is reported and the watch goes on with a
//!   fresh mesh cache (the old one may hold whatever the panic interrupted).
//! - One status line per build on stdout, numbered (`#3 ...`): what changed, the time per
//!   stage, and the time from the first change seen to the image written. Diagnostics go to
//!   stderr, like `render`'s.
//! - Ctrl-C (or SIGTERM) stops the loop after the current build and exits with 0; a second
//!   Ctrl-C exits at once. A closed standard output (`watch s.ron | head -1`) ends it quietly
//!   after the build whose status line found it closed, with 0 too.
//! - `--serve` adds the browser preview (`watch::server`).
//!
//! Rejected: re-running the whole `render` command per change (re-reads every mesh); a loop that
//! polls modification times (latency or CPU, and misses a file replaced within one tick);
//! rendering in a background thread that a new save cancels (the renderer has no cancellation
//! points, and hand-written scenes render in tens of milliseconds: finishing the current render
//! costs little, and its image is a step closer to what the user is typing).

mod debounce;
mod files;
mod pick;
pub mod registry;
mod server;
mod turntable;
pub mod view;

use std::collections::BTreeSet;
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{self, Sender};
use std::time::{Duration, Instant};

use crate::cli::{EXIT_BAD_INPUT, EXIT_OK, EXIT_OUTPUT_FAILED, shadow_maps_part, thousands, use_color};
use crate::diag::render_diagnostics;
use crate::inspect::ImageOrigin;
use crate::output::{self, Destination, Encoding, OutputError, OutputFormat, PngCompression};
use crate::pipeline::{BuildCache, RenderedScene, render_scene_file};
use crate::render::RenderOptions;
use crate::scene::Camera;
use crate::scene::load::{LoadError, LoadOptions};

use debounce::{Changes, Debounce, Signal, Wake, wait_for_changes};
use files::{FolderWatches, WatchedFiles};
use server::PreviewServer;
use view::{Inbox, PreviewError, View};

/// The debounce: long enough to cover the events of one save (a few milliseconds apart),
/// short enough to stay well inside the 100 ms a change may take to show (see `watch::debounce`).
const DEBOUNCE: Debounce = Debounce {
    quiet: Duration::from_millis(50),
    after_save: Duration::from_millis(15),
    max_delay: Duration::from_millis(500),
};

/// The preview's source links when `--editor` is not given: Visual Studio Code's.
pub const DEFAULT_EDITOR_LINK: &str = "vscode://file{path}:{line}:{column}";

/// The preview's port when `--port` is not given.
pub const DEFAULT_PORT: u16 = 7800;

/// Arguments of `lampshade watch`.
#[derive(Debug, clap::Args)]
pub struct WatchArgs {
    /// The scene file (.ron) to render and follow.
    #[arg(value_name = "SCENE")]
    pub scene: PathBuf,
    /// Output image. Default: the scene's path with `.png`.
    #[arg(short, long, value_name = "OUT.png")]
    pub output: Option<PathBuf>,
    /// Image width in pixels, overriding the scene's.
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels, overriding the scene's.
    #[arg(long)]
    pub height: Option<u32>,
    /// Worker threads (default: one per core). The image is identical for any count.
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..))]
    pub threads: Option<u16>,
    /// Also serve a live preview page on http://127.0.0.1 (this machine only).
    #[arg(long)]
    pub serve: bool,
    /// The preview's port; 0, or a port in use, picks a free one (the address is printed).
    #[arg(long, default_value_t = DEFAULT_PORT, requires = "serve")]
    pub port: u16,
    /// The link the preview's inspector opens a source location with: a URL template with
    /// `{path}` (absolute, so starting with `/`; URL-encoded), `{line}` and `{column}` (1-based),
    /// e.g.
    /// `idea://open?file={path}&line={line}&column={column}` or
    /// `subl://open?url=file://{path}&line={line}&column={column}`. Default: VS Code's.
    #[arg(long, value_name = "TEMPLATE", default_value = DEFAULT_EDITOR_LINK, requires = "serve")]
    pub editor: String,
    #[command(flatten)]
    pub limits: crate::cli::InputLimits,
}

/// Runs `lampshade watch` until Ctrl-C; returns the exit code.
///
/// Exit codes: `0` after Ctrl-C, or once standard output is closed (checked after each build's
/// status line); `2` for arguments that cannot work (the output would replace
/// the scene); `1` when watching or serving cannot start at all. Errors in the scene never end
/// the watch.
pub fn run(args: &WatchArgs) -> i32 {
    let started = Instant::now();
    let output = match watch_output(args) {
        Ok(output) => output,
        Err(message) => {
            errln!("error: {message}");
            return EXIT_BAD_INPUT;
        }
    };
    if files::same_location(&args.scene, &output) {
        errln!(
            "error: the output `{}` would replace the scene; give another with `-o`",
            output.display()
        );
        return EXIT_BAD_INPUT;
    }

    let (signal_sender, signals) = mpsc::channel();
    let watches = {
        let sender = signal_sender.clone();
        FolderWatches::new(move |event| {
            // The loop may be gone while notify still delivers: nothing left to tell.
            let _ = sender.send(Signal::FileSystem {
                event,
                at: Instant::now(),
            });
        })
    };
    let watches = match watches {
        Ok(watches) => watches,
        Err(error) => {
            errln!("error: cannot watch files: {error}");
            return EXIT_OUTPUT_FAILED;
        }
    };
    let inbox = Arc::new(Inbox::new(&args.scene, signal_sender.clone()));
    if let Err(error) = stop_on_ctrl_c(signal_sender) {
        errln!("warning: cannot catch Ctrl-C ({error}); it will stop the watch abruptly");
    }

    let preview = if args.serve {
        let scene_name = args.scene.file_name().map_or_else(
            || args.scene.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        // An image from an earlier run is the last good image until the first build says otherwise.
        let earlier_image = std::fs::read(&output).ok();
        match PreviewServer::start(args.port, &scene_name, earlier_image, inbox.clone()) {
            Ok(started) => {
                if let Some(note) = started.port_note {
                    errln!("note: {note}");
                }
                outln!("preview at {}", started.server.url());
                started.server.set_editor_link(&args.editor);
                Some(started.server)
            }
            Err(error) => {
                errln!("error: cannot serve the preview on 127.0.0.1: {error}");
                return EXIT_OUTPUT_FAILED;
            }
        }
    } else {
        None
    };

    // An editor's language server finds the preview through this file (`watch::registry`).
    let _registration =
        preview
            .as_ref()
            .and_then(|server| match registry::register(&args.scene, server.port()) {
                Ok(registration) => Some(registration),
                Err(error) => {
                    errln!("warning: editors will not find this preview: {error}");
                    None
                }
            });

    let load_options = match args.limits.load_options() {
        Ok(limited) => LoadOptions {
            width: args.width,
            height: args.height,
            ..limited
        },
        Err(message) => {
            errln!("error: {message}");
            return EXIT_BAD_INPUT;
        }
    };
    let render_options = RenderOptions {
        threads: args.threads.map(usize::from),
        ..RenderOptions::default()
    };
    let mut session = WatchSession::new(&args.scene, &output, load_options, render_options, watches);
    if let Some(preview) = &preview {
        preview.set_turntable(turntable::TurntableSource {
            scene: args.scene.clone(),
            load_options: session.load_options.clone(),
            render_options,
        });
    }
    if preview.is_some() {
        session.inbox = Some(inbox);
    }
    session.preview = preview;
    session.build(&Trigger::Start(started));
    let mut report_watch_error = |error: notify::Error| errln!("warning: watching files: {error}");
    // Nobody reads the status lines any more (`watch s.ron | head -1`): end quietly, as a
    // Ctrl-C would, rather than render for no one.
    while !crate::console::stdout_closed()
        && let Some(wake) = wait_for_changes(&signals, &session.files, DEBOUNCE, &mut report_watch_error)
    {
        if let Wake::Changes(changes) = wake {
            session.build(&Trigger::Changes(changes));
        }
        session.serve_view_requests();
    }
    outln!("stopped");
    EXIT_OK
}

/// Sends [`Signal::Stop`] on the first Ctrl-C (or SIGTERM); exits at once on the second.
fn stop_on_ctrl_c(signals: Sender<Signal>) -> Result<(), ctrlc::Error> {
    let mut asked_already = false;
    ctrlc::set_handler(move || {
        if asked_already {
            // 128 + SIGINT, the shell's convention for "interrupted"; an image being written
            // is finished first, so no temporary file is left behind.
            crate::output::exit_when_no_write_is_in_progress(130);
        }
        asked_already = true;
        errln!("stopping after the current render (Ctrl-C again to stop now)");
        let _ = signals.send(Signal::Stop);
    })
}

/// Why a build runs.
enum Trigger {
    /// The first build, with the time the watch started.
    Start(Instant),
    Changes(Changes),
}

impl Trigger {
    /// When the change this build answers was first seen.
    fn since(&self) -> Instant {
        match self {
            Trigger::Start(at) => *at,
            Trigger::Changes(changes) => changes.first_seen,
        }
    }

    /// "start", or the changed files: "scene.ron, mats.ron changed".
    fn describe(&self) -> String {
        match self {
            Trigger::Start(_) => String::from("start"),
            Trigger::Changes(changes) => format!("{} changed", list_paths(&changes.files)),
        }
    }
}

/// Up to three paths, then a count: "a.ron, b.ron, c.obj and 2 more".
fn list_paths<'p>(paths: impl IntoIterator<Item = &'p PathBuf>) -> String {
    const SHOWN: usize = 3;
    let paths: Vec<String> = paths.into_iter().map(|p| p.display().to_string()).collect();
    if paths.len() <= SHOWN {
        return paths.join(", ");
    }
    format!("{} and {} more", paths[..SHOWN].join(", "), paths.len() - SHOWN)
}

/// One build: load, render and write the image (the seam tests use to make a build panic).
type BuildFn = fn(&Path, &Path, &LoadOptions, &RenderOptions, &mut BuildCache) -> BuildOutcome;

/// Everything the loop keeps from one build to the next.
struct WatchSession {
    build_once: BuildFn,
    scene: PathBuf,
    output: PathBuf,
    load_options: LoadOptions,
    render_options: RenderOptions,
    /// Meshes and render buffers kept from one build to the next.
    cache: BuildCache,
    files: WatchedFiles,
    watches: FolderWatches,
    preview: Option<PreviewServer>,
    /// The page's and the editor's requests (with `--serve`).
    inbox: Option<Arc<Inbox>>,
    /// What the page asked to see instead of the file's own render.
    view: View,
    /// The camera of the last build that rendered: when an edit changes it, the file's camera
    /// replaces the preview's.
    file_camera: Option<Camera>,
    builds: u64,
    /// The followed files and the missing ones, as last printed (printed again when they change).
    announced_files: Vec<PathBuf>,
    announced_missing: Vec<PathBuf>,
    color: bool,
}

/// What one build did.
enum BuildOutcome {
    /// Boxed: an image's scene and statistics dwarf the other outcomes.
    Written(Box<WrittenImage>),
    BadInput {
        error: LoadError,
        /// Reading and checking, until the problems were found.
        load_time: Duration,
    },
    OutputFailed {
        error: OutputError,
        files_read: Vec<PathBuf>,
    },
}

struct WrittenImage {
    rendered: RenderedScene,
    encode_time: Duration,
    /// When the PNG was in place.
    written_at: Instant,
}

impl WatchSession {
    /// A session that has built nothing yet but already follows the scene, so that an edit
    /// made during the first build is not missed.
    fn new(
        scene: &Path,
        output: &Path,
        load_options: LoadOptions,
        render_options: RenderOptions,
        watches: FolderWatches,
    ) -> Self {
        let mut session = WatchSession {
            build_once,
            scene: scene.to_path_buf(),
            output: output.to_path_buf(),
            load_options,
            render_options,
            cache: BuildCache::default(),
            files: WatchedFiles::new(output),
            watches,
            preview: None,
            inbox: None,
            view: View::default(),
            file_camera: None,
            builds: 0,
            announced_files: Vec::new(),
            announced_missing: Vec::new(),
            color: use_color(),
        };
        session.watch([]);
        session
    }

    fn build(&mut self, trigger: &Trigger) {
        self.builds += 1;
        let outcome = {
            let (scene, output) = (&self.scene, &self.output);
            let (load_options, render_options) = (&self.load_options, &self.render_options);
            let (cache, build_once) = (&mut self.cache, self.build_once);
            panic::catch_unwind(AssertUnwindSafe(|| {
                build_once(scene, output, load_options, render_options, cache)
            }))
        };
        match outcome {
            Ok(BuildOutcome::Written(mut written)) => {
                self.follow_the_file_where_it_changed(trigger, &written.rendered.camera);
                self.watch(std::mem::take(&mut written.rendered.files_read));
                self.report_written(trigger, &written);
                self.announce_followed();
                let rendered = written.rendered;
                // The next build renders into the same pixels.
                self.cache.renderer.reuse_framebuffer(rendered.framebuffer);
                if !self.view.is_the_file_s() {
                    self.show_view(false);
                }
            }
            Ok(BuildOutcome::BadInput { error, load_time }) => {
                let report = render_diagnostics(&error.diagnostics, &error.sources, self.color);
                errout!("{report}");
                let errors = error.diagnostics.iter().filter(|d| d.is_error()).count();
                let problem = format!("{errors} error{}", if errors == 1 { "" } else { "s" });
                self.watch(error.files_read);
                self.report_failure(trigger, &problem, Some(load_time), || {
                    render_diagnostics(&error.diagnostics, &error.sources, false)
                });
                self.announce_followed();
            }
            Ok(BuildOutcome::OutputFailed { error, files_read }) => {
                errln!("error: {error}");
                if matches!(error, OutputError::WouldReplaceInput { .. }) {
                    errln!("  = help: rename the file the scene reads, or watch with another -o");
                }
                self.watch(files_read);
                self.report_failure(trigger, "the image could not be written", None, || {
                    error.to_string()
                });
                self.announce_followed();
            }
            Err(payload) => {
                // The panic hook has printed the message; say what happens next.
                let message = panic_message(payload.as_ref());
                errln!("error: the render failed with an internal error; still watching");
                self.cache = BuildCache::default();
                self.report_failure(trigger, "internal error", None, || {
                    format!("internal error (a bug in lampshade, not in your files): {message}")
                });
                // What the build read is unknown: keep following what the last one did.
            }
        }
    }

    fn report_written(&self, trigger: &Trigger, written: &WrittenImage) {
        let RenderedScene {
            framebuffer,
            stats,
            load_time,
            warnings,
            sources,
            ..
        } = &written.rendered;
        if !warnings.is_empty() {
            errout!("{}", render_diagnostics(warnings, sources, self.color));
        }
        let latency = written.written_at.saturating_duration_since(trigger.since());
        let since = match trigger {
            Trigger::Start(_) => "start",
            Trigger::Changes(_) => "change",
        };
        outln!(
            "#{} {} → {}: {} triangles, {}×{} px | load {}, {}geometry {}, raster+shade {}, encode {} | {since} to image {}",
            self.builds,
            trigger.describe(),
            self.output.display(),
            thousands(stats.triangles),
            framebuffer.width(),
            framebuffer.height(),
            milliseconds(*load_time),
            shadow_maps_part(stats),
            milliseconds(stats.geometry),
            milliseconds(stats.raster_shade),
            milliseconds(written.encode_time),
            milliseconds(latency),
        );
        if let Some(preview) = &self.preview
            && self.view.is_the_file_s()
        {
            match std::fs::read(&self.output) {
                Ok(png) => {
                    let render_time = *load_time
                        + stats.shadow_maps
                        + stats.geometry
                        + stats.raster_shade
                        + written.encode_time;
                    let summary = format!(
                        "#{} · {} triangles · {}×{} px · rendered in {} · {since} to image {}",
                        self.builds,
                        thousands(stats.triangles),
                        framebuffer.width(),
                        framebuffer.height(),
                        milliseconds(render_time),
                        milliseconds(latency),
                    );
                    let origin = ImageOrigin {
                        scene: Arc::clone(&written.rendered.scene),
                        sources: Arc::new(sources.clone()),
                        load_options: self.load_options.clone(),
                        render_options: self.render_options,
                        encoding: Encoding::Linear,
                    };
                    let view = self.view.summary(
                        &written.rendered.camera,
                        framebuffer.width(),
                        framebuffer.height(),
                        false,
                    );
                    preview.publish_image(png, summary, view, Arc::new(origin));
                }
                Err(error) => errln!(
                    "warning: preview: cannot read back `{}`: {error}",
                    self.output.display()
                ),
            }
        }
    }

    /// After a build of the file: an unsaved buffer gives way to the scene file when the scene
    /// file changed (saved), and the preview camera to the file's when the file's camera changed
    /// (written from the page or edited by hand).
    fn follow_the_file_where_it_changed(&mut self, trigger: &Trigger, camera: &Camera) {
        if let Trigger::Changes(changes) = trigger
            && changes
                .files
                .iter()
                .any(|file| files::same_location(file, &self.scene))
        {
            self.view.buffer = None;
        }
        if self.file_camera.is_some_and(|before| before != *camera) {
            self.view.camera = None;
        }
        self.file_camera = Some(*camera);
    }

    /// Takes the newest requests from the page and the editor, shows what they ask for, and
    /// answers the page's request with the state of the image it made.
    fn serve_view_requests(&mut self) {
        let Some(inbox) = &self.inbox else {
            return;
        };
        let taken = inbox.take();
        let buffer_changed = taken.buffer.is_some();
        if let Some(update) = taken.buffer {
            // A buffer as saved is the file: the file's own view (and the image file) again.
            let saved = std::fs::read_to_string(&self.scene).ok();
            self.view.buffer = update.text.filter(|text| saved.as_ref() != Some(text));
        }
        let moving = taken.view.as_ref().is_some_and(|(request, _)| request.moving);
        if let Some((request, _)) = &taken.view {
            self.view.apply(request);
        }
        if buffer_changed || taken.view.is_some() {
            self.show_view(moving);
        }
        if let (Some((_, page)), Some(preview)) = (taken.view, &self.preview) {
            view::respond_json(page, 200, &preview.state_json());
        }
    }

    /// Renders the view the page asked for (the file's own view included, after a reset) and
    /// shows it in the page only; the image file is left as the file's build wrote it.
    fn show_view(&mut self, moving: bool) {
        let Some(preview) = &self.preview else {
            return;
        };
        let (view, scene, cache) = (&mut self.view, &self.scene, &mut self.cache);
        let (load_options, render_options) = (&self.load_options, &self.render_options);
        let rendered = panic::catch_unwind(AssertUnwindSafe(|| {
            view.render(scene, moving, load_options, render_options, cache)
        }));
        let problem = match rendered {
            Ok(Ok(frame)) => {
                let summary = format!(
                    "#{} · preview{} · {}×{} px{} · rendered in {}",
                    self.builds,
                    describe_view(&frame.summary),
                    frame.size.0,
                    frame.size.1,
                    if moving { " while moving" } else { "" },
                    milliseconds(frame.time),
                );
                preview.publish_image(frame.png, summary, frame.summary, Arc::new(frame.origin));
                return;
            }
            Ok(Err(PreviewError::Load(error))) => {
                let report = render_diagnostics(&error.diagnostics, &error.sources, false);
                let errors = error.diagnostics.iter().filter(|d| d.is_error()).count();
                let what = if self.view.buffer.is_some() {
                    "unsaved text"
                } else {
                    "preview"
                };
                (
                    report,
                    format!("{what}: {errors} error{}", if errors == 1 { "" } else { "s" }),
                )
            }
            Ok(Err(PreviewError::Read(error))) => (
                format!("cannot read `{}`: {error}", self.scene.display()),
                String::from("preview: cannot read the scene"),
            ),
            Ok(Err(PreviewError::Encode(error))) => (
                error.to_string(),
                String::from("preview: cannot encode the image"),
            ),
            Err(payload) => {
                self.cache = BuildCache::default();
                let message = panic_message(payload.as_ref());
                (
                    format!("internal error (a bug in lampshade, not in your files): {message}"),
                    String::from("preview: internal error"),
                )
            }
        };
        if let Some(preview) = &self.preview {
            preview.publish_error(problem.0, &problem.1);
        }
    }

    /// Reports a build that produced no image; `report` gives the preview's overlay text.
    fn report_failure(
        &self,
        trigger: &Trigger,
        problem: &str,
        load_time: Option<Duration>,
        report: impl FnOnce() -> String,
    ) {
        let kept = if self.output.exists() {
            format!("{} left as it was", self.output.display())
        } else {
            String::from("no image yet")
        };
        let timing = load_time.map_or_else(String::new, |load| format!(" | load {}", milliseconds(load)));
        outln!(
            "#{} {}: {problem} (see above); {kept}{timing} | waiting for the next save",
            self.builds,
            trigger.describe()
        );
        if let Some(preview) = &self.preview {
            preview.publish_error(report(), &format!("#{}: {problem}", self.builds));
        }
    }

    /// Follows `files_read` (and always the scene) from now on: their folders are watched
    /// before the build's outcome is reported, so that a file saved as soon as the report is
    /// seen (a mesh created once the watcher said it was missing) is not missed.
    fn watch(&mut self, files_read: impl IntoIterator<Item = PathBuf>) {
        let mut followed: Vec<PathBuf> = files_read.into_iter().collect();
        followed.push(self.scene.clone());
        self.files.follow(followed.iter().map(PathBuf::as_path));
        for problem in self.watches.sync(self.files.folders()) {
            errln!("warning: {problem}");
        }
    }

    /// Says which files are followed and which are awaited, when that changed.
    fn announce_followed(&mut self) {
        if self.builds == 0 {
            return; // before the first build there is nothing to announce yet
        }
        let files: Vec<PathBuf> = self.files.files().into_iter().map(Path::to_path_buf).collect();
        if files != self.announced_files {
            outln!("watching {} (Ctrl-C to stop)", list_paths(&files));
            self.announced_files = files;
        }
        let missing: Vec<PathBuf> = self.files.missing().into_iter().map(Path::to_path_buf).collect();
        let newly_missing: BTreeSet<&PathBuf> = missing
            .iter()
            .filter(|m| !self.announced_missing.contains(m))
            .collect();
        if !newly_missing.is_empty() {
            outln!(
                "waiting for {} to be created",
                list_paths(newly_missing.iter().copied())
            );
        }
        self.announced_missing = missing;
    }
}

/// The image `watch` writes: `-o` under the rule every command follows (the format follows the
/// extension, see [`output::choose_format`]), and a PNG, which the preview shows; by default the
/// scene's path with `.png`.
fn watch_output(args: &WatchArgs) -> Result<PathBuf, String> {
    let Some(requested) = &args.output else {
        return Ok(args.scene.with_extension("png"));
    };
    match output::choose_format(Some(requested), None)? {
        (Destination::File(Some(path)), OutputFormat::Png) => Ok(path),
        (Destination::Stdout, _) => Err(
            "watch writes an image on every save and needs a file: name one with -o (`-` is standard output)"
                .to_string(),
        ),
        (_, format) => Err(format!(
            "watch writes PNG images (the preview shows them), but `{}` names {} file; use a .png name",
            requested.display(),
            if format == OutputFormat::Exr {
                "an OpenEXR"
            } else {
                "a Radiance HDR"
            },
        )),
    }
}

/// Loads, renders and writes the image: the whole build, run under `catch_unwind`.
fn build_once(
    scene: &Path,
    output_path: &Path,
    load_options: &LoadOptions,
    render_options: &RenderOptions,
    cache: &mut BuildCache,
) -> BuildOutcome {
    let started = Instant::now();
    let rendered = match render_scene_file(scene, load_options, render_options, cache) {
        Ok(rendered) => rendered,
        Err(error) => {
            return BuildOutcome::BadInput {
                error,
                load_time: started.elapsed(),
            };
        }
    };
    // An edit can make the scene read the output (a texture of the same name): never write over it.
    if let Some(input) =
        output::overwritten_input(output_path, rendered.files_read.iter().map(PathBuf::as_path))
    {
        return BuildOutcome::OutputFailed {
            error: OutputError::WouldReplaceInput {
                path: output_path.to_path_buf(),
                input: input.to_path_buf(),
            },
            files_read: rendered.files_read,
        };
    }
    let encode_started = Instant::now();
    let image = output::to_rgb8(&rendered.framebuffer);
    if let Err(error) = output::write_png(output_path, &image, PngCompression::Fast) {
        return BuildOutcome::OutputFailed {
            error,
            files_read: rendered.files_read,
        };
    }
    let written_at = Instant::now();
    BuildOutcome::Written(Box::new(WrittenImage {
        rendered,
        encode_time: written_at - encode_started,
        written_at,
    }))
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(message) = payload.downcast_ref::<&str>() {
        (*message).to_owned()
    } else if let Some(message) = payload.downcast_ref::<String>() {
        message.clone()
    } else {
        String::from("(no message)")
    }
}

/// What the preview shows besides the file: " · preview camera · shading gouraud".
fn describe_view(view: &view::ViewSummary) -> String {
    let mut parts = String::new();
    if view.preview_camera {
        parts.push_str(" · preview camera");
    }
    for (what, value) in [
        ("shading", &view.shading),
        ("model", &view.model),
        ("debug", &view.debug),
    ] {
        if let Some(value) = value {
            parts.push_str(&format!(" · {what} {value}"));
        }
    }
    if view.buffer {
        parts.push_str(" · unsaved text");
    }
    parts
}

fn milliseconds(duration: Duration) -> String {
    format!("{:.1} ms", duration.as_secs_f64() * 1000.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_lists_of_paths_are_shortened() {
        let paths: Vec<PathBuf> = ["a.ron", "b.ron", "c.obj", "d.mtl", "e.bin"]
            .iter()
            .map(PathBuf::from)
            .collect();
        assert_eq!(list_paths(&paths[..1]), "a.ron");
        assert_eq!(list_paths(&paths[..3]), "a.ron, b.ron, c.obj");
        assert_eq!(list_paths(&paths), "a.ron, b.ron, c.obj and 2 more");
    }

    fn panicking_build(
        _: &Path,
        _: &Path,
        _: &LoadOptions,
        _: &RenderOptions,
        _: &mut BuildCache,
    ) -> BuildOutcome {
        panic!("simulated bug in the renderer");
    }

    #[test]
    fn a_panicking_build_is_reported_and_the_next_build_recovers() {
        let folder = tempfile::tempdir().unwrap();
        let scene = folder.path().join("scene.ron");
        let output = folder.path().join("scene.png");
        std::fs::write(
            &scene,
            "(image: (width: 8, height: 6), objects: [(mesh: Sphere(segments: 4))])",
        )
        .unwrap();
        let watches = FolderWatches::new(|_| {}).unwrap();
        let mut session = WatchSession::new(
            &scene,
            &output,
            LoadOptions::default(),
            RenderOptions::default(),
            watches,
        );
        session.build_once = panicking_build;
        session.build(&Trigger::Start(Instant::now()));
        assert!(!output.exists());
        assert_eq!(
            session.files.files(),
            [scene.as_path()],
            "still following the scene"
        );

        session.build_once = build_once;
        session.build(&Trigger::Start(Instant::now()));
        assert!(output.exists(), "the build after the panic writes the image");
        assert_eq!(session.builds, 2);
    }

    #[test]
    fn panic_messages_are_recovered_from_either_payload() {
        let from_str = panic::catch_unwind(|| panic!("plain")).unwrap_err();
        assert_eq!(panic_message(from_str.as_ref()), "plain");
        let from_string = panic::catch_unwind(|| panic!("formatted {}", 42)).unwrap_err();
        assert_eq!(panic_message(from_string.as_ref()), "formatted 42");
    }
}
