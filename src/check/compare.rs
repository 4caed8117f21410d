//! A rendered image against its reference: the pixel test, the optional FLIP test, and the
//! pictures that show where they differ.
//!
//! The pixel test: a pixel *differs* when any of its channels is more than
//! [`Tolerance::max_channel_difference`] levels (of 255) away from the reference, and a render
//! passes when at most [`Tolerance::max_differing_share`] of its pixels differ. The defaults
//! ([`DEFAULT_TOLERANCE`]: 2 levels, 0.1 %) absorb last-bit differences in `sin`, `powf` and
//! friends between C libraries (README, "Reference images"), and nothing a person would
//! notice: a moved highlight, a changed colour or a missing object changes far more pixels
//! than that, by far more. A zero tolerance (0 levels, share 0) is exact equality, for suites
//! checked on one system, as the bundled one is: lampshade is bit-identical for any thread
//! count, and for the same binary and C library.
//!
//! The FLIP test (`--flip`, NVIDIA's perceptual metric through the `nv-flip` crate, built when
//! the `flip` feature is on): FLIP scores each pixel from 0 (identical) to 1 by how visible
//! the difference is at a typical viewing distance (67 pixels per degree); a render passes
//! when the mean and the [`FLIP_PERCENTILE`] percentile of those scores stay within the
//! tolerance. Both tests must pass; a suite that wants to judge some scenes by FLIP alone sets
//! their `max_differing_share` to 1.
//!
//! Rejected: a mean-squared-error or PSNR limit (one bright speck and a uniformly shifted
//! image can score the same, and neither number says where to look); exact equality as the
//! default (a suite could then not move between systems whose C libraries round differently);
//! a difference image scaled to its own
//! maximum (a one-level difference would look as alarming as a missing object).

use image::RgbImage;

/// How far a render may stray from its reference and still pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    /// A pixel differs when a channel is more than this many levels (of 255) off.
    pub max_channel_difference: u8,
    /// The share of pixels, from 0 to 1, that may differ.
    pub max_differing_share: f64,
    /// With `--flip`: the largest mean FLIP error, from 0 to 1.
    pub max_flip_mean: f64,
    /// With `--flip`: the largest FLIP error at the [`FLIP_PERCENTILE`] percentile, from 0 to 1.
    pub max_flip_percentile: f64,
}

/// The defaults of every suite: the limits of the original golden-image test, and FLIP limits
/// set from measurements on the bundled scenes. FLIP's mean cannot tell an invisible change
/// from a subtle visible one (every channel one level brighter scores 0.02–0.035, a light
/// turned by 2.6° in `matlab-shiny` 0.025), so the mean limit only sits above what the pixel
/// test allows (two levels everywhere: at most 0.058). The 99th percentile separates them:
/// two levels everywhere scores at most 0.081, 0.1 % of the pixels 40 levels off at most 0.090,
/// the turned light 0.197.
pub const DEFAULT_TOLERANCE: Tolerance = Tolerance {
    max_channel_difference: 2,
    max_differing_share: 0.001,
    max_flip_mean: 0.07,
    max_flip_percentile: 0.12,
};

impl Tolerance {
    /// The limits in words, for reports: "a pixel differs when a channel is more than 2 levels
    /// off; up to 0.100% of pixels may differ", with FLIP's limits when `flip`.
    pub fn describe(&self, flip: bool) -> String {
        let mut text = if self.max_differing_share == 0.0 && self.max_channel_difference == 0 {
            "exact: every channel of every pixel must be equal".to_owned()
        } else if self.max_differing_share == 0.0 {
            format!(
                "no channel may be more than {} levels off",
                self.max_channel_difference
            )
        } else {
            format!(
                "a pixel differs when a channel is more than {} levels off; up to {} of pixels \
                 may differ",
                self.max_channel_difference,
                percent(self.max_differing_share)
            )
        };
        if flip {
            text.push_str(&format!(
                "; FLIP mean up to {:.4}, {} up to {:.4}",
                self.max_flip_mean,
                percentile_name(),
                self.max_flip_percentile
            ));
        }
        text
    }
}

impl Default for Tolerance {
    fn default() -> Self {
        DEFAULT_TOLERANCE
    }
}

/// The percentile of per-pixel FLIP errors that [`Tolerance::max_flip_percentile`] limits:
/// the mean alone would let a small, clearly visible change hide in a large image.
pub const FLIP_PERCENTILE: f64 = 0.99;

/// Whether this build can compute FLIP (the `flip` feature compiles NVIDIA's C++ code).
pub const FLIP_AVAILABLE: bool = cfg!(feature = "flip");

/// A rectangle of pixels: `x0..x1` by `y0..y1` (end exclusive).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelRect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

/// FLIP's verdict on a pair of images.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlipScore {
    /// Mean per-pixel error, 0 to 1.
    pub mean: f64,
    /// Per-pixel error at [`FLIP_PERCENTILE`], 0 to 1.
    pub percentile: f64,
}

/// What comparing two images of the same size found.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    pub width: u32,
    pub height: u32,
    /// The per-channel threshold the count below used.
    pub channel_threshold: u8,
    /// Pixels with a channel more than `channel_threshold` levels off.
    pub differing_pixels: usize,
    /// The largest channel difference anywhere, 0 when the images are identical.
    pub largest_difference: u8,
    /// The smallest rectangle holding every differing pixel.
    pub differing_region: Option<PixelRect>,
    /// Set when FLIP was computed.
    pub flip: Option<FlipScore>,
}

/// The images cannot be compared pixel by pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SizeMismatch {
    pub expected: (u32, u32),
    pub actual: (u32, u32),
}

impl std::fmt::Display for SizeMismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the image is {}×{} px but the reference is {}×{} px",
            self.actual.0, self.actual.1, self.expected.0, self.expected.1
        )
    }
}

impl Comparison {
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// The share of pixels that differ, from 0 to 1.
    pub fn differing_share(&self) -> f64 {
        match self.pixel_count() {
            0 => 0.0,
            pixels => self.differing_pixels as f64 / pixels as f64,
        }
    }

    /// Whether every channel of every pixel is equal.
    pub fn is_identical(&self) -> bool {
        self.largest_difference == 0
    }

    /// Every limit of `tolerance` this comparison breaks, as a sentence fragment for a summary
    /// line; empty when it passes. FLIP limits apply only when FLIP was computed.
    pub fn violations(&self, tolerance: &Tolerance) -> Vec<String> {
        let mut violations = Vec::new();
        if self.differing_share() > tolerance.max_differing_share {
            let mut text = if self.channel_threshold == 0 && tolerance.max_differing_share == 0.0 {
                format!(
                    "{} of {} pixels differ (the tolerance is exact), by up to {}",
                    crate::cli::thousands(self.differing_pixels),
                    crate::cli::thousands(self.pixel_count()),
                    self.largest_difference,
                )
            } else {
                format!(
                    "{} of pixels ({} of {}) differ by more than {} levels (allowed {}), by up to {}",
                    percent(self.differing_share()),
                    crate::cli::thousands(self.differing_pixels),
                    crate::cli::thousands(self.pixel_count()),
                    self.channel_threshold,
                    percent(tolerance.max_differing_share),
                    self.largest_difference,
                )
            };
            if let Some(region) = self.differing_region {
                text.push_str(&format!(
                    ", within x {}–{}, y {}–{}",
                    region.x0,
                    region.x1 - 1,
                    region.y0,
                    region.y1 - 1
                ));
            }
            violations.push(text);
        }
        if let Some(flip) = self.flip {
            if flip.mean > tolerance.max_flip_mean {
                violations.push(format!(
                    "FLIP mean {:.4} (allowed {:.4})",
                    flip.mean, tolerance.max_flip_mean
                ));
            }
            if flip.percentile > tolerance.max_flip_percentile {
                violations.push(format!(
                    "FLIP {} {:.4} (allowed {:.4})",
                    percentile_name(),
                    flip.percentile,
                    tolerance.max_flip_percentile
                ));
            }
        }
        violations
    }
}

/// `0.001` → `0.100%`; a share that is not zero never shows as `0.000%` (two pixels of two
/// million are `<0.001%`), since exact suites fail on it.
pub fn percent(share: f64) -> String {
    if share > 0.0 && share < 0.000_005 {
        "<0.001%".to_owned()
    } else {
        format!("{:.3}%", share * 100.0)
    }
}

/// `p99` for [`FLIP_PERCENTILE`] = 0.99.
pub fn percentile_name() -> String {
    format!("p{}", FLIP_PERCENTILE * 100.0)
}

/// Counts the pixels of `actual` more than `tolerance.max_channel_difference` off `expected`.
/// FLIP is not computed here (see [`flip`]).
pub fn compare_pixels(
    expected: &RgbImage,
    actual: &RgbImage,
    tolerance: &Tolerance,
) -> Result<Comparison, SizeMismatch> {
    if expected.dimensions() != actual.dimensions() {
        return Err(SizeMismatch {
            expected: expected.dimensions(),
            actual: actual.dimensions(),
        });
    }
    let (width, height) = actual.dimensions();
    let threshold = tolerance.max_channel_difference;
    let mut comparison = Comparison {
        width,
        height,
        channel_threshold: threshold,
        differing_pixels: 0,
        largest_difference: 0,
        differing_region: None,
        flip: None,
    };
    for (index, difference) in pixel_differences(expected, actual).enumerate() {
        comparison.largest_difference = comparison.largest_difference.max(difference);
        if difference > threshold {
            comparison.differing_pixels += 1;
            // `index < width × height`, both u32, so x and y fit in u32.
            let (x, y) = ((index % width as usize) as u32, (index / width as usize) as u32);
            let region = comparison.differing_region.get_or_insert(PixelRect {
                x0: x,
                y0: y,
                x1: x + 1,
                y1: y + 1,
            });
            // Rows come in order, so the first differing pixel already set `y0`.
            region.x0 = region.x0.min(x);
            region.x1 = region.x1.max(x + 1);
            region.y1 = y + 1;
        }
    }
    Ok(comparison)
}

/// The largest channel difference of each pixel, in row-major order.
fn pixel_differences<'a>(expected: &'a RgbImage, actual: &'a RgbImage) -> impl Iterator<Item = u8> + 'a {
    expected
        .as_raw()
        .chunks_exact(3)
        .zip(actual.as_raw().chunks_exact(3))
        .map(|(e, a)| e.iter().zip(a).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0))
}

/// A picture of where `actual` differs from `expected` (same size; checked by the caller).
///
/// The reference shows through as a dim grey for orientation. Pixels that differ within the
/// threshold are dark blue, so "nearly the same" is visible but quiet; pixels beyond it go from
/// red (just over) to yellow (255 levels off), on a square-root scale so that small
/// differences are not lost next to large ones.
pub fn heat_map(expected: &RgbImage, actual: &RgbImage, threshold: u8) -> RgbImage {
    let (width, height) = expected.dimensions();
    let mut bytes = Vec::with_capacity(expected.as_raw().len());
    for (reference, difference) in expected
        .as_raw()
        .chunks_exact(3)
        .zip(pixel_differences(expected, actual))
    {
        let pixel = if difference > threshold {
            let strength = (f32::from(difference) / 255.0).sqrt();
            [255, (strength * 255.0).round() as u8, 0]
        } else if difference > 0 {
            [0, 0, 160]
        } else {
            // Rec. 601 luma, dimmed to a quarter.
            let luma = 0.299 * f32::from(reference[0])
                + 0.587 * f32::from(reference[1])
                + 0.114 * f32::from(reference[2]);
            [(luma * 0.25).round() as u8; 3]
        };
        bytes.extend(pixel);
    }
    RgbImage::from_raw(width, height, bytes).unwrap_or_else(|| RgbImage::new(width, height))
}

/// FLIP's error statistics and its error map (magma colours, black = no visible difference).
/// `None` when this build has no FLIP ([`FLIP_AVAILABLE`]) or the sizes differ.
pub fn flip(expected: &RgbImage, actual: &RgbImage) -> Option<(FlipScore, RgbImage)> {
    if expected.dimensions() != actual.dimensions() {
        return None;
    }
    flip_same_size(expected, actual)
}

#[cfg(feature = "flip")]
fn flip_same_size(expected: &RgbImage, actual: &RgbImage) -> Option<(FlipScore, RgbImage)> {
    let (width, height) = expected.dimensions();
    if width == 0 || height == 0 {
        return None;
    }
    // FLIP assumes sRGB-encoded 8-bit input, which is what a viewer shows for our PNGs.
    let reference = nv_flip::FlipImageRgb8::with_data(width, height, expected.as_raw());
    let test = nv_flip::FlipImageRgb8::with_data(width, height, actual.as_raw());
    let error = nv_flip::flip(reference, test, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let mut pool = nv_flip::FlipPool::from_image(&error);
    let score = FlipScore {
        mean: f64::from(pool.mean()),
        percentile: f64::from(pool.get_percentile(FLIP_PERCENTILE as f32, false)),
    };
    let colours = error.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    let map = RgbImage::from_raw(width, height, colours)?;
    Some((score, map))
}

#[cfg(not(feature = "flip"))]
fn flip_same_size(_expected: &RgbImage, _actual: &RgbImage) -> Option<(FlipScore, RgbImage)> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: u32, height: u32, pixel: [u8; 3]) -> RgbImage {
        RgbImage::from_pixel(width, height, image::Rgb(pixel))
    }

    fn check(expected: &RgbImage, actual: &RgbImage) -> Comparison {
        compare_pixels(expected, actual, &DEFAULT_TOLERANCE).expect("same size")
    }

    #[test]
    fn identical_images_pass() {
        let a = image(40, 30, [10, 20, 30]);
        let comparison = check(&a, &a);
        assert!(comparison.is_identical());
        assert_eq!(comparison.differing_pixels, 0);
        assert_eq!(comparison.differing_region, None);
        assert!(comparison.violations(&DEFAULT_TOLERANCE).is_empty());
    }

    #[test]
    fn the_channel_threshold_is_inclusive() {
        let a = image(10, 10, [100, 100, 100]);
        let mut b = a.clone();
        b.put_pixel(3, 4, image::Rgb([100, 102, 100]));
        let within = check(&a, &b);
        assert_eq!((within.differing_pixels, within.largest_difference), (0, 2));
        assert!(!within.is_identical());
        b.put_pixel(3, 4, image::Rgb([100, 103, 100]));
        let beyond = check(&a, &b);
        assert_eq!(beyond.differing_pixels, 1);
        assert_eq!(
            beyond.differing_region,
            Some(PixelRect {
                x0: 3,
                y0: 4,
                x1: 4,
                y1: 5
            })
        );
        // One pixel of 100 is 1 %, above the default 0.1 %.
        let violations = beyond.violations(&DEFAULT_TOLERANCE);
        assert_eq!(violations.len(), 1, "{violations:?}");
        assert!(
            violations[0].starts_with("1.000% of pixels (1 of 100)"),
            "{violations:?}"
        );
        assert!(violations[0].contains("within x 3–3, y 4–4"), "{violations:?}");
    }

    #[test]
    fn the_share_limit_allows_a_few_pixels() {
        let a = image(100, 100, [0, 0, 0]);
        let mut b = a.clone();
        for x in 0..10 {
            b.put_pixel(x, 50 + x, image::Rgb([255, 255, 255]));
        }
        let comparison = check(&a, &b);
        assert_eq!(comparison.differing_pixels, 10);
        assert_eq!(comparison.largest_difference, 255);
        assert_eq!(
            comparison.differing_region,
            Some(PixelRect {
                x0: 0,
                y0: 50,
                x1: 10,
                y1: 60
            })
        );
        // 10 of 10,000 pixels is exactly the default share: allowed.
        assert!(comparison.violations(&DEFAULT_TOLERANCE).is_empty());
        let strict = Tolerance {
            max_differing_share: 0.0009,
            ..DEFAULT_TOLERANCE
        };
        assert_eq!(comparison.violations(&strict).len(), 1);
    }

    #[test]
    fn a_zero_tolerance_allows_no_difference_at_all() {
        let exact = Tolerance {
            max_channel_difference: 0,
            max_differing_share: 0.0,
            ..DEFAULT_TOLERANCE
        };
        let a = image(2000, 1000, [100, 100, 100]);
        let same = compare_pixels(&a, &a.clone(), &exact).expect("same size");
        assert!(same.violations(&exact).is_empty());
        let mut b = a.clone();
        b.put_pixel(1999, 999, image::Rgb([100, 100, 101]));
        let comparison = compare_pixels(&a, &b, &exact).expect("same size");
        let violations = comparison.violations(&exact);
        assert_eq!(
            violations,
            [
                "1 of 2,000,000 pixels differ (the tolerance is exact), by up to 1, within x 1999–1999, y 999–999"
            ]
        );
        assert_eq!(
            exact.describe(false),
            "exact: every channel of every pixel must be equal"
        );
        // A share too small for three decimals still does not read as none.
        assert_eq!(percent(comparison.differing_share()), "<0.001%");
    }

    #[test]
    fn different_sizes_do_not_compare() {
        let error = compare_pixels(&image(4, 3, [0; 3]), &image(3, 4, [0; 3]), &DEFAULT_TOLERANCE);
        let mismatch = error.expect_err("sizes differ");
        assert_eq!(mismatch.expected, (4, 3));
        assert_eq!(
            mismatch.to_string(),
            "the image is 3×4 px but the reference is 4×3 px"
        );
        assert!(flip(&image(4, 3, [0; 3]), &image(3, 4, [0; 3])).is_none());
    }

    #[test]
    fn the_heat_map_separates_small_and_large_differences() {
        let a = image(3, 1, [200, 200, 200]);
        let mut b = a.clone();
        b.put_pixel(1, 0, image::Rgb([201, 200, 200]));
        b.put_pixel(2, 0, image::Rgb([0, 200, 200]));
        let map = heat_map(&a, &b, 2);
        assert_eq!(map.get_pixel(0, 0).0, [50, 50, 50]);
        assert_eq!(map.get_pixel(1, 0).0, [0, 0, 160]);
        assert_eq!(map.get_pixel(2, 0).0[0], 255);
        assert!(map.get_pixel(2, 0).0[1] > 200, "{:?}", map.get_pixel(2, 0));
    }

    #[cfg(feature = "flip")]
    #[test]
    fn flip_is_zero_for_identical_images_and_grows_with_the_difference() {
        let a = image(32, 24, [120, 60, 30]);
        let (same, map) = flip(&a, &a).expect("flip is built");
        assert_eq!((same.mean, same.percentile), (0.0, 0.0));
        assert_eq!(map.dimensions(), (32, 24));
        let mut b = a.clone();
        for x in 8..24 {
            for y in 6..18 {
                b.put_pixel(x, y, image::Rgb([30, 60, 220]));
            }
        }
        let (changed, _) = flip(&a, &b).expect("flip is built");
        assert!(changed.mean > DEFAULT_TOLERANCE.max_flip_mean, "{changed:?}");
        assert!(
            changed.percentile > DEFAULT_TOLERANCE.max_flip_percentile,
            "{changed:?}"
        );
        let comparison = Comparison {
            flip: Some(changed),
            ..check(&a, &b)
        };
        assert_eq!(comparison.violations(&DEFAULT_TOLERANCE).len(), 3);
    }
}
