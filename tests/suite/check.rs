//! `lampshade check` on small suites written into temporary folders: verdicts, exit codes,
//! what `--bless` writes, shards, and the JUnit and HTML outputs.
//!
//! Scenes are 32×24 so that a whole suite renders in milliseconds. Every run sets `CI` (plain
//! lines, no progress bar) and `NO_COLOR`, as CI does.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn lampshade(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lampshade"))
        .args(args)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .env("CI", "true")
        .output()
        .expect("the lampshade binary runs")
}

fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

fn everything(output: &Output) -> String {
    format!(
        "--- stdout\n{}--- stderr\n{}",
        stdout(output),
        String::from_utf8_lossy(&output.stderr)
    )
}

/// A tiny lit sphere of the given colour.
fn sphere(color: &str) -> String {
    format!(
        "(image: (width: 32, height: 24), objects: [(mesh: Sphere(segments: 8), material: (color: {color}))])"
    )
}

/// A temporary suite folder `suite/` with the given scenes (relative path, text).
struct Suite {
    work: tempfile::TempDir,
}

impl Suite {
    fn new(scenes: &[(&str, &str)]) -> Self {
        let suite = Suite {
            work: tempfile::tempdir().expect("a temporary folder"),
        };
        for (path, text) in scenes {
            suite.write(path, text);
        }
        suite
    }

    /// The folder the commands run in; the suite is its `suite/` folder.
    fn dir(&self) -> &Path {
        self.work.path()
    }

    fn path(&self, relative: &str) -> PathBuf {
        self.dir().join("suite").join(relative)
    }

    fn write(&self, relative: &str, text: &str) {
        let path = self.path(relative);
        std::fs::create_dir_all(path.parent().expect("a parent")).expect("folders");
        std::fs::write(path, text).expect("a scene");
    }

    fn check(&self, extra: &[&str]) -> Output {
        let mut args = vec!["check", "suite"];
        args.extend(extra);
        lampshade(&args, self.dir())
    }

    /// Blesses every scene and checks the references exist.
    fn bless_all(&self) {
        let output = self.check(&["--bless"]);
        assert_eq!(output.status.code(), Some(0), "{}", everything(&output));
    }

    fn reference(&self, name: &str) -> PathBuf {
        self.path(&format!("refs/{name}.png"))
    }
}

const RED: &str = "(0.8, 0.2, 0.2)";
const GREEN: &str = "(0.2, 0.8, 0.2)";
const BLUE: &str = "(0.2, 0.2, 0.8)";

fn three_spheres() -> Suite {
    Suite::new(&[
        ("a.ron", &sphere(RED)),
        ("b.ron", &sphere(GREEN)),
        ("c.ron", &sphere(BLUE)),
    ])
}

#[test]
fn an_unchanged_suite_passes() {
    let suite = three_spheres();
    suite.bless_all();
    let output = suite.check(&[]);
    let text = everything(&output);
    assert_eq!(output.status.code(), Some(0), "{text}");
    for scene in ["a", "b", "c"] {
        assert!(text.contains(&format!("ok      suite/{scene}.ron")), "{text}");
    }
    assert!(
        stdout(&output).contains("check: 3 passed, 0 failed, 0 errored — 3 scenes in"),
        "{text}"
    );
}

#[test]
fn a_changed_scene_fails_with_a_useful_line() {
    let suite = three_spheres();
    suite.bless_all();
    suite.write("b.ron", &sphere(BLUE));
    let output = suite.check(&[]);
    let text = everything(&output);
    assert_eq!(output.status.code(), Some(1), "{text}");
    let line = stdout(&output)
        .lines()
        .find(|line| line.starts_with("FAILED"))
        .map(str::to_owned)
        .unwrap_or_else(|| panic!("no FAILED line in\n{text}"));
    for part in [
        "suite/b.ron",
        "% of pixels (",
        "differ by more than 2 levels",
        "within x ",
    ] {
        assert!(line.contains(part), "`{part}` missing from: {line}");
    }
    assert!(
        text.contains("ok      suite/a.ron") && text.contains("ok      suite/c.ron"),
        "{text}"
    );
    assert!(text.contains("check: 2 passed, 1 failed, 0 errored"), "{text}");
    assert!(text.contains("--bless"), "the hint names --bless: {text}");
}

#[test]
fn a_broken_scene_errors_with_2_while_the_others_still_run() {
    let suite = three_spheres();
    suite.bless_all();
    suite.write("broken.ron", "(objects: [(mesh: Cone)])");
    // A mismatch as well: exit code 2 wins over 1.
    suite.write("c.ron", &sphere(RED));
    let output = suite.check(&[]);
    let text = everything(&output);
    assert_eq!(output.status.code(), Some(2), "{text}");
    assert!(text.contains("ERROR   suite/broken.ron"), "{text}");
    assert!(
        text.contains("broken.ron:1:19"),
        "the diagnostic is located: {text}"
    );
    assert!(text.contains("check: 2 passed, 1 failed, 1 errored"), "{text}");
}

#[test]
fn a_missing_reference_fails_and_is_not_written() {
    let suite = three_spheres();
    let output = suite.check(&[]);
    let text = everything(&output);
    assert_eq!(output.status.code(), Some(1), "{text}");
    assert!(text.contains("FAILED  suite/a.ron: no reference image"), "{text}");
    assert!(text.contains("check: 0 passed, 3 failed"), "{text}");
    assert!(!suite.path("refs").exists(), "check must not write references");
}

#[test]
fn bless_writes_only_what_it_rendered() {
    let suite = three_spheres();
    let output = suite.check(&["--bless", "--filter", "b"]);
    let text = everything(&output);
    assert_eq!(output.status.code(), Some(0), "{text}");
    assert!(text.contains("BLESSED suite/b.ron"), "{text}");
    assert!(suite.reference("b").is_file());
    assert!(
        !suite.reference("a").exists() && !suite.reference("c").exists(),
        "{text}"
    );
    let reference = image::open(suite.reference("b")).expect("a PNG").to_rgb8();
    assert_eq!(reference.dimensions(), (32, 24));

    // A broken scene gets no reference; a reference with the same pixels is left alone.
    suite.write("broken.ron", "(objects: [(mesh: Cone)])");
    let before = std::fs::metadata(suite.reference("b"))
        .and_then(|m| m.modified())
        .expect("a time");
    let output = suite.check(&["--bless"]);
    assert_eq!(output.status.code(), Some(2), "{}", everything(&output));
    assert!(!suite.reference("broken").exists());
    assert!(suite.reference("a").is_file() && suite.reference("c").is_file());
    let after = std::fs::metadata(suite.reference("b"))
        .and_then(|m| m.modified())
        .expect("a time");
    assert_eq!(before, after, "an identical reference was rewritten");
    assert!(stdout(&output).contains("2 blessed"), "{}", everything(&output));

    // Within a shard, only the shard's scenes.
    std::fs::remove_dir_all(suite.path("refs")).expect("refs removed");
    std::fs::remove_file(suite.path("broken.ron")).expect("broken scene removed");
    let output = suite.check(&["--bless", "--shard", "1/2"]);
    let blessed: BTreeSet<String> = stdout(&output)
        .lines()
        .filter_map(|line| line.strip_prefix("BLESSED suite/"))
        .filter_map(|rest| rest.split_once(".ron"))
        .map(|(name, _)| name.to_owned())
        .collect();
    let written: BTreeSet<String> = ["a", "b", "c"]
        .into_iter()
        .filter(|name| suite.reference(name).exists())
        .map(str::to_owned)
        .collect();
    assert_eq!(blessed, written, "{}", everything(&output));
}

#[test]
fn shards_cover_every_scene_exactly_once() {
    let names: Vec<String> = (0..9).map(|i| format!("scene-{i}")).collect();
    let scenes: Vec<(String, String)> = names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let folder = if i % 3 == 0 { "nested/" } else { "" };
            (format!("{folder}{name}.ron"), sphere(RED))
        })
        .collect();
    let borrowed: Vec<(&str, &str)> = scenes.iter().map(|(p, t)| (p.as_str(), t.as_str())).collect();
    let suite = Suite::new(&borrowed);
    for count in [1, 2, 3, 4] {
        let mut seen: Vec<String> = Vec::new();
        for index in 1..=count {
            let shard = format!("{index}/{count}");
            // Missing references: every scene that runs fails, with one line naming it.
            let output = suite.check(&["--shard", &shard]);
            let text = everything(&output);
            assert!(matches!(output.status.code(), Some(0 | 1)), "{text}");
            seen.extend(
                stdout(&output)
                    .lines()
                    .filter_map(|line| line.strip_prefix("FAILED  suite/"))
                    .filter_map(|rest| rest.split_once(".ron:"))
                    .map(|(name, _)| name.to_owned()),
            );
        }
        seen.sort();
        let mut expected: Vec<String> = scenes
            .iter()
            .map(|(path, _)| path.trim_end_matches(".ron").to_owned())
            .collect();
        expected.sort();
        assert_eq!(seen, expected, "{count} shards");
    }
}

#[test]
fn junit_output_is_well_formed_with_the_right_counts() {
    let suite = three_spheres();
    suite.bless_all();
    suite.write("b.ron", &sphere(RED));
    // A name that needs escaping, and a broken scene whose diagnostic quotes `<` and `&`.
    suite.write("tom&jerry.ron", &sphere(GREEN));
    suite.write("broken.ron", "(objects: [(mesh: Sphere(), material: \"<&>\")])");
    let output = suite.check(&["--junit", "out/results.xml"]);
    assert_eq!(output.status.code(), Some(2), "{}", everything(&output));
    let xml = std::fs::read_to_string(suite.dir().join("out/results.xml")).expect("the JUnit file");
    let document = roxmltree::Document::parse(&xml).unwrap_or_else(|e| panic!("{e}\n{xml}"));
    let root = document.root_element();
    assert_eq!(root.tag_name().name(), "testsuites");
    // a, b (changed), broken, c, tom&jerry (no reference).
    assert_eq!(root.attribute("tests"), Some("5"), "{xml}");
    assert_eq!(root.attribute("failures"), Some("2"), "{xml}");
    assert_eq!(root.attribute("errors"), Some("1"), "{xml}");
    let cases: Vec<roxmltree::Node> = document
        .descendants()
        .filter(|n| n.has_tag_name("testcase"))
        .collect();
    let names: Vec<&str> = cases.iter().filter_map(|n| n.attribute("name")).collect();
    assert_eq!(names, ["a", "b", "broken", "c", "tom&jerry"]);
    let outcome = |name: &str| {
        let case = cases
            .iter()
            .find(|n| n.attribute("name") == Some(name))
            .expect("the test case");
        case.children()
            .find(|n| n.is_element())
            .map(|n| n.tag_name().name().to_owned())
    };
    assert_eq!(outcome("a"), None);
    assert_eq!(outcome("b").as_deref(), Some("failure"));
    assert_eq!(outcome("broken").as_deref(), Some("error"));
    assert_eq!(outcome("tom&jerry").as_deref(), Some("failure"));
    let error_text = document
        .descendants()
        .find(|n| n.has_tag_name("error"))
        .and_then(|n| n.text())
        .unwrap_or_default();
    assert!(error_text.contains("unknown material `<&>`"), "{error_text}");
}

#[test]
fn the_html_report_lists_failures_first_with_their_pictures() {
    let suite = three_spheres();
    suite.bless_all();
    suite.write("c.ron", &sphere(GREEN));
    let output = suite.check(&["--report", "report"]);
    assert_eq!(output.status.code(), Some(1), "{}", everything(&output));
    let report = suite.dir().join("report");
    let html = std::fs::read_to_string(report.join("index.html")).expect("the report");
    let failed = html.find("suite/c.ron").expect("the failure is listed");
    let passed = html.find("suite/a.ron").expect("the passes are listed");
    assert!(failed < passed, "failures come first");
    let sources: Vec<&str> = html
        .split("<img src=\"")
        .skip(1)
        .filter_map(|rest| rest.split_once('"'))
        .map(|(source, _)| source)
        .collect();
    assert_eq!(sources.len(), 3, "expected, actual, difference: {sources:?}");
    for source in sources {
        let picture = image::open(report.join(source)).expect("a picture the report shows");
        assert_eq!(picture.width(), 32);
    }
}

#[test]
fn a_suite_config_sets_tolerances_per_scene() {
    let suite = three_spheres();
    suite.bless_all();
    suite.write("b.ron", &sphere(BLUE));
    suite.write(
        "lampshade-check.ron",
        "(scenes: { \"b\": (max_differing_share: 1.0) })",
    );
    let output = suite.check(&[]);
    assert_eq!(output.status.code(), Some(0), "{}", everything(&output));

    suite.write(
        "lampshade-check.ron",
        "(scenes: {\n  \"b\": (max_differing_shar: 1.0),\n})",
    );
    let output = suite.check(&[]);
    let text = everything(&output);
    assert_eq!(output.status.code(), Some(2), "{text}");
    assert!(text.contains("lampshade-check.ron:2:9"), "{text}");
    assert!(text.contains("no scene was checked"), "{text}");
}

#[test]
fn material_libraries_and_references_are_not_scenes() {
    let suite = Suite::new(&[
        (
            "a.ron",
            "(include: [\"lib/paint.ron\"], image: (width: 32, height: 24), objects: [(mesh: Cube, material: \"paint\")])",
        ),
        (
            "lib/paint.ron",
            "// shared\nMaterials(materials: { \"paint\": (color: (0.9, 0.5, 0.1)) })",
        ),
    ]);
    suite.bless_all();
    let output = suite.check(&[]);
    let text = everything(&output);
    assert_eq!(output.status.code(), Some(0), "{text}");
    assert!(
        text.contains("check: 1 passed, 0 failed, 0 errored — 1 scene in"),
        "{text}"
    );
}

#[test]
fn fail_fast_stops_starting_scenes() {
    let suite = three_spheres();
    // `a` has no reference; with one worker the scenes run in order, so b and c never start.
    let output = suite.check(&["--fail-fast", "--jobs", "1"]);
    let text = everything(&output);
    assert_eq!(output.status.code(), Some(1), "{text}");
    assert!(
        text.contains("0 passed, 1 failed, 0 errored, 2 not run"),
        "{text}"
    );
}

#[test]
fn arguments_that_select_nothing_are_errors() {
    let suite = three_spheres();
    let output = suite.check(&["--filter", "nothing-like-this"]);
    assert_eq!(output.status.code(), Some(2), "{}", everything(&output));
    let output = lampshade(&["check", "no-such-folder"], suite.dir());
    assert_eq!(output.status.code(), Some(2), "{}", everything(&output));
    assert!(everything(&output).contains("no such file or folder"));
    let output = suite.check(&["--shard", "3/2"]);
    assert_eq!(output.status.code(), Some(2), "{}", everything(&output));
}
