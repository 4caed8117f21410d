//! Every bundled scene, rendered, against its reference image `scenes/refs/NAME.png`.
//!
//! Tolerance: a channel may differ by at most [`MAX_CHANNEL_DIFFERENCE`] levels (of 255) on all
//! but [`MAX_DIFFERING_SHARE`] of the pixels, which absorbs last-bit differences in `powf` and
//! friends between machines, and no more: a change a person would see (a moved highlight, a
//! different colour, a missing object) changes far more pixels than that, by far more.
//!
//! After a deliberate change, look at the new images, then bless them:
//! `LAMPSHADE_BLESS=1 cargo test --test suite golden`.

use std::path::Path;

use lampshade::output::{PngCompression, to_rgb8, write_png};
use lampshade::render::{RenderOptions, render};
use lampshade::scene::{LoadOptions, load_scene};

use crate::{repo, ron_files};

const MAX_CHANNEL_DIFFERENCE: u8 = 2;
const MAX_DIFFERING_SHARE: f64 = 0.001;

#[test]
fn bundled_scenes_match_their_reference_images() {
    let scenes = ron_files(&repo().join("scenes"));
    assert!(scenes.len() >= 10, "the bundled scenes are missing");
    let bless = std::env::var_os("LAMPSHADE_BLESS").is_some();
    let mut failures = Vec::new();
    for scene in &scenes {
        let loaded = load_scene(scene, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{} does not load: {:?}", scene.display(), e.diagnostics));
        let (framebuffer, _) = render(&loaded.scene, &RenderOptions::default());
        let image = to_rgb8(&framebuffer);
        let reference_path = reference_path(scene);
        if bless {
            write_png(&reference_path, &image, PngCompression::Best).unwrap();
            continue;
        }
        let Ok(reference) = image::open(&reference_path) else {
            failures.push(format!(
                "{}: no reference image (bless it after looking at it)",
                reference_path.display()
            ));
            continue;
        };
        let reference = reference.to_rgb8();
        if reference.dimensions() != image.dimensions() {
            failures.push(format!(
                "{}: size {:?}, reference {:?}",
                scene.display(),
                image.dimensions(),
                reference.dimensions()
            ));
            continue;
        }
        let differing = image
            .as_raw()
            .chunks(3)
            .zip(reference.as_raw().chunks(3))
            .filter(|(a, b)| {
                a.iter()
                    .zip(b.iter())
                    .any(|(x, y)| x.abs_diff(*y) > MAX_CHANNEL_DIFFERENCE)
            })
            .count();
        let share = differing as f64 / (image.width() * image.height()) as f64;
        if share > MAX_DIFFERING_SHARE {
            let actual = std::env::temp_dir().join(format!(
                "lampshade-{}",
                reference_path.file_name().unwrap().to_string_lossy()
            ));
            let _ = write_png(&actual, &image, PngCompression::Fast);
            failures.push(format!(
                "{}: {:.3}% of pixels differ by more than {MAX_CHANNEL_DIFFERENCE} (new image: {})",
                scene.display(),
                share * 100.0,
                actual.display()
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{}\nIf the change is intended: LAMPSHADE_BLESS=1 cargo test --test suite golden",
        failures.join("\n")
    );
}

fn reference_path(scene: &Path) -> std::path::PathBuf {
    let name = scene.file_stem().unwrap().to_string_lossy();
    scene.parent().unwrap().join("refs").join(format!("{name}.png"))
}

#[test]
fn a_visible_change_fails_the_comparison() {
    // The tolerance must not hide a real change: shift a light a little and count.
    let scene = repo().join("scenes/matlab-shiny.ron");
    let text = std::fs::read_to_string(&scene).unwrap().replace(
        "Directional(direction: (-1, 1, -1))",
        "Directional(direction: (-1, 1.1, -1))",
    );
    let work = tempfile::tempdir().unwrap();
    let changed = work.path().join("changed.ron");
    std::fs::write(&changed, text).unwrap();
    let render_file = |path: &Path| {
        let loaded = load_scene(path, &LoadOptions::default()).unwrap();
        to_rgb8(&render(&loaded.scene, &RenderOptions::default()).0)
    };
    let (a, b) = (render_file(&scene), render_file(&changed));
    let differing = a
        .as_raw()
        .chunks(3)
        .zip(b.as_raw().chunks(3))
        .filter(|(x, y)| {
            x.iter()
                .zip(y.iter())
                .any(|(p, q)| p.abs_diff(*q) > MAX_CHANNEL_DIFFERENCE)
        })
        .count();
    assert!(
        differing as f64 / (a.width() * a.height()) as f64 > MAX_DIFFERING_SHARE * 10.0,
        "{differing} pixels"
    );
}
