//! The error *where it matters*: the pixels where an approximation's error is most visible,
//! found from what the exact reference's samples saw ([`PixelFeatures`]), each measured apart
//! from the mean over the whole image (which a large smooth surface dilutes).
//!
//! - **Shadow boundary**: a pixel the reference covers, where among the samples of the pixel
//!   and its 8 neighbours that face a shadow-casting light within its reach, that light's
//!   shadow ray was blocked for some and reached the light for others. This is where shadow-map
//!   resolution, PCF and bias show (blocky, blurred, shifted or detached edges); the
//!   terminator where `N·L` crosses 0 is not a boundary (no shadow ray decides it).
//! - **Highlight peak**: a pixel whose reference specular luminance (the mean over its samples)
//!   is at least `1 − HIGHLIGHT_SHARE` of the brightest pixel's: where tessellation, Gouraud
//!   and flat shading lose or smear the highlight.
//! - **Texture detail**: a pixel whose 3×3 neighbourhood is covered and textured in the
//!   reference, whose reference luma (8-bit, as the image is written) varies by at least
//!   `TEXTURE_CONTRAST` levels over that neighbourhood, and which is not a shadow boundary:
//!   where mipmap blur and aliasing show.
//!
//! Each region's error is the mean absolute error over its pixels (8-bit levels, all three
//! channels) and the mean of FLIP's per-pixel error there.

use crate::output::quantize_channel;
use crate::reference::PixelFeatures;
use crate::render::FrameBuffer;

/// A highlight-peak pixel's specular is within this share of the brightest.
pub const HIGHLIGHT_SHARE: f64 = 0.2;

/// Reference luma levels (of 255) over a 3×3 neighbourhood that make texture detail.
pub const TEXTURE_CONTRAST: u8 = 24;

/// The three regions as masks over the image, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct Regions {
    pub width: u32,
    pub height: u32,
    pub shadow_boundary: Vec<bool>,
    pub highlight: Vec<bool>,
    pub texture_detail: Vec<bool>,
}

/// One region's error.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RegionError {
    pub pixels: usize,
    /// Mean absolute error over the region's pixels and the three channels, 8-bit levels.
    pub mean_abs: f64,
    /// Mean FLIP error over the region's pixels (when FLIP is built).
    pub flip_mean: Option<f64>,
}

/// The error in each region.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct WhereItMatters {
    pub shadow_boundary: RegionError,
    pub highlight: RegionError,
    pub texture_detail: RegionError,
}

/// The 8-bit luma (Rec. 709 weights on the quantised channels) of a linear colour.
fn luma(color: glam::Vec3) -> u8 {
    let [r, g, b] = [color.x, color.y, color.z].map(|c| f32::from(quantize_channel(c)));
    (0.2126 * r + 0.7152 * g + 0.0722 * b).round() as u8
}

impl Regions {
    /// The regions of `reference`, whose samples saw `features` (one per pixel).
    pub fn find(reference: &FrameBuffer, features: &[PixelFeatures]) -> Regions {
        let (width, height) = (reference.width(), reference.height());
        let pixel_count = (width * height) as usize;
        assert_eq!(features.len(), pixel_count, "one PixelFeatures per pixel");
        let covered = reference.to_coverage();
        let neighbours = |index: usize| {
            let (x, y) = ((index as u32 % width) as i64, (index as u32 / width) as i64);
            (-1..=1i64)
                .flat_map(move |dy| (-1..=1i64).map(move |dx| (x + dx, y + dy)))
                .filter(move |&(nx, ny)| {
                    nx >= 0 && ny >= 0 && nx < i64::from(width) && ny < i64::from(height)
                })
                .map(move |(nx, ny)| (ny as u32 * width + nx as u32) as usize)
        };
        let shadow_boundary: Vec<bool> = (0..pixel_count)
            .map(|index| {
                let (shadowed, lit) = neighbours(index).fold((0u64, 0u64), |(s, l), n| {
                    (s | features[n].shadowed, l | features[n].lit)
                });
                covered[index] && shadowed & lit != 0
            })
            .collect();
        let brightest = features.iter().map(|f| f.specular).fold(0.0f32, f32::max);
        let highlight = features
            .iter()
            .zip(&covered)
            .map(|(f, &covered)| {
                covered
                    && brightest > 0.0
                    && f64::from(f.specular) >= (1.0 - HIGHLIGHT_SHARE) * f64::from(brightest)
            })
            .collect();
        let lumas: Vec<u8> = reference.colors().map(luma).collect();
        let texture_detail = (0..pixel_count)
            .map(|index| {
                if shadow_boundary[index] {
                    return false;
                }
                let mut count = 0;
                let (mut low, mut high) = (u8::MAX, u8::MIN);
                for n in neighbours(index) {
                    if !(covered[n] && features[n].textured) {
                        return false;
                    }
                    count += 1;
                    low = low.min(lumas[n]);
                    high = high.max(lumas[n]);
                }
                count == 9 && high - low >= TEXTURE_CONTRAST
            })
            .collect();
        Regions {
            width,
            height,
            shadow_boundary,
            highlight,
            texture_detail,
        }
    }

    /// The error of `test` against `reference` in each region; `flip` is FLIP's per-pixel
    /// error map of the two, when there is one.
    pub fn errors(
        &self,
        reference: &FrameBuffer,
        test: &FrameBuffer,
        flip: Option<&[f32]>,
    ) -> WhereItMatters {
        let (expected_colors, actual_colors) = (reference.to_colors(), test.to_colors());
        let error_over = |mask: &[bool]| {
            let mut region = RegionError::default();
            let mut sum_abs = 0u64;
            let mut sum_flip = 0.0f64;
            for (index, _) in mask.iter().enumerate().filter(|(_, inside)| **inside) {
                region.pixels += 1;
                let (expected, actual) = (expected_colors[index], actual_colors[index]);
                for channel in 0..3 {
                    sum_abs += u64::from(
                        quantize_channel(expected[channel]).abs_diff(quantize_channel(actual[channel])),
                    );
                }
                if let Some(flip) = flip {
                    sum_flip += f64::from(flip[index]);
                }
            }
            let count = region.pixels.max(1) as f64;
            region.mean_abs = sum_abs as f64 / (3.0 * count);
            region.flip_mean = flip.map(|_| sum_flip / count);
            region
        };
        WhereItMatters {
            shadow_boundary: error_over(&self.shadow_boundary),
            highlight: error_over(&self.highlight),
            texture_detail: error_over(&self.texture_detail),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::{ReferenceOptions, render_reference_with};
    use crate::scene::Scene;
    use crate::scene::load::{LoadOptions, load_scene};

    fn load(folder: &std::path::Path, text: &str) -> Scene {
        let path = folder.join("scene.ron");
        std::fs::write(&path, text).unwrap();
        match load_scene(&path, &LoadOptions::default()) {
            Ok(loaded) => loaded.scene,
            Err(error) => panic!("{:?}", error.diagnostics),
        }
    }

    /// The reference (the rasterizer's one sample per pixel) and its regions.
    fn regions_of(scene: &Scene) -> (FrameBuffer, Regions) {
        let reference = render_reference_with(
            scene,
            &ReferenceOptions {
                threads: Some(2),
                features: true,
                ..ReferenceOptions::default()
            },
        );
        let regions = Regions::find(&reference.framebuffer, &reference.features);
        (reference.framebuffer, regions)
    }

    /// A square occluder one unit above the ground, seen from straight above, lit along
    /// (1, 1, 0): its shadow on the ground is x in (−1.5, −0.5), |z| < 0.5 (the reference's own
    /// test), and the boundary is exactly the ground pixels with a shadowed and a lit ground
    /// pixel among their 3×3 neighbours (the occluder's unlit top has no shadow rays). Pixel
    /// centres are 1/40 unit from every edge.
    #[test]
    fn shadow_boundary_pixels_are_the_analytic_shadow_edge() {
        let folder = tempfile::tempdir().unwrap();
        let scene = load(
            folder.path(),
            "(image: (width: 80, height: 80), ambient: (0, 0, 0), \
             lights: [Directional(direction: (-1, -1, 0), shadows: true)], \
             camera: Orthographic(eye: (0, 5, 0), target: (0, 0, 0), up: (0, 0, -1), height: 4), \
             objects: [(mesh: Plane, scale: 3, \
                        material: (model: Lambert, ambient: (0, 0, 0), diffuse: (1, 1, 1), specular: (0, 0, 0))), \
                       (mesh: Plane, translate: (0, 1, 0), scale: 0.5, \
                        material: (model: Unlit, color: (0, 1, 0), kd: 1))])",
        );
        let (reference, regions) = regions_of(&scene);
        let centre = |p: i64| (p as f64 + 0.5) * 0.05 - 2.0;
        // Per pixel: None on the occluder, Some(shadowed) on the ground.
        let ground = |px: i64, py: i64| {
            let (x, z) = (centre(px), centre(py));
            if x.abs() < 0.5 && z.abs() < 0.5 {
                None
            } else {
                Some(x > -1.5 && x < -0.5 && z.abs() < 0.5)
            }
        };
        let mut boundary_pixels = 0;
        for py in 0..80i64 {
            for px in 0..80i64 {
                let around: Vec<bool> = (-1..=1)
                    .flat_map(|dy| (-1..=1).map(move |dx| (px + dx, py + dy)))
                    .filter(|&(x, y)| (0..80).contains(&x) && (0..80).contains(&y))
                    .filter_map(|(x, y)| ground(x, y))
                    .collect();
                let expected = around.contains(&true) && around.contains(&false);
                let index = (py * 80 + px) as usize;
                assert_eq!(regions.shadow_boundary[index], expected, "pixel ({px}, {py})");
                boundary_pixels += usize::from(expected);
            }
        }
        // Two columns along x = −1.5, two rows along each of z = ±0.5 (20 px long, plus the
        // corners' neighbours).
        assert!((100..140).contains(&boundary_pixels), "{boundary_pixels}");
        // No specular anywhere, no texture: the other regions are empty.
        assert!(!regions.highlight.contains(&true));
        assert!(!regions.texture_detail.contains(&true));
        // The error there: an image dark on the boundary only errs on the boundary.
        let mut colors = reference.to_colors();
        for (index, &edge) in regions.shadow_boundary.iter().enumerate() {
            if edge {
                colors[index] = glam::Vec3::ZERO;
            }
        }
        let test = FrameBuffer::from_pixels(
            reference.width(),
            reference.height(),
            colors,
            reference.to_coverage(),
        );
        let errors = regions.errors(&reference, &test, None);
        assert_eq!(errors.shadow_boundary.pixels, boundary_pixels);
        assert!(errors.shadow_boundary.mean_abs > 20.0, "{errors:?}");
        assert_eq!(errors.highlight, RegionError::default());
    }

    /// A shiny unit sphere seen orthographically along −z, lit along −z: its Phong highlight
    /// is `cos(2θ)ⁿ` at the normal's angle θ from the view, brightest (1) at the pixel centre
    /// over the sphere's centre, so the highlight peak is the disc where `cos(2θ)ⁿ ≥ 0.8`,
    /// `r = sin(acos(0.8^(1/n)) / 2)`.
    #[test]
    fn the_highlight_peak_is_the_analytic_disc() {
        let folder = tempfile::tempdir().unwrap();
        let scene = load(
            folder.path(),
            "(image: (width: 41, height: 41), ambient: (0, 0, 0), \
             lights: [Directional(direction: (0, 0, -1))], \
             camera: Orthographic(eye: (0, 0, 5), target: (0, 0, 0), up: (0, 1, 0), height: 2.4), \
             objects: [(mesh: Sphere(), material: (model: Phong, ambient: (0, 0, 0), diffuse: (0.3, 0.3, 0.3), \
                        specular: (1, 1, 1), shininess: 5))])",
        );
        let (_, regions) = regions_of(&scene);
        let radius = ((1.0 - HIGHLIGHT_SHARE).powf(1.0 / 5.0).acos() / 2.0).sin();
        let pixel = 2.4 / 41.0;
        let mut inside = 0;
        for py in 0..41 {
            for px in 0..41 {
                let r = pixel * f64::hypot(f64::from(px) - 20.0, f64::from(py) - 20.0);
                let marked = regions.highlight[(py * 41 + px) as usize];
                if r < radius - 0.01 {
                    assert!(marked, "({px}, {py}) at {r} inside {radius}");
                    inside += 1;
                } else if r > radius + 0.01 {
                    assert!(!marked, "({px}, {py}) at {r} outside {radius}");
                }
            }
        }
        // r = 0.148 = 2.52 pixels: the pixels at most √5 pixels from the centre.
        assert_eq!(inside, 21);
        assert!(!regions.shadow_boundary.contains(&true));
    }

    /// A checkerboard of 8-texel squares, one texel per pixel, seen from straight above: the
    /// texture-detail pixels are those next to a square's edge, none in a square's interior.
    #[test]
    fn texture_detail_is_along_the_checkerboard_edges() {
        let folder = tempfile::tempdir().unwrap();
        let board = image::RgbImage::from_fn(64, 64, |x, y| {
            if (x / 8 + y / 8) % 2 == 0 {
                image::Rgb([240, 240, 240])
            } else {
                image::Rgb([20, 20, 20])
            }
        });
        board.save(folder.path().join("board.png")).unwrap();
        let scene = load(
            folder.path(),
            "(image: (width: 64, height: 64), ambient: (0, 0, 0), \
             lights: [Directional(direction: (0, -1, 0))], \
             camera: Orthographic(eye: (0, 5, 0), target: (0, 0, 0), up: (0, 0, -1), height: 4), \
             objects: [(mesh: Plane, scale: 2, \
                        material: (model: Lambert, ambient: (0, 0, 0), diffuse: (1, 1, 1), texture: \"board.png\"))])",
        );
        let (_, regions) = regions_of(&scene);
        // The distance from a pixel to the nearest edge between squares (edges at multiples of
        // 8 texels = 8 pixels): 0 for the pixels on either side of it.
        let to_edge = |p: u32| {
            let within = p % 8;
            within.min(7 - within)
        };
        let mut detail = 0;
        for py in 1..63u32 {
            for px in 1..63u32 {
                let marked = regions.texture_detail[(py * 64 + px) as usize];
                let distance = to_edge(px).min(to_edge(py));
                if distance == 0 {
                    assert!(marked, "({px}, {py}) next to an edge");
                } else if distance >= 2 {
                    assert!(!marked, "({px}, {py}) inside a square");
                }
                detail += usize::from(marked);
            }
        }
        assert!(detail > 1000, "{detail}");
        // The image's border pixels have no full neighbourhood.
        assert!((0..64).all(|i| !regions.texture_detail[i] && !regions.texture_detail[i * 64]));
    }
}
