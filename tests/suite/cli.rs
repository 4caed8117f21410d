//! The `lampshade` binary: exit codes, diagnostics with file:line:column, and outputs that are
//! written whole or not at all.
//!
//! `tests/bad-scenes/*.ron` and `tests/bad-scenes/sandbox/*.ron` are data: each starts with
//! comment lines
//! - `// expect: LINE:COLUMN message fragment` (or `// expect: message fragment` when there is
//!   no location): stderr must contain `NAME.ron:LINE:COLUMN` and the fragment;
//! - `// args: ...`: extra command-line arguments (`--sandbox sandbox`, `--max-memory 64M`);
//! - `// exit: N`: the expected exit code, 2 when absent. With 2 no image may be written; with
//!   0 (a warning and a documented fallback) the image must be written.
//!
//! Rendering never panics, whatever the input.

use crate::process::{lampshade, stderr};
use crate::{repo, ron_files};

#[test]
fn every_bad_scene_fails_with_its_expected_diagnostics_and_writes_nothing() {
    let bad = repo().join("tests/bad-scenes");
    let mut scenes = ron_files(&bad);
    scenes.extend(ron_files(&bad.join("sandbox")));
    assert!(scenes.len() >= 60, "the corpus must not be empty");
    let work = tempfile::tempdir().unwrap();
    // Every scene is run and every problem collected, so one run shows them all.
    let mut failures: Vec<String> = Vec::new();
    let mut check = |ok: bool, failure: String| {
        if !ok {
            failures.push(failure);
        }
    };
    for scene in scenes {
        let relative = scene.strip_prefix(&bad).unwrap().to_str().unwrap().to_string();
        let name = scene.file_name().unwrap().to_str().unwrap();
        let text = String::from_utf8_lossy(&std::fs::read(&scene).unwrap()).into_owned();
        let directive = |prefix: &str| -> Vec<String> {
            text.lines()
                .filter_map(|l| l.strip_prefix(prefix))
                .map(str::to_string)
                .collect()
        };
        let expectations = directive("// expect: ");
        assert!(!expectations.is_empty(), "{relative} has no `// expect:` line");
        let extra_args: Vec<String> = directive("// args: ")
            .iter()
            .flat_map(|a| a.split_whitespace().map(str::to_string).collect::<Vec<_>>())
            .collect();
        let expected_exit: i32 = directive("// exit: ")
            .first()
            .map_or(2, |code| code.trim().parse().unwrap());

        // Render in place (meshes and includes are relative to it), the image into a scratch folder.
        let image = work.path().join(name).with_extension("png");
        let mut args = vec!["render", relative.as_str(), "-o", image.to_str().unwrap()];
        args.extend(extra_args.iter().map(String::as_str));
        let output = lampshade(&args, &bad);
        // Diagnostics go to stderr; the summary line of a scene that rendered, to stdout.
        let message = stderr(&output) + &String::from_utf8_lossy(&output.stdout);
        check(
            output.status.code() == Some(expected_exit),
            format!(
                "{relative}: exit code {:?}, expected {expected_exit}\n{message}",
                output.status.code()
            ),
        );
        for expectation in &expectations {
            let (location, fragment) = match expectation.split_once(' ') {
                Some((loc, rest)) if loc.contains(':') && loc.starts_with(|c: char| c.is_ascii_digit()) => {
                    (Some(format!("{name}:{loc}")), rest)
                }
                _ => (None, expectation.as_str()),
            };
            if let Some(location) = location {
                check(
                    message.contains(&location),
                    format!("{relative}: expected `{location}` in\n{message}"),
                );
            }
            check(
                message.contains(fragment),
                format!("{relative}: expected `{fragment}` in\n{message}"),
            );
        }
        check(
            !message.contains("panicked"),
            format!("{relative}: panicked\n{message}"),
        );
        check(
            image.exists() == (expected_exit == 0),
            format!("{relative}: an image must be written if and only if the scene renders"),
        );
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn a_failed_render_keeps_the_previous_image() {
    let work = tempfile::tempdir().unwrap();
    let scene = work.path().join("scene.ron");
    let image = work.path().join("scene.png");
    std::fs::write(&image, b"previous good image").unwrap();
    std::fs::write(&scene, "(objects: [(mesh: Sphere(), material: \"nope\")])").unwrap();
    let output = lampshade(&["render", "scene.ron"], work.path());
    assert_eq!(output.status.code(), Some(2));
    assert_eq!(std::fs::read(&image).unwrap(), b"previous good image");
}

#[test]
fn several_scenes_render_past_a_bad_one_and_exit_2() {
    let work = tempfile::tempdir().unwrap();
    std::fs::write(
        work.path().join("a.ron"),
        "(image: (width: 32, height: 24), objects: [(mesh: Cube)])",
    )
    .unwrap();
    std::fs::write(work.path().join("b.ron"), "(objects: [(mesh: Cone)])").unwrap();
    std::fs::write(
        work.path().join("c.ron"),
        "(image: (width: 32, height: 24), objects: [(mesh: Sphere())])",
    )
    .unwrap();
    let output = lampshade(&["render", "a.ron", "b.ron", "c.ron"], work.path());
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(work.path().join("a.png").exists() && work.path().join("c.png").exists());
    assert!(!work.path().join("b.png").exists());
    assert!(stderr(&output).contains("b.ron:1:19"), "{}", stderr(&output));
    // All the errors again at the end, after the scenes that rendered.
    let summary = stderr(&output);
    let last_line = summary.lines().last().unwrap_or_default();
    assert_eq!(
        last_line, "error: 1 of 3 scenes could not be rendered: b.ron",
        "{summary}"
    );
}

#[test]
fn render_writes_the_image_and_a_summary_line() {
    let work = tempfile::tempdir().unwrap();
    std::fs::write(
        work.path().join("s.ron"),
        "(image: (width: 40, height: 30), objects: [(mesh: Sphere(segments: 8))])",
    )
    .unwrap();
    let output = lampshade(&["render", "s.ron", "-o", "out.png"], work.path());
    assert!(output.status.success(), "{}", stderr(&output));
    let summary = String::from_utf8_lossy(&output.stdout);
    for part in [
        "128 triangles",
        "40×30 px",
        "load",
        "geometry",
        "raster+shade",
        "encode",
    ] {
        assert!(summary.contains(part), "summary lacks `{part}`: {summary}");
    }
    let image = image::open(work.path().join("out.png")).unwrap().to_rgb8();
    assert_eq!(image.dimensions(), (40, 30));
    assert!(
        image.pixels().any(|p| p.0 != [0, 0, 0]),
        "the sphere must be visible"
    );
}

#[test]
fn thread_count_does_not_change_a_byte() {
    let scene = repo().join("scenes/opengl-materials.ron");
    let work = tempfile::tempdir().unwrap();
    let mut images = Vec::new();
    for threads in ["1", "2", "5"] {
        let out = work.path().join(format!("t{threads}.png"));
        let output = lampshade(
            &[
                "render",
                scene.to_str().unwrap(),
                "--threads",
                threads,
                "--width",
                "200",
                "--height",
                "150",
                "-o",
                out.to_str().unwrap(),
            ],
            work.path(),
        );
        assert!(output.status.success(), "{}", stderr(&output));
        images.push(image::open(&out).unwrap().to_rgb8().into_raw());
    }
    assert!(images.windows(2).all(|pair| pair[0] == pair[1]));
}

#[test]
fn debug_views_show_the_separate_terms() {
    let work = tempfile::tempdir().unwrap();
    let scene = work.path().join("s.ron");
    std::fs::write(
        &scene,
        "(image: (width: 48, height: 48), ambient: (1, 1, 1),
          camera: Perspective(eye: (0, 0, 4), target: (0, 0, 0)),
          lights: [Directional(direction: (0, 0, -1))],
          objects: [(mesh: Sphere(segments: 96), rotate: (90, 0, 0), material: (ambient: (0.2, 0, 0), diffuse: (0, 0.5, 0), specular: (0, 0, 0.5), shininess: 1))])",
    )
    .unwrap();
    let center = |view: &str| {
        let out = format!("{view}.png");
        let output = lampshade(&["render", "s.ron", "--debug", view, "-o", &out], work.path());
        assert!(output.status.success(), "{}", stderr(&output));
        image::open(work.path().join(out))
            .unwrap()
            .to_rgb8()
            .get_pixel(24, 24)
            .0
    };
    // Near the centre N ≈ L ≈ V: diffuse 0.5, specular 0.5, ambient 0.2 (the pixel centre sits
    // half a pixel off the axis, hence the tolerance).
    let close = |got: [u8; 3], expected: [u8; 3]| {
        assert!(
            got.iter().zip(expected).all(|(g, e)| g.abs_diff(e) <= 2),
            "got {got:?}, expected {expected:?}"
        )
    };
    close(center("ambient"), [51, 0, 0]);
    close(center("diffuse"), [0, 128, 0]);
    close(center("specular"), [0, 0, 128]);
    let normal = center("normals");
    assert!(
        normal[2] > 250 && (120..=136).contains(&normal[0]) && (120..=136).contains(&normal[1]),
        "{normal:?}"
    );
    assert_eq!(center("depth"), [255, 255, 255]);
}

#[test]
fn bad_arguments_exit_2() {
    let work = tempfile::tempdir().unwrap();
    assert_eq!(lampshade(&["render"], work.path()).status.code(), Some(2));
    assert_eq!(
        lampshade(&["render", "a.ron", "b.ron", "-o", "x.png"], work.path())
            .status
            .code(),
        Some(2)
    );
    assert_eq!(
        lampshade(&["render", "missing.ron"], work.path()).status.code(),
        Some(2)
    );
    let output = lampshade(&["render", "x.ron", "--width", "0"], work.path());
    assert_eq!(output.status.code(), Some(2));
}

#[test]
fn an_unwritable_output_exits_1() {
    let work = tempfile::tempdir().unwrap();
    std::fs::write(
        work.path().join("s.ron"),
        "(image: (width: 8, height: 8), objects: [(mesh: Cube)])",
    )
    .unwrap();
    let output = lampshade(&["render", "s.ron", "-o", "no/such/folder/out.png"], work.path());
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(stderr(&output).contains("out.png"));
}

/// `render --reference` writes the exact image through the same output path, with shadows;
/// mesh files are ray-cast as their triangles; `--reference=mesh` ray-casts the primitives'
/// tessellation; `--reference-samples` needs `--reference` and a count in 1..=64.
#[test]
fn render_reference_writes_the_exact_image_of_any_scene() {
    let work = tempfile::tempdir().unwrap();
    std::fs::write(
        work.path().join("s.ron"),
        "(image: (width: 40, height: 30), \
         lights: [Directional(direction: (0, 0, -1), shadows: true)], \
         objects: [(mesh: Sphere(segments: 8))])",
    )
    .unwrap();
    let output = lampshade(
        &["render", "--reference", "s.ron", "-o", "exact.png"],
        work.path(),
    );
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(!stderr(&output).contains("warning"), "{}", stderr(&output));
    let exact = image::open(work.path().join("exact.png")).unwrap().to_rgb8();
    let output = lampshade(&["render", "s.ron", "-o", "raster.png"], work.path());
    assert!(output.status.success(), "{}", stderr(&output));
    let raster = image::open(work.path().join("raster.png")).unwrap().to_rgb8();
    let output = lampshade(
        &["render", "--reference=mesh", "s.ron", "-o", "mesh.png"],
        work.path(),
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let mesh = image::open(work.path().join("mesh.png")).unwrap().to_rgb8();
    assert_eq!(exact.dimensions(), (40, 30));
    // Sphere(8) is coarse: the exact silhouette is round, the raster one (and the ray-cast
    // tessellation's) a polygon inside it.
    let covered = |image: &image::RgbImage| image.pixels().filter(|p| p.0 != [0, 0, 0]).count();
    assert!(
        covered(&exact) > covered(&raster) && covered(&mesh) == covered(&raster),
        "{} {} {}",
        covered(&exact),
        covered(&raster),
        covered(&mesh)
    );

    std::fs::write(
        work.path().join("mesh.ron"),
        "(objects: [\n    (name: \"tri\", mesh: Obj(\"tri.obj\")),\n])",
    )
    .unwrap();
    std::fs::write(
        work.path().join("tri.obj"),
        "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let output = lampshade(
        &["render", "--reference", "--reference-samples", "4", "mesh.ron"],
        work.path(),
    );
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(work.path().join("mesh.png").is_file());
    for bad in [
        &["render", "--reference-samples", "4", "mesh.ron"][..],
        &["render", "--reference", "--reference-samples", "0", "mesh.ron"],
        &["render", "--reference=triangles", "mesh.ron"],
    ] {
        let output = lampshade(bad, work.path());
        assert_eq!(output.status.code(), Some(2), "{bad:?}: {}", stderr(&output));
    }
}

/// `report speed-error --quick` writes its table, CSV and well-formed SVG plots; a scene with no
/// sphere to sweep gets the knob sweep.
#[test]
fn report_speed_error_writes_its_table_and_plots() {
    let work = tempfile::tempdir().unwrap();
    let scene = repo().join("scenes/matlab-shiny.ron");
    let scene = scene.to_str().unwrap();
    let output = lampshade(
        &[
            "report",
            "speed-error",
            "--quick",
            "--scene",
            scene,
            "--out",
            "out",
        ],
        work.path(),
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let out = work.path().join("out");
    let csv = std::fs::read_to_string(out.join("speed-error.csv")).unwrap();
    // A header, then per shininess (5 and 50) two reference rows and 4 modes × 2 tessellations.
    assert_eq!(csv.lines().count(), 1 + 2 * (2 + 4 * 2), "{csv}");
    let table = std::fs::read_to_string(out.join("speed-error.md")).unwrap();
    assert!(
        table.contains("## Shininess 50, 1 sample(s) per pixel"),
        "{table}"
    );
    for plot in ["speed-error-s5-x1.svg", "speed-error-s50-x1.svg"] {
        let svg = std::fs::read_to_string(out.join(plot)).unwrap();
        roxmltree::Document::parse(&svg).unwrap_or_else(|e| panic!("{plot}: {e}"));
    }

    std::fs::write(work.path().join("cube.ron"), "(objects: [(mesh: Cube)])").unwrap();
    let output = lampshade(
        &[
            "report",
            "speed-error",
            "--quick",
            "--scene",
            "cube.ron",
            "--out",
            "cube",
            "--maps",
            "cube/maps",
        ],
        work.path(),
    );
    // No sphere to vary: the knobs the scene uses are swept instead.
    assert!(output.status.success(), "{}", stderr(&output));
    let table = std::fs::read_to_string(work.path().join("cube/knobs.md")).unwrap();
    assert!(
        table.contains("samples per pixel") && table.contains("(scene)"),
        "{table}"
    );
    let csv = std::fs::read_to_string(work.path().join("cube/knobs.csv")).unwrap();
    // A heat map per point, the quick sweep's 160×120 image over its 30-pixel legend, linked
    // from the table.
    let maps: Vec<_> = std::fs::read_dir(work.path().join("cube/maps"))
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .collect();
    assert_eq!(maps.len(), csv.lines().count() - 1, "{maps:?}");
    for map in &maps {
        let name = map.file_name().unwrap().to_str().unwrap();
        assert!(
            table.contains(&format!("(maps/{name})")),
            "{name} not listed:\n{table}"
        );
        assert_eq!(image::image_dimensions(map).unwrap(), (160, 150), "{name}");
    }
    assert!(table.contains("[map](maps/samples-per-pixel-1.png)"), "{table}");
    // The plot of time against FLIP p99, with its Pareto front.
    let svg = std::fs::read_to_string(work.path().join("cube/knobs-flip-p99.svg")).unwrap();
    roxmltree::Document::parse(&svg).unwrap();
    assert!(svg.contains("Pareto front"));
}

/// `report accuracy` prints the anchor's table: four modes, Phong the most accurate.
#[test]
fn report_accuracy_prints_the_anchor_table() {
    let scene = repo().join("scenes/matlab-shiny.ron");
    let output = lampshade(
        &[
            "report",
            "accuracy",
            "--scene",
            scene.to_str().unwrap(),
            "--width",
            "160",
            "--height",
            "120",
        ],
        repo(),
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let table = String::from_utf8_lossy(&output.stdout).into_owned();
    let mean_of = |row: &str| -> f64 {
        let line = table
            .lines()
            .find(|l| l.starts_with(&format!("| {row}")))
            .unwrap();
        line.split('|').nth(2).unwrap().trim().parse().unwrap()
    };
    assert!(mean_of("phong") < mean_of("gouraud"), "{table}");
    assert!(mean_of("gouraud") < mean_of("flat"), "{table}");
}

#[test]
fn a_mesh_that_cannot_load_is_one_diagnostic() {
    // Every corpus scene whose mesh file fails: one `error` block, which names the mesh file
    // and points at the object (not one block for the file and another for the object).
    let bad = repo().join("tests/bad-scenes");
    let scenes: Vec<_> = ron_files(&bad)
        .into_iter()
        .filter(|scene| {
            std::fs::read_to_string(scene).is_ok_and(|text| {
                text.lines()
                    .any(|l| l.starts_with("// expect: ") && l.ends_with("this mesh could not be loaded"))
            })
        })
        .collect();
    assert!(scenes.len() >= 10, "{} scenes", scenes.len());
    let work = tempfile::tempdir().unwrap();
    for scene in scenes {
        let name = scene.file_name().unwrap().to_str().unwrap();
        let image = work.path().join("out.png");
        let output = lampshade(&["render", name, "-o", image.to_str().unwrap()], &bad);
        let errors = stderr(&output).lines().filter(|l| l.starts_with("error")).count();
        assert_eq!(errors, 1, "{name}:\n{}", stderr(&output));
    }
}
