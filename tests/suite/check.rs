//! `lampshade check` on small suites written into temporary folders: verdicts, exit codes,
//! what `--bless` writes, shards, and the JUnit and HTML outputs.
//!
//! Scenes are 32×24 so that a whole suite renders in milliseconds. Every run sets `CI` (plain
//! lines, no progress bar) and `NO_COLOR`, as CI does.

use crate::process::{everything, lampshade, stdout};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A tiny lit sphere of the given colour.
pub(crate) fn sphere(color: &str) -> String {
    format!(
        "(image: (width: 32, height: 24), objects: [(mesh: Sphere(segments: 8), material: (color: {color}))])"
    )
}

/// A temporary suite folder `suite/` with the given scenes (relative path, text).
pub(crate) struct Suite {
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
    pub(crate) fn dir(&self) -> &Path {
        self.work.path()
    }

    fn path(&self, relative: &str) -> PathBuf {
        self.dir().join("suite").join(relative)
    }

    pub(crate) fn write(&self, relative: &str, text: &str) {
        let path = self.path(relative);
        std::fs::create_dir_all(path.parent().expect("a parent")).expect("folders");
        std::fs::write(path, text).expect("a scene");
    }

    pub(crate) fn check(&self, extra: &[&str]) -> Output {
        let mut args = vec!["check", "suite"];
        args.extend(extra);
        lampshade(&args, self.dir())
    }

    /// Blesses every scene and checks the references exist.
    pub(crate) fn bless_all(&self) {
        let output = self.check(&["--bless"]);
        assert_eq!(output.status.code(), Some(0), "{}", everything(&output));
    }

    pub(crate) fn reference(&self, name: &str) -> PathBuf {
        self.path(&format!("refs/{name}.png"))
    }
}

const RED: &str = "(0.8, 0.2, 0.2)";
pub(crate) const GREEN: &str = "(0.2, 0.8, 0.2)";
const BLUE: &str = "(0.2, 0.2, 0.8)";

pub(crate) fn three_spheres() -> Suite {
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
    // Failure texts are for people: the limits in words, no Rust `Debug` output.
    let failure_text = document
        .descendants()
        .find(|n| n.has_tag_name("failure"))
        .and_then(|n| n.text())
        .unwrap_or_default();
    assert!(
        failure_text.contains("tolerance: a pixel differs when a channel is more than 2 levels off"),
        "{failure_text}"
    );
    for failure in document.descendants().filter(|n| n.has_tag_name("failure")) {
        let text = format!(
            "{} {}",
            failure.attribute("message").unwrap_or_default(),
            failure.text().unwrap_or_default()
        );
        for debug in ["Tolerance", "{", "max_channel_difference", "Some("] {
            assert!(!text.contains(debug), "`{debug}` in\n{text}");
        }
    }
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
    // One self-contained file: every picture is embedded.
    for source in sources {
        let base64 = source
            .strip_prefix("data:image/png;base64,")
            .unwrap_or_else(|| panic!("not an embedded PNG: {}", &source[..source.len().min(80)]));
        let png = crate::browser::decode_base64(base64).expect("base64");
        let picture = image::load_from_memory(&png).expect("a picture the report shows");
        assert_eq!(picture.width(), 32);
    }
    for external in ["<script src", "<link", "http://", "https://"] {
        assert!(!html.contains(external), "the report loads `{external}`");
    }
    // The pictures are written beside it too, and linked.
    let links: Vec<&str> = html
        .split("<a href=\"images/")
        .skip(1)
        .filter_map(|rest| rest.split_once('"'))
        .map(|(file, _)| file)
        .collect();
    assert_eq!(links.len(), 3, "{links:?}");
    for file in links {
        assert!(report.join("images").join(file).is_file(), "{file}");
    }
    // The summary table lists every scene, the failure first, with the filters above it.
    let table = &html[html.find("<table id=\"scenes\">").expect("the summary table")..];
    let table = &table[..table.find("</table>").unwrap()];
    let rows: Vec<&str> = table.split("<tr class=").skip(1).collect();
    assert_eq!(rows.len(), 3, "{table}");
    assert!(
        rows[0].contains("data-verdict=\"failed\"") && rows[0].contains("suite/c.ron"),
        "{table}"
    );
    assert!(html.contains("id=\"name-filter\""), "the name filter");
    assert!(
        html.contains("value=\"passed\" checked> passed (2)"),
        "the verdict filter"
    );
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

#[test]
fn ctrl_c_reports_the_scenes_that_finished_and_exits_130() {
    use std::io::BufRead as _;
    // `a` is tiny; each slow scene takes a second or more, so the interrupt lands while the
    // first of them runs (one worker: scenes start in suite order).
    let slow = "(image: (width: 4000, height: 4000, samples: 16), objects: [(mesh: Sphere(segments: 400))])";
    let suite = Suite::new(&[
        ("a.ron", &sphere(RED)),
        ("slow-1.ron", slow),
        ("slow-2.ron", slow),
        ("slow-3.ron", slow),
    ]);
    let mut child = Command::new(env!("CARGO_BIN_EXE_lampshade"))
        .args([
            "check",
            "suite",
            "--jobs",
            "1",
            "--junit",
            "out/results.xml",
            "--report",
            "report",
        ])
        .current_dir(suite.dir())
        .env("NO_COLOR", "1")
        .env("CI", "true")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the lampshade binary runs");
    let mut lines = std::io::BufReader::new(child.stdout.take().expect("stdout")).lines();
    let mut printed = String::new();
    for line in lines.by_ref() {
        let line = line.expect("a line");
        printed.push_str(&line);
        printed.push('\n');
        if line.starts_with("FAILED  suite/a.ron") {
            break;
        }
    }
    assert!(printed.contains("suite/a.ron"), "{printed}");
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(killed.success());
    for line in lines {
        printed.push_str(&line.expect("a line"));
        printed.push('\n');
    }
    let output = child.wait_with_output().expect("the run ends");
    let errors = String::from_utf8_lossy(&output.stderr);
    let text = format!("--- stdout\n{printed}--- stderr\n{errors}");
    assert_eq!(output.status.code(), Some(130), "{text}");
    assert!(
        printed.contains("check: 0 passed, 1 failed, 0 errored, 3 not run (interrupted)"),
        "{text}"
    );
    assert!(
        errors.contains("interrupted: kept the results of the 1 scene that finished in the JUnit file"),
        "{text}"
    );

    let xml = std::fs::read_to_string(suite.dir().join("out/results.xml")).expect("the JUnit file");
    let document = roxmltree::Document::parse(&xml).unwrap_or_else(|e| panic!("{e}\n{xml}"));
    let outcome = |name: &str| {
        let case = document
            .descendants()
            .find(|n| n.has_tag_name("testcase") && n.attribute("name") == Some(name))
            .unwrap_or_else(|| panic!("no test case {name} in\n{xml}"));
        let element = case.children().find(|n| n.is_element()).expect("an outcome");
        (
            element.tag_name().name().to_owned(),
            element.attribute("message").unwrap_or_default().to_owned(),
        )
    };
    assert_eq!(outcome("a").0, "failure", "{xml}");
    // The scene under way when Ctrl-C came was not waited for.
    for name in ["slow-1", "slow-2", "slow-3"] {
        let (element, message) = outcome(name);
        assert_eq!(element, "skipped", "{xml}");
        assert!(message.contains("interrupted"), "{xml}");
    }
    let html = std::fs::read_to_string(suite.dir().join("report/index.html")).expect("the report");
    assert!(
        html.contains("suite/a.ron") && html.contains("interrupted"),
        "{html}"
    );
}

#[test]
fn a_report_holds_one_run_and_keeps_other_files() {
    let suite = three_spheres();
    suite.bless_all();
    let images = suite.dir().join("report/images");
    std::fs::create_dir_all(&images).expect("the images folder");
    std::fs::write(images.join("notes.txt"), "mine").expect("a file of the user's");
    let pictures = || -> BTreeSet<String> {
        std::fs::read_dir(&images)
            .expect("the images folder")
            .map(|entry| {
                entry
                    .expect("an entry")
                    .file_name()
                    .to_string_lossy()
                    .into_owned()
            })
            .collect()
    };
    let changed_scene = |name: &str| {
        pictures()
            .iter()
            .filter(|file| file.ends_with("-actual.png"))
            .map(|file| file.contains(&format!("-{name}-")))
            .collect::<Vec<bool>>()
    };

    suite.write("c.ron", &sphere(GREEN));
    let output = suite.check(&["--report", "report"]);
    assert_eq!(output.status.code(), Some(1), "{}", everything(&output));
    assert_eq!(changed_scene("c"), [true], "{:?}", pictures());

    // The next run fails on b only: c's pictures are gone, the user's file stays.
    suite.write("c.ron", &sphere(BLUE));
    suite.write("b.ron", &sphere(RED));
    let output = suite.check(&["--report", "report"]);
    assert_eq!(output.status.code(), Some(1), "{}", everything(&output));
    assert_eq!(changed_scene("b"), [true], "{:?}", pictures());
    assert!(
        pictures().iter().all(|file| !file.contains("-c-")),
        "{:?}",
        pictures()
    );
    assert!(pictures().contains("notes.txt"), "{:?}", pictures());

    // A passing run leaves no pictures at all.
    suite.write("b.ron", &sphere(GREEN));
    let output = suite.check(&["--report", "report"]);
    assert_eq!(output.status.code(), Some(0), "{}", everything(&output));
    assert_eq!(pictures(), BTreeSet::from(["notes.txt".to_owned()]));
}

#[test]
fn an_empty_suite_config_keeps_the_defaults_and_a_wrong_one_says_what_it_may_hold() {
    let suite = three_spheres();
    suite.bless_all();
    for empty in ["", "\n  // nothing to change yet\n"] {
        suite.write("lampshade-check.ron", empty);
        let output = suite.check(&[]);
        assert_eq!(output.status.code(), Some(0), "{}", everything(&output));
    }
    suite.write("lampshade-check.ron", "[]");
    let output = suite.check(&[]);
    let text = everything(&output);
    assert_eq!(output.status.code(), Some(2), "{text}");
    assert!(text.contains("lampshade-check.ron:1:1"), "{text}");
    assert!(
        text.contains("help: a `lampshade-check.ron` holds `(tolerance:"),
        "{text}"
    );
    assert!(!text.contains("Suite") && !text.contains("struct"), "{text}");
}

#[test]
fn the_bundled_suite_is_checked_exactly_with_its_subfolders() {
    let scenes = lampshade::check::suite::discover(&[crate::repo().join("scenes")]).expect("the suite reads");
    for folder in ["hard", "bench"] {
        assert!(
            scenes
                .iter()
                .any(|scene| scene.name.starts_with(&format!("{folder}/"))),
            "scenes/{folder}/ is not part of the bundled suite"
        );
    }
    for scene in scenes {
        assert_eq!(
            (
                scene.tolerance.max_channel_difference,
                scene.tolerance.max_differing_share
            ),
            (0, 0.0),
            "{} is not checked exactly",
            scene.path.display()
        );
    }
}
