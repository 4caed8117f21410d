//! The output stage: a linear [`FrameBuffer`] quantised to 8 bits and written as PNG.
//!
//! Quantisation: each channel is clamped to [0, 1] (values above 1, from bright lights, saturate
//! instead of wrapping; NaN, which the renderer never produces, would become 0) and rounded to the
//! nearest of 256 levels, `⌊255·c + ½⌋`. Values are written as they are (linear), as OpenGL writes a
//! framebuffer without sRGB conversion, which is what the reference images assume.
//!
//! Architecture invariant: an image is written to a temporary file in the destination folder and
//! renamed over the destination only once complete, so a failed or interrupted write never leaves
//! a truncated PNG or clobbers the previous one, and a viewer never reads half a file.
//!
//! Interruption: a failed write removes its temporary file (dropping `NamedTempFile`), but a
//! process killed by Ctrl-C runs no destructors. So the commands route Ctrl-C through
//! [`exit_when_no_write_is_in_progress`]: every write holds a shared lock for its whole
//! duration, and the exit takes the lock exclusively, so it waits for the writes under way to be
//! renamed into place and no new one starts. Rendering itself writes nothing, so an interrupted
//! render stops at once and leaves the previous image as it was.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::RwLock;
use std::time::{Duration, Instant};

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ImageEncoder, RgbImage};

use rayon::prelude::*;

use crate::render::{FrameBuffer, RowSpan};

mod fast_png;

/// A problem writing an output file (not the user's scene: the file system's).
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot write `{}`: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}", would_replace_message(path, input))]
    WouldReplaceInput { path: PathBuf, input: PathBuf },
    #[error("cannot encode `{}`: {source}", path.display())]
    Encode {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    #[error("cannot encode `{}`: {source}", path.display())]
    EncodePng {
        path: PathBuf,
        #[source]
        source: png::EncodingError,
    },
}

/// "not writing `out.png`: the scene reads it", naming the input too when it is spelled
/// differently (a symlink, `..`, a hard link).
fn would_replace_message(path: &Path, input: &Path) -> String {
    if path == input {
        format!("not writing `{}`: the scene reads it", path.display())
    } else {
        format!(
            "not writing `{}`: it is `{}`, a file the scene reads",
            path.display(),
            input.display()
        )
    }
}

/// One channel of linear light to an 8-bit level: `⌊255·c + ½⌋` of the channel clamped to
/// [0, 1]. `f32::max` returns the other operand when one is NaN, so NaN becomes 0 without a
/// branch (this runs for every channel of every image); `clamp` would keep the NaN.
///
/// The floor is taken without a float-to-integer cast, because Rust's saturating `as u8` keeps
/// a loop over a frame scalar (28 instructions a pixel) while this form compiles to SSE2 lanes
/// (8 a pixel, by callgrind on a 1080p frame): adding 2²³ rounds the level, which lies in
/// [½, 255½], to the nearest integer and leaves that integer in the low mantissa bits; where
/// the rounding went up, one less is the floor. It equals the plain `(c·255 + ½) as u8` for all
/// 2³² inputs (checked exhaustively when written; the tests check every rounding boundary and
/// a sweep of the rest).
#[inline(always)]
#[allow(clippy::manual_clamp)]
pub fn quantize_channel(value: f32) -> u8 {
    /// 2²³: from here on an `f32`'s unit in the last place is 1.
    const ROUND_TO_INTEGER: f32 = 8_388_608.0;
    let level = value.max(0.0).min(1.0) * 255.0 + 0.5;
    let rounded = level + ROUND_TO_INTEGER;
    let rounded_up = u32::from(rounded - ROUND_TO_INTEGER > level);
    rounded.to_bits().wrapping_sub(rounded_up) as u8
}

/// How 8-bit output stores light.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Encoding {
    /// The linear values as they are, like an OpenGL framebuffer without sRGB conversion (the
    /// reference images of the seeds' scenes assume it).
    #[default]
    Linear,
    /// Through the sRGB transfer function first, as displays expect: mid-tones come out lighter
    /// and gradients perceptually even.
    Srgb,
}

/// The sRGB transfer function (IEC 61966-2-1), linear light in, encoded value out.
pub fn linear_to_srgb(value: f32) -> f32 {
    if value <= 0.003_130_8 {
        12.92 * value
    } else {
        1.055 * value.powf(1.0 / 2.4) - 0.055
    }
}

/// The frame as 8-bit RGB: clamped, encoded, rounded.
pub fn to_rgb8(framebuffer: &FrameBuffer) -> RgbImage {
    to_rgb8_encoded(framebuffer, Encoding::Linear)
}

pub fn to_rgb8_encoded(framebuffer: &FrameBuffer, encoding: Encoding) -> RgbImage {
    let (width, height) = (framebuffer.width(), framebuffer.height());
    let mut bytes = vec![0u8; width as usize * height as usize * 3];
    let quantizer = RowQuantizer::new(framebuffer, encoding);
    // Rows in parallel: each writes its own bytes, so the result does not depend on threads.
    bytes
        .par_chunks_mut(width.max(1) as usize * 3)
        .enumerate()
        .for_each(|(y, row)| quantizer.quantize_row(y as u32, row));
    RgbImage::from_raw(width, height, bytes).expect("a frame buffer holds width × height pixels")
}

/// Quantises a frame's rows to 8-bit RGB, one row at a time, so that [`to_rgb8_encoded`] and
/// the PNG encoder's strips (which quantise their own rows) give the same levels.
struct RowQuantizer<'a> {
    framebuffer: &'a FrameBuffer,
    encoding: Encoding,
    /// The background's three levels, written for every pixel of a blank span.
    background: [u8; 3],
}

impl<'a> RowQuantizer<'a> {
    fn new(framebuffer: &'a FrameBuffer, encoding: Encoding) -> RowQuantizer<'a> {
        let background = framebuffer
            .background()
            .to_array()
            .map(|channel| quantize_encoded(channel, encoding));
        RowQuantizer {
            framebuffer,
            encoding,
            background,
        }
    }

    /// Writes row `y`'s levels (three a pixel) into `levels`. A blank span is the background's
    /// three levels over and over; a drawn span's channels are one flat run of `f32`s, so the
    /// linear loop runs in SIMD lanes.
    fn quantize_row(&self, y: u32, mut levels: &mut [u8]) {
        for span in self.framebuffer.row_spans(y) {
            let (span_levels, rest) = std::mem::take(&mut levels).split_at_mut(span_channels(span));
            levels = rest;
            match span {
                RowSpan::Blank(_) => {
                    for pixel in span_levels.as_chunks_mut::<3>().0 {
                        *pixel = self.background;
                    }
                }
                RowSpan::Drawn { color, .. } => {
                    let channels: &[f32] = bytemuck::cast_slice(color);
                    match self.encoding {
                        Encoding::Linear => {
                            for (level, &channel) in span_levels.iter_mut().zip(channels) {
                                *level = quantize_channel(channel);
                            }
                        }
                        Encoding::Srgb => {
                            for (level, &channel) in span_levels.iter_mut().zip(channels) {
                                *level = quantize_encoded(channel, Encoding::Srgb);
                            }
                        }
                    }
                }
            }
        }
    }
}

/// One channel of linear light to its 8-bit level in `encoding`.
#[inline(always)]
fn quantize_encoded(channel: f32, encoding: Encoding) -> u8 {
    match encoding {
        Encoding::Linear => quantize_channel(channel),
        Encoding::Srgb => quantize_channel(linear_to_srgb(channel.clamp(0.0, 1.0))),
    }
}

/// The number of channels (three a pixel) of `span`.
fn span_channels(span: RowSpan) -> usize {
    3 * match span {
        RowSpan::Blank(pixels) => pixels,
        RowSpan::Drawn { color, .. } => color.len(),
    }
}

/// The frame's linear channels, RGB a pixel, row-major: what the float formats store.
fn linear_channels(framebuffer: &FrameBuffer) -> Vec<f32> {
    let mut channels = Vec::with_capacity(framebuffer.width() as usize * framebuffer.height() as usize * 3);
    let background = framebuffer.background().to_array();
    for y in 0..framebuffer.height() {
        for span in framebuffer.row_spans(y) {
            match span {
                RowSpan::Blank(pixels) => {
                    channels.extend(std::iter::repeat_n(background, pixels).flatten());
                }
                RowSpan::Drawn { color, .. } => channels.extend_from_slice(bytemuck::cast_slice(color)),
            }
        }
    }
    channels
}

/// The file formats lampshade writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputFormat {
    /// 8-bit RGB PNG, clamped to [0, 1].
    Png,
    /// OpenEXR, 32-bit float RGB, linear and unclamped.
    Exr,
    /// Radiance HDR (RGBE), linear and unclamped.
    Hdr,
}

impl OutputFormat {
    /// The format a file name asks for, by its extension (case-insensitive).
    pub fn from_path(path: &Path) -> Option<OutputFormat> {
        let extension = path.extension()?.to_str()?.to_ascii_lowercase();
        match extension.as_str() {
            "png" => Some(OutputFormat::Png),
            "exr" => Some(OutputFormat::Exr),
            "hdr" => Some(OutputFormat::Hdr),
            _ => None,
        }
    }

    /// The format's name in messages.
    pub fn name(self) -> &'static str {
        match self {
            OutputFormat::Png => "PNG",
            OutputFormat::Exr => "OpenEXR",
            OutputFormat::Hdr => "Radiance HDR",
        }
    }

    pub fn extension(self) -> &'static str {
        match self {
            OutputFormat::Png => "png",
            OutputFormat::Exr => "exr",
            OutputFormat::Hdr => "hdr",
        }
    }
}

/// Where a command's image goes, and in which format: the one rule `render` and `watch` share.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Destination {
    /// A file; `None` lets the command choose it (beside the scene, with the format's extension).
    File(Option<PathBuf>),
    /// Standard output (`-o -`), as Unix tools do.
    Stdout,
}

/// The file name `-o -` uses for standard output.
pub const STDOUT_NAME: &str = "-";

/// Decides the format of `output` (`-o`) given `--format`: the format follows the extension; a
/// `--format` that contradicts it is an error; an unsupported or missing extension is an error
/// unless `--format` names the format. `-` is standard output, in `--format` or PNG.
pub fn choose_format(
    output: Option<&Path>,
    requested: Option<OutputFormat>,
) -> Result<(Destination, OutputFormat), String> {
    let Some(output) = output else {
        return Ok((Destination::File(None), requested.unwrap_or(OutputFormat::Png)));
    };
    if output.as_os_str() == STDOUT_NAME {
        return Ok((Destination::Stdout, requested.unwrap_or(OutputFormat::Png)));
    }
    let named = OutputFormat::from_path(output);
    let format = match (named, requested, output.extension()) {
        (Some(named), Some(requested), _) if named != requested => {
            return Err(format!(
                "`{}` names a {} file but --format asks for {}; rename it to `{}` or drop --format",
                output.display(),
                named.name(),
                requested.name(),
                output.with_extension(requested.extension()).display(),
            ));
        }
        (Some(named), _, _) => named,
        (None, Some(requested), None) => requested,
        (None, _, Some(extension)) => {
            return Err(format!(
                "cannot write `{}`: lampshade writes .png, .exr and .hdr images, not .{}",
                output.display(),
                extension.to_string_lossy(),
            ));
        }
        (None, None, None) => {
            return Err(format!(
                "cannot tell the format of `{}`: give it an extension (.png, .exr or .hdr) or use --format",
                output.display(),
            ));
        }
    };
    Ok((Destination::File(Some(output.to_path_buf())), format))
}

/// The first of `inputs` that `output` would overwrite: the same file after symlinks, `..` and
/// hard links. Every command that writes refuses such an output before writing anything.
pub fn overwritten_input<'a>(output: &Path, inputs: impl IntoIterator<Item = &'a Path>) -> Option<&'a Path> {
    let output_identity = FileIdentity::of(output);
    inputs
        .into_iter()
        .find(|input| FileIdentity::of(input) == output_identity)
}

/// What makes two paths the same file: the inode where the file exists (hard links, bind
/// mounts), else the resolved path (symlinks and `..` resolved in the folders that exist).
#[derive(Debug, PartialEq, Eq)]
enum FileIdentity {
    #[cfg(unix)]
    Inode(u64, u64),
    Path(PathBuf),
}

impl FileIdentity {
    fn of(path: &Path) -> FileIdentity {
        #[cfg(unix)]
        if let Ok(metadata) = std::fs::metadata(path) {
            use std::os::unix::fs::MetadataExt;
            return FileIdentity::Inode(metadata.dev(), metadata.ino());
        }
        FileIdentity::Path(resolve_existing_prefix(path))
    }
}

/// `path` made absolute, its longest existing prefix canonicalized and the rest applied lexically.
fn resolve_existing_prefix(path: &Path) -> PathBuf {
    if let Ok(resolved) = std::fs::canonicalize(path) {
        return resolved;
    }
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut rest = Vec::new();
    let mut prefix = absolute.as_path();
    loop {
        if let Ok(mut resolved) = std::fs::canonicalize(prefix) {
            for component in rest.iter().rev() {
                match component {
                    std::path::Component::ParentDir => {
                        resolved.pop();
                    }
                    std::path::Component::CurDir => {}
                    other => resolved.push(other.as_os_str()),
                }
            }
            return resolved;
        }
        let mut components = prefix.components();
        match components.next_back() {
            Some(last) => {
                rest.push(last);
                prefix = components.as_path();
            }
            None => return absolute,
        }
    }
}

/// Encodes `framebuffer` in `format` and writes it to standard output in one piece.
pub fn write_image_to_stdout(
    framebuffer: &FrameBuffer,
    format: OutputFormat,
    encoding: Encoding,
    compression: PngCompression,
) -> Result<(), OutputError> {
    let path = Path::new("standard output");
    let mut bytes = std::io::Cursor::new(Vec::new());
    encode_image(&mut bytes, path, framebuffer, format, encoding, compression)?;
    let mut stdout = std::io::stdout().lock();
    stdout
        .write_all(bytes.get_ref())
        .and_then(|()| stdout.flush())
        .map_err(|source| OutputError::Io {
            path: path.to_path_buf(),
            source,
        })
}

/// Encodes `framebuffer` in `format` into `writer`; `path` names the destination in errors.
fn encode_image<W: Write + std::io::Seek>(
    writer: &mut W,
    path: &Path,
    framebuffer: &FrameBuffer,
    format: OutputFormat,
    encoding: Encoding,
    compression: PngCompression,
) -> Result<(), OutputError> {
    let encode_error = |source| OutputError::Encode {
        path: path.to_path_buf(),
        source,
    };
    match format {
        OutputFormat::Png if compression == PngCompression::Fast => {
            write_all(writer, path, &fast_png_of_frame(path, framebuffer, encoding)?)
        }
        OutputFormat::Png => encode_png(writer, path, &to_rgb8_encoded(framebuffer, encoding), compression),
        OutputFormat::Exr | OutputFormat::Hdr => {
            let image = image::Rgb32FImage::from_raw(
                framebuffer.width(),
                framebuffer.height(),
                linear_channels(framebuffer),
            )
            .expect("a frame buffer holds width × height pixels");
            let image_format = if format == OutputFormat::Exr {
                image::ImageFormat::OpenExr
            } else {
                image::ImageFormat::Hdr
            };
            image::DynamicImage::ImageRgb32F(image)
                .write_to(writer, image_format)
                .map_err(encode_error)
        }
    }
}

/// `framebuffer` as PNG at the fast level; `path` names the destination in errors. Each strip
/// of the encoder quantises its own rows, so the 8-bit frame is never stored whole.
fn fast_png_of_frame(
    path: &Path,
    framebuffer: &FrameBuffer,
    encoding: Encoding,
) -> Result<Vec<u8>, OutputError> {
    let quantizer = RowQuantizer::new(framebuffer, encoding);
    fast_png::encode(framebuffer.width(), framebuffer.height(), |y, row| {
        quantizer.quantize_row(y, row)
    })
    .map_err(|source| OutputError::EncodePng {
        path: path.to_path_buf(),
        source,
    })
}

/// Encodes `image` as PNG into `writer`; `path` names the destination in errors.
fn encode_png<W: Write>(
    mut writer: W,
    path: &Path,
    image: &RgbImage,
    compression: PngCompression,
) -> Result<(), OutputError> {
    if compression == PngCompression::Fast {
        let row_bytes = image.width() as usize * 3;
        let png_bytes = fast_png::encode(image.width(), image.height(), |y, row| {
            row.copy_from_slice(&image.as_raw()[y as usize * row_bytes..][..row_bytes]);
        })
        .map_err(|source| OutputError::EncodePng {
            path: path.to_path_buf(),
            source,
        })?;
        return write_all(&mut writer, path, &png_bytes);
    }
    // References (`check --bless`) choose a filter per row (`Adaptive`: all five tried on
    // every row) and compress harder, for files 3–16 % smaller than the fast level's.
    PngEncoder::new_with_quality(writer, CompressionType::Best, FilterType::Adaptive)
        .write_image(
            image.as_raw(),
            image.width(),
            image.height(),
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|source| OutputError::Encode {
            path: path.to_path_buf(),
            source,
        })
}

/// Writes `bytes` to `writer` in one piece; `path` names the destination in errors.
fn write_all<W: Write>(writer: &mut W, path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    writer.write_all(bytes).map_err(|source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// `image` as PNG bytes in memory (the preview's frames, which never touch a file).
pub fn encode_png_to_vec(image: &RgbImage, compression: PngCompression) -> Result<Vec<u8>, OutputError> {
    let mut bytes = Vec::new();
    encode_png(&mut bytes, Path::new("(preview)"), image, compression)?;
    Ok(bytes)
}

/// Writes `framebuffer` to `path` in `format`, atomically. PNG uses `encoding`; the float
/// formats store linear light without clamping.
pub fn write_image(
    path: &Path,
    framebuffer: &FrameBuffer,
    format: OutputFormat,
    encoding: Encoding,
    compression: PngCompression,
) -> Result<(), OutputError> {
    write_image_timed(path, framebuffer, format, encoding, compression).map(drop)
}

/// Where a write's time went (wall clock).
#[derive(Debug, Clone, Copy, Default)]
pub struct WriteTimings {
    /// Quantising and compressing in memory, before the file is opened (the fast PNG level
    /// only; other formats encode as they write).
    pub encode: Duration,
    /// Creating the temporary file and writing it.
    pub write: Duration,
    /// `fdatasync` of the temporary file.
    pub sync: Duration,
    /// Renaming it over the destination.
    pub rename: Duration,
}

/// [`write_image`], saying where the time went.
pub fn write_image_timed(
    path: &Path,
    framebuffer: &FrameBuffer,
    format: OutputFormat,
    encoding: Encoding,
    compression: PngCompression,
) -> Result<WriteTimings, OutputError> {
    if format == OutputFormat::Png && compression == PngCompression::Fast {
        // Encoded whole in memory first, then written with one call.
        let started = Instant::now();
        let png_bytes = fast_png_of_frame(path, framebuffer, encoding)?;
        let encode = started.elapsed();
        let timings = write_atomically_timed(path, |writer| write_all(writer, path, &png_bytes))?;
        return Ok(WriteTimings { encode, ..timings });
    }
    write_atomically_timed(path, |writer| {
        encode_image(writer, path, framebuffer, format, encoding, compression)
    })
}

/// PNG compression effort: `Fast` favours the edit-to-image loop, `Best` smaller files.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum PngCompression {
    #[default]
    Fast,
    Best,
}

/// Encodes `image` as PNG and puts it at `path` atomically.
pub fn write_png(path: &Path, image: &RgbImage, compression: PngCompression) -> Result<(), OutputError> {
    write_atomically(path, |writer| encode_png(writer, path, image, compression))
}

/// Held shared by every write in progress, exclusively by an exit on Ctrl-C.
static WRITES: RwLock<()> = RwLock::new(());

/// Ends the process with `code` once no output is half-written: waits for the writes in
/// progress to be renamed into place, and lets no new one start. For Ctrl-C handlers.
pub fn exit_when_no_write_is_in_progress(code: i32) -> ! {
    exit_after_writes(code, || {})
}

/// [`exit_when_no_write_is_in_progress`], running `last_words` once the writes under way are in
/// place (so it can say truthfully what was written).
pub fn exit_after_writes(code: i32, last_words: impl FnOnce()) -> ! {
    // A writer that panicked poisons the lock; its temporary file is gone already.
    let _no_writes = WRITES.write().unwrap_or_else(|poisoned| poisoned.into_inner());
    last_words();
    std::process::exit(code)
}

/// Writes through `write` into a temporary file beside `path`, then renames it into place.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<&mut std::fs::File>) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    write_atomically_timed(path, write).map(drop)
}

/// [`write_atomically`], timing its steps (all but `encode`).
fn write_atomically_timed(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<&mut std::fs::File>) -> Result<(), OutputError>,
) -> Result<WriteTimings, OutputError> {
    let _writing = WRITES.read().unwrap_or_else(|poisoned| poisoned.into_inner());
    let io_error = |source| OutputError::Io {
        path: path.to_path_buf(),
        source: without_temporary_path(source),
    };
    let started = Instant::now();
    let folder = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".lampshade-").suffix(".tmp");
    // Temporary files are private (0600) by default; an image is an ordinary file, so ask for
    // 0666 and let the umask decide, as any other program's output would.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let mut temporary = builder.tempfile_in(folder).map_err(io_error)?;
    {
        let mut writer = BufWriter::new(temporary.as_file_mut());
        write(&mut writer)?;
        writer.flush().map_err(io_error)?;
    }
    let written = Instant::now();
    temporary.as_file().sync_data().map_err(io_error)?;
    let synced = Instant::now();
    temporary.persist(path).map_err(|e| io_error(e.error))?;
    Ok(WriteTimings {
        encode: Duration::ZERO,
        write: written - started,
        sync: synced - written,
        rename: synced.elapsed(),
    })
}

/// `error` without the ` at path "DIR/.lampshade-Ab12Cd.tmp"` that `tempfile` appends to the
/// errors of the temporary file: the user named the destination, which the message names.
fn without_temporary_path(error: std::io::Error) -> std::io::Error {
    let text = error.to_string();
    match text.rfind(" at path \"") {
        Some(end) if text.ends_with(".tmp\"") => std::io::Error::new(error.kind(), &text[..end]),
        _ => error,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn srgb_transfer_function_by_hand() {
        assert_eq!(linear_to_srgb(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
        assert!((linear_to_srgb(0.002) - 0.02584).abs() < 1e-5);
        // Mid-grey 0.5 linear is 188 in sRGB.
        assert_eq!(quantize_channel(linear_to_srgb(0.5)), 188);
    }

    #[test]
    fn float_formats_keep_values_above_one() {
        let folder = tempfile::tempdir().unwrap();
        let colors = vec![Vec3::new(4.0, 0.5, 0.0), Vec3::new(0.25, 1.5, 100.0)];
        let framebuffer = FrameBuffer::from_pixels(2, 1, colors.clone(), vec![true, true]);
        for format in [OutputFormat::Exr, OutputFormat::Hdr] {
            let path = folder.path().join(format!("out.{}", format.extension()));
            write_image(
                &path,
                &framebuffer,
                format,
                Encoding::Linear,
                PngCompression::Fast,
            )
            .unwrap();
            let read = image::open(&path).unwrap().to_rgb32f();
            for (got, expected) in read.as_raw().chunks(3).zip(&colors) {
                // RGBE shares one exponent per pixel: 8 bits of mantissa relative to the largest
                // channel. EXR stores f32 exactly.
                let tolerance = expected.max_element() / 128.0;
                for (g, e) in got.iter().zip(expected.to_array()) {
                    assert!((g - e).abs() <= tolerance, "{format:?}: {g} vs {e}");
                }
            }
        }
        assert_eq!(
            OutputFormat::from_path(Path::new("a/b.EXR")),
            Some(OutputFormat::Exr)
        );
        assert_eq!(OutputFormat::from_path(Path::new("a/b.jpg")), None);
    }

    #[test]
    fn quantisation_rounds_and_clamps() {
        assert_eq!(quantize_channel(0.0), 0);
        assert_eq!(quantize_channel(1.0), 255);
        assert_eq!(quantize_channel(0.5), 128); // 127.5 rounds up
        assert_eq!(quantize_channel(0.499 / 255.0), 0);
        assert_eq!(quantize_channel(0.501 / 255.0), 1);
        assert_eq!(quantize_channel(1e9), 255);
        assert_eq!(quantize_channel(f32::INFINITY), 255);
        assert_eq!(quantize_channel(-3.0), 0);
        assert_eq!(quantize_channel(f32::NAN), 0);
    }

    /// The definition `quantize_channel` computes without a float-to-integer cast.
    #[allow(clippy::manual_clamp)]
    fn quantize_by_cast(value: f32) -> u8 {
        (value.max(0.0).min(1.0) * 255.0 + 0.5) as u8
    }

    /// Every input near a level boundary `(k + ½)/255` (where rounding could go either way), the
    /// special values, and a sweep over all bit patterns, through the frame loop (whose lanes
    /// the compiler vectorises) and one channel at a time.
    #[test]
    fn quantisation_equals_the_cast_it_replaces() {
        let mut values: Vec<f32> = (0..=256)
            .flat_map(|k| {
                let boundary = (k as f32 + 0.5) / 255.0;
                (-64..=64).map(move |ulps| f32::from_bits(boundary.to_bits().wrapping_add_signed(ulps)))
            })
            .collect();
        values.extend([
            0.0,
            -0.0,
            1.0,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::MAX,
            f32::MIN,
        ]);
        values.extend([
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            f32::from_bits(1),
        ]);
        values.extend((0..u32::MAX / 4099).map(|step| f32::from_bits(step * 4099)));
        // Rows of 7 pixels, 21 channels: not a multiple of any lane width.
        let width = 7;
        values.truncate(values.len() / (3 * width) * (3 * width));
        let color: Vec<Vec3> = values.chunks_exact(3).map(Vec3::from_slice).collect();
        let height = (color.len() / width) as u32;
        let framebuffer =
            FrameBuffer::from_pixels(width as u32, height, color.clone(), vec![true; color.len()]);
        let image = to_rgb8(&framebuffer);
        for (value, level) in values.iter().zip(image.as_raw()) {
            assert_eq!(
                *level,
                quantize_by_cast(*value),
                "{value:e} ({:#x})",
                value.to_bits()
            );
            assert_eq!(quantize_channel(*value), quantize_by_cast(*value), "{value:e}");
        }
    }

    #[test]
    fn a_failed_write_leaves_the_previous_file_alone() {
        let folder = tempfile::tempdir().unwrap();
        let path = folder.path().join("out.png");
        std::fs::write(&path, b"previous").unwrap();
        let result = write_atomically(&path, |_| {
            Err(OutputError::Io {
                path: path.clone(),
                source: std::io::Error::other("simulated failure"),
            })
        });
        assert!(result.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"previous");
        let leftovers = std::fs::read_dir(folder.path()).unwrap().count();
        assert_eq!(leftovers, 1, "the temporary file must be removed");
    }

    #[test]
    fn png_round_trip() {
        let folder = tempfile::tempdir().unwrap();
        let path = folder.path().join("out.png");
        let colors = vec![Vec3::new(1.0, 0.5, 0.0), Vec3::new(2.0, -1.0, 0.25)];
        let framebuffer = FrameBuffer::from_pixels(2, 1, colors, vec![true, true]);
        write_png(&path, &to_rgb8(&framebuffer), PngCompression::Fast).unwrap();
        let read = image::open(&path).unwrap().to_rgb8();
        assert_eq!(read.as_raw(), &[255, 128, 0, 255, 0, 64]);
    }

    /// A frame written as PNG at the fast level (strips quantising their own rows, blank tiles
    /// among them) decodes to the frame quantised whole, linear and sRGB.
    #[test]
    fn fast_png_of_a_frame_decodes_to_its_quantised_pixels() {
        let folder = tempfile::tempdir().unwrap();
        let path = folder.path().join("out.png");
        let framebuffer =
            crate::render::framebuffer::tests::frame_with_blank_tiles(200, 130, Vec3::new(0.2, 0.7, 1.5));
        for encoding in [Encoding::Linear, Encoding::Srgb] {
            write_image(
                &path,
                &framebuffer,
                OutputFormat::Png,
                encoding,
                PngCompression::Fast,
            )
            .unwrap();
            let read = image::open(&path).unwrap().to_rgb8();
            assert_eq!(read, to_rgb8_encoded(&framebuffer, encoding), "{encoding:?}");
        }
        let leftovers = std::fs::read_dir(folder.path()).unwrap().count();
        assert_eq!(leftovers, 1, "no temporary file is left");
    }

    /// A frame with blank tiles, over stale pixels, quantises (linear and sRGB) and goes to the
    /// float formats exactly as the same image stored pixel by pixel.
    #[test]
    fn blank_spans_give_what_the_dense_frame_gives() {
        // 200×130: partial tiles at the right and the bottom; the background rounds at a
        // level boundary's neighbour and is above 1 in one channel.
        let background = Vec3::new(0.501 / 255.0, 0.3, 1.5);
        let framebuffer = crate::render::framebuffer::tests::frame_with_blank_tiles(200, 130, background);
        assert!(framebuffer.blank_tiles() > 0 && framebuffer.blank_tiles() < 12);
        let dense = FrameBuffer::from_pixels(200, 130, framebuffer.to_colors(), framebuffer.to_coverage());
        for encoding in [Encoding::Linear, Encoding::Srgb] {
            let image = to_rgb8_encoded(&framebuffer, encoding);
            assert_eq!(image, to_rgb8_encoded(&dense, encoding), "{encoding:?}");
            let quantize = |channel: f32| match encoding {
                Encoding::Linear => quantize_channel(channel),
                Encoding::Srgb => quantize_channel(linear_to_srgb(channel.clamp(0.0, 1.0))),
            };
            for (x, y, pixel) in image.enumerate_pixels() {
                assert_eq!(
                    pixel.0,
                    framebuffer.pixel(x, y).to_array().map(quantize),
                    "({x}, {y})"
                );
            }
        }
        let channels = linear_channels(&framebuffer);
        assert_eq!(channels, linear_channels(&dense));
        let expected: Vec<f32> = framebuffer.colors().flat_map(|c| c.to_array()).collect();
        assert_eq!(channels, expected);
    }
}
