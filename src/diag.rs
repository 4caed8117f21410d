//! Diagnostics: problems in the user's files, reported with file, line, column, a snippet and
//! hints.
//!
//! Scene files are written by hand, so a problem report has to say *where* and, where it
//! can, *what to write instead*. The loader collects every problem as a [`Diagnostic`] (it
//! does not stop at the first) and the CLI prints them all with [`render_diagnostics`].
//!
//! Design:
//! - A [`Diagnostic`] is plain data: severity, message, the file it is about, an optional
//!   byte range in a loaded source file, an optional caret label and `help:` hints. Helpers
//!   deeper in the loader return plain messages; the caller that knows the location attaches
//!   it with [`Diagnostic::at`] (the typst pattern).
//! - Locations are byte ranges into texts held by [`Sources`], not line/column pairs, so
//!   that a span found by `scene::locate` or converted from ron's position can be rendered
//!   with a snippet. Line and column are computed when needed: line 1-based, column 1-based
//!   and counted in chars, as ron and codespan count them.
//! - Problems in files that are not kept as text (an OBJ mesh) carry only the path and
//!   optionally a line number.
//! - Rendering uses codespan-reporting's rich format, which prints `┌─ path:line:col` above
//!   the snippet; tests grep for that. codespan stays an implementation detail: nothing in
//!   this module's public API mentions it.
//! - Nothing here panics on bad input: ranges are clamped to the text and to char
//!   boundaries, unknown source ids render without a snippet.
//!
//! Rejected: storing line/column in diagnostics (a snippet needs the byte range anyway);
//! `miette`/`ariadne` (codespan-reporting is smaller and renders to a `String` without a
//! terminal).

use std::fmt::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};

use codespan_reporting::diagnostic as cs;
use codespan_reporting::files::{self as cs_files, Files};
use codespan_reporting::term;

/// How bad a problem is: errors stop the scene from loading, warnings do not.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Severity {
    /// The scene cannot be rendered.
    Error,
    /// The scene renders, but probably not as the author meant.
    Warning,
}

/// Identifies one file in [`Sources`]; only meaningful for the `Sources` that issued it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SourceId(usize);

/// The text files a load read (the scene file, included material files), kept so that
/// diagnostics can show snippets.
#[derive(Debug, Clone, Default)]
pub struct Sources {
    files: Vec<SourceFile>,
}

#[derive(Debug, Clone)]
struct SourceFile {
    path: PathBuf,
    text: String,
    /// Byte offset of the start of each line; the first is always 0.
    line_starts: Vec<usize>,
}

impl Sources {
    /// An empty set of sources.
    pub fn new() -> Self {
        Self::default()
    }

    /// Keeps `text` as the contents of `path` and returns its id.
    pub fn add(&mut self, path: PathBuf, text: String) -> SourceId {
        let line_starts = cs_files::line_starts(&text).collect();
        self.files.push(SourceFile {
            path,
            text,
            line_starts,
        });
        SourceId(self.files.len() - 1)
    }

    /// The path `id` was added with (empty for an id from another `Sources`).
    pub fn path(&self, id: SourceId) -> &Path {
        self.files.get(id.0).map_or(Path::new(""), |f| f.path.as_path())
    }

    /// The text `id` was added with (empty for an id from another `Sources`).
    pub fn text(&self, id: SourceId) -> &str {
        self.files.get(id.0).map_or("", |f| f.text.as_str())
    }

    /// The id of the file added with exactly this path, if any.
    pub fn find(&self, path: &Path) -> Option<SourceId> {
        self.files.iter().position(|f| f.path == path).map(SourceId)
    }

    /// Every file, in the order added.
    pub fn iter(&self) -> impl Iterator<Item = (SourceId, &Path, &str)> {
        self.files
            .iter()
            .enumerate()
            .map(|(i, f)| (SourceId(i), f.path.as_path(), f.text.as_str()))
    }
}

/// One problem in a user's file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Diagnostic {
    /// Whether the scene can still be rendered.
    pub severity: Severity,
    /// One line, lowercase start, no trailing period: "unknown material `rubyy`".
    pub message: String,
    /// The file the problem is about (may be a mesh file that is not in `Sources`).
    pub path: PathBuf,
    /// Where in a source file, when known: the file and a byte range.
    pub location: Option<(SourceId, Range<usize>)>,
    /// Short text under the snippet's caret, e.g. "not a material in this scene".
    pub label: Option<String>,
    /// "help: ..." lines, without the "help: " prefix.
    pub hints: Vec<String>,
    /// 1-based line in a non-source file (e.g. an OBJ), when known.
    pub line_in_file: Option<usize>,
}

impl Diagnostic {
    /// An error about `path`, without a location yet.
    pub fn error(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Self::new(Severity::Error, path.into(), message.into())
    }

    /// A warning about `path`, without a location yet.
    pub fn warning(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Self::new(Severity::Warning, path.into(), message.into())
    }

    fn new(severity: Severity, path: PathBuf, message: String) -> Self {
        Diagnostic {
            severity,
            message,
            path,
            location: None,
            label: None,
            hints: Vec::new(),
            line_in_file: None,
        }
    }

    /// Points the diagnostic at bytes `span` of `source`.
    pub fn at(mut self, source: SourceId, span: Range<usize>) -> Self {
        self.location = Some((source, span));
        self
    }

    /// Sets the text shown under the caret.
    pub fn with_label(mut self, label: impl Into<String>) -> Self {
        self.label = Some(label.into());
        self
    }

    /// Adds a `help:` line.
    pub fn with_hint(mut self, hint: impl Into<String>) -> Self {
        self.hints.push(hint.into());
        self
    }

    /// Sets the 1-based line in a file that is not kept in [`Sources`].
    pub fn with_line(mut self, line: usize) -> Self {
        self.line_in_file = Some(line);
        self
    }

    /// Whether this is an error (as opposed to a warning).
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }

    /// 1-based (line, column in chars) of the start of the location, if there is one.
    pub fn line_column(&self, sources: &Sources) -> Option<(usize, usize)> {
        let (source, span) = self.location.as_ref()?;
        let file = sources.files.get(source.0)?;
        Some(line_column(&file.text, span.start))
    }
}

/// The byte offset of ron's 1-based `line` and 1-based `column` (counted in chars) in `text`.
///
/// Out-of-range positions are clamped: line 0 and column 0 count as 1, a column past the end
/// of its line gives the end of that line, a line past the end gives `text.len()`.
pub fn byte_offset(text: &str, line: usize, column: usize) -> usize {
    let Some(line_start) = cs_files::line_starts(text).nth(line.max(1) - 1) else {
        return text.len();
    };
    let rest = &text[line_start..];
    let line_len = rest.find('\n').unwrap_or(rest.len());
    let in_line = rest[..line_len]
        .char_indices()
        .nth(column.max(1) - 1)
        .map_or(line_len, |(offset, _)| offset);
    line_start + in_line
}

/// 1-based (line, column in chars) of byte `offset` in `text`; the inverse of [`byte_offset`].
/// An offset past the end or inside a char is first moved back to a char boundary.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let offset = text.floor_char_boundary(offset);
    let before = &text[..offset];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let line = 1 + before.matches('\n').count();
    let column = 1 + before[line_start..].chars().count();
    (line, column)
}

/// `span` shrunk to lie within `text` and widened to char boundaries, so it can be sliced.
fn clamp_span(text: &str, span: &Range<usize>) -> Range<usize> {
    let start = text.floor_char_boundary(span.start);
    let end = text.ceil_char_boundary(span.end.max(start));
    start..end
}

/// Converts ron's parse or type error in `source` into a diagnostic pointing at the same
/// place, with the message reworded for scene authors and hints for the common mistakes
/// (unknown field or variant: the expected names and the closest one; missing field: what
/// to add; unclosed brackets; ...).
pub fn from_ron_error(source: SourceId, sources: &Sources, error: &ron::error::SpannedError) -> Diagnostic {
    use ron::error::Error as E;

    let text = sources.text(source);
    let start = byte_offset(text, error.span.start.line, error.span.start.col);
    let end = byte_offset(text, error.span.end.line, error.span.end.col).max(start);
    let (mut start, end) = trim_span(text, start, end);
    let at_end_of_file = start >= text.trim_end().len();

    let in_outer = |outer: &Option<String>| match outer {
        Some(outer) => format!(" in `{outer}`"),
        None => String::new(),
    };
    let mut label = None;
    let mut hints = Vec::new();
    let message = match &error.code {
        E::Eof
        | E::ExpectedComma
        | E::ExpectedArrayEnd
        | E::ExpectedStructLikeEnd
        | E::ExpectedMapEnd
        | E::ExpectedOptionEnd
        | E::ExpectedStringEnd
            if at_end_of_file =>
        {
            label = Some("the file ends here".to_owned());
            hints.push("look for a missing `)`, `]`, `}` or closing `\"`".to_owned());
            "unexpected end of file".to_owned()
        }
        E::NoSuchStructField {
            expected,
            found,
            outer,
        } => {
            label = Some("unknown field".to_owned());
            hints.extend(did_you_mean(found, expected));
            hints.push(expected_one_of("fields", expected));
            format!("unknown field `{found}`{}", in_outer(outer))
        }
        E::NoSuchEnumVariant {
            expected,
            found,
            outer,
        } => {
            label = Some("unknown variant".to_owned());
            hints.extend(did_you_mean(found, expected));
            hints.push(expected_one_of("variants", expected));
            format!("unknown variant `{found}`{}", in_outer(outer))
        }
        E::MissingStructField { field, outer } => {
            label = Some(format!("`{field}` is missing before this"));
            hints.push(format!("add `{field}: ...`"));
            format!("missing field `{field}`{}", in_outer(outer))
        }
        E::DuplicateStructField { field, outer } => {
            label = Some("given again here".to_owned());
            hints.push(format!("remove one of the `{field}: ...` entries"));
            format!("field `{field}` is given twice{}", in_outer(outer))
        }
        E::ExpectedDifferentStructName { expected, found } => {
            label = Some(format!("expected `{expected}`"));
            hints.push(format!("write `{expected}(...)`, or leave the name out: `(...)`"));
            format!("expected `{expected}(...)`, found `{found}(...)`")
        }
        E::TrailingCharacters => {
            label = Some("unexpected text".to_owned());
            hints.push(
                "the file holds one value, which ended before this; remove the text, \
                 or look for a `)` or `]` that closes too early"
                    .to_owned(),
            );
            "unexpected text after the end of the scene".to_owned()
        }
        E::ExpectedComma => {
            hints.push("separate fields and list elements with `,`".to_owned());
            "expected `,`".to_owned()
        }
        E::UnclosedBlockComment => {
            // ron points just after the `/*`.
            if text[..start].ends_with("/*") {
                start -= 2;
            }
            hints.push("close it with `*/` (block comments nest)".to_owned());
            "unclosed block comment".to_owned()
        }
        E::ExpectedDifferentLength { expected, found } => {
            let found = match found {
                0 => "none".to_owned(),
                1 => "one".to_owned(),
                n => n.to_string(),
            };
            if expected.contains("tuple of size 3") {
                hints.push("write all three components: `(x, y, z)`".to_owned());
            }
            format!("expected {expected}, found {found}")
        }
        E::IntegerOutOfBounds => "integer out of range for this field".to_owned(),
        E::Message(message) => message.clone(),
        other => lowercase_first(&other.to_string()),
    };

    let mut diagnostic = Diagnostic::error(sources.path(source), message).at(source, start..end);
    diagnostic.label = label;
    diagnostic.hints = hints;
    diagnostic
}

/// Moves a span off whitespace. ron starts some spans before the whitespace that precedes
/// the offending text, and ends some (trailing characters) before the text itself; at the
/// end of the file, the place after the last token is where something is missing.
fn trim_span(text: &str, start: usize, end: usize) -> (usize, usize) {
    let content_end = text.trim_end().len();
    if start >= content_end {
        return (content_end, content_end);
    }
    let skip = text[start..].find(|c: char| !c.is_whitespace()).unwrap_or(0);
    if skip == 0 || (start == end) {
        return (start, end);
    }
    let new_start = start + skip;
    let first_len = text[new_start..].chars().next().map_or(0, char::len_utf8);
    (new_start, end.max(new_start + first_len))
}

/// "expected one of: `a`, `b`, `c`".
fn expected_one_of(what: &str, expected: &[&str]) -> String {
    if expected.is_empty() {
        return format!("there are no {what} here");
    }
    let names: Vec<String> = expected.iter().map(|name| format!("`{name}`")).collect();
    format!("expected one of: {}", names.join(", "))
}

/// "did you mean `x`?" when one of `candidates` is a likely typo of `found`.
fn did_you_mean(found: &str, candidates: &[&str]) -> Option<String> {
    let threshold = (found.chars().count() / 3).max(1);
    candidates
        .iter()
        .map(|candidate| (edit_distance(found, candidate), candidate))
        .filter(|&(distance, _)| distance <= threshold)
        .min_by_key(|&(distance, _)| distance)
        .map(|(_, candidate)| format!("did you mean `{candidate}`?"))
}

/// Levenshtein distance in chars, ignoring ASCII case (`Sphere` vs `sphere` is a typo too).
fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().map(|c| c.to_ascii_lowercase()).collect();
    let b: Vec<char> = b.chars().map(|c| c.to_ascii_lowercase()).collect();
    let mut previous: Vec<usize> = (0..=b.len()).collect();
    for (i, &ca) in a.iter().enumerate() {
        let mut current = vec![i + 1];
        for (j, &cb) in b.iter().enumerate() {
            let substitute = previous[j] + usize::from(ca != cb);
            current.push(substitute.min(previous[j + 1] + 1).min(current[j] + 1));
        }
        previous = current;
    }
    previous[b.len()]
}

fn lowercase_first(message: &str) -> String {
    let mut chars = message.chars();
    match chars.next() {
        Some(first) => first.to_lowercase().chain(chars).collect(),
        None => String::new(),
    }
}

/// Renders `diagnostics` as text, in order, ANSI-coloured when `color` is set.
///
/// A diagnostic with a location gets codespan-reporting's rich format: the message, then
/// `┌─ path:line:col`, the snippet with carets and label, and `= help: ...` notes. One
/// without gets `error: path: message` (`path:line:` when `line_in_file` is set) and its
/// hints.
pub fn render_diagnostics(diagnostics: &[Diagnostic], sources: &Sources, color: bool) -> String {
    let files = CodespanFiles(sources);
    let config = term::Config::default();
    let mut out = String::new();
    for diagnostic in diagnostics {
        let rendered = to_codespan(diagnostic, sources);
        let result = if color {
            let mut buffer = term::termcolor::Buffer::ansi();
            term::emit_to_write_style(&mut buffer, &config, &files, &rendered)
                .map(|()| String::from_utf8_lossy(buffer.as_slice()).into_owned())
        } else {
            term::emit_into_string(&config, &files, &rendered)
        };
        match result {
            Ok(text) => out.push_str(&text),
            // codespan only fails on a file id or line it cannot find; `to_codespan` checked
            // both, but a plain rendering is still better than losing the problem.
            Err(_) => out.push_str(&render_plain(diagnostic)),
        }
    }
    out
}

fn to_codespan(diagnostic: &Diagnostic, sources: &Sources) -> cs::Diagnostic<SourceId> {
    let severity = match diagnostic.severity {
        Severity::Error => cs::Severity::Error,
        Severity::Warning => cs::Severity::Warning,
    };
    let notes = diagnostic
        .hints
        .iter()
        .map(|hint| format!("help: {hint}"))
        .collect();
    let location = diagnostic
        .location
        .as_ref()
        .filter(|(source, _)| source.0 < sources.files.len());
    match location {
        Some((source, span)) => {
            let span = clamp_span(sources.text(*source), span);
            let label =
                cs::Label::primary(*source, span).with_message(diagnostic.label.as_deref().unwrap_or(""));
            cs::Diagnostic::new(severity)
                .with_message(&diagnostic.message)
                .with_label(label)
                .with_notes(notes)
        }
        None => cs::Diagnostic::new(severity)
            .with_message(plain_message(diagnostic))
            .with_notes(notes),
    }
}

/// "path: message" or "path:line: message".
fn plain_message(diagnostic: &Diagnostic) -> String {
    let path = diagnostic.path.display();
    match diagnostic.line_in_file {
        Some(line) => format!("{path}:{line}: {}", diagnostic.message),
        None => format!("{path}: {}", diagnostic.message),
    }
}

/// The fallback rendering, without codespan.
fn render_plain(diagnostic: &Diagnostic) -> String {
    let severity = match diagnostic.severity {
        Severity::Error => "error",
        Severity::Warning => "warning",
    };
    let mut out = format!("{severity}: {}\n", plain_message(diagnostic));
    for hint in &diagnostic.hints {
        let _ = writeln!(out, "  = help: {hint}");
    }
    out.push('\n');
    out
}

/// codespan's view of [`Sources`]; private so that codespan stays out of the public API.
struct CodespanFiles<'a>(&'a Sources);

impl CodespanFiles<'_> {
    fn file(&self, id: SourceId) -> Result<&SourceFile, cs_files::Error> {
        self.0.files.get(id.0).ok_or(cs_files::Error::FileMissing)
    }
}

impl<'a> Files<'a> for CodespanFiles<'_> {
    type FileId = SourceId;
    type Name = std::path::Display<'a>;
    type Source = &'a str;

    fn name(&'a self, id: SourceId) -> Result<Self::Name, cs_files::Error> {
        Ok(self.file(id)?.path.display())
    }

    fn source(&'a self, id: SourceId) -> Result<&'a str, cs_files::Error> {
        Ok(&self.file(id)?.text)
    }

    fn line_index(&'a self, id: SourceId, byte_index: usize) -> Result<usize, cs_files::Error> {
        let starts = &self.file(id)?.line_starts;
        Ok(starts
            .binary_search(&byte_index)
            .unwrap_or_else(|next_line| next_line.saturating_sub(1)))
    }

    fn line_range(&'a self, id: SourceId, line_index: usize) -> Result<Range<usize>, cs_files::Error> {
        let file = self.file(id)?;
        let line_start = |index: usize| match index.cmp(&file.line_starts.len()) {
            std::cmp::Ordering::Less => Ok(file.line_starts[index]),
            std::cmp::Ordering::Equal => Ok(file.text.len()),
            std::cmp::Ordering::Greater => Err(cs_files::Error::LineTooLarge {
                given: index,
                max: file.line_starts.len() - 1,
            }),
        };
        Ok(line_start(line_index)?..line_start(line_index + 1)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    fn sources_with(path: &str, text: &str) -> (Sources, SourceId) {
        let mut sources = Sources::new();
        let id = sources.add(PathBuf::from(path), text.to_owned());
        (sources, id)
    }

    #[test]
    fn byte_offset_and_line_column_agree_with_non_ascii_text() {
        let text = "// é\n(näme: \"ß\",\n  x: 1)\n";
        // Line 2, column 10 is the `"` before ß: n, ä, m, e, :, space, " is at column 8.
        let checks = [
            ((1, 1), 0),
            ((1, 4), "// ".len()),
            ((2, 1), "// é\n".len()),
            ((2, 8), "// é\n(näme: ".len()),
            ((2, 9), "// é\n(näme: \"".len()),
            ((2, 10), "// é\n(näme: \"ß".len()),
            ((3, 3), "// é\n(näme: \"ß\",\n  ".len()),
        ];
        for ((line, column), offset) in checks {
            assert_eq!(byte_offset(text, line, column), offset, "{line}:{column}");
            assert_eq!(line_column(text, offset), (line, column), "offset {offset}");
        }
    }

    #[test]
    fn byte_offset_clamps() {
        let text = "ab\ncd";
        assert_eq!(byte_offset(text, 0, 0), 0);
        assert_eq!(byte_offset(text, 1, 99), 2, "past the line's end: the newline");
        assert_eq!(byte_offset(text, 2, 99), text.len());
        assert_eq!(byte_offset(text, 9, 1), text.len());
        assert_eq!(byte_offset("", 1, 1), 0);
        assert_eq!(line_column(text, 99), (2, 3));
        assert_eq!(line_column("é", 1), (1, 1), "inside a char");
    }

    #[test]
    fn diagnostic_line_column() {
        let (sources, id) = sources_with("a.ron", "(\n  ünit: 1,\n  bad: 2)\n");
        let offset = "(\n  ünit: 1,\n  ".len();
        let diagnostic = Diagnostic::error("a.ron", "x").at(id, offset..offset + 3);
        assert_eq!(diagnostic.line_column(&sources), Some((3, 3)));
        assert_eq!(Diagnostic::error("a.ron", "x").line_column(&sources), None);
    }

    #[test]
    fn rendering_shows_path_line_column_snippet_label_and_hints() {
        let text = "Scene(\n  objects: [\n    (material: \"rubyy\"),\n  ],\n)\n";
        let (sources, id) = sources_with("file.ron", text);
        let start = text.find("material").unwrap();
        let diagnostic = Diagnostic::error("file.ron", "unknown material `rubyy`")
            .at(id, start..start + "material".len())
            .with_label("not a material in this scene")
            .with_hint("did you mean `ruby`?");
        let text = render_diagnostics(&[diagnostic], &sources, false);
        assert!(text.contains("error: unknown material `rubyy`"), "{text}");
        assert!(text.contains("file.ron:3:6"), "{text}");
        assert!(text.contains("(material: \"rubyy\"),"), "{text}");
        assert!(text.contains("^^^^^^^^ not a material in this scene"), "{text}");
        assert!(text.contains("= help: did you mean `ruby`?"), "{text}");
    }

    #[test]
    fn rendering_reports_file_line_column_of_the_given_span() {
        let text = "(\n a: 1,\n b: 2,\n    c: 3,\n)";
        let (sources, id) = sources_with("file.ron", text);
        let start = byte_offset(text, 3, 5);
        let diagnostic = Diagnostic::warning("file.ron", "w").at(id, start..start + 1);
        let rendered = render_diagnostics(&[diagnostic], &sources, false);
        assert!(rendered.starts_with("warning: w"), "{rendered}");
        assert!(rendered.contains("file.ron:3:5"), "{rendered}");
    }

    #[test]
    fn rendering_without_location() {
        let sources = Sources::new();
        let diagnostics = [
            Diagnostic::error("meshes/teapot.obj", "face refers to vertex 9, there are 8")
                .with_line(12)
                .with_hint("vertex indices start at 1"),
            Diagnostic::warning("meshes/cube.obj", "material library not found"),
        ];
        let text = render_diagnostics(&diagnostics, &sources, false);
        assert!(
            text.contains("error: meshes/teapot.obj:12: face refers to vertex 9, there are 8"),
            "{text}"
        );
        assert!(text.contains("= help: vertex indices start at 1"), "{text}");
        assert!(
            text.contains("warning: meshes/cube.obj: material library not found"),
            "{text}"
        );
    }

    #[test]
    fn color_rendering_uses_ansi_escapes() {
        let (sources, id) = sources_with("c.ron", "(x: 1)");
        let diagnostic = Diagnostic::error("c.ron", "bad").at(id, 1..2);
        let text = render_diagnostics(&[diagnostic], &sources, true);
        assert!(text.contains('\u{1b}'), "{text:?}");
        assert!(text.contains("c.ron:1:2"), "{text:?}");
    }

    #[test]
    fn out_of_range_spans_do_not_panic() {
        let text = "(ä: \"é\")\n";
        let (sources, id) = sources_with("o.ron", text);
        #[allow(clippy::reversed_empty_ranges)] // One span is reversed on purpose.
        let spans = [
            0..0,
            0..1000,
            2..3, // inside `ä`
            3..2, // reversed
            text.len()..text.len(),
            text.len() + 5..text.len() + 50,
            usize::MAX - 1..usize::MAX,
        ];
        for span in spans {
            let diagnostic = Diagnostic::error("o.ron", "m").at(id, span.clone());
            let rendered = render_diagnostics(std::slice::from_ref(&diagnostic), &sources, false);
            assert!(rendered.contains("o.ron:"), "{span:?}: {rendered}");
            diagnostic.line_column(&sources);
        }
        // An id from a bigger `Sources` renders without a snippet.
        let mut bigger = Sources::new();
        bigger.add("x.ron".into(), String::new());
        let foreign = bigger.add("w.ron".into(), String::new());
        let diagnostic = Diagnostic::error("w.ron", "m").at(foreign, 0..5);
        let rendered = render_diagnostics(&[diagnostic], &sources, false);
        assert!(rendered.contains("error: w.ron: m"), "{rendered}");
        assert_eq!(sources.text(foreign), "");
        assert_eq!(sources.path(foreign), Path::new(""));
    }

    #[test]
    fn sources_find_paths() {
        let mut sources = Sources::new();
        let a = sources.add("scene.ron".into(), "()".into());
        let b = sources.add("materials.ron".into(), "{}".into());
        assert_eq!(sources.find(Path::new("materials.ron")), Some(b));
        assert_eq!(sources.find(Path::new("scene.ron")), Some(a));
        assert_eq!(sources.find(Path::new("nope.ron")), None);
        assert_eq!(sources.path(b), Path::new("materials.ron"));
        assert_eq!(sources.text(a), "()");
        assert_eq!(sources.iter().count(), 2);
    }

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)] // Only deserialised to provoke errors.
    struct Camera {
        eye: (f32, f32, f32),
        fov_y_degrees: f32,
    }

    #[derive(Debug, Deserialize)]
    #[allow(dead_code)] // Only deserialised to provoke errors.
    enum Shape {
        Sphere { segments: u32 },
        Cube,
        Obj(String),
    }

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)] // Only deserialised to provoke errors.
    struct Scene {
        camera: Camera,
        #[serde(default)]
        shapes: Vec<Shape>,
    }

    /// Parses `text` as a `Scene`, which must fail, and returns the diagnostic and its
    /// rendering.
    fn ron_diagnostic(text: &str) -> (Diagnostic, String) {
        let (sources, id) = sources_with("scene.ron", text);
        let error = ron::from_str::<Scene>(text).expect_err("the test scene must be invalid");
        let diagnostic = from_ron_error(id, &sources, &error);
        let rendered = render_diagnostics(std::slice::from_ref(&diagnostic), &sources, false);
        (diagnostic, rendered)
    }

    fn spanned_text<'a>(text: &'a str, diagnostic: &Diagnostic) -> &'a str {
        let (_, span) = diagnostic.location.clone().unwrap();
        &text[span]
    }

    #[test]
    fn ron_unknown_field_lists_expected_fields() {
        let text = "Scene(\n  camera: Camera(\n    eye: (0, 0, 5),\n    fov_y_degree: 45,\n  ),\n)";
        let (diagnostic, rendered) = ron_diagnostic(text);
        assert_eq!(diagnostic.message, "unknown field `fov_y_degree` in `Camera`");
        assert_eq!(spanned_text(text, &diagnostic), "fov_y_degree");
        assert_eq!(diagnostic.line_column(&ron_sources(text)), Some((4, 5)));
        assert!(
            diagnostic
                .hints
                .contains(&"expected one of: `eye`, `fov_y_degrees`".to_owned()),
            "{:?}",
            diagnostic.hints
        );
        assert!(
            diagnostic
                .hints
                .contains(&"did you mean `fov_y_degrees`?".to_owned()),
            "{:?}",
            diagnostic.hints
        );
        assert!(rendered.contains("scene.ron:4:5"), "{rendered}");
        assert!(
            rendered.contains("= help: expected one of: `eye`, `fov_y_degrees`"),
            "{rendered}"
        );
    }

    fn ron_sources(text: &str) -> Sources {
        sources_with("scene.ron", text).0
    }

    #[test]
    fn ron_unknown_variant_lists_expected_variants() {
        let text = "Scene(camera: Camera(eye: (0, 0, 5), fov_y_degrees: 45), shapes: [Cub])";
        let (diagnostic, _) = ron_diagnostic(text);
        assert_eq!(diagnostic.message, "unknown variant `Cub` in `Shape`");
        assert_eq!(spanned_text(text, &diagnostic), "Cub");
        assert_eq!(
            diagnostic.hints,
            ["did you mean `Cube`?", "expected one of: `Sphere`, `Cube`, `Obj`"]
        );
    }

    #[test]
    fn ron_missing_field_says_what_to_add() {
        let text = "Scene(camera: Camera(eye: (0, 0, 5)))";
        let (diagnostic, _) = ron_diagnostic(text);
        assert_eq!(diagnostic.message, "missing field `fov_y_degrees` in `Camera`");
        assert_eq!(diagnostic.hints, ["add `fov_y_degrees: ...`"]);
        // ron points at the `)` that closes the struct.
        assert_eq!(diagnostic.location.unwrap().1, text.len() - 2..text.len() - 2);
    }

    #[test]
    fn ron_wrong_struct_name() {
        let text = "Scene(camera: Cam(eye: (0, 0, 5), fov_y_degrees: 45))";
        let (diagnostic, _) = ron_diagnostic(text);
        assert_eq!(diagnostic.message, "expected `Camera(...)`, found `Cam(...)`");
        assert_eq!(spanned_text(text, &diagnostic), "Cam");
    }

    #[test]
    fn ron_trailing_characters() {
        let text = "Scene(camera: Camera(eye: (0, 0, 5), fov_y_degrees: 45))\n)";
        let (diagnostic, rendered) = ron_diagnostic(text);
        assert_eq!(diagnostic.message, "unexpected text after the end of the scene");
        assert!(rendered.contains("scene.ron:2:1"), "{rendered}");
    }

    #[test]
    fn ron_unclosed_bracket_at_end_of_file() {
        let text = "Scene(camera: Camera(eye: (0, 0, 5), fov_y_degrees: 45)\n";
        let (diagnostic, rendered) = ron_diagnostic(text);
        assert_eq!(diagnostic.message, "unexpected end of file");
        // After the last token, not on the empty line after the final newline.
        assert!(rendered.contains("scene.ron:1:56"), "{rendered}");
        assert!(
            diagnostic.hints.iter().any(|hint| hint.contains("missing `)`")),
            "{diagnostic:?}"
        );
    }

    #[test]
    fn ron_short_tuple() {
        let text = "Scene(camera: Camera(eye: (0, 5), fov_y_degrees: 45))";
        let (diagnostic, _) = ron_diagnostic(text);
        assert_eq!(diagnostic.message, "expected a tuple of size 3, found 2");
        assert_eq!(diagnostic.hints, ["write all three components: `(x, y, z)`"]);
    }

    #[test]
    fn ron_other_errors_keep_ron_wording() {
        let text = "Scene(camera: Camera(eye: (0, 0, 5), fov_y_degrees: \"wide\"))";
        let (diagnostic, rendered) = ron_diagnostic(text);
        assert_eq!(diagnostic.message, "expected float");
        assert!(rendered.contains("scene.ron:1:"), "{rendered}");
    }

    #[test]
    fn edit_distance_counts_edits() {
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("Sphere", "sphere"), 0);
        assert_eq!(
            did_you_mean("colour", &["color", "position"]).as_deref(),
            Some("did you mean `color`?")
        );
        assert_eq!(did_you_mean("xyz", &["color", "position"]), None);
    }
}
