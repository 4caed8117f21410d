//! Finding a suite: its scene files, their reference images and their tolerances.
//!
//! Layout: the reference image of `DIR/NAME.ron` is `DIR/refs/NAME.png`. `lampshade render`
//! writes `DIR/NAME.png` beside the scene, so a reference there would be overwritten by the
//! first render; a `refs/` folder keeps the two apart and keeps suites tidy.
//!
//! Discovery: every `*.ron` file below each folder named on the command line, recursively, in
//! path order, except
//! - anything in a folder named `refs` (reference images live there, never scenes);
//! - hidden files and folders (`.git`, editors' `.#scene.ron` lock files), and symlinked
//!   folders (they can form cycles); symlinked files are followed;
//! - material libraries: files whose top-level value is `Materials(...)` (found by skipping
//!   whitespace, comments and `#![...]` attributes at the start, not by parsing: a library with
//!   a syntax error is still a library, and its scenes will report the error);
//! - suite configs, [`CONFIG_FILE_NAME`].
//!
//! A file named on the command line is always a scene, whatever it holds. The same file
//! reached twice is checked once.
//!
//! Each scene has a *name*, its path relative to the folder named on the command line (for a
//! file named alone: its own folder), without `.ron` and with `/` between folders. Names key
//! the per-scene overrides, the shards and the reports, so they are the same on every
//! machine.
//!
//! Tolerances: the defaults, then the `tolerance` of every `lampshade-check.ron` from the
//! suite folder down to the scene's folder, then the entries for the scene in those configs'
//! `scenes` tables, outermost first, so the most specific setting wins. Configs above the
//! folder named on the command line are not read: run a part of a suite with `--filter`, not
//! by naming a subfolder, to keep its overrides.
//!
//! Rejected: references beside the scenes as `NAME.ref.png` (a glob for `*.png` in a suite
//! would pick them up as outputs, and they clutter the folder a person edits); looking for
//! configs in every parent folder up to the file-system root (a stray config in a home
//! folder would change a suite's verdicts, and CI could not reproduce it).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::check::compare::{DEFAULT_TOLERANCE, Tolerance};
use crate::check::config::{CONFIG_FILE_NAME, SuiteConfig, load_config};
use crate::diag::{Diagnostic, Sources};

/// The folder, beside the scenes, that holds their reference images.
pub const REFERENCE_FOLDER: &str = "refs";

/// One scene of a suite, ready to run.
#[derive(Debug, Clone, PartialEq)]
pub struct SuiteScene {
    /// The scene file: the folder named on the command line joined with the relative path.
    pub path: PathBuf,
    /// The path relative to `suite`, without `.ron`, with `/` between folders.
    pub name: String,
    /// The folder named on the command line (for a file named alone: its folder).
    pub suite: PathBuf,
    /// Where its reference image is, or is to be written.
    pub reference: PathBuf,
    pub tolerance: Tolerance,
}

/// Why a suite could not be put together: missing paths, unreadable folders, bad configs.
#[derive(Debug, Clone, Default)]
pub struct SuiteProblems {
    pub diagnostics: Vec<Diagnostic>,
    pub sources: Sources,
}

/// The reference image of the scene file `scene`: `DIR/refs/NAME.png` for `DIR/NAME.ron`.
pub fn reference_path(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().map(|s| s.to_string_lossy()).unwrap_or_default();
    let folder = scene.parent().unwrap_or(Path::new(""));
    folder.join(REFERENCE_FOLDER).join(format!("{stem}.png"))
}

/// Every scene below `paths` (files or folders), sorted by path, with its reference and
/// tolerance; or every problem found on the way.
pub fn discover(paths: &[PathBuf]) -> Result<Vec<SuiteScene>, SuiteProblems> {
    let mut problems = SuiteProblems::default();
    let mut found = Vec::new();
    // Config files by the folder holding them, found while walking.
    let mut config_paths = BTreeMap::new();
    for path in paths {
        match std::fs::metadata(path) {
            Ok(metadata) if metadata.is_dir() => {
                walk(
                    path,
                    path,
                    &mut Vec::new(),
                    &mut found,
                    &mut config_paths,
                    &mut problems,
                );
            }
            Ok(_) => {
                let suite = match path.parent() {
                    Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
                    _ => PathBuf::from("."),
                };
                let config = suite.join(CONFIG_FILE_NAME);
                if config.is_file() {
                    config_paths.insert(suite.clone(), config);
                }
                let file_name = path.file_name().map(|n| n.to_string_lossy().into_owned());
                found.push(Found {
                    path: path.clone(),
                    suite,
                    components: file_name.into_iter().collect(),
                });
            }
            Err(error) => problems.diagnostics.push(Diagnostic::error(
                path,
                match error.kind() {
                    std::io::ErrorKind::NotFound => "no such file or folder".to_owned(),
                    _ => format!("cannot read: {error}"),
                },
            )),
        }
    }

    let mut configs = BTreeMap::new();
    for (folder, config_path) in &config_paths {
        if let Some(config) = load_config(config_path, &mut problems.sources, &mut problems.diagnostics) {
            configs.insert(folder.clone(), config);
        }
    }
    if !problems.diagnostics.is_empty() {
        return Err(problems);
    }

    found.sort_by(|a, b| a.path.cmp(&b.path));
    let mut seen = std::collections::HashSet::new();
    let scenes = found
        .into_iter()
        .filter(|scene| {
            seen.insert(std::fs::canonicalize(&scene.path).unwrap_or_else(|_| scene.path.clone()))
        })
        .map(|scene| SuiteScene {
            tolerance: resolve_tolerance(&scene, &configs),
            name: scene_name(&scene.components),
            reference: reference_path(&scene.path),
            path: scene.path,
            suite: scene.suite,
        })
        .collect();
    Ok(scenes)
}

/// A scene file found by the walk.
struct Found {
    path: PathBuf,
    suite: PathBuf,
    /// Folders below `suite`, then the file name.
    components: Vec<String>,
}

/// `["lights", "spot.ron"]` → `lights/spot`.
fn scene_name(components: &[String]) -> String {
    let joined = components.join("/");
    match joined.strip_suffix(".ron") {
        Some(stem) => stem.to_owned(),
        None => joined,
    }
}

/// Adds the scene files below `folder` (which is `suite` joined with `below`) to `found`.
fn walk(
    suite: &Path,
    folder: &Path,
    below: &mut Vec<String>,
    found: &mut Vec<Found>,
    config_paths: &mut BTreeMap<PathBuf, PathBuf>,
    problems: &mut SuiteProblems,
) {
    let cannot_list =
        |error: std::io::Error| Diagnostic::error(folder, format!("cannot list the folder: {error}"));
    let entries = match std::fs::read_dir(folder) {
        Ok(entries) => entries,
        Err(error) => {
            problems.diagnostics.push(cannot_list(error));
            return;
        }
    };
    let mut entries: Vec<_> = match entries.collect::<Result<_, _>>() {
        Ok(entries) => entries,
        Err(error) => {
            problems.diagnostics.push(cannot_list(error));
            return;
        }
    };
    entries.sort_by_key(|entry| entry.file_name());
    for entry in entries {
        let name = entry.file_name().to_string_lossy().into_owned();
        let path = entry.path();
        if name.starts_with('.') {
            continue;
        }
        // `file_type` does not follow symlinks: symlinked folders are skipped, files followed.
        let is_symlink = entry.file_type().is_ok_and(|t| t.is_symlink());
        let is_dir = !is_symlink && entry.file_type().is_ok_and(|t| t.is_dir());
        if is_dir {
            if name != REFERENCE_FOLDER {
                below.push(name);
                walk(suite, &path, below, found, config_paths, problems);
                below.pop();
            }
            continue;
        }
        if !name.ends_with(".ron") || !path.is_file() {
            continue;
        }
        if name == CONFIG_FILE_NAME {
            config_paths.insert(folder.to_path_buf(), path);
            continue;
        }
        // An unreadable file stays a scene: its load will report why.
        if std::fs::read(&path).is_ok_and(|bytes| is_material_library(&bytes)) {
            continue;
        }
        let mut components = below.clone();
        components.push(name);
        found.push(Found {
            path,
            suite: suite.to_path_buf(),
            components,
        });
    }
}

/// The defaults, then every config's folder-wide limits from the suite folder down, then
/// every config's entry for this scene from the suite folder down.
fn resolve_tolerance(scene: &Found, configs: &BTreeMap<PathBuf, SuiteConfig>) -> Tolerance {
    let folders = scene.components.len().saturating_sub(1);
    // (config, the scene's name relative to the config's folder), outermost first.
    let applicable: Vec<(&SuiteConfig, String)> = (0..=folders)
        .filter_map(|depth| {
            let mut folder = scene.suite.clone();
            folder.extend(&scene.components[..depth]);
            let config = configs.get(&folder)?;
            Some((config, scene_name(&scene.components[depth..])))
        })
        .collect();
    let mut tolerance = DEFAULT_TOLERANCE;
    for (config, _) in &applicable {
        config.tolerance.apply_to(&mut tolerance);
    }
    for (config, name) in &applicable {
        if let Some(limits) = config.scene(name) {
            limits.apply_to(&mut tolerance);
        }
    }
    tolerance
}

/// Whether a RON file's top-level value is `Materials(...)`: a material library, not a scene.
pub fn is_material_library(text: &[u8]) -> bool {
    let mut rest = text.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(text);
    rest = skip_trivia(rest);
    let Some(after_name) = rest.strip_prefix(b"Materials") else {
        return false;
    };
    skip_trivia(after_name).starts_with(b"(")
}

/// `text` after any leading whitespace, comments (`//`, nested `/* */`) and `#![...]`.
pub(crate) fn skip_trivia(mut text: &[u8]) -> &[u8] {
    loop {
        let start = text
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(text.len());
        text = &text[start..];
        if text.starts_with(b"//") {
            let end = text.iter().position(|&b| b == b'\n').unwrap_or(text.len());
            text = &text[end..];
        } else if text.starts_with(b"/*") {
            text = skip_nested(text, b"/*", b"*/");
        } else if text.starts_with(b"#![") {
            text = skip_nested(&text[2..], b"[", b"]");
        } else {
            return text;
        }
    }
}

/// `text`, which starts with `open`, after the matching `close` (all of it when unclosed).
fn skip_nested<'a>(mut text: &'a [u8], open: &[u8], close: &[u8]) -> &'a [u8] {
    let mut depth = 0usize;
    while !text.is_empty() {
        if text.starts_with(open) {
            depth += 1;
            text = &text[open.len()..];
        } else if text.starts_with(close) {
            depth = depth.saturating_sub(1);
            text = &text[close.len()..];
            if depth == 0 {
                return text;
            }
        } else {
            text = &text[1..];
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn material_libraries_are_recognised() {
        let libraries: [&[u8]; 5] = [
            b"Materials(materials: {})",
            b"  // comment\n/* block /* nested */ */ Materials (",
            b"\xEF\xBB\xBF#![enable(implicit_some)]\nMaterials(",
            b"Materials\n// between\n(",
            b"Materials /* broken",
        ];
        for text in libraries {
            let expected = !text.ends_with(b"broken");
            assert_eq!(
                is_material_library(text),
                expected,
                "{}",
                String::from_utf8_lossy(text)
            );
        }
        let scenes: [&[u8]; 5] = [
            b"(objects: [])",
            b"Scene(materials: {})",
            b"// Materials(\n(objects: [])",
            b"MaterialsX(",
            b"",
        ];
        for text in scenes {
            assert!(!is_material_library(text), "{}", String::from_utf8_lossy(text));
        }
    }

    #[test]
    fn references_live_in_refs() {
        assert_eq!(
            reference_path(Path::new("scenes/lights/spot.ron")),
            Path::new("scenes/lights/refs/spot.png")
        );
        assert_eq!(reference_path(Path::new("a.ron")), Path::new("refs/a.png"));
    }

    fn write(root: &Path, relative: &str, text: &str) {
        let path = root.join(relative);
        std::fs::create_dir_all(path.parent().expect("a parent")).expect("folders");
        std::fs::write(path, text).expect("a file");
    }

    #[test]
    fn discovery_skips_references_libraries_configs_and_hidden_files() {
        let folder = tempfile::tempdir().expect("a temporary folder");
        let root = folder.path();
        write(root, "b.ron", "(objects: [])");
        write(root, "a.ron", "(objects: [])");
        write(root, "lib.ron", "// shared\nMaterials(materials: {})");
        write(root, "refs/old.ron", "(objects: [])");
        write(root, ".hidden/x.ron", "(objects: [])");
        write(root, ".#a.ron", "(objects: [])");
        write(root, "notes.txt", "not a scene");
        write(root, "lights/spot.ron", "(objects: [])");
        write(root, "lights/refs/spot.png", "");
        write(
            root,
            CONFIG_FILE_NAME,
            "(tolerance: (max_channel_difference: 5), scenes: { \"lights/spot\": (max_differing_share: 0.5) })",
        );
        write(
            root,
            "lights/lampshade-check.ron",
            "(tolerance: (max_differing_share: 0.25, max_channel_difference: 7))",
        );

        let scenes = discover(&[root.to_path_buf(), root.join("a.ron")]).expect("a good suite");
        let names: Vec<&str> = scenes.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["a", "b", "lights/spot"]);
        assert_eq!(scenes[0].path, root.join("a.ron"));
        assert_eq!(scenes[2].reference, root.join("lights/refs/spot.png"));
        assert_eq!(scenes[0].tolerance.max_channel_difference, 5);
        // The inner config's folder-wide limits beat the outer one's, and the outer config's
        // entry for the scene beats both.
        assert_eq!(scenes[2].tolerance.max_channel_difference, 7);
        assert_eq!(scenes[2].tolerance.max_differing_share, 0.5);

        // A file named alone is a scene, named after itself, under its folder's config.
        let alone = discover(&[root.join("lib.ron")]).expect("a good suite");
        assert_eq!(alone.len(), 1);
        assert_eq!(alone[0].name, "lib");
        assert_eq!(alone[0].tolerance.max_channel_difference, 5);
    }

    #[test]
    fn missing_paths_and_bad_configs_are_problems() {
        let folder = tempfile::tempdir().expect("a temporary folder");
        let missing = discover(&[folder.path().join("nope")]).expect_err("no such folder");
        assert_eq!(missing.diagnostics.len(), 1);
        assert_eq!(missing.diagnostics[0].message, "no such file or folder");

        write(folder.path(), "a.ron", "(objects: [])");
        write(folder.path(), CONFIG_FILE_NAME, "(tolerance: (bogus: 1))");
        let bad = discover(&[folder.path().to_path_buf()]).expect_err("a bad config");
        assert!(
            bad.diagnostics[0].message.contains("bogus"),
            "{:?}",
            bad.diagnostics
        );
    }
}
