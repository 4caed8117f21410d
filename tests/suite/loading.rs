//! Scene files as users write them: includes, defaults, many lights, mirrored objects, and the
//! examples of the format reference.

use std::path::Path;

use glam::Vec3;
use lampshade::render::{FrameBuffer, RenderOptions, render};
use lampshade::scene::{LoadOptions, Scene, load_scene, load_scene_from_str};

use crate::repo;

fn write(folder: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let path = folder.join(name);
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    std::fs::write(&path, text).unwrap();
    path
}

fn load(path: &Path) -> Scene {
    match load_scene(path, &LoadOptions::default()) {
        Ok(loaded) => loaded.scene,
        Err(error) => panic!(
            "{}",
            lampshade::diag::render_diagnostics(&error.diagnostics, &error.sources, false)
        ),
    }
}

fn draw(scene: &Scene) -> FrameBuffer {
    render(scene, &RenderOptions::default()).0
}

#[test]
fn includes_nest_resolve_bases_and_the_scene_overrides_them() {
    let folder = tempfile::tempdir().unwrap();
    write(
        folder.path(),
        "lib/base.ron",
        r#"Materials(materials: { "base-red": (color: (1, 0, 0), kd: 0.5) })"#,
    );
    write(
        folder.path(),
        "lib/paints.ron",
        r#"Materials(include: ["base.ron"], materials: {
            "bright-red": (base: "base-red", kd: 1.0),
            "overridden": (diffuse: (0, 1, 0)),
        })"#,
    );
    let scene = write(
        folder.path(),
        "scene.ron",
        r#"Scene(
            include: ["lib/paints.ron"],
            materials: { "overridden": (diffuse: (0, 0, 1)) },
            objects: [
                (mesh: Cube, material: "bright-red"),
                (mesh: Cube, material: "overridden"),
                (mesh: Cube, material: (base: "Bright_Red", ks: 0)),
            ],
        )"#,
    );
    let loaded = load_scene(&scene, &LoadOptions::default()).unwrap();
    let materials: Vec<_> = loaded.scene.objects.iter().map(|o| o.material.unwrap()).collect();
    assert_eq!(materials[0].diffuse, Vec3::new(1.0, 0.0, 0.0));
    assert_eq!(
        materials[0].ambient,
        Vec3::new(0.3, 0.0, 0.0),
        "ka from the default recipe"
    );
    assert_eq!(materials[1].diffuse, Vec3::new(0.0, 0.0, 1.0));
    assert_eq!(materials[2].specular, Vec3::ZERO);
    for file in ["scene.ron", "lib/paints.ron", "lib/base.ron"] {
        assert!(
            loaded.files_read.iter().any(|f| f.ends_with(file)),
            "{file} not recorded"
        );
    }
}

#[test]
fn the_default_camera_frames_every_object() {
    let folder = tempfile::tempdir().unwrap();
    // Objects far from the origin and of very different sizes.
    let scene = write(
        folder.path(),
        "s.ron",
        "(image: (width: 160, height: 100), objects: [
            (mesh: Sphere(), translate: (1000, 20, 5), scale: 3),
            (mesh: Cube, translate: (1010, 20, 5), scale: 0.5),
        ])",
    );
    let image = draw(&load(&scene));
    let (w, h) = (image.width() as usize, image.height() as usize);
    let covered = image.to_coverage().iter().filter(|&&c| c).count();
    assert!(
        covered > w * h / 50,
        "the objects should fill a good part of the frame: {covered}"
    );
    for y in 0..h {
        for x in 0..w {
            if x == 0 || y == 0 || x == w - 1 || y == h - 1 {
                assert!(
                    !image.is_covered(x as u32, y as u32),
                    "({x}, {y}) touches the border: the framing cuts an object"
                );
            }
        }
    }
}

#[test]
fn nine_lights_all_contribute() {
    let folder = tempfile::tempdir().unwrap();
    let scene_with = |n: usize| {
        let lights: Vec<String> = (0..n)
            .map(|_| "Directional(direction: (0, 0, -1), color: (0.1, 0.1, 0.1))".to_string())
            .collect();
        let text = format!(
            "(image: (width: 16, height: 16), ambient: (0, 0, 0),
              camera: Orthographic(eye: (0, 0, 5), target: (0, 0, 0), height: 1),
              lights: [{}],
              objects: [(mesh: Cube, material: (diffuse: (1, 1, 1), model: Lambert))])",
            lights.join(", ")
        );
        draw(&load(&write(folder.path(), &format!("l{n}.ron"), &text))).to_colors()[8 * 16 + 8].x
    };
    let brightness: Vec<f32> = (1..=9).map(scene_with).collect();
    for (n, pair) in brightness.windows(2).enumerate() {
        assert!(
            (pair[1] - pair[0] - 0.1).abs() < 1e-4,
            "light {} adds {}",
            n + 2,
            pair[1] - pair[0]
        );
    }
}

#[test]
fn a_mirrored_object_keeps_its_front_faces() {
    let folder = tempfile::tempdir().unwrap();
    let scene = |scale: &str| {
        let text = format!(
            "(image: (width: 64, height: 64),
              camera: Perspective(eye: (3, 2.5, 4), target: (0, 0, 0)),
              lights: [Directional(direction: (-1, -2, -3))],
              objects: [(mesh: Cube, scale: {scale}, shading: Flat, back_faces: Cull)])"
        );
        draw(&load(&write(folder.path(), "m.ron", &text)))
    };
    let plain = scene("(1, 1, 1)");
    assert!(plain.to_coverage().iter().any(|&c| c));
    for mirror in ["(-1, 1, 1)", "(1, -1, 1)", "(-1, -1, -1)"] {
        assert_eq!(scene(mirror).to_colors(), plain.to_colors(), "scale {mirror}");
    }
}

#[test]
fn the_format_reference_examples_load() {
    let folder = tempfile::tempdir().unwrap();
    // The include example of docs/scene-format.md, verbatim.
    write(
        folder.path(),
        "materials/metals.ron",
        r#"Materials(
    include: ["base.ron"],   // libraries may include libraries
    materials: { "brushed-steel": (base: "chrome", shininess: 20) },
)"#,
    );
    write(folder.path(), "materials/base.ron", "Materials()");
    let scene = write(
        folder.path(),
        "scene.ron",
        r#"Scene(include: ["materials/metals.ron"], objects: [(mesh: Cube, material: "brushed-steel")])"#,
    );
    load(&scene);
    // Every `Scene(`/`(objects:` block of the reference is a complete scene that loads.
    let reference = std::fs::read_to_string(repo().join("docs/scene-format.md")).unwrap();
    let mut complete = 0;
    for block in reference.split("```ron").skip(1) {
        let code = block.split("```").next().unwrap();
        let first_line = code
            .lines()
            .find(|l| !l.trim().is_empty() && !l.trim_start().starts_with("//"))
            .unwrap_or("");
        if first_line.starts_with("Scene(") || first_line.starts_with("(objects") {
            load(&write(folder.path(), "example.ron", code));
            complete += 1;
        }
    }
    assert!(complete >= 1);
}

#[test]
fn every_bundled_scene_loads_without_warnings_except_unsampled_gltf_textures() {
    for scene in crate::ron_files(&repo().join("scenes")) {
        let loaded = load_scene(&scene, &LoadOptions::default()).unwrap();
        for warning in &loaded.warnings {
            assert!(
                warning.message.contains("not sampled yet"),
                "{}: {}",
                scene.display(),
                warning.message
            );
        }
    }
}

/// The benchmark scenes are what `bench` and benches/llvmpipe.py time: a scene that no longer
/// loads (a renamed field, a moved asset) would turn a benchmark row into an error.
#[test]
fn every_bench_scene_loads_without_warnings() {
    let scenes = crate::ron_files(&repo().join("scenes/bench"));
    assert!(scenes.len() >= 20, "{} bench scenes", scenes.len());
    for scene in scenes {
        let loaded = load_scene(&scene, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{}: {e:?}", scene.display()));
        assert!(
            loaded.warnings.is_empty(),
            "{}: {:?}",
            scene.display(),
            loaded.warnings
        );
        assert!(loaded.scene.triangle_count() > 0, "{}", scene.display());
    }
}

/// The mistakes a new user makes, applied to every complete scene of the docs: each must give
/// an error with a location, a hint, and no word of ron's or serde's internals.
#[test]
fn mistakes_made_on_the_docs_examples_give_located_plain_errors_with_hints() {
    let mut examples = Vec::new();
    for doc in ["docs/scene-format.md", "README.md"] {
        let text = std::fs::read_to_string(repo().join(doc)).unwrap();
        for block in text.split("```ron").skip(1) {
            let code = block.split("```").next().unwrap();
            let body = code.trim_start_matches(|c: char| c.is_whitespace());
            let first = body
                .lines()
                .find(|l| !l.trim_start().starts_with("//"))
                .unwrap_or("");
            if first.starts_with("Scene(") || first.starts_with("(objects") {
                examples.push((doc, code.to_owned()));
            }
        }
    }
    assert!(examples.len() >= 2, "the docs have complete scenes");
    // (what the mistake is, the text it changes, what it becomes)
    let mistakes: [(&str, &str, &str); 10] = [
        ("parentheses after a unit variant", "Cube", "Cube()"),
        ("no parentheses after Sphere", "Sphere(segments: 12)", "Sphere"),
        ("no parentheses after Sphere", "Sphere()", "Sphere"),
        ("a positional field", "segments: ", ""),
        ("a quoted variant", "Phong", "\"Phong\""),
        ("a quoted variant", "Flat", "\"Flat\""),
        ("a fraction for an integer", "width: 900", "width: 900.5"),
        ("a vector in brackets", "eye: (0, 0, 9)", "eye: [0, 0, 9]"),
        (
            "an unquoted name",
            "material: \"porcelain\"",
            "material: porcelain",
        ),
        ("a wrong-case variant", "Directional(", "directional("),
    ];
    let mut tried = 0;
    for (doc, full) in &examples {
        // Mistakes are made in the scene, not in the comments before it.
        let scene_start = full
            .split_inclusive('\n')
            .take_while(|line| line.trim().is_empty() || line.trim_start().starts_with("//"))
            .map(str::len)
            .sum();
        let (comments, example) = full.split_at(scene_start);
        let mutations = mistakes
            .iter()
            .filter(|(_, from, _)| example.contains(from))
            .map(|(what, from, to)| (what.to_string(), example.replacen(from, to, 1)))
            .chain([
                ("trailing text".to_owned(), format!("{example})")),
                ("JSON braces".to_owned(), example.replacen("(", "{", 1)),
            ])
            .chain(
                example
                    .contains(',')
                    .then(|| ("a missing comma".to_owned(), example.replacen(",", "", 1))),
            );
        for (what, text) in mutations {
            let text = format!("{comments}{text}");
            tried += 1;
            let error = match load_scene_from_str(Path::new("example.ron"), &text, &LoadOptions::default()) {
                Ok(_) => panic!("{doc}, {what}: loads\n{text}"),
                Err(error) => error,
            };
            let rendered = lampshade::diag::render_diagnostics(&error.diagnostics, &error.sources, false);
            let first = &error.diagnostics[0];
            assert!(first.location.is_some(), "{doc}, {what}: no location\n{rendered}");
            assert!(!first.hints.is_empty(), "{doc}, {what}: no hint\n{rendered}");
            for internal in ["r#", "std identifier", "struct `", "unit value"] {
                assert!(
                    !rendered.contains(internal),
                    "{doc}, {what}: `{internal}` in\n{rendered}"
                );
            }
        }
    }
    assert!(tried >= 15, "only {tried} mistakes tried");
}

#[test]
fn an_empty_scene_file_says_so_and_shows_a_scene() {
    for text in ["", "\n  \n", "// a scene, later\n"] {
        let error = load_scene_from_str(Path::new("empty.ron"), text, &LoadOptions::default())
            .expect_err("an empty file is an error");
        let rendered = lampshade::diag::render_diagnostics(&error.diagnostics, &error.sources, false);
        assert!(rendered.contains("the file "), "{rendered}");
        assert!(rendered.contains("empty.ron:"), "{rendered}");
        assert!(rendered.contains("(objects: [(mesh: Sphere())])"), "{rendered}");
        assert!(!rendered.contains("Scene`"), "{rendered}");
    }
}

/// A scene with one object of mesh file `mesh` (relative to the repository), seen from outside,
/// lit from two sides, with its back faces lit (so that a back face drawn would show).
fn mesh_scene(mesh: &str, eye: &str) -> Scene {
    let text = format!(
        r#"Scene(
            image: (width: 480, height: 360),
            camera: Perspective(eye: {eye}, target: (0, 0, 0), fov: 40),
            lights: [Directional(direction: (-1, -1, -1)), Directional(direction: (1, 0.5, 1), color: (0.4, 0.4, 0.4))],
            objects: [(mesh: Obj("{}"), shading: Phong, back_faces: Lit, material: "brass")],
        )"#,
        repo().join(mesh).display()
    );
    match load_scene_from_str(Path::new("closed.ron"), &text, &LoadOptions::default()) {
        Ok(loaded) => loaded.scene,
        Err(error) => panic!(
            "{}",
            lampshade::diag::render_diagnostics(&error.diagnostics, &error.sources, false)
        ),
    }
}

#[test]
fn closed_mesh_files_are_found_and_culling_their_back_faces_changes_no_pixel() {
    // Spot (the cow) is one closed, outward-wound surface; the teapot has a hole at the spout
    // and a lid apart; the Cornell box is open boxes.
    let spot = mesh_scene("assets/obj/spot/spot_triangulated.obj", "(2.2, 1.2, 3.0)");
    assert!(spot.objects[0].mesh.closed, "spot is closed");
    for open in [
        "assets/obj/teapot/teapot.obj",
        "assets/obj/cornell-box/CornellBox-Original.obj",
    ] {
        let scene = mesh_scene(open, "(0, 3, 9)");
        assert!(!scene.objects[0].mesh.closed, "{open} is open");
    }

    let (culled, culled_stats) = render(&spot, &RenderOptions::default());
    let mut drawn_whole = spot.clone();
    let mut mesh = (*drawn_whole.objects[0].mesh).clone();
    mesh.closed = false;
    drawn_whole.objects[0].mesh = std::sync::Arc::new(mesh);
    let (whole, whole_stats) = render(&drawn_whole, &RenderOptions::default());
    assert!(
        culled_stats.raster_triangles * 10 < whole_stats.raster_triangles * 7,
        "back faces are culled: {} raster triangles against {}",
        culled_stats.raster_triangles,
        whole_stats.raster_triangles
    );
    assert!(
        culled.to_coverage().iter().filter(|&&c| c).count() > 20_000,
        "spot fills the frame"
    );
    assert_eq!(culled.to_coverage(), whole.to_coverage());
    let differing = culled
        .to_colors()
        .iter()
        .zip(&whole.to_colors())
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(differing, 0, "pixels changed by culling");
}
