//! Every bundled scene against its reference image `scenes/refs/NAME.png`, through the library
//! behind `lampshade check` (the same discovery, tolerances and comparison that CI's
//! `lampshade check scenes/` uses), so `cargo test` alone catches a changed image too.
//!
//! After a deliberate change, look at the new images (`lampshade check scenes/ --report DIR`),
//! then bless them: `cargo run --release -- check --bless scenes/`.

use std::path::Path;

use lampshade::check::compare::{DEFAULT_TOLERANCE, compare_pixels, flip};
use lampshade::check::runner::{RunOptions, SceneStatus, check_scene};
use lampshade::check::suite::discover;
use lampshade::output::to_rgb8;
use lampshade::render::{RenderOptions, render};
use lampshade::scene::{LoadOptions, load_scene};

use crate::repo;

#[test]
fn bundled_scenes_match_their_reference_images() {
    let scenes = discover(&[repo().join("scenes")]).expect("the bundled suite reads");
    assert!(scenes.len() >= 10, "the bundled scenes are missing");
    let mut failures = Vec::new();
    for (index, scene) in scenes.iter().enumerate() {
        let result = check_scene(scene, index, &RunOptions::default());
        match &result.status {
            SceneStatus::Passed(_) => {}
            SceneStatus::Failed(failure) => {
                failures.push(format!("{}: {}", scene.path.display(), failure.describe(scene)))
            }
            SceneStatus::Errored(error) => failures.push(format!(
                "{}: {}: {error:?}",
                scene.path.display(),
                error.describe()
            )),
            other => failures.push(format!("{}: unexpected {other:?}", scene.path.display())),
        }
    }
    assert!(
        failures.is_empty(),
        "{}\nLook at the differences: cargo run -- check scenes/ --report /tmp/report\n\
         If the change is intended: cargo run --release -- check --bless scenes/",
        failures.join("\n")
    );
}

#[test]
fn a_visible_change_fails_the_comparison() {
    // The default tolerance must not hide a real change: shift a light a little.
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
    let (original, moved) = (render_file(&scene), render_file(&changed));
    let comparison = compare_pixels(&original, &moved, &DEFAULT_TOLERANCE).unwrap();
    assert!(
        comparison.differing_share() > DEFAULT_TOLERANCE.max_differing_share * 10.0,
        "{comparison:?}"
    );
    assert!(!comparison.violations(&DEFAULT_TOLERANCE).is_empty());
    // FLIP's default limit on its 99th percentile catches it too.
    if let Some((score, _)) = flip(&original, &moved) {
        assert!(
            score.percentile > DEFAULT_TOLERANCE.max_flip_percentile,
            "{score:?}"
        );
    }
}
