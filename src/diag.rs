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

/// What the serde types of a file expect, so that a hint can show the right form
/// (`attenuation: (constant: 0, linear: 0.1, quadratic: 0)`) instead of ron's wording
/// (`invalid std identifier "0"`). Each file kind has one (`scene::format::SCENE_SCHEMA`, the
/// suite config's); the names of the serde types never reach a message.
#[derive(Clone, Copy)]
pub struct Schema {
    /// The fields of the struct that the value of field `holder` is, or of the struct variant
    /// `name` written there (`holder: None` at the top level).
    pub fields: fn(holder: Option<&str>, name: Option<&str>) -> Option<&'static [&'static str]>,
    /// The variants of the enum that the value of field `holder` is.
    pub variants: fn(holder: &str) -> Option<&'static [&'static str]>,
    /// What the file holds, for messages about an empty file: "a scene".
    pub what: &'static str,
    /// A small complete file, for hints.
    pub example: &'static str,
}

/// Converts ron's parse or type error in `source` into a diagnostic pointing at the same
/// place, with the message reworded for scene authors and hints for the common mistakes
/// (unknown field or variant: the expected names and the closest one; missing field: what
/// to add; unclosed brackets; positional values where fields are named; parentheses after a
/// unit variant or none after a struct variant; a fraction where a whole number goes; quotes
/// around a variant or none around a string; JSON; an empty file...). Messages quote what the
/// user wrote and name the field, never ron's or serde's internal names.
pub fn from_ron_error(
    source: SourceId,
    sources: &Sources,
    error: &ron::error::SpannedError,
    schema: &Schema,
) -> Diagnostic {
    use ron::error::Error as E;

    let text = sources.text(source);
    let start = byte_offset(text, error.span.start.line, error.span.start.col);
    let end = byte_offset(text, error.span.end.line, error.span.end.col).max(start);
    let (mut start, end) = trim_span(text, start, end);
    let at_end_of_file = start >= text.trim_end().len();

    if let Some(plain) = reword_common_mistake(text, start, &error.code, schema) {
        let mut diagnostic = Diagnostic::error(sources.path(source), plain.message).at(source, plain.span);
        diagnostic.label = plain.label;
        diagnostic.hints = plain.hints;
        return diagnostic;
    }

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

/// A ron error reworded in the user's terms.
struct Reworded {
    message: String,
    label: Option<String>,
    hints: Vec<String>,
    span: Range<usize>,
}

/// The longest quote of the user's text a message shows.
const MAX_QUOTE_CHARS: usize = 40;

/// `text` as a message quotes it: in backticks, cut to [`MAX_QUOTE_CHARS`].
fn quote(text: &str) -> String {
    let mut chars = text.chars();
    let short: String = chars.by_ref().take(MAX_QUOTE_CHARS).collect();
    let ellipsis = if chars.next().is_some() { "…" } else { "" };
    format!("`{short}{ellipsis}`")
}

/// What a message says was found: "the string `"Cube"`", "`400.5`", "the end of the file".
fn describe(token: &str) -> String {
    if token.is_empty() {
        "the end of the file".to_owned()
    } else if token.starts_with('"') {
        format!("the string {}", quote(token))
    } else {
        quote(token)
    }
}

fn is_identifier(token: &str) -> bool {
    token.starts_with(|c: char| c.is_alphabetic() || c == '_')
        && token != "true"
        && token != "false"
        && !matches!(token, "inf" | "NaN")
}

fn is_number(token: &str) -> bool {
    token.starts_with(|c: char| c.is_ascii_digit() || matches!(c, '-' | '+' | '.'))
}

/// Rewords the ron errors that hand-written scenes actually produce, using what surrounds the
/// error (the field being written, the variant before a bracket, the token found). `None`
/// leaves the error to the general wording of [`from_ron_error`].
fn reword_common_mistake(
    text: &str,
    start: usize,
    code: &ron::error::Error,
    schema: &Schema,
) -> Option<Reworded> {
    use ron::error::Error as E;

    let around = crate::scene::locate::surroundings(text, start);
    let slice = |range: &Option<Range<usize>>| range.clone().and_then(|r| text.get(r)).unwrap_or("");
    // A character the tokenizer does not know (`;`, `=`) is still what was found.
    let stray = text
        .get(start..)
        .and_then(|rest| rest.chars().next())
        .filter(|c| !c.is_whitespace());
    let token_span = around
        .token
        .clone()
        .or_else(|| stray.map(|c| start..start + c.len_utf8()))
        .unwrap_or(start..start);
    let found = text.get(token_span.clone()).unwrap_or("");
    let previous = slice(&around.previous);
    let previous_span = around.previous.clone().unwrap_or(start..start);
    let field = around.value_of.as_deref();
    let reworded = |message: String, label: &str, hints: Vec<String>, span: Range<usize>| {
        Some(Reworded {
            message,
            label: (!label.is_empty()).then(|| label.to_owned()),
            hints,
            span,
        })
    };
    // "`width`" when the field is known, else "this value".
    let subject = |field: Option<&str>| field.map_or("this value".to_owned(), |f| format!("`{f}`"));

    // Nothing but whitespace and comments (a stray `/` that starts no comment is something).
    if around.previous.is_none() && around.token.is_none() && stray.is_none() {
        let content_end = text.trim_end().len();
        return reworded(
            if text.trim().is_empty() {
                "the file is empty".to_owned()
            } else {
                "the file holds only comments".to_owned()
            },
            &format!("expected {} here", schema.what),
            vec![format!(
                "{} is one value in parentheses, e.g. `{}`",
                capitalized(schema.what),
                schema.example
            )],
            content_end..content_end,
        );
    }

    // A `/` that starts neither `//` nor `/*`: ron stumbles on the character after it.
    if stray == Some('/') && !text[start..].starts_with("//") && !text[start..].starts_with("/*") {
        return reworded(
            "`/` starts no comment here".to_owned(),
            "not a comment",
            vec!["a comment is `// …` to the end of the line, or `/* … */`".to_owned()],
            start..start + 1,
        );
    }

    // The first token is not the file's `(`: JSON, a bare list, YAML-like `name: value` lines.
    if around.group.is_none() && around.previous.is_none() {
        let what = schema.what;
        let example = schema.example;
        let after = crate::scene::locate::surroundings(text, token_span.end).token;
        if found == "{" || found == "[" {
            let (kind, label) = if found == "{" {
                ("RON, not JSON", "JSON object")
            } else {
                ("RON", "a list")
            };
            return reworded(
                format!("expected `(` at the start of {what}, found {}", describe(found)),
                label,
                vec![format!(
                    "the file is {kind}: fields go in `( )` and names are not quoted, e.g. `{example}`"
                )],
                token_span,
            );
        }
        if is_identifier(found) && slice(&after) == ":" {
            return reworded(
                format!("expected `(` before `{found}:`"),
                "fields go inside `( )`",
                vec![format!(
                    "{} is one value in parentheses, e.g. `{example}`",
                    capitalized(what)
                )],
                token_span,
            );
        }
    }
    // At the end of the file something is missing; the general wording says so.
    if found.is_empty() {
        return None;
    }
    let in_parentheses = around.group.as_ref().is_some_and(|g| g.bracket == '(');

    match code {
        // A field name was expected (after `(` or `,` in a struct) and something else came.
        E::SuggestRawIdentifier(_) | E::ExpectedIdentifier | E::InvalidIdentifier(_)
            if in_parentheses && matches!(previous, "(" | ",") =>
        {
            let group = around.group.as_ref()?;
            let holder = group.holder.as_deref();
            let name = group.name.as_deref();
            let owner = name.or(holder);
            let fields = (schema.fields)(holder, name);
            let field_list =
                fields.map(|f| f.iter().map(|f| format!("`{f}`")).collect::<Vec<_>>().join(", "));
            let after = crate::scene::locate::surroundings(text, token_span.end).token;
            if found.starts_with('"') && slice(&after) == ":" {
                let bare = found.trim_matches('"');
                return reworded(
                    format!(
                        "field names are written without quotes, found {}",
                        describe(found)
                    ),
                    "no quotes here",
                    vec![format!("write `{bare}: ...`")],
                    token_span,
                );
            }
            if previous == "," && is_number(found) && is_number(slice(&around.before_previous)) {
                let whole = slice(&around.before_previous);
                return reworded(
                    format!(
                        "expected a field name after `{whole},`, found {}",
                        describe(found)
                    ),
                    "not a field name",
                    vec![format!(
                        "numbers use a decimal point: `{whole}.{found}`; `,` separates fields"
                    )],
                    token_span,
                );
            }
            let owner_text = owner.map_or("this value".to_owned(), |o| format!("`{o}`"));
            let mut hints = Vec::new();
            // The values written in order, as the fields they probably mean.
            let group_start = if name.is_some() {
                previous_span_of_name(text, group.open)
            } else {
                group.open
            };
            if let (Some(fields), Some((_, elements))) = (
                fields,
                crate::scene::locate::value_and_elements(text, group_start),
            ) && !elements.is_empty()
                && elements.len() <= fields.len()
            {
                let pairs: Vec<String> = fields
                    .iter()
                    .zip(&elements)
                    .map(|(f, e)| format!("{f}: {}", text.get(e.clone()).unwrap_or("...")))
                    .collect();
                let prefix = match (holder, name) {
                    (_, Some(name)) => name.to_owned(),
                    (Some(holder), None) => format!("{holder}: "),
                    (None, None) => String::new(),
                };
                hints.push(format!("write `{prefix}({})`", pairs.join(", ")));
            }
            match field_list {
                Some(list) => hints.push(format!("the fields of {owner_text} are {list}")),
                None => hints.push("write each field as `name: value`".to_owned()),
            }
            reworded(
                format!(
                    "{owner_text} has named fields: expected `name: value`, found {}",
                    describe(found)
                ),
                "a field name goes here",
                hints,
                token_span,
            )
        }
        // A variant name was expected.
        E::ExpectedIdentifier | E::ExpectedStructLike | E::ExpectedNamedStructLike(_)
            if field.and_then(schema.variants).is_some() && !is_identifier(previous) =>
        {
            let variants = field.and_then(schema.variants)?;
            let list = variants
                .iter()
                .map(|v| format!("`{v}`"))
                .collect::<Vec<_>>()
                .join(", ");
            let owner = subject(field);
            if found.starts_with('"') {
                let bare = found.trim_matches('"');
                let mut hints = vec![format!("write `{bare}` without quotes")];
                if !variants.contains(&bare) {
                    hints.push(format!("{owner} is one of {list}"));
                }
                return reworded(
                    format!("{owner} takes a name without quotes, found {}", describe(found)),
                    "no quotes here",
                    hints,
                    token_span,
                );
            }
            reworded(
                format!("expected the kind of {owner}, found {}", describe(found)),
                "expected a name here",
                vec![format!("{owner} is one of {list}, e.g. `{}(...)`", variants[0])],
                token_span,
            )
        }
        // After a unit variant (`Cube(`) or a number ron read as an integer (`400.5`, `400px`).
        E::ExpectedComma | E::InvalidIntegerDigit { .. } => {
            let number_span = if around.previous.as_ref().is_some_and(|p| p.end > start) {
                Some(previous_span.clone())
            } else if matches!(code, E::InvalidIntegerDigit { .. }) && is_number(found) {
                Some(token_span.clone())
            } else {
                None
            };
            if let Some(number_span) = number_span {
                let number = text.get(number_span.clone()).unwrap_or("");
                let digits_end = number
                    .char_indices()
                    .skip(1)
                    .find(|&(_, c)| !c.is_ascii_digit())
                    .map_or(number.len(), |(i, _)| i);
                let (whole, rest) = number.split_at(digits_end);
                if rest.starts_with(['.', 'e', 'E']) {
                    let integer = match number.replace('_', "").parse::<f64>() {
                        Ok(value) if value.is_finite() && value.abs() < 1e15 => format!("{}", value.trunc()),
                        _ => whole.to_owned(),
                    };
                    return reworded(
                        format!("{} is a whole number, found `{number}`", subject(field)),
                        "not a whole number",
                        vec![format!("write an integer, e.g. `{integer}`")],
                        number_span,
                    );
                }
                return reworded(
                    format!("unexpected `{rest}` after the number `{whole}`"),
                    "not part of a number",
                    vec!["numbers are written without units or suffixes".to_owned()],
                    number_span.start + digits_end..number_span.end,
                );
            }
            if found == "(" && is_identifier(previous) {
                let span =
                    crate::scene::locate::value_and_elements(text, start).map_or(token_span, |(r, _)| r);
                let field_part = field.map_or(String::new(), |f| format!("{f}: "));
                return reworded(
                    format!("`{previous}` takes no parentheses"),
                    "remove these",
                    vec![format!("write `{field_part}{previous}`")],
                    span,
                );
            }
            // A closing bracket of another kind: the group open here was never closed.
            if let Some(group) = around.group.as_ref().filter(|_| matches!(found, ")" | "]" | "}")) {
                let close = match group.bracket {
                    '(' => ')',
                    '[' => ']',
                    _ => '}',
                };
                let (line, column) = line_column(text, group.open);
                return reworded(
                    format!("expected `,` or `{close}`, found `{found}`"),
                    &format!("`{}` at {line}:{column} is not closed yet", group.bracket),
                    vec![format!(
                        "look for a missing `{close}` that closes the `{}` at {line}:{column}",
                        group.bracket
                    )],
                    token_span,
                );
            }
            let before_or_found = if stray.is_some() && around.token.is_none() {
                ", found"
            } else {
                " before"
            };
            reworded(
                format!("expected `,`{before_or_found} {}", describe(found)),
                "",
                vec!["separate fields and list elements with `,`".to_owned()],
                token_span,
            )
        }
        // A struct variant without its parentheses (`Sphere`), or a tuple or struct written
        // another way (`[0, 0, 5]`, `1`).
        E::ExpectedStructLike | E::ExpectedNamedStructLike(_)
            if around.group.is_some() || is_identifier(previous) =>
        {
            if is_identifier(previous) && matches!(found, "{" | "[") {
                return reworded(
                    format!("`{previous}` is followed by `( )`, found `{found}`"),
                    "expected `(`",
                    vec![format!(
                        "write `{previous}(...)`: RON uses parentheses for fields"
                    )],
                    token_span,
                );
            }
            if is_identifier(previous) && found != "(" {
                let example = match (schema.fields)(field, Some(previous)) {
                    Some(fields) => format!(
                        "write `{previous}()` for the defaults, or give fields: `{previous}({}: ...)`",
                        fields.first().copied().unwrap_or("name")
                    ),
                    None => format!("write `{previous}(...)`"),
                };
                return reworded(
                    format!("`{previous}` needs parentheses"),
                    "expected `(...)` after this",
                    vec![example],
                    previous_span,
                );
            }
            if found == "[" {
                let span =
                    crate::scene::locate::value_and_elements(text, start).map_or(token_span, |(r, _)| r);
                let inner = text
                    .get(span.start + 1..span.end.saturating_sub(1))
                    .unwrap_or("...");
                return reworded(
                    format!("{} is written in parentheses, found `[`", subject(field)),
                    "a list",
                    vec![format!("vectors and colours are tuples: `({inner})`")],
                    span,
                );
            }
            let owner = subject(field);
            reworded(
                format!("expected `(` to start {owner}, found {}", describe(found)),
                "expected `(`",
                vec![match (field, (schema.fields)(field, None)) {
                    (Some(f), Some(fields)) => format!("write `{f}: ({}: ...)`", fields[0]),
                    (Some(f), None) => format!("write `{f}: (...)`, e.g. `(0, 0, 1)` for a vector or colour"),
                    _ => "write `(...)`".to_owned(),
                }],
                token_span,
            )
        }
        E::ExpectedBoolean => {
            let hint = if found.eq_ignore_ascii_case("true") || found.eq_ignore_ascii_case("\"true\"") {
                "write `true`, in lowercase and without quotes"
            } else if found.eq_ignore_ascii_case("false") || found.eq_ignore_ascii_case("\"false\"") {
                "write `false`, in lowercase and without quotes"
            } else {
                "booleans are `true` or `false`"
            };
            reworded(
                format!(
                    "{} is `true` or `false`, found {}",
                    subject(field),
                    describe(found)
                ),
                "not a boolean",
                vec![hint.to_owned()],
                token_span,
            )
        }
        E::ExpectedFloat | E::ExpectedInteger => {
            let kind = if matches!(code, E::ExpectedFloat) {
                "a number"
            } else {
                "a whole number"
            };
            let mut hints = Vec::new();
            let bare = found.trim_matches('"');
            if found.starts_with('"') && is_number(bare) {
                hints.push(format!("write `{bare}` without quotes"));
            } else if found == "(" {
                hints.push("a single number has no parentheses".to_owned());
            }
            reworded(
                format!("{} is {kind}, found {}", subject(field), describe(found)),
                "not a number",
                hints,
                token_span,
            )
        }
        E::ExpectedString => {
            // The text up to the end of the value, to show it quoted.
            let bare_end = text[start..]
                .find([',', ')', ']', '}', ':', '\n'])
                .map_or(text.len(), |i| start + i);
            let bare = text.get(start..bare_end).unwrap_or("").trim_end();
            let after = crate::scene::locate::surroundings(text, token_span.end).token;
            let hint = if is_identifier(found) && slice(&after) == ":" && in_parentheses {
                let owner = around.group.as_ref().and_then(|g| g.name.clone());
                match owner {
                    Some(owner) => {
                        format!("`{owner}` takes the string alone, without a field name: `{owner}(\"...\")`")
                    }
                    None => "names and paths are strings in quotes".to_owned(),
                }
            } else if !bare.is_empty() && !bare.starts_with(['(', '[', '{']) {
                format!(
                    "strings are written in double quotes: `\"{}\"`",
                    bare.trim_matches('\'')
                )
            } else {
                "strings are written in double quotes: `\"...\"`".to_owned()
            };
            let variant = around
                .group
                .as_ref()
                .and_then(|g| g.name.as_deref())
                .filter(|_| field.is_none());
            let what = if around.group.as_ref().is_some_and(|g| g.bracket == '{') && field.is_none() {
                "a name in quotes".to_owned()
            } else if let Some(variant) = variant {
                format!("`{variant}` takes a string in quotes")
            } else {
                format!("{} is a string in quotes", subject(field))
            };
            let message = if what.starts_with('a') {
                format!("expected {what}, found {}", describe(found))
            } else {
                format!("{what}, found {}", describe(found))
            };
            reworded(message, "expected `\"...\"`", vec![hint], token_span)
        }
        E::ExpectedArray => reworded(
            format!("{} is a list in `[ ]`, found {}", subject(field), describe(found)),
            "expected `[`",
            vec![match field {
                Some(f) => format!("write `{f}: [...]`, even for one element"),
                None => "write `[...]`, even for one element".to_owned(),
            }],
            token_span,
        ),
        E::ExpectedMap => reworded(
            format!(
                "{} is a map in `{{ }}`, found {}",
                subject(field),
                describe(found)
            ),
            "expected `{`",
            vec!["write `{ \"name\": (...), ... }`".to_owned()],
            token_span,
        ),
        E::ExpectedMapColon => reworded(
            format!("expected `:`, found {}", describe(found)),
            "expected `:`",
            vec!["fields and map entries are written `name: value`".to_owned()],
            token_span,
        ),
        // `[mesh: Cube]`: the fields of an element written without its `( )`.
        E::ExpectedDifferentStructName { .. }
            if is_identifier(found)
                && slice(&crate::scene::locate::surroundings(text, token_span.end).token) == ":" =>
        {
            let element = field.map_or(String::new(), |f| format!(" of `{f}`"));
            reworded(
                format!("expected `(` before `{found}:`"),
                "fields go inside `( )`",
                vec![format!("each element{element} is written `({found}: ..., ...)`")],
                token_span,
            )
        }
        E::ExpectedStructLikeEnd | E::ExpectedArrayEnd if previous == "," && in_parentheses => reworded(
            format!(
                "expected `)` to close {}, found {}",
                subject(around.group.as_ref().and_then(|g| g.holder.as_deref())),
                describe(found)
            ),
            "one value too many",
            vec!["vectors and colours have three values: `(x, y, z)`".to_owned()],
            token_span,
        ),
        E::ExpectedAttribute if previous == "#" || found == "#" => reworded(
            "`#` does not start a comment in RON".to_owned(),
            "not a comment",
            vec!["comments are `// ...` to the end of the line, or `/* ... */`".to_owned()],
            if previous == "#" {
                previous_span
            } else {
                token_span
            },
        ),
        // A name without quotes where a string goes: ron reads `ruby` as a unit value.
        E::InvalidValueForType {
            expected,
            found: what,
        } if what == "a unit value" && is_identifier(previous) => reworded(
            format!("expected {expected}, found `{previous}`"),
            "not in quotes",
            vec![format!("names are strings: write `\"{previous}\"`")],
            previous_span,
        ),
        E::IntegerOutOfBounds => {
            let negative = text[..start].trim_end().ends_with('-');
            let span = if negative {
                text[..start].trim_end().len() - 1..token_span.end
            } else {
                token_span
            };
            let number = text.get(span.clone()).unwrap_or("");
            reworded(
                format!("`{number}` is out of range for {}", subject(field)),
                "out of range",
                vec![if negative {
                    format!("{} cannot be negative", subject(field))
                } else {
                    format!("{} is too large", quote(number))
                }],
                span,
            )
        }
        _ => None,
    }
}

/// The start of the name before the `(` at `open` (`Sphere` in `Sphere(64)`).
fn previous_span_of_name(text: &str, open: usize) -> usize {
    let before = text.get(..open).unwrap_or("").trim_end();
    let name_len = before
        .chars()
        .rev()
        .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == '#')
        .map(char::len_utf8)
        .sum::<usize>();
    before.len() - name_len
}

fn capitalized(text: &str) -> String {
    let mut chars = text.chars();
    match chars.next() {
        Some(first) => first.to_uppercase().chain(chars).collect(),
        None => String::new(),
    }
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

    /// No knowledge of the test types: the general wording and hints only.
    const TEST_SCHEMA: Schema = Schema {
        fields: |_, _| None,
        variants: |_| None,
        what: "a test scene",
        example: "(camera: (eye: (0, 0, 5), fov_y_degrees: 45))",
    };

    /// Parses `text` as a `Scene`, which must fail, and returns the diagnostic and its
    /// rendering.
    fn ron_diagnostic(text: &str) -> (Diagnostic, String) {
        let (sources, id) = sources_with("scene.ron", text);
        let error = ron::from_str::<Scene>(text).expect_err("the test scene must be invalid");
        let diagnostic = from_ron_error(id, &sources, &error, &TEST_SCHEMA);
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
    fn ron_type_errors_name_the_field_and_quote_what_was_found() {
        let text = "Scene(camera: Camera(eye: (0, 0, 5), fov_y_degrees: \"wide\"))";
        let (diagnostic, rendered) = ron_diagnostic(text);
        assert_eq!(
            diagnostic.message,
            "`fov_y_degrees` is a number, found the string `\"wide\"`"
        );
        assert_eq!(spanned_text(text, &diagnostic), "\"wide\"");
        assert!(rendered.contains("scene.ron:1:53"), "{rendered}");
    }

    /// The common mistakes, each as (text, message, a fragment of a hint, the text spanned).
    #[test]
    fn ron_common_mistakes_are_reworded_with_hints() {
        let camera = "camera: Camera(eye: (0, 0, 5), fov_y_degrees: 45)";
        let cases = [
            ("", "the file is empty", "`(camera: (eye: (0, 0, 5)", ""),
            (
                "  // nothing\n",
                "the file holds only comments",
                "A test scene is one value",
                "",
            ),
            (
                "/, / not a comment\n(camera: 1)",
                "`/` starts no comment here",
                "a comment is `// …`",
                "/",
            ),
            (
                "{\"camera\": 1}",
                "expected `(` at the start of a test scene, found `{`",
                "RON, not JSON",
                "{",
            ),
            (
                "camera: 1",
                "expected `(` before `camera:`",
                "A test scene is one value",
                "camera",
            ),
            (
                &format!("({camera}, shapes: [Cube()])"),
                "`Cube` takes no parentheses",
                "write `shapes: Cube`",
                "()",
            ),
            (
                &format!("({camera}, shapes: [Sphere(segments: 4.5)])"),
                "`segments` is a whole number, found `4.5`",
                "e.g. `4`",
                "4.5",
            ),
            (
                &format!("({camera}, shapes: [Sphere])"),
                "`Sphere` needs parentheses",
                "`Sphere(...)`",
                "Sphere",
            ),
            (
                &format!("({camera}, shapes: [Obj(teapot.obj)])"),
                "`Obj` takes a string in quotes, found `teapot`",
                "`\"teapot.obj\"`",
                "teapot",
            ),
            (
                "(camera: Camera(eye: [0, 0, 5], fov_y_degrees: 45))",
                "`eye` is written in parentheses, found `[`",
                "`(0, 0, 5)`",
                "[0, 0, 5]",
            ),
            (
                "(camera: Camera(0, 0))",
                "`Camera` has named fields: expected `name: value`, found `0`",
                "",
                "0",
            ),
            (
                "(camera: Camera(eye = (0, 0, 5)))",
                "expected `:`, found `=`",
                "`name: value`",
                "=",
            ),
            (
                "# hello\n()",
                "`#` does not start a comment in RON",
                "`// ...`",
                "#",
            ),
        ];
        for (text, message, hint, spanned) in cases {
            let (diagnostic, rendered) = ron_diagnostic(text);
            assert_eq!(diagnostic.message, message, "{text}\n{rendered}");
            assert!(
                diagnostic.hints.iter().any(|h| h.contains(hint)) && !diagnostic.hints.is_empty(),
                "{text}: hint `{hint}` in {:?}",
                diagnostic.hints
            );
            assert_eq!(spanned_text(text, &diagnostic), spanned, "{text}\n{rendered}");
            for internal in ["r#", "std identifier", "struct `", "Scene`"] {
                assert!(
                    !rendered.contains(internal),
                    "{text}: `{internal}` in\n{rendered}"
                );
            }
        }
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
