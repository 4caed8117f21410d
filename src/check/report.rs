//! `--report DIR`: an HTML page for people, `DIR/index.html`, one self-contained file: the
//! pictures of every failing scene are embedded in it (data URLs) and also written to
//! `DIR/images/` (linked, for tools and full-size viewing).
//!
//! The page opens with a summary table of every scene (verdict, metrics, time), failures and
//! errors first, with filters (a checkbox per verdict, a text filter on the path; `report.js`).
//! Then each failure and error, in suite order, with its reason, its metrics and its pictures:
//! expected (the reference, copied byte for byte), actual (the new render), the difference heat
//! map ([`crate::check::compare::heat_map`]) and, with `--flip`, FLIP's error map, in the
//! viewer the watch preview uses (`src/watch/page/compare.js`, inlined): side by side, swipe,
//! onion skin, the difference amplified, the heat map, FLIP. Passing scenes get no pictures: a
//! suite of a thousand passing scenes would otherwise carry three thousand images nobody looks
//! at. Images are pixelated when enlarged, since a reference test is about single pixels. The
//! page loads nothing from elsewhere, so it can be opened from a CI artifact as is.
//!
//! The pictures are written by the workers as scenes fail ([`crate::check::runner`]); this
//! module writes only the page, atomically, once all results are in.
//!
//! A report holds one run: before the scenes run, [`remove_old_pictures`] removes what an
//! earlier report wrote into `DIR/images/`, recognised by the names reports give their
//! pictures ([`is_report_picture`]), so a folder shared with a person's own files keeps them.
//! Rejected: removing `DIR/images/` whole (`--report .` or a shared folder would lose files
//! lampshade never wrote); a manifest of written files (one more file to keep in step, and
//! lost with an interrupted run, which is exactly when stale pictures would linger).

use std::fmt::Write as _;
use std::path::Path;

use crate::check::compare::{percent, percentile_name};
use crate::check::escape;
use crate::check::runner::{Failure, PhaseTimes, SceneError, SceneResult, SceneStatus};
use crate::check::suite::SuiteScene;
use crate::cli::thousands;
use crate::diag::render_diagnostics;
use crate::output::{OutputError, write_atomically};

/// The folder, inside the report folder, that holds the pictures.
pub const PICTURE_FOLDER: &str = "images";

/// The kinds of picture a report shows, as the last part of their file names.
pub const PICTURE_KINDS: [&str; 4] = ["expected", "actual", "difference", "flip"];

/// Whether `name` is a file name a report gives its pictures, `NNNN-NAME-KIND.png`
/// (see [`crate::check::runner`]), or a temporary file of one being written.
pub fn is_report_picture(name: &str) -> bool {
    if name.starts_with(".lampshade-") && name.ends_with(".tmp") {
        return true;
    }
    let Some(stem) = name.strip_suffix(".png") else {
        return false;
    };
    // At least four digits: a suite of ten thousand scenes or more numbers with five.
    let digits = stem.bytes().take_while(u8::is_ascii_digit).count();
    let Some(rest) = stem[digits..].strip_prefix('-') else {
        return false;
    };
    digits >= 4
        && PICTURE_KINDS
            .iter()
            .any(|kind| rest.ends_with(&format!("-{kind}")))
}

/// Removes the pictures an earlier report left in `folder` (`DIR/images/`); other files stay.
pub fn remove_old_pictures(folder: &Path) -> Result<(), OutputError> {
    let io_error = |path: &Path, source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    };
    let entries = match std::fs::read_dir(folder) {
        Ok(entries) => entries,
        Err(error) if error.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(error) => return Err(io_error(folder, error)),
    };
    for entry in entries {
        let entry = entry.map_err(|error| io_error(folder, error))?;
        let is_ours = entry.file_name().to_str().is_some_and(is_report_picture)
            && entry.file_type().is_ok_and(|kind| kind.is_file());
        if is_ours {
            std::fs::remove_file(entry.path()).map_err(|error| io_error(&entry.path(), error))?;
        }
    }
    Ok(())
}

/// Writes `DIR/index.html`; the pictures are already in `DIR/images/`.
pub fn write_report(folder: &Path, html: &str) -> Result<(), OutputError> {
    let path = folder.join("index.html");
    write_atomically(&path, |writer| {
        use std::io::Write as _;
        writer
            .write_all(html.as_bytes())
            .map_err(|source| OutputError::Io {
                path: path.clone(),
                source,
            })
    })
}

/// The report page for `results` (one per scene, in `scenes` order), headed by `summary`.
/// `picture` reads a picture the run wrote (by its file name in `DIR/images/`), to embed it;
/// a picture it cannot read is linked instead.
pub fn report_html(
    scenes: &[SuiteScene],
    results: &[SceneResult],
    summary: &str,
    picture: &dyn Fn(&str) -> Option<Vec<u8>>,
) -> String {
    let mut html = String::new();
    let _ = write!(
        html,
        "<!doctype html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>lampshade check: {}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n\
         <h1>lampshade check</h1>\n<p class=\"summary\">{}</p>\n",
        escape::text(summary),
        escape::text(summary)
    );
    // Failures and errors first, then the rest, each part in suite order.
    let pairs: Vec<(usize, &SuiteScene, &SceneResult)> = scenes
        .iter()
        .zip(results)
        .enumerate()
        .map(|(index, (scene, result))| (index, scene, result))
        .collect();
    let (problems, others): (Vec<_>, Vec<_>) = pairs.iter().partition(|(_, _, result)| result.is_problem());
    write_filters(&mut html, &pairs);
    html.push_str(
        "<table id=\"scenes\">\n<thead><tr><th>scene</th><th>verdict</th><th>differing pixels</th>\
         <th>largest difference</th><th>FLIP mean</th><th>time</th></tr></thead>\n<tbody>\n",
    );
    for &&(index, scene, result) in problems.iter().chain(&others) {
        write_summary_row(&mut html, index, scene, result);
    }
    html.push_str("</tbody>\n</table>\n");
    if problems.is_empty() {
        html.push_str("<p>No failures.</p>\n");
    } else {
        html.push_str(LEGEND);
    }
    for &(index, scene, result) in problems {
        write_problem(&mut html, index, scene, result, picture);
    }
    let _ = write!(
        html,
        "<script>\n{}\n</script>\n<script>\n{}\n</script>\n</body>\n</html>\n",
        COMPARE_SCRIPT, FILTER_SCRIPT
    );
    html
}

/// The viewer the preview shows too: swipe, onion skin, amplified difference.
const COMPARE_SCRIPT: &str = include_str!("../watch/page/compare.js");

/// The summary table's filters.
const FILTER_SCRIPT: &str = include_str!("report.js");

/// A scene's verdict, as the summary table and the filters name it.
fn verdict(result: &SceneResult) -> (&'static str, String) {
    match &result.status {
        SceneStatus::Passed(_) => ("passed", String::new()),
        SceneStatus::Failed(_) => ("failed", String::new()),
        SceneStatus::Errored(_) => ("errored", String::new()),
        SceneStatus::Blessed(reason) => ("blessed", format!(": {reason}")),
        SceneStatus::NotRun(reason) => ("not run", format!(": {}", reason.describe())),
    }
}

/// A checkbox per verdict the run has (with its count) and a text filter on the name.
fn write_filters(html: &mut String, pairs: &[(usize, &SuiteScene, &SceneResult)]) {
    html.push_str("<form id=\"filters\" onsubmit=\"return false\"><span>show</span>\n");
    for name in ["failed", "errored", "passed", "blessed", "not run"] {
        let count = pairs
            .iter()
            .filter(|(_, _, result)| verdict(result).0 == name)
            .count();
        if count > 0 {
            let _ = writeln!(
                html,
                "<label><input type=\"checkbox\" value=\"{}\" checked> {name} ({count})</label>",
                name.replace(' ', "-")
            );
        }
    }
    html.push_str(
        "<label>name <input type=\"search\" id=\"name-filter\" placeholder=\"part of a scene's path\"></label>\n\
         <span id=\"shown\"></span></form>\n",
    );
}

fn write_summary_row(html: &mut String, index: usize, scene: &SuiteScene, result: &SceneResult) {
    let (status, note) = verdict(result);
    let name = scene.path.display().to_string();
    let comparison = result.comparison();
    let shown_name = if result.is_problem() {
        format!("<a href=\"#scene-{index}\">{}</a>", escape::text(&name))
    } else {
        escape::text(&name)
    };
    let _ = writeln!(
        html,
        "<tr class=\"{verdict}\" data-verdict=\"{verdict}\" data-name=\"{}\"><td>{shown_name}</td>\
         <td>{status}{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
        escape::attribute(&name),
        escape::text(&note),
        comparison.map_or(String::new(), |c| thousands(c.differing_pixels)),
        comparison.map_or(String::new(), |c| c.largest_difference.to_string()),
        comparison
            .and_then(|c| c.flip)
            .map_or(String::new(), |flip| format!("{:.4}", flip.mean)),
        milliseconds(result.times.total()),
        verdict = status.replace(' ', "-"),
    );
}

fn write_problem(
    html: &mut String,
    index: usize,
    scene: &SuiteScene,
    result: &SceneResult,
    picture: &dyn Fn(&str) -> Option<Vec<u8>>,
) {
    let (class, reason) = match &result.status {
        SceneStatus::Failed(failure) => ("failed", failure.describe(scene)),
        SceneStatus::Errored(error) => ("errored", error.describe()),
        _ => return,
    };
    let name = scene.path.display().to_string();
    let _ = write!(
        html,
        "<section class=\"scene {class}\" id=\"scene-{index}\" data-verdict=\"{class}\" data-name=\"{}\">\n\
         <h2><span class=\"status\">{class}</span> {}</h2>\n<p class=\"reason\">{}</p>\n",
        escape::attribute(&name),
        escape::text(&name),
        escape::text(&reason)
    );
    if let SceneStatus::Errored(SceneError::Load(error)) = &result.status {
        let diagnostics = render_diagnostics(&error.diagnostics, &error.sources, false);
        let _ = writeln!(html, "<pre>{}</pre>", escape::text(&diagnostics));
    }
    html.push_str("<table class=\"metrics\">\n");
    let mut row = |name: &str, value: String| {
        let _ = writeln!(html, "<tr><th>{name}</th><td>{}</td></tr>", escape::text(&value));
    };
    row("reference", scene.reference.display().to_string());
    let tolerance = scene.tolerance;
    if let SceneStatus::Failed(Failure::Mismatch { comparison, .. }) = &result.status {
        row(
            "differing pixels",
            format!(
                "{} of {} ({}; allowed {}), more than {} levels off",
                thousands(comparison.differing_pixels),
                thousands(comparison.pixel_count()),
                percent(comparison.differing_share()),
                percent(tolerance.max_differing_share),
                comparison.channel_threshold,
            ),
        );
        row(
            "largest difference",
            format!("{} levels", comparison.largest_difference),
        );
        if let Some(region) = comparison.differing_region {
            row(
                "differing region",
                format!(
                    "x {}–{}, y {}–{}",
                    region.x0,
                    region.x1 - 1,
                    region.y0,
                    region.y1 - 1
                ),
            );
        }
        if let Some(flip) = comparison.flip {
            row(
                "FLIP mean",
                format!("{:.4} (allowed {:.4})", flip.mean, tolerance.max_flip_mean),
            );
            row(
                &format!("FLIP {}", percentile_name()),
                format!(
                    "{:.4} (allowed {:.4})",
                    flip.percentile, tolerance.max_flip_percentile
                ),
            );
        }
    }
    row("time", phase_times(&result.times));
    html.push_str("</table>\n");

    // Expected and actual feed the viewer (compare.js); the heat map and FLIP's map are modes
    // of it. Without scripts the figures still show side by side.
    let pictures = [
        ("expected", "expected", "expected", &result.pictures.expected),
        ("actual", "actual", "actual", &result.pictures.actual),
        ("difference", "layer", "heat map", &result.pictures.difference),
        ("FLIP error", "layer", "FLIP", &result.pictures.flip),
    ];
    if pictures.iter().any(|(.., file)| file.is_some()) {
        html.push_str("<div class=\"pictures\" data-compare>\n");
        for (caption, role, mode, file) in pictures {
            let Some(file) = file else { continue };
            let link = escape::attribute(&format!("{PICTURE_FOLDER}/{file}"));
            // Embedded, so the page is one file; linked when it cannot be read back.
            let source =
                picture(file).map_or_else(|| link.clone(), |png| escape::data_url("image/png", &png));
            let _ = writeln!(
                html,
                "<figure><img src=\"{source}\" alt=\"{caption}\" data-role=\"{role}\" data-name=\"{mode}\">\
                 <figcaption>{caption} <a href=\"{link}\">(file)</a></figcaption></figure>"
            );
        }
        html.push_str("</div>\n");
    }
    html.push_str("</section>\n");
}

fn milliseconds(duration: std::time::Duration) -> String {
    format!("{:.1} ms", duration.as_secs_f64() * 1000.0)
}

fn phase_times(times: &PhaseTimes) -> String {
    let phases: Vec<String> = times
        .phases()
        .iter()
        .map(|(name, time)| format!("{name} {}", milliseconds(*time)))
        .collect();
    phases.join(", ")
}

const LEGEND: &str = "<p class=\"legend\">Difference: the reference in dim grey; \
    <span style=\"color:#0000a0\">■</span> differs within the per-channel threshold; \
    <span style=\"color:#ff0000\">■</span>→<span style=\"color:#ffff00\">■</span> differs by more \
    (red just over, yellow 255 levels off). FLIP error: black where no difference is visible, \
    through purple to yellow where it is most visible.</p>\n";

const STYLE: &str = "body{font:14px/1.4 system-ui,sans-serif;margin:1.5em;color:#222}\
    #filters{display:flex;flex-wrap:wrap;gap:.3em 1em;align-items:center;margin:.6em 0}\
    #shown{color:#666}\
    #scenes td,#scenes th{border-bottom:1px solid #eee}\
    tr.failed td:nth-child(2){color:#c33;font-weight:600}tr.errored td:nth-child(2){color:#e80;font-weight:600}\
    .compare-frame canvas{background:#888}
    h2{font-size:1.1em;margin:0 0 .4em}\
    .scene{border:1px solid #ccc;border-left:6px solid #c33;padding:.8em;margin:1em 0}\
    .scene.errored{border-left-color:#e80}\
    .status{text-transform:uppercase;font-size:.8em;color:#fff;background:#c33;padding:.1em .4em;border-radius:3px}\
    .errored .status{background:#e80}\
    .reason{font-weight:600}\
    pre{background:#f6f6f6;padding:.6em;overflow:auto}\
    table{border-collapse:collapse}th,td{text-align:left;padding:.15em .8em .15em 0;vertical-align:top}\
    .pictures{display:grid;grid-template-columns:repeat(auto-fill,minmax(260px,1fr));gap:.8em;margin-top:.8em}\
    figure{margin:0}figure img{width:100%;image-rendering:pixelated;background:#888;display:block}\
    figcaption{font-size:.9em;color:#555}";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_pictures_are_recognised_by_name() {
        for ours in [
            "0000-minimal-actual.png",
            "0012-hard-large-image-expected.png",
            "0003-a-difference.png",
            "9999-x-y-flip.png",
            "12345-many-actual.png",
            ".lampshade-Ab12cd.tmp",
        ] {
            assert!(is_report_picture(ours), "{ours}");
        }
        for theirs in [
            "notes.txt",
            "actual.png",
            "0001-actual.jpg",
            "12-a-actual.png",
            "0001-a-actual-2.png",
            "0001_a-actual.png",
            "index.html",
        ] {
            assert!(!is_report_picture(theirs), "{theirs}");
        }
    }
}
