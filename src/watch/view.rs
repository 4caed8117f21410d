//! The preview's own view of the scene: a camera moved in the page, the shading, lighting-model
//! and debug-view overrides `render` has on its command line, and an editor's unsaved text
//! (`lampshade lsp` sends it); none of them touches the scene file until the page asks to write
//! the camera into it.
//!
//! ```text
//! page ── POST /api/view {camera, moving, shading, model, debug} ──► Inbox (newest only) ──► watch loop
//! lsp  ── POST /api/buffer {path, text} ─────────────────────────────┘                     │
//!                                                                                           ▼
//!      scene text (buffer or file) ─► camera value replaced (with_camera) ─► load (mesh cache) ─► render ─► publish
//! ```
//!
//! Design:
//! - A preview frame is the render of the scene *text with the camera value replaced* by the
//!   preview camera, exactly as [`write_camera`] would write it, loaded through the mesh cache.
//!   So what the page shows at full resolution is bit for bit what the file renders once the
//!   camera is written into it, including everything that follows the camera (default `near`
//!   and `far`, default lights at the eye). Loading a scene whose meshes are cached (files and
//!   generated spheres alike) costs a fraction of a millisecond (0.3 ms for `matlab-shiny`,
//!   whose two 180-segment spheres took longer to generate than to draw at half size), small
//!   against the render. Each frame's server time, split into load, render and encode, goes to
//!   the page with it (`timings`).
//! - While the page drags (`moving`), frames are rendered at a reduced size (half to an eighth,
//!   adapted so a frame stays under [`MOVING_BUDGET`]) with one sample per pixel; once the
//!   moves stop the page asks once more without `moving` and gets the full image.
//! - Only the newest request matters: the inbox holds one view request and one buffer; a
//!   request that arrives while another waits replaces it (the replaced page request is answered
//!   `superseded` at once), and a request is answered with the state of the image it made, so a
//!   page keeps one request in flight and never builds a queue.
//! - The preview camera stays through edits of the scene (the view does not jump while the user
//!   edits a colour), except when the edit changes the file's own camera (writing the camera, or
//!   editing it by hand): then the file's camera is shown again. "Reset" in the page returns to
//!   the file's camera and the scene's own shading at once.
//! - While the view differs from the file's (a preview camera, an override, an unsaved buffer),
//!   the image file `watch` writes still holds the scene file's own render; only the page shows
//!   the preview.
//! - An unsaved buffer is rendered instead of the file (its includes and meshes still read from
//!   disk) until the editor saves or closes it (it sends `text: null`) or the scene file changes
//!   on disk: then the file wins again.
//!
//! Rejected: moving the camera of the loaded `Scene` in place (cheaper by the load, but the
//! defaults that depend on the camera would differ from the file's render, and the page could
//! not promise that the written camera gives the image it showed); JavaScript sending deltas
//! for the server to apply (a dropped request would lose motion; the page owns its camera).

use crate::inspect::ImageOrigin;
use std::io::{self, Read};
use std::path::{Path, PathBuf};
use std::sync::mpsc::Sender;
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

use clap::ValueEnum;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use tiny_http::Request;

use crate::cli::{DebugArg, ModelArg, ShadingArg};
use crate::output::{self, OutputError, PngCompression};
use crate::pipeline::BuildCache;
use crate::render::RenderOptions;
use crate::scene::load::{LoadError, LoadOptions, load_scene_from_str_cached};
use crate::scene::locate::{locate, top_level_fields};
use crate::scene::{Camera, Projection};

use super::debounce::Signal;

/// How long a frame rendered while moving may take (load, render and encode) before the next
/// ones are made smaller: 40 ms leaves 10 ms of each 50 (20 updates a second) for the page to
/// fetch and decode the image.
pub const MOVING_BUDGET: Duration = Duration::from_millis(40);

/// The largest body a request may send (an editor's buffer included).
const MAX_BODY: u64 = 16 << 20;

/// A perspective camera as the page moves it and the scene format writes it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PreviewCamera {
    pub eye: [f64; 3],
    pub target: [f64; 3],
    pub up: [f64; 3],
    /// Vertical field of view, degrees.
    pub fov: f64,
}

impl PreviewCamera {
    /// The camera a scene was rendered with, when it is a perspective one (the page orbits
    /// perspective cameras only).
    pub fn of(camera: &Camera) -> Option<Self> {
        let Projection::Perspective { fov_y_degrees, .. } = camera.projection else {
            return None;
        };
        Some(PreviewCamera {
            eye: camera.eye.to_array(),
            target: camera.target.to_array(),
            up: camera.up.to_array(),
            fov: fov_y_degrees,
        })
    }

    /// Whether the loader would accept it: finite, `eye` apart from `target`, `up` not along the
    /// line of sight, `fov` in range (the same tests as the loader's, so a camera the page sends
    /// never turns a good scene into an error).
    fn is_valid(&self) -> bool {
        let (eye, target, up) = (
            DVec3::from_array(self.eye),
            DVec3::from_array(self.target),
            DVec3::from_array(self.up),
        );
        let finite = eye.is_finite() && target.is_finite() && up.is_finite() && self.fov.is_finite();
        let offset = target - eye;
        finite
            && up.length() > 1e-12
            && offset.length() >= 1e-12
            && offset.normalize().cross(up.normalize()).length() >= 1e-9
            && (1e-3..=179.0).contains(&self.fov)
    }

    /// The camera as the scene format writes it: `Perspective(eye: (…), target: (…), up: (…), fov: …)`.
    /// Numbers are written in the shortest form that reads back as the same `f64`.
    pub fn to_ron(&self) -> String {
        let vector = |v: [f64; 3]| format!("({}, {}, {})", number(v[0]), number(v[1]), number(v[2]));
        format!(
            "Perspective(eye: {}, target: {}, up: {}, fov: {})",
            vector(self.eye),
            vector(self.target),
            vector(self.up),
            number(self.fov)
        )
    }
}

/// `f64` in the shortest text that reads back as the same number; `-0` as `0`.
fn number(value: f64) -> String {
    if value == 0.0 {
        String::from("0")
    } else {
        format!("{value}")
    }
}

/// `text` (a scene) with its `camera` value replaced by `camera_ron`, or a `camera` field
/// inserted first in the scene's struct when it has none. Nothing else changes: comments,
/// formatting and every other byte are kept. `None` when the text is not a scene struct.
pub fn with_camera(text: &str, camera_ron: &str) -> Option<String> {
    let mut edited = String::with_capacity(text.len() + camera_ron.len() + 16);
    if let Some(span) = locate(text, &crate::ron_path!["camera"]) {
        edited.push_str(&text[..span.start]);
        edited.push_str(camera_ron);
        edited.push_str(&text[span.end..]);
        return Some(edited);
    }
    let (open, first_field) = top_level_fields(text)?;
    let (at, inserted) = match first_field {
        None => (open, format!("camera: {camera_ron}")),
        Some(first) => {
            let line_start = text[..first].rfind('\n').map_or(0, |newline| newline + 1);
            let indent = &text[line_start..first];
            if line_start > open && indent.trim().is_empty() {
                // The fields are one per line: the camera gets a line of its own, indented alike.
                (first, format!("camera: {camera_ron},\n{indent}"))
            } else {
                (first, format!("camera: {camera_ron}, "))
            }
        }
    };
    edited.push_str(&text[..at]);
    edited.push_str(&inserted);
    edited.push_str(&text[at..]);
    Some(edited)
}

/// Why the camera could not be written.
#[derive(Debug)]
pub enum WriteError {
    Read(io::Error),
    /// The file holds no scene struct to put a camera in.
    NotAScene,
    Write(OutputError),
}

impl std::fmt::Display for WriteError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            WriteError::Read(error) => write!(f, "cannot read the scene: {error}"),
            WriteError::NotAScene => {
                f.write_str("the scene file does not hold a scene `( … )` to put the camera in")
            }
            WriteError::Write(error) => write!(f, "cannot write the scene: {error}"),
        }
    }
}

/// Writes `camera` into the scene file at `scene` in place (see [`with_camera`]), atomically:
/// the file is replaced by a complete new one, never left half written.
pub fn write_camera(scene: &Path, camera: &PreviewCamera) -> Result<(), WriteError> {
    let text = std::fs::read_to_string(scene).map_err(WriteError::Read)?;
    let edited = with_camera(&text, &camera.to_ron()).ok_or(WriteError::NotAScene)?;
    output::write_atomically(scene, |writer| {
        io::Write::write_all(writer, edited.as_bytes()).map_err(|source| OutputError::Io {
            path: scene.to_path_buf(),
            source,
        })
    })
    .map_err(WriteError::Write)
}

/// What the page asks to see: the whole view every time (so a dropped request loses nothing).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewRequest {
    /// The preview camera; `None` shows the file's.
    #[serde(default)]
    pub camera: Option<PreviewCamera>,
    /// The page is dragging: a reduced-size frame will do.
    #[serde(default)]
    pub moving: bool,
    /// `render --shading`, `--model` and `--debug` values, by their command-line names.
    #[serde(default)]
    pub shading: Option<String>,
    #[serde(default)]
    pub model: Option<String>,
    #[serde(default)]
    pub debug: Option<String>,
}

/// An editor's unsaved text for the scene, or `None` when it saved or closed the file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BufferUpdate {
    pub path: PathBuf,
    pub text: Option<String>,
}

/// The overrides of a view, parsed.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Overrides {
    pub shading: Option<ShadingArg>,
    pub model: Option<ModelArg>,
    pub debug: Option<DebugArg>,
}

impl Overrides {
    fn parse(request: &ViewRequest) -> Result<Self, String> {
        fn value<T: ValueEnum>(what: &str, name: &Option<String>) -> Result<Option<T>, String> {
            name.as_deref()
                .map(|name| T::from_str(name, false).map_err(|_| format!("unknown {what} `{name}`")))
                .transpose()
        }
        Ok(Overrides {
            shading: value("shading mode", &request.shading)?,
            model: value("lighting model", &request.model)?,
            debug: value("debug view", &request.debug)?,
        })
    }

    fn is_none(&self) -> bool {
        *self == Overrides::default()
    }
}

/// What the page is told about the view of the image it is sent (part of the preview state).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ViewSummary {
    /// The camera the image was rendered with, when it is a perspective camera.
    pub camera: Option<PreviewCamera>,
    /// That camera in the scene format, for the page's "copy".
    pub camera_ron: Option<String>,
    /// Whether the camera is the preview's own rather than the file's.
    pub preview_camera: bool,
    pub shading: Option<String>,
    pub model: Option<String>,
    pub debug: Option<String>,
    /// Whether the image shows an editor's unsaved text.
    pub buffer: bool,
    /// The size of a full image; a frame rendered while moving is smaller and shown at this size.
    pub width: u32,
    pub height: u32,
    /// Whether this frame is a reduced one, made while moving.
    pub moving: bool,
    /// Where the frame's time went on the server.
    pub timings: FrameTimings,
}

/// The server's part of a preview frame's time, in milliseconds: reading and loading the scene
/// text (meshes come from the cache), rendering, and encoding the PNG. The page adds its own
/// part (fetching and decoding the image) to `lampshadeView.frames`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct FrameTimings {
    pub load_ms: f64,
    pub render_ms: f64,
    pub encode_ms: f64,
}

/// Names a value the way the command line does (`blinn-phong`).
fn value_name<T: ValueEnum>(value: Option<T>) -> Option<String> {
    value
        .and_then(|v| v.to_possible_value())
        .map(|v| v.get_name().to_owned())
}

/// The requests waiting for the watch loop: the newest view request and the newest buffer.
pub struct Inbox {
    scene: PathBuf,
    wake: Mutex<Sender<Signal>>,
    waiting: Mutex<Waiting>,
}

#[derive(Default)]
struct Waiting {
    view: Option<(ViewRequest, Request)>,
    buffer: Option<BufferUpdate>,
}

/// What the loop takes from the inbox at once.
pub struct Taken {
    pub view: Option<(ViewRequest, Request)>,
    pub buffer: Option<BufferUpdate>,
}

impl Inbox {
    pub fn new(scene: &Path, wake: Sender<Signal>) -> Self {
        Inbox {
            scene: scene.to_path_buf(),
            wake: Mutex::new(wake),
            waiting: Mutex::new(Waiting::default()),
        }
    }

    fn waiting(&self) -> MutexGuard<'_, Waiting> {
        self.waiting
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn wake_loop(&self) {
        let wake = self.wake.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        // The loop is gone when the watch is stopping: nobody to render for.
        let _ = wake.send(Signal::View);
    }

    /// Everything waiting, emptied.
    pub fn take(&self) -> Taken {
        let mut waiting = self.waiting();
        Taken {
            view: waiting.view.take(),
            buffer: waiting.buffer.take(),
        }
    }

    /// Answers `POST /api/view`, `/api/camera` (write the camera into the file) and
    /// `/api/buffer`; the server's route match hands every POST here.
    pub fn answer_post(&self, mut request: Request) {
        let path = request.url().split('?').next().unwrap_or_default().to_owned();
        let mut body = Vec::new();
        if let Err(error) = request.as_reader().take(MAX_BODY).read_to_end(&mut body) {
            respond_json(
                request,
                400,
                &error_json(&format!("cannot read the request: {error}")),
            );
            return;
        }
        match path.as_str() {
            "/api/view" => match serde_json::from_slice::<ViewRequest>(&body) {
                Ok(view) => {
                    if let Err(problem) = Overrides::parse(&view) {
                        respond_json(request, 400, &error_json(&problem));
                        return;
                    }
                    if view.camera.is_some_and(|camera| !camera.is_valid()) {
                        respond_json(request, 400, &error_json("the camera is degenerate"));
                        return;
                    }
                    let replaced = self.waiting().view.replace((view, request));
                    if let Some((_, stale)) = replaced {
                        respond_json(stale, 200, r#"{"superseded":true}"#);
                    }
                    self.wake_loop();
                }
                Err(error) => respond_json(request, 400, &error_json(&error.to_string())),
            },
            "/api/camera" => match serde_json::from_slice::<PreviewCamera>(&body) {
                Ok(camera) if camera.is_valid() => match write_camera(&self.scene, &camera) {
                    Ok(()) => {
                        let written = serde_json::json!({ "written": self.scene, "camera": camera.to_ron() });
                        respond_json(request, 200, &written.to_string());
                    }
                    Err(error) => respond_json(request, 500, &error_json(&error.to_string())),
                },
                Ok(_) => respond_json(request, 400, &error_json("the camera is degenerate")),
                Err(error) => respond_json(request, 400, &error_json(&error.to_string())),
            },
            "/api/buffer" => match serde_json::from_slice::<BufferUpdate>(&body) {
                Ok(update) if super::files::same_location(&update.path, &self.scene) => {
                    self.waiting().buffer = Some(update);
                    self.wake_loop();
                    respond_json(request, 202, r#"{"accepted":true}"#);
                }
                Ok(update) => respond_json(
                    request,
                    404,
                    &error_json(&format!(
                        "this watch renders `{}`, not `{}`",
                        self.scene.display(),
                        update.path.display()
                    )),
                ),
                Err(error) => respond_json(request, 400, &error_json(&error.to_string())),
            },
            _ => respond_json(request, 404, &error_json("not found")),
        }
    }
}

fn error_json(message: &str) -> String {
    serde_json::json!({ "error": message }).to_string()
}

/// Answers `request` with `json`.
pub fn respond_json(request: Request, status: u16, json: &str) {
    let mut response = tiny_http::Response::from_string(json).with_status_code(status);
    if let Ok(header) = tiny_http::Header::from_bytes(&b"Content-Type"[..], &b"application/json"[..]) {
        response.add_header(header);
    }
    // A page that went away mid-answer is not our problem.
    let _ = request.respond(response);
}

/// The view the loop keeps between requests.
#[derive(Debug, Default)]
pub struct View {
    pub camera: Option<PreviewCamera>,
    pub overrides: Overrides,
    /// An editor's unsaved text of the scene.
    pub buffer: Option<String>,
    /// How much smaller than the full image a frame made while moving is (2, 4 or 8).
    moving_scale: u32,
}

/// A preview frame, rendered and encoded.
pub struct PreviewFrame {
    pub png: Vec<u8>,
    pub summary: ViewSummary,
    /// The frame's own size (smaller than the summary's while moving).
    pub size: (u32, u32),
    /// Load, render and encode.
    pub time: Duration,
    /// What made the frame, for `/api/pick` about it.
    pub origin: ImageOrigin,
}

impl View {
    /// Whether the page shows the scene file as `watch` renders it.
    pub fn is_the_file_s(&self) -> bool {
        self.camera.is_none() && self.overrides.is_none() && self.buffer.is_none()
    }

    /// Takes the page's request; an invalid one was refused before it got here.
    pub fn apply(&mut self, request: &ViewRequest) {
        self.camera = request.camera;
        self.overrides = Overrides::parse(request).unwrap_or_default();
    }

    /// What the page is told of an image rendered with `camera` at `width`×`height`.
    pub fn summary(&self, camera: &Camera, width: u32, height: u32, moving: bool) -> ViewSummary {
        let shown = PreviewCamera::of(camera);
        ViewSummary {
            camera: shown,
            camera_ron: shown.map(|camera| camera.to_ron()),
            preview_camera: self.camera.is_some(),
            shading: value_name(self.overrides.shading),
            model: value_name(self.overrides.model),
            debug: value_name(self.overrides.debug),
            buffer: self.buffer.is_some(),
            width,
            height,
            moving,
            timings: FrameTimings::default(),
        }
    }

    /// Renders the view of `scene`: its unsaved buffer or the file, with the preview camera and
    /// the overrides; reduced while `moving`.
    pub fn render(
        &mut self,
        scene: &Path,
        moving: bool,
        load_options: &LoadOptions,
        render_options: &RenderOptions,
        cache: &mut BuildCache,
    ) -> Result<PreviewFrame, PreviewError> {
        let started = Instant::now();
        let file_text;
        let text = match &self.buffer {
            Some(buffer) => buffer.as_str(),
            None => {
                file_text = std::fs::read_to_string(scene).map_err(PreviewError::Read)?;
                file_text.as_str()
            }
        };
        let edited;
        let text = match &self.camera {
            Some(camera) => {
                edited = with_camera(text, &camera.to_ron()).unwrap_or_else(|| text.to_owned());
                edited.as_str()
            }
            None => text,
        };
        let options = LoadOptions {
            shading: self
                .overrides
                .shading
                .map(ShadingArg::shading)
                .or(load_options.shading),
            model: self.overrides.model.map(ModelArg::model).or(load_options.model),
            ..load_options.clone()
        };
        let mut loaded = load_scene_from_str_cached(scene, text, &options, &mut cache.meshes)
            .map_err(PreviewError::Load)?;
        let loaded_at = Instant::now();
        let (width, height) = (loaded.scene.image.width, loaded.scene.image.height);
        let scale = if moving { self.moving_scale.max(2) } else { 1 };
        if moving {
            let image = &mut loaded.scene.image;
            image.width = width.div_ceil(scale);
            image.height = height.div_ceil(scale);
            image.samples = 1;
        }
        let render_options = RenderOptions {
            debug_view: self
                .overrides
                .debug
                .map(DebugArg::debug_view)
                .or(render_options.debug_view),
            ..*render_options
        };
        cache.renderer.render(&loaded.scene, &render_options);
        let rendered_at = Instant::now();
        let framebuffer = cache.renderer.take_framebuffer();
        let size = (framebuffer.width(), framebuffer.height());
        let png = output::encode_png_to_vec(&output::to_rgb8(&framebuffer), PngCompression::Fast);
        cache.renderer.reuse_framebuffer(framebuffer);
        let time = started.elapsed();
        if moving {
            self.moving_scale = next_moving_scale(scale, time);
        }
        let milliseconds = |duration: Duration| duration.as_secs_f64() * 1000.0;
        let summary = ViewSummary {
            timings: FrameTimings {
                load_ms: milliseconds(loaded_at - started),
                render_ms: milliseconds(rendered_at - loaded_at),
                encode_ms: milliseconds(rendered_at.elapsed()),
            },
            ..self.summary(&loaded.scene.camera, width, height, moving)
        };
        Ok(PreviewFrame {
            png: png.map_err(PreviewError::Encode)?,
            summary,
            size,
            time,
            origin: ImageOrigin {
                scene: std::sync::Arc::new(loaded.scene),
                sources: std::sync::Arc::new(loaded.sources),
                load_options: options,
                render_options,
                encoding: crate::output::Encoding::Linear,
            },
        })
    }
}

/// The reduction for the next frame made while moving, from how long this one took at `scale`:
/// finer while well inside the budget, coarser past it; between 2 and 8.
fn next_moving_scale(scale: u32, took: Duration) -> u32 {
    if took > MOVING_BUDGET && scale < 8 {
        scale * 2
    } else if took < MOVING_BUDGET / 5 && scale > 2 {
        scale / 2
    } else {
        scale
    }
}

/// Why a preview frame could not be made.
pub enum PreviewError {
    Read(io::Error),
    Load(LoadError),
    Encode(OutputError),
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> PreviewCamera {
        PreviewCamera {
            eye: [1.5, -2.0, 0.1],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 0.0, 1.0],
            fov: 32.5,
        }
    }

    /// `after` is `before` with `range` of `before` replaced: nothing outside it moved.
    fn only_span_changed(before: &str, after: &str, expected_span: &str) {
        let start = before.find(expected_span).unwrap();
        let end = start + expected_span.len();
        let tail = &before[end..];
        assert!(after.starts_with(&before[..start]), "{after}");
        assert!(after.ends_with(tail), "{after}");
    }

    #[test]
    fn cameras_are_written_in_the_scene_format_and_read_back_exactly() {
        let camera = PreviewCamera {
            eye: [0.1 + 0.2, -5.8, 1e-7],
            target: [-1.0, -0.0, 0.0],
            up: [0.0, 0.0, 1.0],
            fov: 30.0,
        };
        let ron = camera.to_ron();
        assert_eq!(
            ron,
            "Perspective(eye: (0.30000000000000004, -5.8, 0.0000001), target: (-1, 0, 0), up: (0, 0, 1), fov: 30)"
        );
        let text = format!("(camera: {ron}, objects: [(mesh: Sphere(segments: 8))])");
        let loaded =
            crate::scene::load_scene_from_str(Path::new("s.ron"), &text, &LoadOptions::default()).unwrap();
        assert_eq!(PreviewCamera::of(&loaded.scene.camera), Some(camera));
    }

    #[test]
    fn the_camera_value_alone_is_replaced_keeping_comments_and_fields() {
        let before = "// a scene\nScene(\n    image: (width: 64, height: 48), // small\n    camera: Perspective(eye: (0, 0, 5), /* comment inside */ fov: 40),\n    objects: [(mesh: Cube)], /* end */\n)\n";
        let after = with_camera(before, &camera().to_ron()).unwrap();
        only_span_changed(
            before,
            &after,
            "Perspective(eye: (0, 0, 5), /* comment inside */ fov: 40)",
        );
        assert!(after.contains(&format!("    camera: {},\n", camera().to_ron())));
    }

    #[test]
    fn a_scene_without_a_camera_gets_one_as_its_first_field() {
        let ron = camera().to_ron();
        let multiline = "#![enable(implicit_some)]\n// lights only\nScene(\n  // the object\n  objects: [(mesh: Cube)],\n)\n";
        let after = with_camera(multiline, &ron).unwrap();
        assert_eq!(
            after,
            format!(
                "#![enable(implicit_some)]\n// lights only\nScene(\n  // the object\n  camera: {ron},\n  objects: [(mesh: Cube)],\n)\n"
            )
        );
        assert_eq!(
            with_camera("(objects: [(mesh: Cube)])", &ron).unwrap(),
            format!("(camera: {ron}, objects: [(mesh: Cube)])")
        );
        assert_eq!(
            with_camera("Scene()", &ron).unwrap(),
            format!("Scene(camera: {ron})")
        );
        assert_eq!(with_camera("[1, 2]", &ron), None);
        for text in [multiline, "(objects: [(mesh: Cube)])"] {
            let edited = with_camera(text, &ron).unwrap();
            let loaded =
                crate::scene::load_scene_from_str(Path::new("s.ron"), &edited, &LoadOptions::default())
                    .unwrap();
            assert_eq!(PreviewCamera::of(&loaded.scene.camera), Some(camera()));
        }
    }

    #[test]
    fn writing_the_camera_touches_only_the_scene_file_and_only_its_camera() {
        let folder = tempfile::tempdir().unwrap();
        let library = "(materials: { \"red\": (diffuse: (1, 0, 0)) }) // library\n";
        std::fs::write(folder.path().join("mats.ron"), library).unwrap();
        let scene = folder.path().join("scene.ron");
        let before = "Scene(\n    include: [\"mats.ron\"],\n    camera: Perspective(fov: 20), // was\n    objects: [(mesh: Cube, material: \"red\")],\n)\n";
        std::fs::write(&scene, before).unwrap();
        write_camera(&scene, &camera()).unwrap();
        let after = std::fs::read_to_string(&scene).unwrap();
        only_span_changed(before, &after, "Perspective(fov: 20)");
        assert_eq!(
            std::fs::read_to_string(folder.path().join("mats.ron")).unwrap(),
            library
        );
        let loaded = crate::scene::load_scene(&scene, &LoadOptions::default()).unwrap();
        assert_eq!(PreviewCamera::of(&loaded.scene.camera), Some(camera()));
        let leftovers: Vec<_> = std::fs::read_dir(folder.path()).unwrap().collect();
        assert_eq!(leftovers.len(), 2, "no temporary file left behind");
    }

    #[test]
    fn degenerate_cameras_are_refused() {
        let valid = camera();
        assert!(valid.is_valid());
        let cases = [
            PreviewCamera {
                eye: valid.target,
                ..valid
            },
            PreviewCamera {
                up: [1.5, -2.0, 0.1],
                ..valid
            },
            PreviewCamera {
                up: [0.0; 3],
                ..valid
            },
            PreviewCamera { fov: 180.0, ..valid },
            PreviewCamera {
                eye: [f64::NAN, 0.0, 0.0],
                ..valid
            },
        ];
        for case in cases {
            assert!(!case.is_valid(), "{case:?}");
        }
    }

    #[test]
    fn overrides_use_the_command_line_names() {
        let request = ViewRequest {
            shading: Some("gouraud".into()),
            model: Some("blinn-phong".into()),
            debug: Some("normals".into()),
            ..ViewRequest::default()
        };
        let overrides = Overrides::parse(&request).unwrap();
        assert_eq!(overrides.model, Some(ModelArg::BlinnPhong));
        assert_eq!(value_name(overrides.model).as_deref(), Some("blinn-phong"));
        let unknown = ViewRequest {
            debug: Some("wireframe".into()),
            ..ViewRequest::default()
        };
        assert_eq!(
            Overrides::parse(&unknown),
            Err("unknown debug view `wireframe`".into())
        );
    }

    #[test]
    fn frames_made_while_moving_shrink_past_the_budget_and_grow_back_well_inside_it() {
        assert_eq!(next_moving_scale(2, MOVING_BUDGET * 2), 4);
        assert_eq!(next_moving_scale(8, MOVING_BUDGET * 2), 8);
        assert_eq!(next_moving_scale(4, MOVING_BUDGET / 10), 2);
        assert_eq!(next_moving_scale(2, MOVING_BUDGET / 10), 2);
        assert_eq!(next_moving_scale(4, MOVING_BUDGET / 2), 4);
    }

    #[test]
    fn a_preview_frame_at_full_size_is_the_render_of_the_written_camera() {
        let folder = tempfile::tempdir().unwrap();
        let scene = folder.path().join("scene.ron");
        // A point light without a position sits at the eye: it must follow the preview camera.
        std::fs::write(
            &scene,
            "(image: (width: 40, height: 30), lights: [Point()], objects: [(mesh: Sphere(segments: 12))])",
        )
        .unwrap();
        let mut view = View {
            camera: Some(camera()),
            ..View::default()
        };
        let mut cache = BuildCache::default();
        let (load, render) = (LoadOptions::default(), RenderOptions::default());
        let preview = view
            .render(&scene, false, &load, &render, &mut cache)
            .ok()
            .unwrap();
        let moving = view
            .render(&scene, true, &load, &render, &mut cache)
            .ok()
            .unwrap();
        assert_eq!((moving.summary.width, moving.summary.height), (40, 30));
        assert!(moving.summary.moving);
        let timings = moving.summary.timings;
        assert!(timings.render_ms > 0.0 && timings.encode_ms > 0.0, "{timings:?}");
        let state = serde_json::to_value(&moving.summary).unwrap();
        assert!(state["timings"]["load_ms"].is_number(), "{state}");
        let small = image::load_from_memory(&moving.png).unwrap();
        assert_eq!((small.width(), small.height()), (20, 15));

        write_camera(&scene, &camera()).unwrap();
        let mut file_view = View::default();
        let written = file_view
            .render(&scene, false, &load, &render, &mut cache)
            .ok()
            .unwrap();
        assert_eq!(preview.png, written.png);
        assert_eq!(written.summary.camera, Some(camera()));
        assert!(!written.summary.preview_camera);
    }
}
