//! Error metrics between a test image and a reference, over the pixels where either has
//! geometry ([`FrameBuffer::covered`]): the background both share is not error-free credit.
//!
//! Both images are first quantised to 8 bits exactly as the PNG output does
//! (`output::quantize_channel`: clamp to [0, 1], round), so every figure is on the 0..255 scale
//! of the llvmpipe anchor's accuracy table and describes what a viewer of the PNGs sees:
//! - mean and max absolute error per channel and over all channels;
//! - RMSE over all channels, and PSNR = 20·log10(255 / RMSE) (infinite for identical images);
//! - the share of pixels with a channel off by more than 2 and by more than 8 levels (the
//!   anchor table's columns);
//! - the highlight's peak loss: how much dimmer the test's brightest pixel is than the
//!   reference's (mean of the three channels), which says whether a highlight survived where
//!   the mean error, diluted over the whole surface, cannot;
//! - FLIP (NVIDIA's perceptual metric, feature `flip`): mean and 99th percentile of the
//!   per-pixel error, over the same pixels. FLIP itself looks at the whole image (its filters
//!   need the neighbourhood); only the pooling is restricted to the covered pixels.
//!
//! Rejected: metrics on the unclamped linear values (a highlight at 3.0 against 1.2 is an
//! error nobody sees in a PNG) and over the whole image (a small object on a large background
//! would look accurate whatever it looked like).

pub mod regions;

use crate::output::quantize_channel;
use crate::render::FrameBuffer;

/// How far a test image is from a reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorMetrics {
    /// Pixels compared: covered in either image.
    pub pixels: usize,
    /// Mean absolute error per channel (R, G, B), in 8-bit levels.
    pub mean_abs: [f64; 3],
    /// Largest absolute error per channel, in 8-bit levels.
    pub max_abs: [u8; 3],
    /// Root mean square error over all channels, in 8-bit levels.
    pub rmse: f64,
    /// `20·log10(255 / rmse)` in dB; infinite when the images agree.
    pub psnr_db: f64,
    /// Share of compared pixels with some channel off by more than 2 levels.
    pub share_over_2: f64,
    /// Share of compared pixels with some channel off by more than 8 levels.
    pub share_over_8: f64,
    /// The brightest compared pixel of the reference minus that of the test, in levels (mean
    /// of the channels): positive when the test lost part of the highlight.
    pub peak_loss: f64,
    /// FLIP error over the compared pixels, when the `flip` feature is built.
    pub flip: Option<FlipError>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlipError {
    pub mean: f64,
    /// The 99th percentile of the per-pixel error.
    pub percentile_99: f64,
}

impl ErrorMetrics {
    /// Mean absolute error over the three channels.
    pub fn mean_abs_all(&self) -> f64 {
        self.mean_abs.iter().sum::<f64>() / 3.0
    }

    /// Largest absolute error over the three channels.
    pub fn max_abs_all(&self) -> u8 {
        self.max_abs.into_iter().max().unwrap_or(0)
    }
}

/// Which pixels are compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Compared {
    /// Covered in either image: a missing or extra silhouette pixel counts (the default).
    EitherCovered,
    /// Covered in both: the llvmpipe anchor's convention, which leaves silhouettes out.
    BothCovered,
}

/// Compares `test` with `reference` over the pixels either covers; `None` when their sizes
/// differ.
pub fn compare(reference: &FrameBuffer, test: &FrameBuffer) -> Option<ErrorMetrics> {
    compare_over(reference, test, Compared::EitherCovered)
}

/// [`compare`] over the pixels `compared` selects.
pub fn compare_over(reference: &FrameBuffer, test: &FrameBuffer, compared: Compared) -> Option<ErrorMetrics> {
    if (reference.width(), reference.height()) != (test.width(), test.height()) {
        return None;
    }
    let quantize = |c: glam::Vec3| {
        [
            quantize_channel(c.x),
            quantize_channel(c.y),
            quantize_channel(c.z),
        ]
    };
    let mut pixels = 0usize;
    let mut sum_abs = [0u64; 3];
    let mut max_abs = [0u8; 3];
    let mut sum_squares = 0u64;
    let (mut over_2, mut over_8) = (0usize, 0usize);
    let (mut expected_peak, mut actual_peak) = (0u32, 0u32);
    let mask: Vec<bool> = reference
        .coverage()
        .zip(test.coverage())
        .map(|(a, b)| match compared {
            Compared::EitherCovered => a || b,
            Compared::BothCovered => a && b,
        })
        .collect();
    for ((expected, actual), _) in reference
        .colors()
        .zip(test.colors())
        .zip(&mask)
        .filter(|(_, compared)| **compared)
    {
        pixels += 1;
        let (expected, actual) = (quantize(expected), quantize(actual));
        let brightness = |c: [u8; 3]| c.iter().map(|&v| u32::from(v)).sum::<u32>();
        expected_peak = expected_peak.max(brightness(expected));
        actual_peak = actual_peak.max(brightness(actual));
        let mut largest = 0;
        for channel in 0..3 {
            let difference = expected[channel].abs_diff(actual[channel]);
            sum_abs[channel] += u64::from(difference);
            sum_squares += u64::from(difference) * u64::from(difference);
            max_abs[channel] = max_abs[channel].max(difference);
            largest = largest.max(difference);
        }
        over_2 += usize::from(largest > 2);
        over_8 += usize::from(largest > 8);
    }
    let count = pixels.max(1) as f64;
    let rmse = (sum_squares as f64 / (3.0 * count)).sqrt();
    Some(ErrorMetrics {
        pixels,
        mean_abs: sum_abs.map(|sum| sum as f64 / count),
        max_abs,
        rmse,
        psnr_db: if rmse == 0.0 {
            f64::INFINITY
        } else {
            20.0 * (255.0 / rmse).log10()
        },
        share_over_2: over_2 as f64 / count,
        share_over_8: over_8 as f64 / count,
        peak_loss: (f64::from(expected_peak) - f64::from(actual_peak)) / 3.0,
        flip: flip(reference, test, &mask),
    })
}

/// FLIP's per-pixel error of `test` against `reference` (0 to 1, row-major, the 8-bit images
/// as written), when the `flip` feature is built and the sizes agree.
#[cfg(feature = "flip")]
pub fn flip_map(reference: &FrameBuffer, test: &FrameBuffer) -> Option<Vec<f32>> {
    let (width, height) = (reference.width(), reference.height());
    if (width, height) != (test.width(), test.height()) || width == 0 || height == 0 {
        return None;
    }
    let expected = crate::output::to_rgb8(reference);
    let actual = crate::output::to_rgb8(test);
    let error = nv_flip::flip(
        nv_flip::FlipImageRgb8::with_data(width, height, expected.as_raw()),
        nv_flip::FlipImageRgb8::with_data(width, height, actual.as_raw()),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    Some(error.to_vec())
}

#[cfg(not(feature = "flip"))]
pub fn flip_map(_reference: &FrameBuffer, _test: &FrameBuffer) -> Option<Vec<f32>> {
    None
}

fn flip(reference: &FrameBuffer, test: &FrameBuffer, mask: &[bool]) -> Option<FlipError> {
    if !mask.contains(&true) {
        return None;
    }
    let mut values: Vec<f32> = flip_map(reference, test)?
        .into_iter()
        .zip(mask)
        .filter(|(_, compared)| **compared)
        .map(|(value, _)| value)
        .collect();
    values.sort_by(f32::total_cmp);
    let mean = values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len() as f64;
    Some(FlipError {
        mean,
        percentile_99: f64::from(percentile(&values, 0.99)),
    })
}

/// The value below which a share `p` of the sorted `values` lie (nearest rank).
pub fn percentile(sorted: &[f32], p: f64) -> f32 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = (p * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn image(width: u32, height: u32, color: Vec3, covered: bool) -> FrameBuffer {
        let n = (width * height) as usize;
        FrameBuffer::from_pixels(width, height, vec![color; n], vec![covered; n])
    }

    /// `frame` with its pixels changed by `edit` (colours, coverage).
    fn edited(frame: &FrameBuffer, edit: impl FnOnce(&mut [Vec3], &mut [bool])) -> FrameBuffer {
        let (mut colors, mut coverage) = (frame.to_colors(), frame.to_coverage());
        edit(&mut colors, &mut coverage);
        FrameBuffer::from_pixels(frame.width(), frame.height(), colors, coverage)
    }

    #[test]
    fn identical_images_have_no_error() {
        let a = image(8, 8, Vec3::new(0.2, 0.5, 0.9), true);
        let m = compare(&a, &a).unwrap();
        assert_eq!(m.pixels, 64);
        assert_eq!(m.mean_abs, [0.0; 3]);
        assert_eq!(m.max_abs, [0; 3]);
        assert_eq!(m.psnr_db, f64::INFINITY);
        assert_eq!(m.peak_loss, 0.0);
        assert_eq!((m.share_over_2, m.share_over_8), (0.0, 0.0));
        if let Some(flip) = m.flip {
            assert_eq!((flip.mean, flip.percentile_99), (0.0, 0.0));
        }
    }

    /// One pixel of 16 off by 51 levels in red only: mean 51/16 in red, RMSE √(51²/48),
    /// PSNR 20·log10(255/RMSE), 1/16 of pixels over 2 and over 8.
    #[test]
    fn one_wrong_pixel_by_hand() {
        let reference = image(4, 4, Vec3::ZERO, true);
        let test = edited(&reference, |colors, _| colors[5] = Vec3::new(0.2, 0.0, 0.0)); // 0.2·255 = 51
        let m = compare(&reference, &test).unwrap();
        assert_eq!(m.max_abs, [51, 0, 0]);
        assert!((m.mean_abs[0] - 51.0 / 16.0).abs() < 1e-12);
        assert_eq!(m.mean_abs[1], 0.0);
        let rmse = (51.0f64 * 51.0 / 48.0).sqrt();
        assert!((m.rmse - rmse).abs() < 1e-12);
        assert!((m.psnr_db - 20.0 * (255.0 / rmse).log10()).abs() < 1e-9);
        assert_eq!((m.share_over_2, m.share_over_8), (1.0 / 16.0, 1.0 / 16.0));
        // The test's brightest pixel is 51 levels of red brighter than the reference's black.
        assert_eq!(m.peak_loss, -17.0);
        assert!((m.mean_abs_all() - 51.0 / 48.0).abs() < 1e-12);
        assert_eq!(m.max_abs_all(), 51);
    }

    /// Only pixels covered in either image count: a difference on uncovered background is not
    /// compared, and uncovered pixels do not dilute the mean.
    #[test]
    fn only_covered_pixels_count() {
        let background = image(4, 1, Vec3::ZERO, false);
        let reference = edited(&background, |_, covered| covered[0] = true); // geometry in the reference only
        let test = edited(&background, |colors, covered| {
            colors[0] = Vec3::splat(10.0 / 255.0);
            covered[1] = true; // geometry in the test only, same colour
            colors[3] = Vec3::ONE; // background differs, but nobody covers it
        });
        let m = compare(&reference, &test).unwrap();
        assert_eq!(m.pixels, 2);
        assert_eq!(m.max_abs, [10; 3]);
        assert_eq!(m.mean_abs, [5.0; 3]);
        assert_eq!((m.share_over_2, m.share_over_8), (0.5, 0.5));
        // Covered in both: pixel 2 only, where the two agree.
        let reference = edited(&reference, |_, covered| covered[2] = true);
        let test = edited(&test, |_, covered| covered[2] = true);
        let both = compare_over(&reference, &test, Compared::BothCovered).unwrap();
        assert_eq!((both.pixels, both.max_abs), (1, [0; 3]));
    }

    /// Values above 1 are compared as the PNG stores them: clamped.
    #[test]
    fn errors_are_measured_after_clamping() {
        let reference = image(2, 2, Vec3::splat(1.0), true);
        let test = image(2, 2, Vec3::splat(7.0), true);
        assert_eq!(compare(&reference, &test).unwrap().max_abs, [0; 3]);
        assert!(compare(&reference, &image(2, 3, Vec3::ONE, true)).is_none());
    }

    #[test]
    fn percentile_by_nearest_rank() {
        let values: Vec<f32> = (1..=100).map(|v| v as f32).collect();
        assert_eq!(percentile(&values, 0.99), 99.0);
        assert_eq!(percentile(&values, 1.0), 100.0);
        assert_eq!(percentile(&values, 0.0), 1.0);
        assert_eq!(percentile(&[], 0.5), 0.0);
    }

    #[cfg(feature = "flip")]
    #[test]
    fn flip_grows_with_the_difference_and_ignores_uncovered_pixels() {
        let reference = image(32, 32, Vec3::splat(0.5), true);
        let slightly = image(32, 32, Vec3::splat(0.52), true);
        let very = image(32, 32, Vec3::splat(0.9), true);
        let small = compare(&reference, &slightly).unwrap().flip.unwrap();
        let large = compare(&reference, &very).unwrap().flip.unwrap();
        assert!(small.mean > 0.0 && small.mean < large.mean, "{small:?} {large:?}");
        assert!(large.percentile_99 >= large.mean);
        let half = edited(&reference, |_, covered| covered[..512].fill(false));
        let half_test = edited(&very, |colors, covered| {
            covered[..512].fill(false);
            colors[512..].fill(Vec3::splat(0.5));
        });
        // The covered half is identical, so, away from the boundary, FLIP is low there.
        let pooled = compare(&half, &half_test).unwrap().flip.unwrap();
        assert!(pooled.mean < large.mean / 2.0, "{pooled:?} against {large:?}");
    }
}
