//! `/turntable.png?frames=N` of the preview: the watched scene as it is on disk, its camera
//! orbiting about its up direction, as an animated PNG the page plays in an `<img>`.
//!
//! It is made on request, on a thread of its own (the server's one accepting thread keeps
//! answering), from the same files and options as the watch's builds, through the same code as
//! `render --turntable` ([`crate::turntable::render_animation`]), at a reduced size: the longest
//! side [`PREVIEW_SIZE`] pixels, so 36 frames cost about as much as one full-size image.
//! Rejected: rendering it with every build (most builds are never turned); caching it across
//! builds (the page asks again with the new image's version, and a stale turntable would lie).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use tiny_http::{Request, Response};

use super::server::{respond, text, with_headers};
use crate::diag::render_diagnostics;
use crate::output::Encoding;
use crate::render::RenderOptions;
use crate::scene::load::{LoadOptions, load_scene};
use crate::turntable::{Orbit, TurntableAxis, orbit_problem, render_animation};

/// The longest side of a preview turntable's frames, in pixels.
pub const PREVIEW_SIZE: u32 = 320;

/// Frames when the request does not say, and the most it may ask for.
pub const DEFAULT_FRAMES: u32 = 36;
pub const MAX_FRAMES: u32 = 360;

/// What a turntable is made from: the watch's scene and options.
#[derive(Debug, Clone)]
pub struct TurntableSource {
    pub scene: PathBuf,
    pub load_options: LoadOptions,
    pub render_options: RenderOptions,
}

impl TurntableSource {
    /// The APNG of `frames` frames, or what went wrong (the scene's diagnostics, plain).
    pub fn render(&self, frames: u32) -> Result<Vec<u8>, String> {
        let loaded = load_scene(&self.scene, &self.load_options)
            .map_err(|error| render_diagnostics(&error.diagnostics, &error.sources, false))?;
        let mut scene = loaded.scene;
        let (width, height) = (scene.image.width, scene.image.height);
        let longest = width.max(height);
        if longest > PREVIEW_SIZE {
            let shrink =
                |side: u32| ((u64::from(side) * u64::from(PREVIEW_SIZE)) / u64::from(longest)).max(1) as u32;
            scene.image.width = shrink(width);
            scene.image.height = shrink(height);
        }
        let axis = TurntableAxis::Up.direction(&scene.camera);
        if let Some(problem) = orbit_problem(&scene.camera, axis) {
            return Err(problem);
        }
        let numbers: Vec<u32> = (0..frames).collect();
        let orbit = Orbit {
            axis,
            frame_count: frames,
            frames: &numbers,
        };
        render_animation(
            &scene,
            &orbit,
            &self.render_options,
            Encoding::Linear,
            Path::new("turntable.png"),
        )
        .map(|(bytes, _)| bytes)
        .map_err(|error| error.to_string())
    }
}

/// The frame count `url` asks for (`?frames=N`), [`DEFAULT_FRAMES`] when it does not say.
pub fn frames_asked(url: &str) -> Result<u32, String> {
    let query = url.split_once('?').map_or("", |(_, query)| query);
    let asked = query.split('&').find_map(|pair| pair.strip_prefix("frames="));
    match asked {
        None => Ok(DEFAULT_FRAMES),
        Some(text) => match text.parse::<u32>() {
            Ok(frames) if (1..=MAX_FRAMES).contains(&frames) => Ok(frames),
            _ => Err(format!(
                "frames must be a whole number from 1 to {MAX_FRAMES}, not `{text}`"
            )),
        },
    }
}

/// Answers `/turntable.png` on a thread of its own.
pub fn answer(request: Request, source: Option<Arc<TurntableSource>>) {
    let work = move || {
        let frames = match frames_asked(request.url()) {
            Ok(frames) => frames,
            Err(message) => return respond(request, text(400, &message)),
        };
        let Some(source) = source else {
            return respond(request, text(503, "the watch has not started building yet"));
        };
        match source.render(frames) {
            Ok(png) => respond(
                request,
                with_headers(
                    Response::from_data(png),
                    &[("Content-Type", "image/png"), ("Cache-Control", "no-store")],
                ),
            ),
            Err(message) => respond(request, text(422, &message)),
        }
    };
    if let Err(error) = std::thread::Builder::new()
        .name("preview turntable".into())
        .spawn(work)
    {
        errln!("warning: preview: cannot start a turntable: {error}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_counts_from_the_query() {
        assert_eq!(frames_asked("/turntable.png"), Ok(DEFAULT_FRAMES));
        assert_eq!(frames_asked("/turntable.png?v=3&frames=12"), Ok(12));
        for bad in ["0", "-1", "many", "361"] {
            assert!(
                frames_asked(&format!("/turntable.png?frames={bad}")).is_err(),
                "{bad}"
            );
        }
    }
}
