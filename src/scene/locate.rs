//! Finds where a value sits in RON source text, so that problems found after parsing can
//! point at a line and column.
//!
//! ron reports positions for syntax and type errors only. The loader finds the rest (an
//! unknown material name, a NaN colour, a mesh file that does not exist) on the
//! deserialised values, which carry no positions (ron has no `Spanned<T>`, and wrapping every
//! format type would make them noisy anyway). Instead the loader
//! remembers the *path* of a value (`objects[2].material`) and asks [`locate`] for its byte
//! range in the text, which a [`crate::diag::Diagnostic`] then points at.
//!
//! The walker is a small tolerant tokenizer plus a recursive reader of RON's value grammar:
//! strings (escaped, raw, byte), chars, numbers (`1e400`, `-inf`, `NaN`, hex), identifiers,
//! `(...)` structs, tuples and variants (named or not), `[...]` lists, `{...}` maps, trailing
//! commas, nested block comments and `#![enable(...)]` attributes. It does not check types
//! or reject everything ron would; it only has to find values in files ron has already
//! accepted, and to give up (return `None`) on anything it cannot read. It never panics and
//! always terminates: every loop consumes a token, and nesting is capped at 128 levels (ron's
//! default recursion limit).
//!
//! Rejected: re-parsing into `ron::Value` (it keeps no positions) and positions recorded
//! during deserialisation (serde has no hook for them).

use std::ops::Range;

/// One step of a path from the top-level value to the value of interest.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum PathSegment {
    /// The field `name: ...` of a struct-like `( ... )`, named or not, or of a struct
    /// variant such as `Spot(position: ...)`.
    Field(String),
    /// The i-th element of a list `[ ... ]`, or the i-th positional element of a tuple or
    /// tuple variant: `Index(0)` of `Obj("a.obj")` is `"a.obj"`.
    Index(usize),
    /// The value of the map entry `{ "key": value }` whose key is this string (or whose
    /// unquoted key is this text, e.g. an enum variant). When a key is repeated, the last
    /// entry, which is the one ron's map deserialisation keeps.
    Key(String),
}

impl PathSegment {
    /// A [`PathSegment::Key`].
    pub fn key(key: impl Into<String>) -> Self {
        PathSegment::Key(key.into())
    }
}

impl From<&str> for PathSegment {
    /// A string is a field name.
    fn from(name: &str) -> Self {
        PathSegment::Field(name.to_owned())
    }
}

impl From<String> for PathSegment {
    /// A string is a field name.
    fn from(name: String) -> Self {
        PathSegment::Field(name)
    }
}

impl From<usize> for PathSegment {
    /// A number is an index.
    fn from(index: usize) -> Self {
        PathSegment::Index(index)
    }
}

/// Builds a `[PathSegment; N]`: string literals are fields, numbers are indices, and any
/// [`PathSegment`] (e.g. [`PathSegment::key`]) is taken as is.
///
/// ```
/// use lampshade::ron_path;
/// use lampshade::scene::locate::{PathSegment, locate};
///
/// let source = r#"(objects: [(material: "ruby")], materials: { "ruby": (shininess: 1) })"#;
/// let range = locate(source, &ron_path!["objects", 0, "material"]).unwrap();
/// assert_eq!(&source[range], r#""ruby""#);
/// let range = locate(source, &ron_path!["materials", PathSegment::key("ruby")]).unwrap();
/// assert_eq!(&source[range], "(shininess: 1)");
/// ```
#[macro_export]
macro_rules! ron_path {
    ($($segment:expr),* $(,)?) => {
        [$($crate::scene::locate::PathSegment::from($segment)),*]
    };
}

/// How deeply brackets may nest before the walker gives up, so that hostile input cannot
/// overflow the stack.
const MAX_DEPTH: usize = 128;

/// Byte range of the value found by following `path` from the top-level value of `source`,
/// or `None` when there is no such value or the text cannot be read that far.
///
/// The range covers the whole value: `(0.1, 0.2, NaN)`, `"ruby"` with its quotes,
/// `Sphere(segments: 180)` with its name. `Some(...)` is transparent to paths.
pub fn locate(source: &str, path: &[PathSegment]) -> Option<Range<usize>> {
    let mut walker = Walker::new(source);
    walker.skip_attributes()?;
    walker.seek(path)?;
    walker.skip_value()
}

/// Byte range of the *key* of the entry `key` in the map at `path_to_map`, the last such
/// entry when the key is repeated (the one whose value ron keeps).
pub fn locate_key(source: &str, path_to_map: &[PathSegment], key: &str) -> Option<Range<usize>> {
    locate_keys(source, path_to_map, key).pop()
}

/// Byte ranges of every key `key` in the map at `path_to_map`, in source order: for
/// messages such as "material `ruby` is defined twice (first at 3:5)". Empty when there is
/// no such map or key.
pub fn locate_keys(source: &str, path_to_map: &[PathSegment], key: &str) -> Vec<Range<usize>> {
    let mut walker = Walker::new(source);
    let entries = walker
        .skip_attributes()
        .and_then(|()| walker.seek(path_to_map))
        .and_then(|()| walker.next())
        .filter(|open| open.kind == Kind::Open(b'{'))
        .and_then(|_| walker.group_entries(b'}'))
        .unwrap_or_default();
    entries
        .iter()
        .filter(|entry| walker.key_matches(entry, key))
        .filter_map(|entry| entry.key.clone())
        .collect()
}

/// What surrounds a position in RON text that ron rejected, read from the start of the text up
/// to the position: enough to reword a syntax or type error in the user's terms ("`attenuation`
/// has named fields") without knowing what follows, which is broken.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Surroundings {
    /// The innermost bracket still open at the position.
    pub group: Option<OpenGroup>,
    /// The field whose value is being written at the position: the pending `name:` in a
    /// `( )`; for a list element or a map value, the field holding the list or map. `None`
    /// where a field name or map key is expected, and at the top level.
    pub value_of: Option<String>,
    /// The token just before the position, and the one before that.
    pub previous: Option<Range<usize>>,
    pub before_previous: Option<Range<usize>>,
    /// The token at (or just after) the position, when one can be read there.
    pub token: Option<Range<usize>>,
}

/// A bracket opened before a position and not yet closed there.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OpenGroup {
    /// `(`, `[` or `{`.
    pub bracket: char,
    /// Byte offset of the bracket.
    pub open: usize,
    /// The name written before a `(`: `Sphere` in `Sphere(`, `Scene` in `Scene(`.
    pub name: Option<String>,
    /// The field whose value the group is (`attenuation` for `attenuation: (`); for a list
    /// element or map value, the field holding the list or map (`lights` for `lights: [(`).
    pub holder: Option<String>,
    /// Inside a `{ }`: whether the position is in a value (after the key's `:`).
    after_colon: bool,
    /// Inside a `( )`: the field whose `name:` came last since the last `,`.
    pending: Option<String>,
}

impl OpenGroup {
    fn value_of(&self) -> Option<String> {
        match self.bracket {
            '(' => self.pending.clone(),
            '[' => self.holder.clone(),
            _ => self.after_colon.then(|| self.holder.clone()).flatten(),
        }
    }
}

/// Reads `source` up to byte `offset` and says what surrounds it (see [`Surroundings`]).
/// Reading stops early at anything the tokenizer cannot read; nesting is followed to any depth
/// (the stack is a `Vec`, not recursion).
pub fn surroundings(source: &str, offset: usize) -> Surroundings {
    let mut stack: Vec<OpenGroup> = Vec::new();
    let mut previous: Option<Token> = None;
    let mut before_previous: Option<Token> = None;
    let mut pos = 0;
    let text = |token: Token| source.get(token.range()).unwrap_or("").to_owned();
    while let Some(token) = lex(source, pos).filter(|token| token.start < offset) {
        match token.kind {
            Kind::Open(bracket) => {
                let name = previous
                    .filter(|p| p.kind == Kind::Ident && bracket == b'(')
                    .map(text);
                let holder = stack.last().and_then(OpenGroup::value_of);
                stack.push(OpenGroup {
                    bracket: char::from(bracket),
                    open: token.start,
                    // `Some(x)` is transparent: `x` is the value of the same field.
                    name: name.filter(|n| n != "Some"),
                    holder,
                    after_colon: false,
                    pending: None,
                });
            }
            Kind::Close(_) => {
                stack.pop();
            }
            Kind::Colon => {
                if let Some(group) = stack.last_mut() {
                    match (group.bracket, previous) {
                        ('(', Some(p)) if p.kind == Kind::Ident => {
                            group.pending = Some(strip_raw(&text(p)).to_owned());
                        }
                        ('{', _) => group.after_colon = true,
                        _ => {}
                    }
                }
            }
            Kind::Comma => {
                if let Some(group) = stack.last_mut() {
                    group.pending = None;
                    group.after_colon = false;
                }
            }
            _ => {}
        }
        before_previous = previous;
        previous = Some(token);
        pos = token.end;
    }
    Surroundings {
        value_of: stack.last().and_then(OpenGroup::value_of),
        group: stack.pop(),
        previous: previous.map(|t| t.range()),
        before_previous: before_previous.map(|t| t.range()),
        token: lex(source, offset).map(|t| t.range()),
    }
}

/// Where the fields of the top-level struct begin: the byte just after its `(` (past an optional
/// name such as `Scene`), and where its first field starts, if it has one; `None` when the text
/// does not begin (after comments and attributes) with a `( )` struct. For inserting a field the
/// text does not have yet.
pub fn top_level_fields(source: &str) -> Option<(usize, Option<usize>)> {
    let mut walker = Walker::new(source);
    walker.skip_attributes()?;
    let mut open = walker.next()?;
    if open.kind == Kind::Ident {
        open = walker.next()?;
    }
    if open.kind != Kind::Open(b'(') {
        return None;
    }
    let first = walker.peek()?;
    let first_field = (first.kind != Kind::Close(b')')).then_some(first.start);
    Some((open.end, first_field))
}

/// The field names written in the `( )` group whose `(` is at byte `open`, in order (what an
/// editor leaves out of the fields it offers); `None` when the group cannot be read to its end.
pub fn fields_in_group(source: &str, open: usize) -> Option<Vec<String>> {
    let mut walker = Walker::new(source);
    walker.pos = open;
    if walker.next()?.kind != Kind::Open(b'(') {
        return None;
    }
    let entries = walker.group_entries(b')')?;
    let names = entries
        .iter()
        .filter_map(|entry| entry.key.clone())
        .filter_map(|key| source.get(key))
        .map(|name| strip_raw(name).to_owned())
        .collect();
    Some(names)
}

/// The byte range of the value that starts at `offset` (`(0, 0.1, 0)`, `"a"`, `Sphere(...)`),
/// and the ranges of its positional elements when it is a bracketed group without field names.
pub fn value_and_elements(source: &str, offset: usize) -> Option<(Range<usize>, Vec<Range<usize>>)> {
    let mut walker = Walker::new(source);
    walker.pos = offset;
    let range = walker.skip_value()?;
    let text = &source[range.clone()];
    let elements = (0..)
        .map_while(|i| locate(text, &[PathSegment::Index(i)]))
        .map(|element| range.start + element.start..range.start + element.end)
        .collect();
    Some((range, elements))
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// `(`, `[` or `{`.
    Open(u8),
    /// `)`, `]` or `}`.
    Close(u8),
    Comma,
    Colon,
    /// A string or byte string, escaped or raw.
    Str,
    /// An identifier, possibly raw (`r#type`): names, variants, `true`, `None`, `inf`...
    Ident,
    /// A number or a char: a value on its own that no path can enter.
    Literal,
    /// `#` or `!` (only in attributes).
    Punct(u8),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Token {
    kind: Kind,
    start: usize,
    end: usize,
}

impl Token {
    fn range(&self) -> Range<usize> {
        self.start..self.end
    }
}

/// One element of a bracketed group.
struct Entry {
    /// The field name (in `( )`) or the key (in `{ }`), if the element has one.
    key: Option<Range<usize>>,
    /// Where the value starts.
    value_start: usize,
}

/// A cursor over `source` that reads tokens on demand.
struct Walker<'a> {
    source: &'a str,
    /// Where the next token (or the whitespace before it) starts.
    pos: usize,
    /// Current bracket nesting, capped at [`MAX_DEPTH`].
    depth: usize,
}

impl<'a> Walker<'a> {
    fn new(source: &'a str) -> Self {
        Walker {
            source,
            pos: 0,
            depth: 0,
        }
    }

    fn peek(&self) -> Option<Token> {
        lex(self.source, self.pos)
    }

    fn next(&mut self) -> Option<Token> {
        let token = self.peek()?;
        self.pos = token.end;
        Some(token)
    }

    fn text(&self, range: Range<usize>) -> &'a str {
        self.source.get(range).unwrap_or("")
    }

    /// Skips `#![enable(...)]` attributes at the top of the file.
    fn skip_attributes(&mut self) -> Option<()> {
        while self.peek()?.kind == Kind::Punct(b'#') {
            self.next()?;
            if self.next()?.kind != Kind::Punct(b'!') || self.peek()?.kind != Kind::Open(b'[') {
                return None;
            }
            // `[enable(a, b)]` reads as a list holding one tuple variant.
            self.skip_value()?;
        }
        Some(())
    }

    /// Moves to the start of the value at `path` below the value starting here.
    fn seek(&mut self, path: &[PathSegment]) -> Option<()> {
        let Some((segment, rest)) = path.split_first() else {
            return Some(());
        };
        let mut token = self.next()?;
        // `Some(x)` is transparent; so is the name of a struct or variant.
        while token.kind == Kind::Ident {
            let after = self.peek()?;
            if after.kind != Kind::Open(b'(') {
                return None;
            }
            self.next()?;
            if self.text(token.range()) == "Some" {
                token = self.next()?;
            } else {
                token = after;
                break;
            }
        }
        let Kind::Open(open) = token.kind else {
            return None;
        };
        let entries = self.group_entries(closing(open))?;
        let entry = match (segment, open) {
            (PathSegment::Field(name), b'(') => entries.iter().find(|entry| {
                entry
                    .key
                    .clone()
                    .is_some_and(|key| strip_raw(self.text(key)) == name)
            }),
            (PathSegment::Index(index), b'(' | b'[') => {
                entries.iter().filter(|entry| entry.key.is_none()).nth(*index)
            }
            (PathSegment::Key(key), b'{') => entries.iter().rev().find(|entry| self.key_matches(entry, key)),
            _ => None,
        }?;
        self.pos = entry.value_start;
        self.seek(rest)
    }

    /// Whether a map entry's key is the string `key` (or, unquoted, the text `key`).
    fn key_matches(&self, entry: &Entry, key: &str) -> bool {
        let Some(range) = entry.key.clone() else {
            return false;
        };
        let text = self.text(range);
        match string_contents(text) {
            Some(contents) => contents == key,
            None => text == key,
        }
    }

    /// Reads one value and returns its range.
    fn skip_value(&mut self) -> Option<Range<usize>> {
        let first = self.next()?;
        let end = match first.kind {
            Kind::Str | Kind::Literal => first.end,
            Kind::Ident => match self.peek() {
                Some(Token {
                    kind: Kind::Open(b'('),
                    ..
                }) => {
                    self.next()?;
                    self.skip_group(b')')?
                }
                _ => first.end,
            },
            Kind::Open(open) => self.skip_group(closing(open))?,
            _ => return None,
        };
        Some(first.start..end)
    }

    /// Reads the rest of a group whose opening bracket was just read; returns its end.
    fn skip_group(&mut self, close: u8) -> Option<usize> {
        self.group_entries(close)?;
        Some(self.pos)
    }

    /// Reads the elements of a group whose opening bracket was just read, up to and
    /// including `close`.
    fn group_entries(&mut self, close: u8) -> Option<Vec<Entry>> {
        if self.depth >= MAX_DEPTH {
            return None;
        }
        self.depth += 1;
        let entries = self.group_entries_inner(close);
        self.depth -= 1;
        entries
    }

    fn group_entries_inner(&mut self, close: u8) -> Option<Vec<Entry>> {
        let mut entries = Vec::new();
        loop {
            let token = self.peek()?;
            if token.kind == Kind::Close(close) {
                self.next()?;
                return Some(entries);
            }
            let key = match close {
                b')' if token.kind == Kind::Ident && lex(self.source, token.end)?.kind == Kind::Colon => {
                    self.next()?;
                    self.next()?;
                    Some(token.range())
                }
                b'}' => {
                    let key = self.skip_value()?;
                    if self.next()?.kind != Kind::Colon {
                        return None;
                    }
                    Some(key)
                }
                _ => None,
            };
            let value_start = self.peek()?.start;
            self.skip_value()?;
            entries.push(Entry { key, value_start });
            match self.next()?.kind {
                Kind::Comma => {}
                Kind::Close(found) if found == close => return Some(entries),
                _ => return None,
            }
        }
    }
}

fn closing(open: u8) -> u8 {
    match open {
        b'(' => b')',
        b'[' => b']',
        _ => b'}',
    }
}

fn strip_raw(identifier: &str) -> &str {
    identifier.strip_prefix("r#").unwrap_or(identifier)
}

/// The next token at or after `pos`, skipping whitespace and comments; `None` at the end of
/// the text or on anything unreadable (an unclosed string or comment, a stray character).
fn lex(source: &str, pos: usize) -> Option<Token> {
    let bytes = source.as_bytes();
    let start = skip_trivia(source, pos)?;
    let &first = bytes.get(start)?;
    let at = |i: usize| bytes.get(i).copied().unwrap_or(0);
    let token = |kind, end| Some(Token { kind, start, end });
    match first {
        b'(' | b'[' | b'{' => token(Kind::Open(first), start + 1),
        b')' | b']' | b'}' => token(Kind::Close(first), start + 1),
        b',' => token(Kind::Comma, start + 1),
        b':' => token(Kind::Colon, start + 1),
        b'#' | b'!' => token(Kind::Punct(first), start + 1),
        b'"' => token(Kind::Str, end_of_string(bytes, start + 1)?),
        b'\'' => token(Kind::Literal, end_of_char(bytes, start + 1)?),
        b'b' if at(start + 1) == b'"' => token(Kind::Str, end_of_string(bytes, start + 2)?),
        b'b' if at(start + 1) == b'\'' => token(Kind::Literal, end_of_char(bytes, start + 2)?),
        b'b' if at(start + 1) == b'r' && matches!(at(start + 2), b'"' | b'#') => {
            token(Kind::Str, end_of_raw_string(bytes, start + 2)?)
        }
        b'r' if at(start + 1) == b'"' || (at(start + 1) == b'#' && at(start + 2) != b'#') => {
            match end_of_raw_string(bytes, start + 1) {
                Some(end) => token(Kind::Str, end),
                // `r#name`, a raw identifier.
                None if at(start + 1) == b'#' => match end_of_identifier(source, start + 2) {
                    end if end > start + 2 => token(Kind::Ident, end),
                    _ => None,
                },
                None => None,
            }
        }
        b'r' if at(start + 1) == b'#' => token(Kind::Str, end_of_raw_string(bytes, start + 1)?),
        b'0'..=b'9' | b'.' | b'+' | b'-' => token(Kind::Literal, end_of_number(source, start)?),
        _ => match end_of_identifier(source, start) {
            end if end > start => token(Kind::Ident, end),
            _ => None,
        },
    }
}

/// Skips whitespace, `//` comments and nested `/* */` comments; `None` on an unclosed block
/// comment.
fn skip_trivia(source: &str, mut pos: usize) -> Option<usize> {
    let bytes = source.as_bytes();
    loop {
        let rest = source.get(pos..)?;
        let trimmed = rest.trim_start();
        pos += rest.len() - trimmed.len();
        if trimmed.starts_with("//") {
            pos += trimmed.find('\n').unwrap_or(trimmed.len());
        } else if trimmed.starts_with("/*") {
            let mut depth = 0usize;
            loop {
                match (bytes.get(pos), bytes.get(pos + 1)) {
                    (Some(b'/'), Some(b'*')) => {
                        depth += 1;
                        pos += 2;
                    }
                    (Some(b'*'), Some(b'/')) => {
                        depth -= 1;
                        pos += 2;
                        if depth == 0 {
                            break;
                        }
                    }
                    (Some(_), _) => pos += 1,
                    (None, _) => return None,
                }
            }
        } else {
            return Some(pos);
        }
    }
}

/// The end of an escaped string whose contents start at `pos` (just after the `"`).
fn end_of_string(bytes: &[u8], mut pos: usize) -> Option<usize> {
    loop {
        match bytes.get(pos)? {
            b'\\' => pos += 2,
            b'"' => return Some(pos + 1),
            _ => pos += 1,
        }
    }
}

/// The end of a char literal whose contents start at `pos` (just after the `'`).
fn end_of_char(bytes: &[u8], pos: usize) -> Option<usize> {
    let mut end = pos;
    loop {
        match bytes.get(end)? {
            b'\\' => end += 2,
            b'\'' if end > pos => return Some(end + 1),
            b'\n' => return None,
            _ => end += 1,
        }
    }
}

/// The end of a raw string `#*"..."#*` starting at `pos` (just after the `r`).
fn end_of_raw_string(bytes: &[u8], pos: usize) -> Option<usize> {
    let hashes = bytes.get(pos..)?.iter().take_while(|&&b| b == b'#').count();
    let contents = pos + hashes;
    if bytes.get(contents) != Some(&b'"') {
        return None;
    }
    let mut closing = Vec::with_capacity(hashes + 1);
    closing.push(b'"');
    closing.resize(hashes + 1, b'#');
    let rest = bytes.get(contents + 1..)?;
    let found = rest
        .windows(closing.len())
        .position(|window| window == closing.as_slice())?;
    Some(contents + 1 + found + closing.len())
}

/// The end of a number (`12`, `-0.5e-3`, `0xFF`, `1_000`, `-inf`, `NaN`) starting at `pos`.
fn end_of_number(source: &str, pos: usize) -> Option<usize> {
    let bytes = source.as_bytes();
    let mut end = pos;
    if matches!(bytes.get(end), Some(b'+' | b'-')) {
        end += 1;
    }
    let digits_start = end;
    let hex = bytes
        .get(end..end + 2)
        .is_some_and(|p| p.eq_ignore_ascii_case(b"0x"));
    while let Some(&b) = bytes.get(end) {
        let exponent_sign =
            matches!(b, b'+' | b'-') && !hex && end > digits_start && matches!(bytes[end - 1], b'e' | b'E');
        if b.is_ascii_alphanumeric() || b == b'_' || b == b'.' || exponent_sign {
            end += 1;
        } else {
            break;
        }
    }
    (end > digits_start).then_some(end)
}

/// The end of an identifier starting at `pos` (equal to `pos` if there is none).
fn end_of_identifier(source: &str, pos: usize) -> usize {
    let Some(rest) = source.get(pos..) else {
        return pos;
    };
    let mut chars = rest.char_indices();
    match chars.next() {
        Some((_, c)) if c.is_alphabetic() || c == '_' => {}
        _ => return pos,
    }
    let len = chars
        .find(|&(_, c)| !(c.is_alphanumeric() || c == '_'))
        .map_or(rest.len(), |(i, _)| i);
    pos + len
}

/// The value of a string token (`"a\"b"`, `r#"a"#`), or `None` if `token` is not a string.
fn string_contents(token: &str) -> Option<String> {
    let token = token.strip_prefix('b').unwrap_or(token);
    if let Some(raw) = token.strip_prefix('r') {
        let hashes = &raw[..raw.len() - raw.trim_start_matches('#').len()];
        let inner = raw[hashes.len()..]
            .strip_prefix('"')?
            .strip_suffix(hashes)?
            .strip_suffix('"')?;
        return Some(inner.to_owned());
    }
    let inner = token.strip_prefix('"')?.strip_suffix('"')?;
    let mut value = String::with_capacity(inner.len());
    let mut chars = inner.chars();
    while let Some(c) = chars.next() {
        if c != '\\' {
            value.push(c);
            continue;
        }
        match chars.next()? {
            'n' => value.push('\n'),
            'r' => value.push('\r'),
            't' => value.push('\t'),
            '0' => value.push('\0'),
            'x' => {
                let hex: String = chars.by_ref().take(2).collect();
                value.push(char::from(u8::from_str_radix(&hex, 16).ok()?));
            }
            'u' => {
                let rest = chars.as_str().strip_prefix('{')?;
                let close = rest.find('}')?;
                let code = u32::from_str_radix(&rest[..close], 16).ok()?;
                value.push(char::from_u32(code)?);
                chars = rest[close + 1..].chars();
            }
            other => value.push(other),
        }
    }
    Some(value)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_top_level_struct_s_fields_are_found_past_comments_attributes_and_its_name() {
        let source = "#![enable(implicit_some)]\n// a scene\nScene( /* first */ objects: [])";
        let (open, first) = top_level_fields(source).unwrap();
        assert_eq!(&source[..open], "#![enable(implicit_some)]\n// a scene\nScene(");
        assert!(source[first.unwrap()..].starts_with("objects"));
        assert_eq!(top_level_fields("( )"), Some((1, None)));
        assert_eq!(top_level_fields("[1, 2]"), None);
    }

    /// Asserts that `path` leads to exactly `expected` in `source`.
    #[track_caller]
    fn check(source: &str, path: &[PathSegment], expected: &str) {
        let range = locate(source, path).unwrap_or_else(|| panic!("{path:?} not found in:\n{source}"));
        assert_eq!(&source[range], expected, "path {path:?}");
    }

    #[track_caller]
    fn check_missing(source: &str, path: &[PathSegment]) {
        assert_eq!(locate(source, path), None, "path {path:?}");
    }

    const SCENE: &str = r##"#![enable(implicit_some)]
// A scene (with a comment holding "quotes" and parens: ())
Scene(
    image: (width: 640, height: 480, background: (0.1, 0.2, NaN)),
    camera: Camera(
        eye: (0, 0, -1e400),
        projection: Perspective(fov_y_degrees: 45, near: 0.1, far: inf),
    ),
    /* block /* nested ) */ comment " */
    lights: [
        Directional(direction: (0, -1, 0), color: (1, 1, 1)),
        Spot(position: (1, 2, 3), cutoff_degrees: -inf, attenuation: Some((constant: 1))),
    ],
    materials: {
        "ruby": (diffuse: (0.6, 0.05, 0.05), note: "a ) paren // not a comment"),
        r#"jade"#: (diffuse: (0, 1, 0x1F)),
        "caf\u{e9} \"x\"": (diffuse: (1, 1, 1)),
    },
    objects: [
        (mesh: Sphere(segments: 180), material: "ruby", shading: Flat,),
        (mesh: Obj("meshes/teapot.obj"), material: 'x', r#type: 1_000),
        (mesh: Cube, material: Some("jade"), transform: Some([(1, 2), (3, 4)])),
    ],
)
"##;

    #[test]
    fn the_sample_scene_is_valid_ron() {
        ron::from_str::<ron::Value>(SCENE).unwrap();
    }

    #[test]
    fn top_level_value_after_attributes_and_comments() {
        let found = locate(SCENE, &[]).unwrap();
        assert!(SCENE[found.clone()].starts_with("Scene(\n    image"));
        assert!(SCENE[found].ends_with("],\n)"));
    }

    #[test]
    fn nested_structs() {
        check(SCENE, &ron_path!["image", "width"], "640");
        check(SCENE, &ron_path!["camera", "eye"], "(0, 0, -1e400)");
        check(
            SCENE,
            &ron_path!["camera", "projection"],
            "Perspective(fov_y_degrees: 45, near: 0.1, far: inf)",
        );
        check(SCENE, &ron_path!["camera", "projection", "far"], "inf");
    }

    #[test]
    fn tuple_components() {
        check(SCENE, &ron_path!["image", "background", 2], "NaN");
        check(SCENE, &ron_path!["camera", "eye", 2], "-1e400");
        check(SCENE, &ron_path!["lights", 0, "direction", 1], "-1");
    }

    #[test]
    fn list_indices() {
        check(
            SCENE,
            &ron_path!["lights", 0],
            "Directional(direction: (0, -1, 0), color: (1, 1, 1))",
        );
        check(SCENE, &ron_path!["objects", 2, "mesh"], "Cube");
        check(SCENE, &ron_path!["objects", 0, "shading"], "Flat");
        check_missing(SCENE, &ron_path!["objects", 3]);
    }

    #[test]
    fn enum_variants() {
        check(SCENE, &ron_path!["objects", 0, "mesh"], "Sphere(segments: 180)");
        check(SCENE, &ron_path!["objects", 0, "mesh", "segments"], "180");
        check(
            SCENE,
            &ron_path!["objects", 1, "mesh", 0],
            "\"meshes/teapot.obj\"",
        );
        check(SCENE, &ron_path!["lights", 1, "cutoff_degrees"], "-inf");
        check_missing(SCENE, &ron_path!["objects", 2, "mesh", 0]);
    }

    #[test]
    fn some_is_transparent() {
        check(SCENE, &ron_path!["lights", 1, "attenuation", "constant"], "1");
        check(
            SCENE,
            &ron_path!["lights", 1, "attenuation"],
            "Some((constant: 1))",
        );
        check(SCENE, &ron_path!["objects", 2, "material"], "Some(\"jade\")");
        check(SCENE, &ron_path!["objects", 2, "transform", 1, 0], "3");
    }

    #[test]
    fn map_keys() {
        check(
            SCENE,
            &ron_path!["materials", PathSegment::key("ruby"), "diffuse", 1],
            "0.05",
        );
        check(
            SCENE,
            &ron_path!["materials", PathSegment::key("jade"), "diffuse", 2],
            "0x1F",
        );
        check(
            SCENE,
            &ron_path!["materials", PathSegment::key("café \"x\""), "diffuse"],
            "(1, 1, 1)",
        );
        check_missing(SCENE, &ron_path!["materials", PathSegment::key("emerald")]);
        check_missing(SCENE, &ron_path!["materials", "ruby"]);
        assert_eq!(
            locate_key(SCENE, &ron_path!["materials"], "jade").map(|r| &SCENE[r]),
            Some("r#\"jade\"#")
        );
        assert_eq!(locate_key(SCENE, &ron_path!["materials"], "opal"), None);
        assert_eq!(locate_key(SCENE, &ron_path!["objects"], "ruby"), None);
    }

    #[test]
    fn repeated_map_key_means_the_last_entry() {
        let source = r#"{ "a": 1, "b": 2, "a": 3 }"#;
        check(source, &[PathSegment::key("a")], "3");
        assert_eq!(locate_keys(source, &[], "a"), [2..5, 18..21]);
        assert_eq!(locate_key(source, &[], "a"), Some(18..21));
        assert_eq!(locate_keys(source, &[], "c"), []);
        let unquoted = "{ Red: 1, Green: 2 }";
        check(unquoted, &[PathSegment::key("Green")], "2");
    }

    #[test]
    fn strings_and_comments_with_brackets_and_quotes() {
        check(
            SCENE,
            &ron_path!["materials", PathSegment::key("ruby"), "note"],
            r#""a ) paren // not a comment""#,
        );
        // The block comment between `camera` and `lights` holds `)` and `"`.
        check(SCENE, &ron_path!["lights", 1, "position", 0], "1");
        check(SCENE, &ron_path!["objects", 1, "material"], "'x'");
        check(SCENE, &ron_path!["objects", 1, "type"], "1_000");
        let source = "( a: r##\"x\"#)\"## , b: 'a', c: '\\'', d: b\"\\\"\", e: br#\")\"#, f: 2 )";
        check(source, &ron_path!["a"], "r##\"x\"#)\"##");
        check(source, &ron_path!["c"], "'\\''");
        check(source, &ron_path!["e"], "br#\")\"#");
        check(source, &ron_path!["f"], "2");
    }

    #[test]
    fn anonymous_and_trailing_commas() {
        check("(a: (b: [1, 2, 3,],),)", &ron_path!["a", "b", 2], "3");
        check("(1, (2, 3), [4])", &ron_path![1, 1], "3");
        check("[]", &[], "[]");
        check("  42  ", &[], "42");
        check_missing("[]", &ron_path![0]);
        check_missing("(a: 1)", &ron_path!["b"]);
        check_missing("(a: 1)", &ron_path!["a", "b"]);
        check_missing("(a: 1)", &ron_path![0]);
        check_missing("[1]", &ron_path!["a"]);
    }

    #[test]
    fn numbers() {
        let source = "[1e400, -1.5e-3, +2, .5, 0xFF, 0b101, -inf, NaN, 1_000.0]";
        let expected = [
            "1e400", "-1.5e-3", "+2", ".5", "0xFF", "0b101", "-inf", "NaN", "1_000.0",
        ];
        for (index, expected) in expected.into_iter().enumerate() {
            check(source, &ron_path![index], expected);
        }
    }

    #[test]
    fn garbage_and_truncated_input_give_none_without_panicking() {
        let path = ron_path!["objects", 2, "transform", 1, 0];
        for end in 0..=SCENE.len() {
            if let Some(prefix) = SCENE.get(..end) {
                let _ = locate(prefix, &path);
                let _ = locate(prefix, &[]);
                let _ = locate_key(prefix, &ron_path!["materials"], "ruby");
            }
        }
        // Every suffix too: starts in the middle of strings and comments.
        for start in 0..=SCENE.len() {
            if let Some(suffix) = SCENE.get(start..) {
                let _ = locate(suffix, &path);
            }
        }
        let garbage = [
            "",
            "(",
            ")",
            "[(])",
            "(a: )",
            "(a 1)",
            "{ 1 }",
            "{ \"a\" 1 }",
            "\"unclosed",
            "/* unclosed",
            "/* /* */",
            "r#\"x\"",
            "'",
            "'\n'",
            "-",
            "#",
            "#!",
            "#![",
            "@",
            "(a: 1,,)",
            "b",
            "br",
            "r#",
            "r##",
            "\\",
            "(a: \"\\",
            "é(ü: 1)",
        ];
        for source in garbage {
            let _ = locate(source, &ron_path!["a"]);
            let _ = locate(source, &[]);
            let _ = locate_key(source, &[], "a");
        }
        check_missing("(a: [1, 2)", &ron_path!["a", 1]);
        let deep = "[".repeat(100_000);
        assert_eq!(locate(&deep, &[]), None);
        let deep = format!("{}{}", "[".repeat(1000), "]".repeat(1000));
        assert_eq!(locate(&deep, &[]), None, "deeper than MAX_DEPTH");
    }

    #[test]
    fn pseudo_random_bytes() {
        // A fixed linear congruential generator: reproducible, no dependency.
        let alphabet = b"()[]{},:\"'#!/*\\ \nabr0123456789.-+eE_x";
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..2000 {
            let len = (state % 40) as usize;
            let mut bytes = Vec::with_capacity(len);
            for _ in 0..len {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                bytes.push(alphabet[(state >> 33) as usize % alphabet.len()]);
            }
            let source = String::from_utf8(bytes).unwrap();
            let _ = locate(&source, &ron_path![0, "a"]);
            let _ = locate(&source, &[]);
        }
    }

    #[test]
    fn string_contents_unescapes() {
        assert_eq!(string_contents(r#""a\"b\n""#).as_deref(), Some("a\"b\n"));
        assert_eq!(string_contents(r#""\u{e9}\x41""#).as_deref(), Some("éA"));
        assert_eq!(string_contents(r###"r##"a"#b"##"###).as_deref(), Some("a\"#b"));
        assert_eq!(string_contents("r\"x\"").as_deref(), Some("x"));
        assert_eq!(string_contents("ruby").as_deref(), None);
        assert_eq!(string_contents("r#").as_deref(), None);
    }

    #[test]
    fn surroundings_name_the_field_the_variant_and_the_neighbouring_tokens() {
        let source = "(lights: [Point(position: (0, 1, 0), attenuation: (0, 0.1, 0))], materials: { \"a\": (kd: 1.5e) })";
        let at = source.find("(0, 0.1").unwrap() + 1;
        let around = surroundings(source, at);
        let group = around.group.clone().unwrap();
        assert_eq!(
            (group.bracket, group.holder.as_deref(), group.name),
            ('(', Some("attenuation"), None)
        );
        assert_eq!(around.value_of, None, "a field name is expected there");
        assert_eq!(&source[around.previous.unwrap()], "(");
        assert_eq!(&source[around.before_previous.unwrap()], ":");
        assert_eq!(&source[around.token.unwrap()], "0");
        let point = surroundings(source, source.find("(0, 1").unwrap());
        let group = point.group.unwrap();
        assert_eq!(
            (group.holder.as_deref(), group.name.as_deref()),
            (Some("lights"), Some("Point"))
        );
        assert_eq!(point.value_of.as_deref(), Some("position"));
        // A map value is held by the map's field; a list element by the list's.
        let entry = surroundings(source, source.find("(kd").unwrap());
        assert_eq!(entry.value_of.as_deref(), Some("materials"));
        let element = surroundings(source, source.find("Point").unwrap());
        assert_eq!(element.value_of.as_deref(), Some("lights"));
        // Nothing before the first token; nothing readable at all in an empty text.
        assert_eq!(surroundings(source, 0).previous, None);
        assert_eq!(surroundings("", 0), Surroundings::default());
        assert_eq!(surroundings("  // c", 6), Surroundings::default());
    }

    #[test]
    fn value_and_elements_split_a_tuple() {
        let source = "x: Sphere(64, (1, 2), \"a,b\")";
        let (range, elements) = value_and_elements(source, 3).unwrap();
        assert_eq!(&source[range], "Sphere(64, (1, 2), \"a,b\")");
        let texts: Vec<&str> = elements.into_iter().map(|e| &source[e]).collect();
        assert_eq!(texts, ["64", "(1, 2)", "\"a,b\""]);
        assert_eq!(value_and_elements(source, source.len()), None);
    }
}
