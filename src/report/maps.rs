//! `report speed-error --knobs --maps DIR`: where each point's error is, as a heat map.
//!
//! Each map is the image's size plus a legend strip below it: FLIP's per-pixel error (0 to 1)
//! where FLIP is built, otherwise the largest channel's absolute error over 255, through a
//! magma colour scale (black: no visible difference; pale yellow: the largest), and under it
//! the colour bar with its scale's name and ticks at 0, 0.25, 0.5, 0.75 and 1, drawn with a
//! 3×5 pixel font so the PNG needs no font file.

use image::{ImageEncoder as _, Rgb, RgbImage};

use crate::output::quantize_channel;
use crate::render::FrameBuffer;

/// Height of the legend strip below the image, in pixels.
pub const LEGEND_HEIGHT: u32 = 30;

/// Matplotlib's magma at 0, 0.2, …, 1 (the scale FLIP's own maps use), linearly between.
const MAGMA: [[f32; 3]; 6] = [
    [0.0, 0.0, 4.0],
    [59.0, 15.0, 111.0],
    [140.0, 41.0, 129.0],
    [221.0, 73.0, 104.0],
    [253.0, 159.0, 109.0],
    [252.0, 253.0, 191.0],
];

/// The scale's colour for `value` in [0, 1] (clamped).
pub fn magma(value: f32) -> Rgb<u8> {
    let position = value.clamp(0.0, 1.0) * (MAGMA.len() - 1) as f32;
    let lower = (position.floor() as usize).min(MAGMA.len() - 2);
    let fraction = position - lower as f32;
    let (a, b) = (MAGMA[lower], MAGMA[lower + 1]);
    Rgb(std::array::from_fn(|c| {
        (a[c] + (b[c] - a[c]) * fraction).round() as u8
    }))
}

/// What a map shows per pixel: the values (0 to 1, row-major) and the scale's name.
pub fn error_values(
    reference: &FrameBuffer,
    test: &FrameBuffer,
    flip: Option<&[f32]>,
) -> (Vec<f32>, &'static str) {
    match flip {
        Some(flip) => (flip.to_vec(), "FLIP"),
        None => {
            let values = reference
                .colors()
                .zip(test.colors())
                .map(|(a, b)| {
                    (0..3)
                        .map(|c| quantize_channel(a[c]).abs_diff(quantize_channel(b[c])))
                        .max()
                        .unwrap_or(0) as f32
                        / 255.0
                })
                .collect();
            (values, "ABS")
        }
    }
}

/// Rows of each glyph, three bits a row (most significant on the left).
fn glyph(character: char) -> Option<[u8; 5]> {
    Some(match character {
        '0' => [0b111, 0b101, 0b101, 0b101, 0b111],
        '1' => [0b010, 0b110, 0b010, 0b010, 0b111],
        '2' => [0b111, 0b001, 0b111, 0b100, 0b111],
        '3' => [0b111, 0b001, 0b111, 0b001, 0b111],
        '4' => [0b101, 0b101, 0b111, 0b001, 0b001],
        '5' => [0b111, 0b100, 0b111, 0b001, 0b111],
        '6' => [0b111, 0b100, 0b111, 0b101, 0b111],
        '7' => [0b111, 0b001, 0b010, 0b010, 0b010],
        '8' => [0b111, 0b101, 0b111, 0b101, 0b111],
        '9' => [0b111, 0b101, 0b111, 0b001, 0b111],
        '.' => [0b000, 0b000, 0b000, 0b000, 0b010],
        'A' => [0b010, 0b101, 0b111, 0b101, 0b101],
        'B' => [0b110, 0b101, 0b110, 0b101, 0b110],
        'F' => [0b111, 0b100, 0b110, 0b100, 0b100],
        'I' => [0b111, 0b010, 0b010, 0b010, 0b111],
        'L' => [0b100, 0b100, 0b100, 0b100, 0b111],
        'P' => [0b110, 0b101, 0b110, 0b100, 0b100],
        'S' => [0b111, 0b100, 0b111, 0b001, 0b111],
        _ => return None,
    })
}

/// Draws `text` in white with its top-left corner at (`x`, `y`), each font pixel `scale`
/// image pixels; what falls outside the image is left out.
fn draw_text(image: &mut RgbImage, text: &str, x: u32, y: u32, scale: u32) {
    for (index, character) in text.chars().enumerate() {
        let Some(rows) = glyph(character) else { continue };
        let left = x + index as u32 * 4 * scale;
        for (row, bits) in rows.iter().enumerate() {
            for column in 0..3 {
                if bits & (0b100 >> column) == 0 {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let (px, py) = (left + column * scale + dx, y + row as u32 * scale + dy);
                        if px < image.width() && py < image.height() {
                            image.put_pixel(px, py, Rgb([255, 255, 255]));
                        }
                    }
                }
            }
        }
    }
}

/// The heat map of `values` (row-major, `width`×`height`, each 0 to 1) with its legend strip.
pub fn heat_map(values: &[f32], width: u32, height: u32, scale_name: &str) -> RgbImage {
    let mut image = RgbImage::from_pixel(width, height + LEGEND_HEIGHT, Rgb([32, 32, 32]));
    for (index, &value) in values.iter().enumerate().take((width * height) as usize) {
        image.put_pixel(index as u32 % width, index as u32 / width, magma(value));
    }
    // The scale's name on the left, the bar to its right, the ticks' values under the bar.
    let name_width = scale_name.len() as u32 * 4 + 2;
    let bar_left = (name_width + 2).min(width);
    let bar_right = width.saturating_sub(8).max(bar_left);
    let (bar_top, bar_bottom) = (height + 3, height + 13);
    draw_text(&mut image, scale_name, 1, bar_top + 3, 1);
    let span = (bar_right - bar_left).max(1);
    for x in bar_left..bar_right {
        let colour = magma((x - bar_left) as f32 / span as f32);
        for y in bar_top..bar_bottom {
            image.put_pixel(x, y, colour);
        }
    }
    for (tick, label) in [(0.0, "0"), (0.25, ".25"), (0.5, ".5"), (0.75, ".75"), (1.0, "1")] {
        let x = bar_left + (tick * span as f32).round() as u32;
        for y in bar_bottom..bar_bottom + 3 {
            if x < width {
                image.put_pixel(x, y, Rgb([255, 255, 255]));
            }
        }
        let text_width = label.len() as u32 * 4;
        let text_x = x
            .saturating_sub(text_width / 2)
            .min(width.saturating_sub(text_width));
        draw_text(&mut image, label, text_x, bar_bottom + 5, 1);
    }
    image
}

/// A file name for the point `knob` = `value`: lower case, a number's sign and decimal point
/// in the value as `m` and `p` (so 0.5 and -0.5 differ), every run of other characters one
/// `-`, and `.png`.
pub fn map_file_name(knob: &str, value: &str) -> String {
    let value: String = value
        .chars()
        .map(|c| match c {
            '-' => 'm',
            '.' => 'p',
            c => c,
        })
        .collect();
    let mut name = String::new();
    for character in format!("{knob} {value}").chars() {
        if character.is_ascii_alphanumeric() {
            name.push(character.to_ascii_lowercase());
        } else if !name.ends_with('-') {
            name.push('-');
        }
    }
    format!("{}.png", name.trim_matches('-'))
}

/// `image` as PNG bytes.
pub fn png_bytes(image: &RgbImage) -> Vec<u8> {
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(
            image.as_raw(),
            image.width(),
            image.height(),
            image::ExtendedColorType::Rgb8,
        )
        .expect("encoding into memory cannot fail");
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scale_runs_from_black_to_pale_yellow() {
        assert_eq!(magma(0.0), Rgb([0, 0, 4]));
        assert_eq!(magma(1.0), Rgb([252, 253, 191]));
        assert_eq!(magma(-3.0), magma(0.0));
        assert_eq!(magma(0.4), Rgb([140, 41, 129]));
        // Brighter with the value, in the mean of the channels.
        let brightness = |v: f32| magma(v).0.iter().map(|&c| u32::from(c)).sum::<u32>();
        assert!((1..=10).all(|i| brightness(i as f32 / 10.0) > brightness((i - 1) as f32 / 10.0)));
    }

    /// The map is the image with the legend below it, its pixels the scale's colours, and the
    /// PNG decodes to the same size.
    #[test]
    fn a_map_is_the_image_and_its_legend() {
        let (width, height) = (40, 20);
        let values: Vec<f32> = (0..width * height)
            .map(|i| if i % width < 20 { 0.0 } else { 1.0 })
            .collect();
        let map = heat_map(&values, width, height, "FLIP");
        assert_eq!(map.dimensions(), (width, height + LEGEND_HEIGHT));
        assert_eq!(*map.get_pixel(3, 5), magma(0.0));
        assert_eq!(*map.get_pixel(30, 5), magma(1.0));
        // The legend has the scale's name (white pixels) and its colour bar.
        let legend_white = (height..height + LEGEND_HEIGHT)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .filter(|&(x, y)| *map.get_pixel(x, y) == Rgb([255, 255, 255]))
            .count();
        assert!(legend_white > 20, "{legend_white}");
        let decoded = image::load_from_memory(&png_bytes(&map)).unwrap().to_rgb8();
        assert_eq!(decoded, map);
    }

    #[test]
    fn file_names_come_from_the_point() {
        assert_eq!(
            map_file_name("shadow-map resolution", "1024"),
            "shadow-map-resolution-1024.png"
        );
        assert_eq!(map_file_name("shading: Duck", "Phong"), "shading-duck-phong.png");
        assert_eq!(
            map_file_name("sphere tessellation", "Sphere(48)"),
            "sphere-tessellation-sphere-48.png"
        );
        assert_eq!(map_file_name("mip bias", "-0.5"), "mip-bias-m0p5.png");
        assert_eq!(map_file_name("mip bias", "0.5"), "mip-bias-0p5.png");
    }
}
