//! Textures: decoded images with their mipmap chains, and how they are sampled.
//!
//! # Decoding
//!
//! PNG and JPEG files are decoded by the `image` crate (under `catch_unwind`, since a decoder
//! bug must not take the renderer down) into linear RGBA `f32` texels, row-major from the
//! top-left texel: (u, v) = (0, 0) is the top-left corner of the image, as in glTF (the OBJ
//! loader flips its v to match). Colour images ([`ColorSpace::Srgb`]) are decoded with the
//! exact sRGB transfer function (IEC 61966-2-1),
//!
//! ```text
//! linear(c) = c / 12.92                      for c ≤ 0.04045
//!             ((c + 0.055) / 1.055)^2.4      otherwise
//! ```
//!
//! through a 256-entry table for 8-bit images and per texel for 16-bit ones; alpha is linear
//! in every format and only rescaled. Data images ([`ColorSpace::Linear`], normal maps) are
//! only rescaled to [0, 1]. Non-finite texels (possible only in float images) become 0, and
//! every texel is clamped to ±[`MAX_TEXEL_MAGNITUDE`], so that no weighted sum in the filters
//! can overflow. Images larger than [`MAX_TEXELS`] are refused rather than decoded into
//! gigabytes of `f32`; on-load downscaling was rejected for now as complexity for files that
//! a user can shrink once.
//!
//! # Mipmaps
//!
//! Level `k + 1` is level `k` reduced by a box filter in linear space (filtering sRGB values
//! would darken every edge), each dimension `max(1, ⌊n/2⌋)` as in OpenGL, down to 1×1. The
//! filter is separable and exact for odd sizes: a destination texel covers `n/m` source
//! texels, so for `n = 2m + 1` destination texel `i` weighs source texels `2i, 2i+1, 2i+2` by
//! `(m − i)/n, m/n, (i + 1)/n` (the areas of overlap; see Ivanov's "Non-power-of-two
//! mipmapping" note from NVIDIA). Every source texel then carries the same total weight, so
//! each level has exactly the mean of level 0 up to rounding. Alpha is filtered straight, not
//! premultiplied: the renderer treats every surface as opaque, and premultiplying would darken
//! the colour where alpha < 1 without anything to composite against. Each pass of the filter
//! runs over the rows of a large level in parallel; a texel's sum is the same on any thread, so
//! the chain does not depend on the thread count.
//!
//! # Sampling
//!
//! [`Texture::sample`] takes the UV derivatives per pixel step (`uv_dx`, `uv_dy`) and picks the
//! level of detail from the isotropic footprint of the pixel in level-0 texels (OpenGL 4.6
//! §8.14, the "scale factor" ρ):
//!
//! ```text
//! ρ = max(|uv_dx · size₀|, |uv_dy · size₀|)        λ = log₂ ρ
//! ```
//!
//! * λ ≤ 0 (magnification): bilinear filtering of level 0.
//! * λ > 0 (minification): trilinear filtering, `LINEAR_MIPMAP_LINEAR`: bilinear in levels
//!   ⌊λ⌋ and ⌊λ⌋ + 1, blended by the fraction of λ; λ is clamped to the last level.
//!
//! Bilinear filtering puts texel centres at `(i + 0.5) / size` (as OpenGL and glTF): the texel
//! coordinate is `x = u·w − 0.5`, the two texels are ⌊x⌋ and ⌊x⌋ + 1, weighted by the
//! fraction of `x`. Each texel index is then wrapped per axis by the sampler's [`Wrap`] mode:
//! `Repeat` takes it modulo `w`, `MirroredRepeat` modulo `2w` reflected into `[0, w)`,
//! `ClampToEdge` clamps it to `[0, w − 1]`. Texel coordinates are computed in `f64`, where
//! `u·w` cannot overflow and the modulo is exact, so very large coordinates still wrap
//! correctly. Non-finite UVs or derivatives are taken as 0. Sampling is a pure function of
//! its inputs (the image is bit-identical for any thread count) and cannot panic.
//! [`Texture::sample`] is the specification: the renderer samples eight points at a time with
//! `render::texture_lanes`, which a test holds to it bit for bit.
//!
//! Rejected for now: anisotropic filtering (several probes along the footprint's major axis:
//! sharper at grazing angles, but several times the cost, and isotropic trilinear is what the
//! issue asks for); the mip filters of `image::imageops` (they resample in the stored 8-bit
//! sRGB values and use their own filter kernels; the exact box keeps the mean); honouring
//! glTF's `minFilter`/`magFilter` (every texture is filtered trilinearly: the nearest filters
//! exist for GPU speed and pixel art, which the scenes here do not need).

use std::io::Cursor;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

/// How texture coordinates outside [0, 1] are brought back (glTF sampler wrap modes).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    #[default]
    Repeat,
    MirroredRepeat,
    ClampToEdge,
}

/// How a texture is read.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Sampler {
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
}

/// What the texel values mean.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ColorSpace {
    /// Colour images (base colour, `map_Kd`): sRGB-encoded, decoded to linear on load.
    Srgb,
    /// Data (normal maps): used as stored.
    Linear,
}

/// The largest image decoded, in texels (4096 × 4096): level 0 alone then takes 256 MiB as
/// `f32` RGBA, the whole chain a third more.
pub const MAX_TEXELS: u64 = 4096 * 4096;

/// The largest magnitude a texel component may have (that of a half float): far beyond any
/// colour, and small enough that no filter sum can overflow `f32`.
pub const MAX_TEXEL_MAGNITUDE: f32 = 65504.0;

/// One level of a mipmap chain: linear RGBA texels, row-major from the top-left.
///
/// Invariant (kept by every constructor here): `width` and `height` are at least 1 and
/// `texels.len() == width · height`.
#[derive(Debug, Clone, PartialEq)]
pub struct MipLevel {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec4>,
}

impl MipLevel {
    /// The texel at column `x`, row `y` (from the top-left); zero outside the level, so that
    /// a malformed level cannot make sampling panic.
    pub fn texel(&self, x: usize, y: usize) -> Vec4 {
        if x >= self.width as usize {
            return Vec4::ZERO;
        }
        self.texels
            .get(y * self.width as usize + x)
            .copied()
            .unwrap_or(Vec4::ZERO)
    }
}

/// The mipmap levels a lookup reads: `level`, blended towards the next one by `fraction`
/// (0: `level` alone).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MipChoice {
    pub level: usize,
    pub fraction: f32,
}

/// A decoded texture: level 0 is the image, each next level half the size.
///
/// Invariant (kept by every constructor here): at least one level, each a valid
/// [`MipLevel`], each next one `max(1, ⌊n/2⌋)` in each dimension, the last 1×1.
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    pub levels: Vec<MipLevel>,
    /// The image file it was read from (for the pixel inspector); `None` for texels made in
    /// memory or an image embedded in a glTF file.
    pub file: Option<PathBuf>,
}

impl Texture {
    /// A texture from linear RGBA texels, row-major from the top-left, with its mipmap chain.
    /// Fails when a dimension is 0 or `texels` does not hold `width · height` texels.
    pub fn from_texels(width: u32, height: u32, texels: Vec<Vec4>) -> Result<Texture, String> {
        if width == 0 || height == 0 {
            return Err(format!("a {width}×{height} texture has no texels"));
        }
        if texels.len() as u64 != u64::from(width) * u64::from(height) {
            return Err(format!(
                "{} texels given for a {width}×{height} texture",
                texels.len()
            ));
        }
        let texels = texels.into_iter().map(sanitize_texel).collect();
        Ok(Texture::with_mipmaps(MipLevel {
            width,
            height,
            texels,
        }))
    }

    /// Converts a decoded image to linear texels (module documentation) and builds its
    /// mipmap chain. An image with a zero dimension gives a 1×1 transparent black texture.
    pub fn from_image(image: &image::DynamicImage, color_space: ColorSpace) -> Texture {
        let (width, height) = (image.width(), image.height());
        if width == 0 || height == 0 {
            return Texture::with_mipmaps(MipLevel {
                width: 1,
                height: 1,
                texels: vec![Vec4::ZERO],
            });
        }
        use image::DynamicImage::{ImageLuma8, ImageLumaA8, ImageRgb8, ImageRgba8};
        let table = decode_table(color_space);
        let alpha = |a: u8| f32::from(a) / 255.0;
        // 8-bit images are converted from their own layout, without an RGBA copy first: each
        // texel is what `to_rgba8` would give (grey repeated, alpha 255 when absent).
        let texels: Vec<Vec4> = if let ImageRgb8(rgb) = image {
            let (pixels, _) = rgb.as_raw().as_chunks::<3>();
            pixels
                .par_iter()
                .map(|&[r, g, b]| Vec4::new(table[r as usize], table[g as usize], table[b as usize], 1.0))
                .collect()
        } else if let ImageRgba8(rgba) = image {
            let (pixels, _) = rgba.as_raw().as_chunks::<4>();
            pixels
                .par_iter()
                .map(|&[r, g, b, a]| {
                    Vec4::new(table[r as usize], table[g as usize], table[b as usize], alpha(a))
                })
                .collect()
        } else if let ImageLuma8(grey) = image {
            grey.as_raw()
                .par_iter()
                .map(|&l| Vec3::splat(table[l as usize]).extend(1.0))
                .collect()
        } else if let ImageLumaA8(grey_alpha) = image {
            let (pixels, _) = grey_alpha.as_raw().as_chunks::<2>();
            pixels
                .par_iter()
                .map(|&[l, a]| Vec3::splat(table[l as usize]).extend(alpha(a)))
                .collect()
        } else {
            // 16-bit and float images: through f32, the transfer function per texel.
            image
                .to_rgba32f()
                .pixels()
                .map(|pixel| {
                    let [r, g, b, a] = pixel.0;
                    let decode = |c: f32| match color_space {
                        ColorSpace::Srgb => srgb_to_linear(c),
                        ColorSpace::Linear => c,
                    };
                    sanitize_texel(Vec4::new(decode(r), decode(g), decode(b), a))
                })
                .collect()
        };
        Texture::with_mipmaps(MipLevel {
            width,
            height,
            texels,
        })
    }

    /// Reads and decodes an image file (PNG or JPEG). The message of an error does not name
    /// the file: the caller does.
    pub fn load(path: &Path, color_space: ColorSpace) -> Result<Texture, String> {
        let bytes = std::fs::read(path)
            .map_err(|error| format!("cannot read it: {}", crate::mesh::io_error_text(&error)))?;
        Texture::from_encoded(&bytes, color_space)
    }

    /// Decodes a PNG or JPEG image held in memory (a glTF data URI or buffer view, a file's
    /// contents). The format is recognised from the bytes, not from a name or MIME type.
    pub fn from_encoded(bytes: &[u8], color_space: ColorSpace) -> Result<Texture, String> {
        // The header alone gives the size: refuse a huge image before decoding it. (The
        // decoders run under `catch_unwind`: a bug in one must not end the render.)
        let (width, height) = catch_unwind(AssertUnwindSafe(|| {
            image_reader(bytes)?
                .into_dimensions()
                .map_err(|error| format!("cannot decode it: {error}"))
        }))
        .unwrap_or_else(|_| Err(DECODER_PANICKED.to_string()))?;
        if u64::from(width) * u64::from(height) > MAX_TEXELS {
            return Err(format!(
                "it is {width}×{height}: textures are limited to {MAX_TEXELS} texels (4096×4096); scale it down"
            ));
        }
        let image = catch_unwind(AssertUnwindSafe(|| {
            image_reader(bytes)?
                .decode()
                .map_err(|error| format!("cannot decode it: {error}"))
        }))
        .unwrap_or_else(|_| Err(DECODER_PANICKED.to_string()))?;
        Ok(Texture::from_image(&image, color_space))
    }

    /// Builds the mipmap chain below `base` (module documentation).
    fn with_mipmaps(base: MipLevel) -> Texture {
        let mut levels = vec![base];
        while let Some(last) = levels.last().filter(|level| level.width > 1 || level.height > 1) {
            let next = downsample(last);
            levels.push(next);
        }
        Texture { levels, file: None }
    }

    /// The texture, noting that it was read from `file`.
    pub fn read_from(self, file: &Path) -> Texture {
        Texture {
            file: Some(file.to_path_buf()),
            ..self
        }
    }

    /// Width of level 0 in texels.
    pub fn width(&self) -> u32 {
        self.levels.first().map_or(0, |level| level.width)
    }

    /// Height of level 0 in texels.
    pub fn height(&self) -> u32 {
        self.levels.first().map_or(0, |level| level.height)
    }

    /// The mipmap level of detail [`Texture::sample`] reads at for a footprint spanning `uv_dx`
    /// and `uv_dy`: log2 of its longer side in texels of level 0 (≤ 0 reads level 0 alone).
    #[inline]
    pub fn level_of_detail(&self, uv_dx: Vec2, uv_dy: Vec2) -> f32 {
        let Some(base) = self.levels.first() else {
            return 0.0;
        };
        let size = Vec2::new(base.width as f32, base.height as f32);
        // Lengths of finite vectors: finite or +∞ (for huge derivatives), never NaN.
        let footprint = (finite_or_zero(uv_dx) * size)
            .length()
            .max((finite_or_zero(uv_dy) * size).length());
        footprint.log2()
    }

    /// The filtered value at `uv` for a pixel whose footprint spans `uv_dx` and `uv_dy` (the
    /// change of `uv` per pixel step in x and y): trilinear when minified, bilinear when
    /// magnified, wrapped per `sampler` (module documentation). Never NaN for a texture built
    /// here; zero for a texture without levels.
    pub fn sample(&self, uv: Vec2, uv_dx: Vec2, uv_dy: Vec2, sampler: &Sampler) -> Vec4 {
        self.sample_biased(uv, uv_dx, uv_dy, sampler, 0.0)
    }

    /// [`Texture::sample`] with `mip_bias` added to the level of detail `λ = log₂ ρ` before
    /// it is clamped: positive picks blurrier levels (less aliasing, less detail), negative
    /// sharper ones. A bias of 0 gives `sample`'s bits (`λ + 0 = λ` for every `λ`).
    pub fn sample_biased(
        &self,
        uv: Vec2,
        uv_dx: Vec2,
        uv_dy: Vec2,
        sampler: &Sampler,
        mip_bias: f32,
    ) -> Vec4 {
        let Some(MipChoice { level, fraction }) = self.mip_choice(uv_dx, uv_dy, mip_bias) else {
            return Vec4::ZERO;
        };
        let uv = finite_or_zero(uv);
        let near = bilinear(&self.levels[level], uv, sampler);
        match self.levels.get(level + 1) {
            Some(upper) if fraction > 0.0 => near + (bilinear(upper, uv, sampler) - near) * fraction,
            _ => near,
        }
    }

    /// The levels [`Texture::sample_biased`] reads for a footprint spanning `uv_dx` and
    /// `uv_dy` with `mip_bias` added: `None` for a texture without levels.
    pub fn mip_choice(&self, uv_dx: Vec2, uv_dy: Vec2, mip_bias: f32) -> Option<MipChoice> {
        self.levels.first()?;
        let lod = self.level_of_detail(uv_dx, uv_dy) + mip_bias;
        let last_level = self.levels.len() - 1;
        if lod.is_nan() || lod <= 0.0 || last_level == 0 {
            return Some(MipChoice {
                level: 0,
                fraction: 0.0,
            });
        }
        let lod = lod.min(last_level as f32);
        let level = (lod.floor() as usize).min(last_level);
        Some(MipChoice {
            level,
            fraction: lod - level as f32,
        })
    }
}

/// The error of a decoder that panicked.
const DECODER_PANICKED: &str = "cannot decode it: the image decoder gave up on it";

/// A reader for an encoded PNG or JPEG image, its format recognised from the bytes. `image`'s
/// default limits stay on (at most 512 MiB allocated while decoding).
fn image_reader(bytes: &[u8]) -> Result<image::ImageReader<Cursor<&[u8]>>, String> {
    let reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|error| format!("cannot decode it: {error}"))?;
    match reader.format() {
        Some(_) => Ok(reader),
        None => Err("not a PNG or JPEG image (the formats textures can have)".to_string()),
    }
}

/// The exact sRGB electro-optical transfer function (IEC 61966-2-1) for an encoded value in
/// [0, 1]: the linear value it stands for.
pub fn srgb_to_linear(encoded: f32) -> f32 {
    if encoded <= 0.04045 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

/// The linear value of every 8-bit code: the sRGB transfer function or plain rescaling.
fn decode_table(color_space: ColorSpace) -> [f32; 256] {
    std::array::from_fn(|code| {
        let encoded = code as f32 / 255.0;
        match color_space {
            ColorSpace::Srgb => srgb_to_linear(encoded),
            ColorSpace::Linear => encoded,
        }
    })
}

/// Non-finite components become 0, the rest are clamped to ±[`MAX_TEXEL_MAGNITUDE`].
fn sanitize_texel(texel: Vec4) -> Vec4 {
    let clean = |c: f32| {
        if c.is_finite() {
            c.clamp(-MAX_TEXEL_MAGNITUDE, MAX_TEXEL_MAGNITUDE)
        } else {
            0.0
        }
    };
    Vec4::new(clean(texel.x), clean(texel.y), clean(texel.z), clean(texel.w))
}

fn finite_or_zero(v: Vec2) -> Vec2 {
    Vec2::new(
        if v.x.is_finite() { v.x } else { 0.0 },
        if v.y.is_finite() { v.y } else { 0.0 },
    )
}

/// The next mipmap level: separable exact box filter (module documentation).
fn downsample(level: &MipLevel) -> MipLevel {
    let (width, height) = (level.width as usize, level.height as usize);
    let new_width = (width / 2).max(1);
    let new_height = (height / 2).max(1);
    let columns = box_taps(width, new_width);
    let rows = box_taps(height, new_height);

    let mut narrowed = vec![Vec4::ZERO; new_width * height];
    fill_rows(&mut narrowed, new_width, |y, row| {
        let source = level.texels.get(y * width..(y + 1) * width).unwrap_or_default();
        for (texel, taps) in row.iter_mut().zip(&columns) {
            *texel = weighted_sum(taps, |x| source.get(x).copied().unwrap_or(Vec4::ZERO));
        }
    });
    // Whole rows at a time: each texel starts at zero and adds its taps in order, the same
    // sums as `weighted_sum` takes.
    let mut texels = vec![Vec4::ZERO; new_width * new_height];
    fill_rows(&mut texels, new_width, |y, row| {
        for &(source_y, weight) in &rows[y] {
            let source = narrowed
                .get(source_y * new_width..(source_y + 1) * new_width)
                .unwrap_or_default();
            for (texel, &above) in row.iter_mut().zip(source) {
                *texel += above * weight;
            }
        }
    });
    MipLevel {
        width: new_width as u32,
        height: new_height as u32,
        texels,
    }
}

/// Below this many texels a level's rows are filtered on the calling thread: rayon's tasks
/// would cost more than the sums.
const PARALLEL_TEXELS: usize = 16 * 1024;

/// Calls `fill(y, row)` for each row of `width` texels of `texels`, in parallel on large
/// levels. Every texel is computed the same way on any thread, so the result does not depend
/// on how the rows are shared out.
fn fill_rows(texels: &mut [Vec4], width: usize, fill: impl Fn(usize, &mut [Vec4]) + Sync) {
    if texels.len() < PARALLEL_TEXELS {
        texels
            .chunks_mut(width)
            .enumerate()
            .for_each(|(y, row)| fill(y, row));
    } else {
        texels
            .par_chunks_mut(width)
            .enumerate()
            .for_each(|(y, row)| fill(y, row));
    }
}

/// Source texels and weights of a box filter from `source` to `destination` texels along one
/// axis, where `destination` is `max(1, ⌊source/2⌋)`.
fn box_taps(source: usize, destination: usize) -> Vec<Vec<(usize, f32)>> {
    if source == destination {
        return (0..source).map(|i| vec![(i, 1.0)]).collect();
    }
    if source.is_multiple_of(2) {
        return (0..destination)
            .map(|i| vec![(2 * i, 0.5), (2 * i + 1, 0.5)])
            .collect();
    }
    // source = 2m + 1, destination = m: overlaps (m − i)/n, m/n, (i + 1)/n.
    let (n, m) = (source as f32, destination as f32);
    (0..destination)
        .map(|i| {
            let k = i as f32;
            vec![
                (2 * i, (m - k) / n),
                (2 * i + 1, m / n),
                (2 * i + 2, (k + 1.0) / n),
            ]
        })
        .collect()
}

fn weighted_sum(taps: &[(usize, f32)], texel: impl Fn(usize) -> Vec4) -> Vec4 {
    taps.iter().map(|&(index, weight)| texel(index) * weight).sum()
}

/// Bilinear filtering of one level at `uv` (finite), wrapped per axis.
fn bilinear(level: &MipLevel, uv: Vec2, sampler: &Sampler) -> Vec4 {
    let (x0, x1, fx) = texel_pair(uv.x, level.width, sampler.wrap_s);
    let (y0, y1, fy) = texel_pair(uv.y, level.height, sampler.wrap_t);
    // `a + (b − a)·f` rather than `a(1 − f) + b·f`: exact when f = 0 or a = b, so texel
    // centres and clamped edges return the stored value bit for bit.
    let lerp = |a: Vec4, b: Vec4, f: f32| a + (b - a) * f;
    let top = lerp(level.texel(x0, y0), level.texel(x1, y0), fx);
    let bottom = lerp(level.texel(x0, y1), level.texel(x1, y1), fx);
    lerp(top, bottom, fy)
}

/// The two texel indices around coordinate `t` on an axis of `size` texels, wrapped, and the
/// weight of the second.
fn texel_pair(t: f32, size: u32, wrap: Wrap) -> (usize, usize, f32) {
    let x = f64::from(t) * f64::from(size) - 0.5;
    let first = x.floor();
    let fraction = (x - first) as f32;
    let size = f64::from(size.max(1));
    (
        wrap_index(first, size, wrap),
        wrap_index(first + 1.0, size, wrap),
        fraction,
    )
}

/// A whole texel index (any finite value) brought into `[0, size)`.
pub(crate) fn wrap_index(index: f64, size: f64, wrap: Wrap) -> usize {
    let wrapped = match wrap {
        Wrap::Repeat => index.rem_euclid(size),
        Wrap::MirroredRepeat => {
            let period = index.rem_euclid(2.0 * size);
            if period >= size {
                2.0 * size - 1.0 - period
            } else {
                period
            }
        }
        Wrap::ClampToEdge => index.clamp(0.0, size - 1.0),
    };
    // `as` saturates; the value is already in range.
    wrapped as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    const REPEAT: Sampler = Sampler {
        wrap_s: Wrap::Repeat,
        wrap_t: Wrap::Repeat,
    };

    /// Asserts that `actual` is within `tolerance` of `expected` in every component.
    fn check(actual: Vec4, expected: Vec4, tolerance: f32, what: &str) {
        assert!(
            (actual - expected).abs().max_element() <= tolerance,
            "{what}: got {actual}, expected {expected}"
        );
    }

    /// A texture whose texel (x, y) has red = the value `value(x, y)`, other channels 0/1.
    fn texture(width: u32, height: u32, value: impl Fn(u32, u32) -> f32) -> Texture {
        let texels = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| Vec4::new(value(x, y), 0.0, 0.0, 1.0))
            .collect();
        Texture::from_texels(width, height, texels).unwrap_or_else(|e| panic!("{e}"))
    }

    /// Samples with no footprint (magnification: level 0, bilinear) and returns red.
    fn magnified(texture: &Texture, u: f32, v: f32, sampler: Sampler) -> f32 {
        texture
            .sample(Vec2::new(u, v), Vec2::ZERO, Vec2::ZERO, &sampler)
            .x
    }

    #[test]
    fn srgb_decoding_uses_the_exact_transfer_function() {
        let table = decode_table(ColorSpace::Srgb);
        assert_eq!(table[0], 0.0);
        assert_eq!(table[255], 1.0);
        assert!((table[188] - 0.502_886).abs() < 1e-5, "{}", table[188]);
        // The linear segment: 10/255 = 0.0392 < 0.04045.
        assert!((table[10] - 10.0 / 255.0 / 12.92).abs() < 1e-9);
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
        assert_eq!(decode_table(ColorSpace::Linear)[51], 0.2);
    }

    /// Every 8-bit layout (grey, grey and alpha, RGB, RGBA) converted from its own bytes gives
    /// exactly the texels of its RGBA copy (`to_rgba8`) through the table, for every code.
    #[test]
    fn eight_bit_layouts_equal_their_rgba_copy_bit_for_bit() {
        let codes =
            |channels: usize| -> Vec<u8> { (0..256 * channels).map(|i| (i * 37 % 256) as u8).collect() };
        let images = [
            image::DynamicImage::ImageLuma8(
                image::ImageBuffer::from_raw(16, 16, codes(1)).unwrap_or_default(),
            ),
            image::DynamicImage::ImageLumaA8(
                image::ImageBuffer::from_raw(16, 16, codes(2)).unwrap_or_default(),
            ),
            image::DynamicImage::ImageRgb8(
                image::ImageBuffer::from_raw(16, 16, codes(3)).unwrap_or_default(),
            ),
            image::DynamicImage::ImageRgba8(
                image::ImageBuffer::from_raw(16, 16, codes(4)).unwrap_or_default(),
            ),
        ];
        for color_space in [ColorSpace::Srgb, ColorSpace::Linear] {
            let table = decode_table(color_space);
            for image in &images {
                assert_eq!(image.width(), 16, "{:?}", image.color());
                let expected: Vec<Vec4> = image
                    .to_rgba8()
                    .pixels()
                    .map(|p| {
                        let [r, g, b, a] = p.0;
                        Vec4::new(
                            table[r as usize],
                            table[g as usize],
                            table[b as usize],
                            f32::from(a) / 255.0,
                        )
                    })
                    .collect();
                let texels = &Texture::from_image(image, color_space).levels[0].texels;
                let bits = |texels: &[Vec4]| -> Vec<[u32; 4]> {
                    texels.iter().map(|t| t.to_array().map(f32::to_bits)).collect()
                };
                assert_eq!(
                    bits(texels),
                    bits(&expected),
                    "{:?} {color_space:?}",
                    image.color()
                );
            }
        }
    }

    #[test]
    fn images_decode_to_linear_with_linear_alpha() {
        let pixels = image::RgbaImage::from_raw(2, 1, vec![188, 0, 255, 128, 255, 255, 255, 255])
            .unwrap_or_else(|| panic!("pixel buffer size"));
        let image = image::DynamicImage::ImageRgba8(pixels);
        let srgb = Texture::from_image(&image, ColorSpace::Srgb);
        check(
            srgb.levels[0].texel(0, 0),
            Vec4::new(0.502_886, 0.0, 1.0, 128.0 / 255.0),
            1e-5,
            "sRGB colour, linear alpha",
        );
        let linear = Texture::from_image(&image, ColorSpace::Linear);
        check(
            linear.levels[0].texel(0, 0),
            Vec4::new(188.0 / 255.0, 0.0, 1.0, 128.0 / 255.0),
            1e-6,
            "data texture",
        );
        // 16 bits per channel go through f32 with the same function.
        let wide = image::DynamicImage::ImageRgba16(
            image::ImageBuffer::from_raw(1, 1, vec![32768u16, 65535, 0, 65535])
                .unwrap_or_else(|| panic!("pixel buffer size")),
        );
        let wide = Texture::from_image(&wide, ColorSpace::Srgb);
        check(
            wide.levels[0].texel(0, 0),
            Vec4::new(srgb_to_linear(32768.0 / 65535.0), 1.0, 0.0, 1.0),
            1e-6,
            "16-bit sRGB",
        );
    }

    #[test]
    fn encoded_png_and_jpeg_round_trip_and_junk_is_an_error() {
        let mut png = Vec::new();
        let pixels = image::RgbImage::from_raw(1, 1, vec![255, 188, 0]).unwrap_or_else(|| panic!("size"));
        image::DynamicImage::ImageRgb8(pixels)
            .write_to(&mut Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap_or_else(|e| panic!("{e}"));
        let texture = Texture::from_encoded(&png, ColorSpace::Srgb).unwrap_or_else(|e| panic!("{e}"));
        check(
            texture.levels[0].texel(0, 0),
            Vec4::new(1.0, 0.502_886, 0.0, 1.0),
            1e-5,
            "decoded PNG",
        );
        // JPEG (lossy: a flat grey survives within a code or two).
        let mut jpeg = Vec::new();
        let grey = image::RgbImage::from_pixel(8, 8, image::Rgb([188, 188, 188]));
        image::DynamicImage::ImageRgb8(grey)
            .write_to(&mut Cursor::new(&mut jpeg), image::ImageFormat::Jpeg)
            .unwrap_or_else(|e| panic!("{e}"));
        let texture = Texture::from_encoded(&jpeg, ColorSpace::Srgb).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            (texture.width(), texture.height(), texture.levels.len()),
            (8, 8, 4)
        );
        check(
            texture.levels[3].texel(0, 0),
            Vec4::new(0.502_886, 0.502_886, 0.502_886, 1.0),
            0.01,
            "decoded JPEG",
        );
        let junk = Texture::from_encoded(b"not an image at all", ColorSpace::Srgb);
        assert!(junk.is_err_and(|e| e.contains("not a PNG or JPEG")));
        let truncated = Texture::from_encoded(&png[..png.len() / 2], ColorSpace::Srgb);
        assert!(truncated.is_err_and(|e| e.starts_with("cannot decode it")));
    }

    #[test]
    fn images_beyond_the_texel_limit_are_refused() {
        let mut png = Vec::new();
        image::DynamicImage::ImageLuma8(image::GrayImage::new(4097, 4096))
            .write_to(&mut Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap_or_else(|e| panic!("{e}"));
        let refused = Texture::from_encoded(&png, ColorSpace::Linear);
        assert!(refused.is_err_and(|e| e.contains("4097×4096") && e.contains("limited")));
    }

    #[test]
    fn mip_chain_halves_odd_sizes_down_to_one_texel() {
        let sizes: Vec<(u32, u32)> = texture(5, 3, |_, _| 0.0)
            .levels
            .iter()
            .map(|level| (level.width, level.height))
            .collect();
        assert_eq!(sizes, vec![(5, 3), (2, 1), (1, 1)]);
        let sizes: Vec<(u32, u32)> = texture(16, 1, |_, _| 0.0)
            .levels
            .iter()
            .map(|level| (level.width, level.height))
            .collect();
        assert_eq!(sizes, vec![(16, 1), (8, 1), (4, 1), (2, 1), (1, 1)]);
        assert_eq!(texture(1, 1, |_, _| 0.0).levels.len(), 1);
    }

    /// Levels large enough to be filtered in parallel rows hold, texel for texel, the sums of
    /// the separable filter taken one texel at a time (odd and even sizes).
    #[test]
    fn rows_filtered_in_parallel_equal_the_filter_texel_by_texel() {
        let values = |x: u32, y: u32| ((x * 7919 + y * 104_729) % 1000) as f32 / 7.0;
        let (width, height) = (515, 258);
        const {
            assert!(
                515 / 2 * 258 >= PARALLEL_TEXELS,
                "the first level must take the parallel path"
            )
        };
        let large = texture(width, height, values);
        for pair in large.levels.windows(2) {
            let (source, level) = (&pair[0], &pair[1]);
            let columns = box_taps(source.width as usize, level.width as usize);
            let rows = box_taps(source.height as usize, level.height as usize);
            for (y, row_taps) in rows.iter().enumerate() {
                for (x, column_taps) in columns.iter().enumerate() {
                    let narrowed = |source_y: usize| {
                        weighted_sum(column_taps, |source_x| source.texel(source_x, source_y))
                    };
                    let expected = weighted_sum(row_taps, narrowed);
                    assert_eq!(
                        level.texel(x, y),
                        expected,
                        "{}×{} at ({x}, {y})",
                        level.width,
                        level.height
                    );
                }
            }
        }
    }

    #[test]
    fn box_filter_averages_areas_and_keeps_the_mean() {
        // Even: 4×2 → 2×1, each texel the mean of a 2×2 block.
        let even = texture(4, 2, |x, y| (x + 4 * y) as f32);
        let level = &even.levels[1];
        assert_eq!(
            level.texels.iter().map(|t| t.x).collect::<Vec<_>>(),
            vec![2.5, 4.5]
        );
        // Odd: a row 0 1 2 3 4 → 2 texels weighing (2/5, 2/5, 1/5) and (1/5, 2/5, 2/5).
        let odd = texture(5, 1, |x, _| x as f32);
        let level = &odd.levels[1];
        check(level.texel(0, 0), Vec4::new(0.8, 0.0, 0.0, 1.0), 1e-6, "left");
        check(level.texel(1, 0), Vec4::new(3.2, 0.0, 0.0, 1.0), 1e-6, "right");
        // 5×3 with arbitrary values: every level has the mean of level 0.
        let values = |x: u32, y: u32| ((x * 7 + y * 13) % 11) as f32;
        let odd = texture(5, 3, values);
        let mean = (0..3)
            .flat_map(|y| (0..5).map(move |x| values(x, y)))
            .sum::<f32>()
            / 15.0;
        for level in &odd.levels {
            let level_mean = level.texels.iter().map(|t| t.x).sum::<f32>() / level.texels.len() as f32;
            assert!((level_mean - mean).abs() < 1e-5, "{level_mean} vs {mean}");
        }
    }

    #[test]
    fn bilinear_returns_texels_at_centres_and_blends_between() {
        // 2×2: 0 1 / 2 3.
        let square = texture(2, 2, |x, y| (x + 2 * y) as f32);
        for (x, y) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let (u, v) = ((x as f32 + 0.5) / 2.0, (y as f32 + 0.5) / 2.0);
            assert_eq!(
                magnified(&square, u, v, REPEAT),
                (x + 2 * y) as f32,
                "texel ({x}, {y})"
            );
        }
        let clamp = Sampler {
            wrap_s: Wrap::ClampToEdge,
            wrap_t: Wrap::ClampToEdge,
        };
        assert_eq!(magnified(&square, 0.5, 0.25, clamp), 0.5, "between 0 and 1");
        assert_eq!(magnified(&square, 0.25, 0.5, clamp), 1.0, "between 0 and 2");
        assert_eq!(magnified(&square, 0.5, 0.5, clamp), 1.5, "centre of all four");
        assert_eq!(
            magnified(&square, 0.375, 0.25, clamp),
            0.25,
            "a quarter of the way"
        );
        // (0, 0) is the top-left texel.
        assert_eq!(magnified(&square, 0.0, 0.0, clamp), 0.0);
    }

    #[test]
    fn wrap_modes_at_minus_a_quarter_and_one_and_a_quarter() {
        // One row 0 1 2 3; texel coordinate x = 4u − 0.5.
        let row = texture(4, 1, |x, _| x as f32);
        let check_wrap = |wrap: Wrap, u: f32, expected: f32| {
            let sampler = Sampler {
                wrap_s: wrap,
                wrap_t: Wrap::ClampToEdge,
            };
            assert_eq!(magnified(&row, u, 0.5, sampler), expected, "{wrap:?} at u = {u}");
        };
        // u = −0.25: x = −1.5, texels −2 and −1 half and half.
        check_wrap(Wrap::Repeat, -0.25, 2.5); // texels 2 and 3, as u = 0.75
        check_wrap(Wrap::MirroredRepeat, -0.25, 0.5); // texels 1 and 0, as u = 0.25
        check_wrap(Wrap::ClampToEdge, -0.25, 0.0);
        // u = 1.25: x = 4.5, texels 4 and 5.
        check_wrap(Wrap::Repeat, 1.25, 0.5); // texels 0 and 1, as u = 0.25
        check_wrap(Wrap::MirroredRepeat, 1.25, 2.5); // texels 3 and 2, as u = 0.75
        check_wrap(Wrap::ClampToEdge, 1.25, 3.0);
        // Across the seam at u = 0: Repeat blends the last and first texels.
        check_wrap(Wrap::Repeat, 0.0, 1.5);
        // Coordinates far away still wrap exactly (u·w is computed in f64).
        check_wrap(Wrap::Repeat, 1_000_000.25, 0.5);
    }

    #[test]
    fn footprint_selects_the_level_of_detail() {
        // A 16×16 texture whose level k is replaced by the constant k, to read λ back.
        let mut levels = texture(16, 16, |_, _| 0.0);
        for (k, level) in levels.levels.iter_mut().enumerate() {
            level.texels.fill(Vec4::splat(k as f32));
        }
        let sample_lod = |dx: Vec2, dy: Vec2| levels.sample(Vec2::splat(0.3), dx, dy, &REPEAT).x;
        let texels = |n: f32| n / 16.0;
        // A footprint of 4 texels reads level 2 exactly.
        assert_eq!(sample_lod(Vec2::new(texels(4.0), 0.0), Vec2::ZERO), 2.0);
        // The larger of the two derivatives counts, and its length (not its components).
        assert_eq!(
            sample_lod(Vec2::new(texels(1.0), 0.0), Vec2::new(0.0, texels(4.0))),
            2.0
        );
        let diagonal = Vec2::splat(texels(4.0) / 2f32.sqrt());
        assert!((sample_lod(diagonal, Vec2::ZERO) - 2.0).abs() < 1e-5);
        // Between levels: linear in λ (2√2 texels: λ = 1.5).
        assert!((sample_lod(Vec2::new(texels(2.0 * 2f32.sqrt()), 0.0), Vec2::ZERO) - 1.5).abs() < 1e-5);
        // Magnification and tiny footprints read level 0; huge ones the last level.
        assert_eq!(sample_lod(Vec2::new(texels(0.5), 0.0), Vec2::ZERO), 0.0);
        assert_eq!(sample_lod(Vec2::new(1e30, 0.0), Vec2::ZERO), 4.0);
        assert_eq!(sample_lod(Vec2::new(f32::MAX, f32::MAX), Vec2::ZERO), 4.0);
    }

    #[test]
    fn minified_checkerboard_tends_to_its_mean_grey() {
        // 64×64 texels in 4×4-texel squares: level 2 still resolves them, level 3 is grey.
        let board = texture(64, 64, |x, y| ((x / 4 + y / 4) % 2) as f32);
        let largest_error = |footprint_texels: f32| {
            let dx = Vec2::new(footprint_texels / 64.0, 0.0);
            (0..97)
                .map(|i| {
                    let uv = Vec2::new(i as f32 * 0.0173, i as f32 * 0.0311);
                    (board.sample(uv, dx, Vec2::ZERO, &REPEAT).x - 0.5).abs()
                })
                .fold(0.0f32, f32::max)
        };
        let errors: Vec<f32> = [1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 16.0, 64.0]
            .map(largest_error)
            .to_vec();
        assert!(errors[0] > 0.4, "magnified, the squares are sharp: {errors:?}");
        assert!(
            errors.windows(2).all(|pair| pair[1] <= pair[0] + 1e-6),
            "{errors:?}"
        );
        assert!(
            errors[5..].iter().all(|&e| e < 1e-6),
            "grey from 8 texels on: {errors:?}"
        );
    }

    #[test]
    fn sampling_never_produces_nan_or_panics() {
        let board = texture(3, 5, |x, y| ((x + y) % 2) as f32);
        let odd = [
            0.0,
            -0.0,
            1.0,
            -1e30,
            1e30,
            f32::MAX,
            f32::MIN,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        for &a in &odd {
            for &b in &odd {
                for wrap in [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::ClampToEdge] {
                    let sampler = Sampler {
                        wrap_s: wrap,
                        wrap_t: wrap,
                    };
                    let value = board.sample(Vec2::new(a, b), Vec2::new(b, a), Vec2::new(a, 0.0), &sampler);
                    assert!(value.is_finite(), "uv ({a}, {b}) {wrap:?}: {value}");
                }
            }
        }
        // Non-finite UVs are taken as 0.
        assert_eq!(
            magnified(&board, f32::NAN, f32::INFINITY, REPEAT),
            magnified(&board, 0.0, 0.0, REPEAT)
        );
        let empty = Texture {
            levels: Vec::new(),
            file: None,
        };
        assert_eq!(
            empty.sample(Vec2::ZERO, Vec2::ZERO, Vec2::ZERO, &REPEAT),
            Vec4::ZERO
        );
        assert!(Texture::from_texels(0, 4, Vec::new()).is_err());
        assert!(Texture::from_texels(2, 2, vec![Vec4::ONE; 3]).is_err());
        let cleaned = Texture::from_texels(1, 1, vec![Vec4::new(f32::NAN, f32::INFINITY, -1e9, 0.5)])
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            cleaned.levels[0].texels[0],
            Vec4::new(0.0, 0.0, -MAX_TEXEL_MAGNITUDE, 0.5)
        );
    }
}
