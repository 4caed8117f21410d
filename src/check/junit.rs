//! `--junit FILE`: the results as JUnit XML, the format CI systems (GitHub Actions reporters,
//! GitLab, Jenkins, Buildkite) read and merge across jobs.
//!
//! One `<testsuite>` per folder named on the command line, one `<testcase>` per scene that
//! was selected (`name` = the scene name, `classname` = the suite folder, `file` = the scene
//! file). A mismatch or missing reference is a `<failure>`, a scene that could not be
//! rendered an `<error>` with its diagnostics, a scene `--fail-fast` or Ctrl-C kept from running
//! (or finishing) `<skipped>`.
//! Shards write separate files with disjoint test cases, which CI systems merge as usual.
//!
//! Written by hand: the format is a few elements, and the only subtlety is escaping
//! ([`escape`]). Rejected: an XML crate (`quick-xml`) for a dozen lines of output.

use std::fmt::Write as _;
use std::time::Duration;

use crate::check::escape;
use crate::check::runner::{SceneError, SceneResult, SceneStatus, Tally};
use crate::check::suite::SuiteScene;
use crate::diag::render_diagnostics;

/// The JUnit XML document for `results` (one per scene, in `scenes` order).
pub fn junit_xml(scenes: &[SuiteScene], results: &[SceneResult], title: &str, elapsed: Duration) -> String {
    let all = Tally::of(results);
    let mut xml = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        xml,
        "<testsuites name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"{}\" skipped=\"{}\" time=\"{:.3}\">",
        escape::attribute(title),
        results.len(),
        all.failed,
        all.errored,
        all.not_run,
        elapsed.as_secs_f64()
    );
    // Suite folders in order of their first scene.
    let mut suites: Vec<&std::path::Path> = Vec::new();
    for scene in scenes {
        if !suites.contains(&scene.suite.as_path()) {
            suites.push(&scene.suite);
        }
    }
    for suite in suites {
        let members: Vec<(&SuiteScene, &SceneResult)> = scenes
            .iter()
            .zip(results)
            .filter(|(scene, _)| scene.suite == suite)
            .collect();
        let tally = Tally::of(members.iter().map(|(_, result)| *result));
        let time: Duration = members.iter().map(|(_, result)| result.times.total()).sum();
        let suite_name = suite.display().to_string();
        let _ = writeln!(
            xml,
            "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"{}\" skipped=\"{}\" time=\"{:.3}\">",
            escape::attribute(&suite_name),
            members.len(),
            tally.failed,
            tally.errored,
            tally.not_run,
            time.as_secs_f64()
        );
        for (scene, result) in members {
            write_test_case(&mut xml, scene, result, &suite_name);
        }
        xml.push_str("  </testsuite>\n");
    }
    xml.push_str("</testsuites>\n");
    xml
}

fn write_test_case(xml: &mut String, scene: &SuiteScene, result: &SceneResult, suite_name: &str) {
    let _ = write!(
        xml,
        "    <testcase name=\"{}\" classname=\"{}\" file=\"{}\" time=\"{:.3}\"",
        escape::attribute(&scene.name),
        escape::attribute(suite_name),
        escape::attribute(&scene.path.display().to_string()),
        result.times.total().as_secs_f64()
    );
    let (element, message, body) = match &result.status {
        SceneStatus::Passed(_) => {
            xml.push_str("/>\n");
            return;
        }
        SceneStatus::Blessed(reason) => (
            "system-out",
            None,
            format!("blessed {}: {reason}", scene.reference.display()),
        ),
        SceneStatus::NotRun(reason) => (
            "skipped",
            Some(format!("not run: {}", reason.describe())),
            String::new(),
        ),
        SceneStatus::Failed(failure) => {
            let message = failure.describe(scene);
            // FLIP's limits matter only where FLIP was computed (`--flip`).
            let flip = result.comparison().is_some_and(|c| c.flip.is_some());
            let body = format!(
                "{message}\nscene: {}\nreference: {}\ntolerance: {}",
                scene.path.display(),
                scene.reference.display(),
                scene.tolerance.describe(flip)
            );
            ("failure", Some(message), body)
        }
        SceneStatus::Errored(error) => {
            let body = match error {
                SceneError::Load(load) => render_diagnostics(&load.diagnostics, &load.sources, false),
                _ => error.describe(),
            };
            ("error", Some(error.describe()), body)
        }
    };
    xml.push_str(">\n      <");
    xml.push_str(element);
    if let Some(message) = message {
        let _ = write!(xml, " message=\"{}\"", escape::attribute(&message));
    }
    if body.is_empty() {
        xml.push_str("/>\n");
    } else {
        let _ = writeln!(xml, ">{}</{element}>", escape::text(&body));
    }
    xml.push_str("    </testcase>\n");
}
