//! `lampshade-check.ron`: a suite's tolerances, for a folder and for single scenes.
//!
//! ```ron
//! // scenes/lampshade-check.ron
//! (
//!     tolerance: (max_channel_difference: 2, max_differing_share: 0.001),
//!     scenes: {
//!         "matlab-shiny": (max_channel_difference: 3),
//!         "lights/spot": (max_differing_share: 0.01, max_flip_mean: 0.01),
//!     },
//! )
//! ```
//!
//! Every field is optional; what is left out keeps the value from further out (the defaults,
//! then configs in enclosing folders). An empty file (or one of comments only) is a config
//! with every field left out, as `()` is: `touch lampshade-check.ron` marks a suite, and a
//! config whose last override was deleted is still valid. `scenes` keys are scene names relative to the config's
//! folder, without `.ron`. Parsed by serde with `deny_unknown_fields` (a misspelt limit must
//! not silently keep the default), with the scene files' ron options (`Some(...)` may be left
//! out); every problem becomes a located [`Diagnostic`], all of them collected, like a scene
//! file's. Checked after parsing: shares and FLIP limits lie in 0..=1, no scene is named twice,
//! and every named scene exists (a renamed scene must not leave its override behind unseen).

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::check::compare::Tolerance;
use crate::check::suite::skip_trivia;
use crate::diag::{Diagnostic, Schema, SourceId, Sources, from_ron_error};
use crate::scene::format::{OrderedMap, probe_fields, ron_options};
use crate::scene::locate::{PathSegment, locate, locate_key, locate_keys};

/// The file name of a suite config; it is never taken for a scene.
pub const CONFIG_FILE_NAME: &str = "lampshade-check.ron";

/// The file as written: serde types and nothing else.
#[derive(Debug, Default, Deserialize)]
#[serde(rename = "Suite", deny_unknown_fields)]
struct SuiteConfigFile {
    #[serde(default)]
    tolerance: ToleranceOverride,
    #[serde(default)]
    scenes: OrderedMap<ToleranceOverride>,
}

/// What a config holds, for error hints (see [`Schema`]).
const SUITE_SCHEMA: Schema = Schema {
    fields: suite_fields,
    variants: |_| None,
    what: "a suite config",
    example: "(tolerance: (max_channel_difference: 2))",
};

fn suite_fields(holder: Option<&str>, _name: Option<&str>) -> Option<&'static [&'static str]> {
    let probe = "(lampshade_probe: 0)";
    match holder {
        None => probe_fields::<SuiteConfigFile>(probe),
        Some("tolerance" | "scenes") => probe_fields::<ToleranceOverride>(probe),
        Some(_) => None,
    }
}

/// Some of the limits of a [`Tolerance`]; the rest come from further out.
#[derive(Debug, Default, Clone, Copy, PartialEq, Deserialize)]
#[serde(rename = "Tolerance", deny_unknown_fields)]
pub struct ToleranceOverride {
    pub max_channel_difference: Option<u8>,
    pub max_differing_share: Option<f64>,
    pub max_flip_mean: Option<f64>,
    pub max_flip_percentile: Option<f64>,
}

impl ToleranceOverride {
    /// Replaces the limits this override sets.
    pub fn apply_to(&self, tolerance: &mut Tolerance) {
        if let Some(value) = self.max_channel_difference {
            tolerance.max_channel_difference = value;
        }
        if let Some(value) = self.max_differing_share {
            tolerance.max_differing_share = value;
        }
        if let Some(value) = self.max_flip_mean {
            tolerance.max_flip_mean = value;
        }
        if let Some(value) = self.max_flip_percentile {
            tolerance.max_flip_percentile = value;
        }
    }

    /// The limits that must lie in 0..=1, by field name.
    fn unit_limits(&self) -> [(&'static str, Option<f64>); 3] {
        [
            ("max_differing_share", self.max_differing_share),
            ("max_flip_mean", self.max_flip_mean),
            ("max_flip_percentile", self.max_flip_percentile),
        ]
    }
}

/// A checked `lampshade-check.ron`.
#[derive(Debug, Clone, PartialEq)]
pub struct SuiteConfig {
    /// The folder holding the file: its limits apply to every scene below it.
    pub folder: PathBuf,
    /// For every scene below `folder`.
    pub tolerance: ToleranceOverride,
    /// For single scenes, by name relative to `folder` (without `.ron`).
    pub scenes: Vec<(String, ToleranceOverride)>,
}

impl SuiteConfig {
    /// The override for the scene called `name` relative to this config's folder.
    pub fn scene(&self, name: &str) -> Option<&ToleranceOverride> {
        self.scenes.iter().find(|(key, _)| key == name).map(|(_, o)| o)
    }
}

/// Reads and checks the config at `path`, adding its text to `sources` and its problems to
/// `diagnostics`; `None` when it has errors.
pub fn load_config(
    path: &Path,
    sources: &mut Sources,
    diagnostics: &mut Vec<Diagnostic>,
) -> Option<SuiteConfig> {
    let text = match std::fs::read(path) {
        Ok(bytes) => match String::from_utf8(bytes) {
            Ok(text) => text,
            Err(_) => {
                diagnostics.push(Diagnostic::error(path, "the suite config is not UTF-8 text"));
                return None;
            }
        },
        Err(error) => {
            diagnostics.push(Diagnostic::error(
                path,
                format!("cannot read the suite config: {error}"),
            ));
            return None;
        }
    };
    let source = sources.add(path.to_path_buf(), text);
    let file: SuiteConfigFile = match ron_options().from_str(sources.text(source)) {
        Ok(file) => file,
        // Nothing but whitespace and comments (an unclosed comment is another error).
        Err(error)
            if !matches!(
                error.code,
                ron::error::Error::UnclosedBlockComment | ron::error::Error::UnclosedLineComment
            ) && skip_trivia(sources.text(source).as_bytes()).is_empty() =>
        {
            SuiteConfigFile::default()
        }
        Err(error) => {
            diagnostics.push(config_syntax_error(source, sources, &error));
            return None;
        }
    };
    let folder = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let errors_before = diagnostics.len();
    let checker = Checker {
        source,
        sources,
        path,
    };
    checker.check_limits(&file.tolerance, &[PathSegment::from("tolerance")], diagnostics);
    for (index, (name, limits)) in file.scenes.0.iter().enumerate() {
        let entry_path = [PathSegment::from("scenes"), PathSegment::key(name.as_str())];
        if file.scenes.0[..index].iter().any(|(earlier, _)| earlier == name) {
            diagnostics.push(checker.duplicate_scene(name));
            continue;
        }
        checker.check_limits(limits, &entry_path, diagnostics);
        if let Some(problem) = checker.check_scene_name(&folder, name) {
            diagnostics.push(problem);
        }
    }
    if diagnostics.len() > errors_before {
        return None;
    }
    Some(SuiteConfig {
        folder,
        tolerance: file.tolerance,
        scenes: file.scenes.0,
    })
}

/// What a config may hold, for hints.
const CONFIG_EXAMPLE: &str = "a `lampshade-check.ron` holds `(tolerance: (max_channel_difference: 2, \
     max_differing_share: 0.001), scenes: { \"NAME\": (max_channel_difference: 3) })`; every \
     field may be left out, and an empty file keeps the defaults";

/// What a `tolerance` or a scene's entry may hold, for hints.
const LIMITS_EXAMPLE: &str = "limits are written in parentheses, each optional: \
     `(max_channel_difference: 2, max_differing_share: 0.001, max_flip_mean: 0.07, \
     max_flip_percentile: 0.12)`";

/// A syntax error in a config, in the words of the config: the serde type names (`Suite`,
/// `Tolerance`) that ron's own messages use are the code's, not the user's.
fn config_syntax_error(source: SourceId, sources: &Sources, error: &ron::error::SpannedError) -> Diagnostic {
    use ron::error::Error as E;
    // The scene format's rewriting first (JSON, quoting, numbers, named fields), then what only
    // a config has.
    let mut diagnostic = from_ron_error(source, sources, error, &SUITE_SCHEMA);
    let (message, hint) = match &error.code {
        E::ExpectedNamedStructLike("Suite") => {
            diagnostic.hints.push(CONFIG_EXAMPLE.to_owned());
            return diagnostic;
        }
        E::ExpectedNamedStructLike("Tolerance") => ("expected limits, `(...)`".to_owned(), LIMITS_EXAMPLE),
        E::ExpectedMap => (
            "expected the scenes' limits by name, `{ ... }`".to_owned(),
            "write `scenes: { \"NAME\": (max_channel_difference: 3) }`, NAME being the scene's \
             path below this folder without `.ron`",
        ),
        E::NoSuchStructField { outer, .. }
        | E::MissingStructField { outer, .. }
        | E::DuplicateStructField { outer, .. } => {
            let message = match outer.as_deref() {
                Some("Suite") => diagnostic.message.replace(" in `Suite`", " at the top level"),
                Some("Tolerance") => diagnostic.message.replace(" in `Tolerance`", " in the limits"),
                _ => diagnostic.message.clone(),
            };
            diagnostic.message = message;
            return diagnostic;
        }
        _ => return diagnostic,
    };
    diagnostic.message = message;
    diagnostic.hints = vec![hint.to_owned()];
    diagnostic
}

/// Checks on a parsed config, pointing each problem at its place in the text.
struct Checker<'a> {
    source: SourceId,
    sources: &'a Sources,
    path: &'a Path,
}

impl Checker<'_> {
    fn text(&self) -> &str {
        self.sources.text(self.source)
    }

    fn error_at(&self, span: Option<std::ops::Range<usize>>, message: String) -> Diagnostic {
        let diagnostic = Diagnostic::error(self.path, message);
        match span {
            Some(span) => diagnostic.at(self.source, span),
            None => diagnostic,
        }
    }

    fn check_limits(
        &self,
        limits: &ToleranceOverride,
        at: &[PathSegment],
        diagnostics: &mut Vec<Diagnostic>,
    ) {
        for (field, value) in limits.unit_limits() {
            let Some(value) = value else { continue };
            if (0.0..=1.0).contains(&value) {
                continue;
            }
            let mut path = at.to_vec();
            path.push(PathSegment::from(field));
            let span = locate(self.text(), &path);
            diagnostics.push(
                self.error_at(span, format!("`{field}` must be between 0 and 1, not {value}"))
                    .with_label("out of range")
                    .with_hint("it is a share: 0.001 allows one pixel in a thousand (0.1 %)"),
            );
        }
    }

    fn duplicate_scene(&self, name: &str) -> Diagnostic {
        let keys = locate_keys(self.text(), &[PathSegment::from("scenes")], name);
        let diagnostic = self
            .error_at(keys.last().cloned(), format!("scene `{name}` is given twice"))
            .with_label("given again here");
        match keys.first() {
            Some(first) if keys.len() > 1 => {
                let (line, column) = crate::diag::line_column(self.text(), first.start);
                diagnostic.with_hint(format!("merge it with the entry at {line}:{column}"))
            }
            _ => diagnostic,
        }
    }

    /// A problem when `name` is not the name of a scene file below `folder`.
    fn check_scene_name(&self, folder: &Path, name: &str) -> Option<Diagnostic> {
        let span = locate_key(self.text(), &[PathSegment::from("scenes")], name);
        let relative_and_plain = !name.is_empty()
            && !name.starts_with('/')
            && !name.contains('\\')
            && name
                .split('/')
                .all(|part| !part.is_empty() && part != "." && part != "..");
        if !relative_and_plain {
            return Some(
                self.error_at(span, format!("`{name}` is not a scene name"))
                    .with_label("not a scene name")
                    .with_hint(
                        "write the scene's path below this folder without `.ron`, \
                         with `/` between folders, e.g. `lights/spot`",
                    ),
            );
        }
        if folder.join(format!("{name}.ron")).is_file() {
            return None;
        }
        let mut diagnostic = self
            .error_at(
                span,
                format!("there is no scene `{name}.ron` in `{}`", folder.display()),
            )
            .with_label("no such scene");
        diagnostic = match name.strip_suffix(".ron") {
            Some(stem) => diagnostic.with_hint(format!("leave out `.ron`: `\"{stem}\"`")),
            None => diagnostic.with_hint(
                "scenes are named by their path below this folder without `.ron`; \
                 remove entries for scenes that were renamed or deleted",
            ),
        };
        Some(diagnostic)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check::compare::DEFAULT_TOLERANCE;
    use crate::diag::render_diagnostics;

    /// Writes `text` as the config of a folder holding `a.ron` and `sub/b.ron`, loads it, and
    /// returns the config or the rendered diagnostics.
    fn load(text: &str) -> Result<SuiteConfig, String> {
        let folder = tempfile::tempdir().expect("a temporary folder");
        std::fs::create_dir(folder.path().join("sub")).expect("a subfolder");
        for scene in ["a.ron", "sub/b.ron"] {
            std::fs::write(folder.path().join(scene), "(objects: [])").expect("a scene file");
        }
        let path = folder.path().join(CONFIG_FILE_NAME);
        std::fs::write(&path, text).expect("the config file");
        let mut sources = Sources::new();
        let mut diagnostics = Vec::new();
        match load_config(&path, &mut sources, &mut diagnostics) {
            Some(config) if diagnostics.is_empty() => Ok(config),
            _ => Err(render_diagnostics(&diagnostics, &sources, false)),
        }
    }

    #[test]
    fn overrides_apply_field_by_field() {
        let config = load(
            "(tolerance: (max_channel_difference: 4), \
              scenes: { \"a\": (max_differing_share: 0.5), \"sub/b\": (max_flip_mean: 0.25) })",
        )
        .expect("a good config");
        let mut tolerance = DEFAULT_TOLERANCE;
        config.tolerance.apply_to(&mut tolerance);
        config
            .scene("a")
            .expect("an entry for a")
            .apply_to(&mut tolerance);
        assert_eq!(
            tolerance,
            Tolerance {
                max_channel_difference: 4,
                max_differing_share: 0.5,
                ..DEFAULT_TOLERANCE
            }
        );
        assert_eq!(config.scene("sub/b").and_then(|o| o.max_flip_mean), Some(0.25));
        assert_eq!(config.scene("b"), None);
    }

    #[test]
    fn an_empty_config_and_named_structs_are_fine() {
        assert_eq!(load("()").expect("empty").scenes, []);
        for empty in ["", " \n\t", "// nothing yet\n/* later */"] {
            let config = load(empty).unwrap_or_else(|e| panic!("{empty:?}: {e}"));
            assert_eq!(
                (config.tolerance, config.scenes),
                (ToleranceOverride::default(), vec![])
            );
        }
        let config = load("Suite(tolerance: Tolerance(max_channel_difference: 1))").expect("named");
        assert_eq!(config.tolerance.max_channel_difference, Some(1));
    }

    fn expect_error(text: &str, expected: &[&str]) {
        let rendered = load(text).expect_err("the config is bad");
        for fragment in expected {
            assert!(
                rendered.contains(fragment),
                "expected `{fragment}` in\n{rendered}"
            );
        }
    }

    /// ron's errors name the serde types (`struct `Suite``); the messages must not.
    #[test]
    fn syntax_errors_speak_of_the_config_not_of_internal_types() {
        for (text, expected) in [
            (
                "{\"tolerance\": {}}",
                "expected `(` at the start of a suite config",
            ),
            (
                "(tolerance: (2, 0.001))",
                "write `tolerance: (max_channel_difference: 2, max_differing_share: 0.001)`",
            ),
        ] {
            let rendered = load(text).expect_err("the config is bad");
            assert!(
                rendered.contains(expected),
                "{text:?}: expected `{expected}` in\n{rendered}"
            );
            assert!(rendered.contains("lampshade-check.ron:1:"), "{rendered}");
            assert!(
                !rendered.contains("Suite"),
                "{text:?}: an internal type name in\n{rendered}"
            );
        }
    }

    #[test]
    fn shape_errors_say_what_the_file_may_hold_without_type_names() {
        for (text, message, help) in [
            (
                "[]",
                "expected `(` at the start of a suite config",
                "every field may be left out",
            ),
            (
                "(tolerance: 3)",
                "expected limits, `(...)`",
                "max_differing_share: 0.001",
            ),
            (
                "(scenes: [])",
                "expected the scenes' limits by name",
                "scenes: { \"NAME\"",
            ),
            (
                "(toleranc: ())",
                "unknown field `toleranc` at the top level",
                "`tolerance`",
            ),
            (
                "(tolerance: (max: 1))",
                "unknown field `max` in the limits",
                "max_flip_mean",
            ),
            ("/* unclosed", "", ""),
        ] {
            let rendered = load(text).expect_err(text);
            assert!(
                rendered.contains(message) && rendered.contains(help),
                "{text}:\n{rendered}"
            );
            for internal in ["Suite", "Tolerance", "struct"] {
                assert!(!rendered.contains(internal), "{text}:\n{rendered}");
            }
        }
    }

    #[test]
    fn problems_are_located() {
        expect_error(
            "(\n  tolerance: (max_chanel_difference: 3),\n)",
            &[
                "unknown field `max_chanel_difference`",
                "lampshade-check.ron:2:15",
            ],
        );
        expect_error(
            "(tolerance: (max_channel_difference: 300))",
            &["lampshade-check.ron:1:38"],
        );
        expect_error(
            "(\n  scenes: {\n    \"a\": (max_differing_share: 2),\n  },\n)",
            &[
                "`max_differing_share` must be between 0 and 1, not 2",
                "lampshade-check.ron:3:32",
            ],
        );
        expect_error(
            "(scenes: {\n  \"a\": (),\n  \"a\": (max_channel_difference: 1),\n})",
            &[
                "scene `a` is given twice",
                "lampshade-check.ron:3:3",
                "entry at 2:3",
            ],
        );
        expect_error(
            "(scenes: {\n  \"missing\": (),\n  \"a.ron\": (),\n  \"../a\": (),\n})",
            &[
                "there is no scene `missing.ron`",
                "lampshade-check.ron:2:3",
                "leave out `.ron`: `\"a\"`",
                "`../a` is not a scene name",
            ],
        );
    }
}
