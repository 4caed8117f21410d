//! `lampshade render --turntable N`: N frames of the camera orbiting its target, written as one
//! animated PNG (APNG) or as numbered images (`-o spin-%03d.png`).
//!
//! Design:
//! - Frame `i` of `N` is the scene's camera turned by `i/N` of a full turn about an axis through
//!   its target ([`orbit_camera`]): eye and up rotate, target, distance and projection stay, so
//!   frame 0 is the scene's own camera. Each frame is the scene with that camera rendered by
//!   the ordinary renderer, so a frame is bit for bit the image `render` gives for that camera
//!   (the image never depends on threads or on the frame rendered before).
//! - Frames are rendered in parallel across frames as well as across tiles: a group of as many
//!   frames as the pool has threads is in flight at once, each with its own [`Renderer`] (kept
//!   from group to group), then handed on in frame order. Only one group's frame buffers exist
//!   at a time, so memory grows with the thread count, not with N.
//! - Writing is atomic as everywhere ([`output::write_atomically`]): the APNG is encoded in
//!   memory as the groups finish (compressed, so a long sequence stays small) and written in one
//!   piece at the end; a numbered frame is written as soon as its group is done, each file
//!   atomically. Ctrl-C or an error leaves no half-written file.
//! - `--shard K/N` takes the frames whose number is K−1 modulo N (every N-th frame), parsed as
//!   `check --shard` is ([`Shard`]), so a long sequence splits over a CI matrix and the shards'
//!   numbered files together are every frame exactly once. An APNG cannot be split, so a shard
//!   needs numbered frames.
//!
//! Rejected: a `--fps` knob (a preview plays at 25 frames per second; numbered frames are for
//! a video tool that sets its own rate); GIF (256 colours, no exact frames); encoding each APNG
//! frame in parallel (the `png` crate encodes one stream in order, and encoding is a small part
//! of a frame's time).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use glam::{DQuat, DVec3};
use rayon::prelude::*;

use crate::check::select::Shard;
use crate::output::{self, Encoding, OutputError, OutputFormat, PngCompression};
use crate::render::{FrameBuffer, RenderOptions, RenderStats, Renderer};
use crate::scene::{Camera, Scene};

/// An APNG plays at this many frames per second (numerator, denominator of a frame's delay).
const FRAME_DELAY: (u16, u16) = (1, 25);

/// The axis a turntable turns about, through the camera's target.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum TurntableAxis {
    /// The camera's up direction: the model turns as on a potter's wheel, whatever the
    /// scene's convention.
    #[default]
    Up,
    X,
    Y,
    Z,
}

impl TurntableAxis {
    /// The axis as a unit vector for `camera`.
    pub fn direction(self, camera: &Camera) -> DVec3 {
        match self {
            TurntableAxis::Up => camera.up.normalize(),
            TurntableAxis::X => DVec3::X,
            TurntableAxis::Y => DVec3::Y,
            TurntableAxis::Z => DVec3::Z,
        }
    }
}

/// The camera of frame `frame` of `frames`: `camera` turned by `frame/frames` of a full turn
/// about `axis` (a unit vector) through its target. Frame 0 is `camera` itself, bit for bit.
pub fn orbit_camera(camera: &Camera, axis: DVec3, frame: u32, frames: u32) -> Camera {
    let angle = std::f64::consts::TAU * f64::from(frame) / f64::from(frames);
    let rotation = DQuat::from_axis_angle(axis, angle);
    // An up along the axis stays as it is, bit for bit (the rotation would round it).
    let up_is_axis = camera.up.reject_from(axis).length() <= 1e-12 * camera.up.length();
    Camera {
        eye: camera.target + rotation * (camera.eye - camera.target),
        up: if up_is_axis {
            camera.up
        } else {
            rotation * camera.up
        },
        ..*camera
    }
}

/// Why an orbit about `axis` is impossible for `camera`, if it is: an eye on the axis would
/// stand still and look along it.
pub fn orbit_problem(camera: &Camera, axis: DVec3) -> Option<String> {
    let offset = camera.eye - camera.target;
    let off_axis = offset.reject_from(axis).length();
    (off_axis <= 1e-9 * offset.length().max(f64::MIN_POSITIVE)).then(|| {
        String::from(
            "the camera looks along the turntable axis, so it cannot orbit about it\n  \
             = help: choose another axis with --axis x, y or z",
        )
    })
}

/// Where numbered frames go: `-o spin-%03d.png` is `spin-` + the frame number, zero-padded to
/// three digits, + `.png`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FramePattern {
    prefix: String,
    /// Zero-padded to this many digits (`%03d`); 0 for `%d`.
    digits: usize,
    suffix: String,
}

impl FramePattern {
    /// The pattern in `path`, `None` when it has no `%`; an error for a `%` that is not one
    /// `%d` or `%0Nd`.
    pub fn parse(path: &Path) -> Result<Option<FramePattern>, String> {
        let Some(text) = path.to_str() else {
            return Ok(None);
        };
        let Some(start) = text.find('%') else {
            return Ok(None);
        };
        let usage = || {
            format!(
                "`{text}` is not a frame pattern: write one `%d` or `%03d` where the frame number \
                 goes, e.g. `-o spin-%03d.png`"
            )
        };
        let rest = &text[start + 1..];
        let width_len = rest.bytes().take_while(u8::is_ascii_digit).count();
        let (width, after) = rest.split_at(width_len);
        let Some(suffix) = after.strip_prefix('d') else {
            return Err(usage());
        };
        let digits = match width {
            "" => 0,
            _ if width.starts_with('0') && width.len() > 1 => width[1..].parse().map_err(|_| usage())?,
            _ => return Err(usage()),
        };
        if suffix.contains('%') || digits > 9 {
            return Err(usage());
        }
        Ok(Some(FramePattern {
            prefix: text[..start].to_owned(),
            digits,
            suffix: suffix.to_owned(),
        }))
    }

    /// The file of frame `frame`.
    pub fn path(&self, frame: u32) -> PathBuf {
        let FramePattern {
            prefix,
            digits,
            suffix,
        } = self;
        PathBuf::from(format!("{prefix}{frame:0digits$}{suffix}"))
    }
}

/// What a turntable writes.
#[derive(Debug, Clone)]
pub enum TurntableOutput {
    /// One animated PNG.
    Animation(PathBuf),
    /// One file per frame, in `format`.
    Numbered(FramePattern, OutputFormat),
}

/// Which frames this run renders: all, or every `count`-th from `index − 1` with `--shard`.
pub fn frames_to_render(frames: u32, shard: Option<Shard>) -> Vec<u32> {
    (0..frames)
        .filter(|frame| shard.is_none_or(|shard| frame % shard.count == shard.index - 1))
        .collect()
}

/// What rendering a turntable took.
#[derive(Debug, Default)]
pub struct TurntableStats {
    pub frames: usize,
    /// Wall time rendering, all frames.
    pub render: Duration,
    /// Wall time quantising, encoding and writing.
    pub encode: Duration,
    pub triangles: usize,
    pub threads: usize,
}

/// The orbit a turntable renders: which frames of how many, about which axis.
#[derive(Debug, Clone)]
pub struct Orbit<'a> {
    /// A unit vector through the camera's target.
    pub axis: DVec3,
    /// Frames in a full turn.
    pub frame_count: u32,
    /// The frame numbers to render, in the order they are handed on.
    pub frames: &'a [u32],
}

/// Renders `frames` (frame numbers of `frame_count`) of `scene` orbiting about `axis` and writes
/// them to `destination`; `written` is told each file as it is in place.
pub fn render_turntable(
    scene: &Scene,
    orbit: &Orbit,
    render_options: &RenderOptions,
    destination: &TurntableOutput,
    encoding: Encoding,
    mut written: impl FnMut(&Path) + Send,
) -> Result<TurntableStats, OutputError> {
    match destination {
        TurntableOutput::Animation(path) => {
            let (bytes, mut stats) = render_animation(scene, orbit, render_options, encoding, path)?;
            let started = Instant::now();
            write_bytes(path, &bytes)?;
            written(path);
            stats.encode += started.elapsed();
            Ok(stats)
        }
        TurntableOutput::Numbered(pattern, format) => {
            render_frames(scene, orbit, render_options, |frame, framebuffer| {
                let path = pattern.path(frame);
                output::write_image(&path, framebuffer, *format, encoding, PngCompression::Fast)?;
                written(&path);
                Ok(())
            })
        }
    }
}

/// The frames of `orbit` as one APNG in memory (`path` names it in errors).
pub fn render_animation(
    scene: &Scene,
    orbit: &Orbit,
    render_options: &RenderOptions,
    encoding: Encoding,
    path: &Path,
) -> Result<(Vec<u8>, TurntableStats), OutputError> {
    let mut bytes = Vec::new();
    let mut animation = AnimationEncoder::new(path, scene, orbit.frames.len(), &mut bytes)?;
    let mut stats = render_frames(scene, orbit, render_options, |_, framebuffer| {
        animation.add_frame(framebuffer, encoding)
    })?;
    let started = Instant::now();
    animation.finish()?;
    stats.encode += started.elapsed();
    Ok((bytes, stats))
}

/// Renders the frames of `orbit` in groups of one per thread and hands each to `take`, in
/// order.
fn render_frames(
    scene: &Scene,
    orbit: &Orbit,
    render_options: &RenderOptions,
    mut take: impl FnMut(u32, &FrameBuffer) -> Result<(), OutputError> + Send,
) -> Result<TurntableStats, OutputError> {
    let mut run = || {
        let frames = orbit.frames;
        let mut stats = TurntableStats {
            frames: frames.len(),
            threads: rayon::current_num_threads(),
            ..TurntableStats::default()
        };
        // Each render uses the pool this runs in; building a pool per frame would cost threads.
        let options = RenderOptions {
            threads: None,
            ..*render_options
        };
        let group_size = rayon::current_num_threads().clamp(1, frames.len().max(1));
        let mut renderers: Vec<Renderer> = (0..group_size).map(|_| Renderer::default()).collect();
        for group in frames.chunks(group_size) {
            let started = Instant::now();
            let rendered: Vec<(u32, FrameBuffer, RenderStats)> = renderers
                .par_iter_mut()
                .zip(group)
                .map(|(renderer, &frame)| {
                    let mut orbiting = scene.clone();
                    orbiting.camera = orbit_camera(&scene.camera, orbit.axis, frame, orbit.frame_count);
                    let frame_stats = renderer.render(&orbiting, &options);
                    (frame, renderer.take_framebuffer(), frame_stats)
                })
                .collect();
            stats.render += started.elapsed();
            let started = Instant::now();
            for ((frame, framebuffer, frame_stats), renderer) in rendered.into_iter().zip(&mut renderers) {
                stats.triangles = frame_stats.triangles;
                take(frame, &framebuffer)?;
                renderer.reuse_framebuffer(framebuffer);
            }
            stats.encode += started.elapsed();
        }
        Ok(stats)
    };
    match render_options.threads {
        Some(threads) => match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
            Ok(pool) => pool.install(run),
            Err(_) => run(),
        },
        None => run(),
    }
}

/// An APNG being encoded into memory, frame by frame.
struct AnimationEncoder<'a> {
    writer: png::Writer<&'a mut Vec<u8>>,
    path: PathBuf,
}

impl<'a> AnimationEncoder<'a> {
    fn new(
        path: &Path,
        scene: &Scene,
        frames: usize,
        bytes: &'a mut Vec<u8>,
    ) -> Result<AnimationEncoder<'a>, OutputError> {
        let encode_error = |error: png::EncodingError| encode_error(path, error);
        let (width, height) = (scene.image.width, scene.image.height);
        let mut encoder = png::Encoder::new(bytes, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        // As `output` writes a still: fast deflate, every row filtered by the row above.
        encoder.set_compression(png::Compression::Fast);
        encoder.set_filter(png::Filter::Up);
        let frame_count = u32::try_from(frames).unwrap_or(u32::MAX);
        // 0 plays: loop for ever.
        encoder.set_animated(frame_count, 0).map_err(encode_error)?;
        encoder
            .set_frame_delay(FRAME_DELAY.0, FRAME_DELAY.1)
            .map_err(encode_error)?;
        let writer = encoder.write_header().map_err(encode_error)?;
        Ok(AnimationEncoder {
            writer,
            path: path.to_path_buf(),
        })
    }

    fn add_frame(&mut self, framebuffer: &FrameBuffer, encoding: Encoding) -> Result<(), OutputError> {
        let pixels = output::to_rgb8_encoded(framebuffer, encoding);
        self.writer
            .write_image_data(pixels.as_raw())
            .map_err(|error| encode_error(&self.path, error))
    }

    /// Ends the stream (checks that every announced frame was written).
    fn finish(self) -> Result<(), OutputError> {
        self.writer
            .finish()
            .map_err(|error| encode_error(&self.path, error))
    }
}

/// Puts `bytes` at `path` atomically.
fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    output::write_atomically(path, |file| {
        use std::io::Write as _;
        file.write_all(bytes).map_err(|source| OutputError::Io {
            path: path.to_path_buf(),
            source,
        })
    })
}

fn encode_error(path: &Path, error: png::EncodingError) -> OutputError {
    OutputError::Encode {
        path: path.to_path_buf(),
        source: image::ImageError::IoError(std::io::Error::other(error)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_patterns() {
        let pattern = FramePattern::parse(Path::new("out/spin-%03d.png"))
            .unwrap()
            .unwrap();
        assert_eq!(pattern.path(7), Path::new("out/spin-007.png"));
        assert_eq!(pattern.path(1234), Path::new("out/spin-1234.png"));
        let plain = FramePattern::parse(Path::new("f%d.exr")).unwrap().unwrap();
        assert_eq!(plain.path(12), Path::new("f12.exr"));
        assert_eq!(FramePattern::parse(Path::new("spin.png")).unwrap(), None);
        for bad in [
            "spin-%s.png",
            "spin-%3d.png",
            "a-%d-%d.png",
            "spin-%.png",
            "%0d.png",
            "%%.png",
        ] {
            assert!(FramePattern::parse(Path::new(bad)).is_err(), "{bad}");
        }
    }

    #[test]
    fn shards_take_every_nth_frame_and_cover_each_once() {
        let shard = |text: &str| Some(text.parse::<Shard>().unwrap());
        assert_eq!(frames_to_render(5, None), [0, 1, 2, 3, 4]);
        assert_eq!(frames_to_render(10, shard("2/3")), [1, 4, 7]);
        let mut all: Vec<u32> = (1..=4)
            .flat_map(|k| frames_to_render(10, shard(&format!("{k}/4"))))
            .collect();
        all.sort_unstable();
        assert_eq!(all, (0..10).collect::<Vec<_>>());
    }

    #[test]
    fn orbits_keep_target_distance_and_start_at_the_scene_camera() {
        let camera = Camera {
            eye: DVec3::new(3.8, -5.8, 3.4),
            target: DVec3::new(-1.0, -1.0, 0.0),
            up: DVec3::Z,
            projection: crate::scene::Projection::Perspective {
                fov_y_degrees: 30.0,
                near: 0.1,
                far: 100.0,
            },
        };
        assert_eq!(orbit_camera(&camera, DVec3::Z, 0, 12), camera);
        let distance = camera.eye.distance(camera.target);
        for frame in 1..12 {
            let turned = orbit_camera(&camera, DVec3::Z, frame, 12);
            assert_eq!(turned.target, camera.target);
            assert_eq!(turned.up, camera.up, "up along the axis does not move");
            assert!((turned.eye.distance(turned.target) - distance).abs() < 1e-12);
            assert!(
                (turned.eye.z - camera.eye.z).abs() < 1e-12,
                "height about the axis kept"
            );
        }
        let half = orbit_camera(&camera, DVec3::Z, 6, 12);
        let mirrored = 2.0 * camera.target - camera.eye;
        assert!((half.eye.truncate() - mirrored.truncate()).length() < 1e-12);
        assert!(orbit_problem(&camera, DVec3::Z).is_none());
        let looking_down = Camera {
            eye: DVec3::new(-1.0, -1.0, 5.0),
            up: DVec3::Y,
            ..camera
        };
        assert!(orbit_problem(&looking_down, DVec3::Z).is_some());
    }
}
