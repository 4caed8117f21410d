//! The text of an OBJ file, parsed: ranges of lines in parallel, then the faces assembled into
//! one indexed triangle list in file order. MTL files are not read here; the caller loads each
//! library when asked ([`assemble`]).
//!
//! # Design
//!
//! 1. **Ranges of lines.** The text is cut at line ends into ranges of about
//!    [`RANGE_BYTES`]. A first parallel pass counts each range's lines and its `v`, `vt` and
//!    `vn` statements; their prefix sums give every range its first line number and the number
//!    of each element defined above it. OBJ indices are 1-based, negative ones count back from
//!    the last element defined so far, and an index may only refer to an element defined above
//!    it, so with those counts every range resolves and checks its own faces.
//! 2. **Parse** ([`parse_obj_text`], the ranges in parallel). Each line is cut into words at
//!    whitespace (bytes for ASCII lines, `char::is_whitespace` otherwise, as `str::split_whitespace`
//!    does) and checked, with the line and the column of the offending word: face indices that
//!    are 0, malformed or out of range; vertex lines without three numbers or with a non-finite
//!    one, and `vt`/`vn` lines with a non-finite number (non-finite input is rejected, not
//!    repaired); `w = 0`; faces with fewer than three vertices (what a file cut off in its last
//!    face line looks like); `usemtl` without a name. The first error in file order is the
//!    error. Polygons are fanned from their first corner; polyline (`l`) and point (`p`)
//!    lines are skipped. Numbers are parsed by [`parse_f32`], whose results are `str::parse`'s
//!    bit for bit. The plain `v` and `f` lines of a scan are read in one pass
//!    ([`RangeParser::plain_statement`]), their digits eight bytes at a time.
//! 3. **Assemble** ([`assemble`], in file order). As `tobj` did with `triangulate` and
//!    `single_index`: faces are grouped into models, a new one at each `o` or `g` and at each
//!    `usemtl` that changes the material (when the current model has faces); within a model
//!    each distinct (position, texture coordinate, normal) triple is one vertex, numbered in the
//!    order its first corner is met; material names resolve against the libraries named by
//!    `mtllib` lines above them. The models are then merged into one list (the rules for texture
//!    coordinates and normals that only some vertices have are on [`ObjGeometry`]).
//!
//! **Memory.** Every page of memory the load touches for the first time is zeroed by the kernel
//! first, which on these machines costs about as much per byte as parsing it: loading a mesh of
//! a million triangles once spent more than half its time there. So the arrays that live
//! only during a load are kept small: face corners as `u32` indices, texture coordinate and
//! normal indices only from the first face that has them ([`RangeTriangles`]), materials as
//! runs, and the file's bytes freed before the faces are assembled (`obj::read_and_parse_text`).
//!
//! Statement names (`mtllib`, `usemtl`, `o`, `g`) are the rest of the line after the keyword,
//! trimmed, so they may contain spaces. `tobj` took the text after the line's first space
//! character instead, which differed for indented lines and tab separators (an indented
//! `usemtl` named a material "usemtl name", and a tab after `usemtl` failed the file).
//!
//! Rejected: `tobj`'s OBJ parser. It reads line by line through `BufRead::lines` (a `String`
//! allocated per line) on one thread, has no line numbers in its errors (so every line was
//! scanned a second time before it, for diagnostics), and keys its vertex map by three
//! `usize` through SipHash: loading the 3.4 MB koala scan took 86–125 ms, about 30 MB/s.

use std::borrow::Cow;
use std::collections::HashMap;
use std::ops::Range;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// A face corner: indices (0-based, resolved) into the file's positions, texture coordinates
/// and normals; [`ABSENT`] where the corner has no texture coordinate or normal.
pub(super) type Corner = [u32; 3];

/// The index of an element a face corner does not name.
pub(super) const ABSENT: u32 = u32::MAX;

/// About how many bytes of text one parallel task parses: large enough that a task's set-up is
/// negligible, small enough that two cores stay balanced on files of a few megabytes.
const RANGE_BYTES: usize = 256 * 1024;

/// The name tobj gave a model before any `o` or `g` line, or after one without a name.
const UNNAMED_MODEL: &str = "unnamed_object";

/// A problem found in the text: where (1-based line, and column in chars) and what.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct ScanError {
    pub line: usize,
    pub column: usize,
    pub message: String,
}

/// A statement that changes how the faces after it are grouped or which material they use.
#[derive(Debug, Clone, PartialEq)]
enum Statement {
    /// `o` or `g` with its name.
    Group(String),
    /// `usemtl` with its material name.
    UseMaterial(String),
    /// `mtllib` with the library's file name (relative to the OBJ file) and its line.
    MaterialLibrary { file: String, line: usize },
}

/// One range of lines, parsed.
#[derive(Debug, Default)]
struct ParsedRange {
    positions: Vec<Vec3>,
    texcoords: Vec<Vec2>,
    normals: Vec<Vec3>,
    triangles: RangeTriangles,
    /// Each statement with the number of this range's triangles above it.
    statements: Vec<(usize, Statement)>,
    /// The line numbers of polyline (`l`) statements.
    polyline_lines: Vec<usize>,
    /// Every `usemtl` name with its line.
    material_uses: Vec<(String, usize)>,
}

/// An OBJ text, parsed and checked but not yet grouped into models.
#[derive(Debug)]
pub(super) struct ObjText {
    /// Every `v` (divided by its `w`), `vt` (as written: v up) and `vn`, in file order.
    positions: Vec<Vec3>,
    texcoords: Vec<Vec2>,
    normals: Vec<Vec3>,
    /// Triangles and statements, range by range, in file order.
    ranges: Vec<RangeFaces>,
    /// The line numbers of polyline (`l`) statements, which are not drawn.
    pub polyline_lines: Vec<usize>,
    /// Every `usemtl` name with its line, to report names no library defines.
    pub material_uses: Vec<(String, usize)>,
}

/// The faces of one range of lines.
#[derive(Debug)]
struct RangeFaces {
    triangles: RangeTriangles,
    /// Each statement with the number of the range's triangles above it.
    statements: Vec<(usize, Statement)>,
}

/// The triangles of a range of lines, corner by corner: the position indices, and the texture
/// coordinate and normal indices only from the first triangle that has one of them on (before
/// it every corner has neither). A scan's faces name positions only: 12 bytes a triangle
/// instead of 36, on a file of a million triangles the difference between 14 and 40 MB of
/// fresh memory.
#[derive(Debug, Default)]
struct RangeTriangles {
    positions: Vec<[u32; 3]>,
    /// Texture coordinate and normal indices of each corner of the triangles from
    /// `extras_from` on.
    extras: Vec<[[u32; 2]; 3]>,
    extras_from: usize,
}

impl RangeTriangles {
    fn len(&self) -> usize {
        self.positions.len()
    }

    fn push(&mut self, triangle: [Corner; 3]) {
        let extras = triangle.map(|[_, texcoord, normal]| [texcoord, normal]);
        if !self.extras.is_empty() || extras != [[ABSENT; 2]; 3] {
            if self.extras.is_empty() {
                self.extras_from = self.positions.len();
            }
            self.extras.push(extras);
        }
        self.positions.push(triangle.map(|[position, _, _]| position));
    }

    /// Triangle `index`'s corners.
    fn corners(&self, index: usize) -> [Corner; 3] {
        let extras = match index.checked_sub(self.extras_from) {
            Some(offset) if offset < self.extras.len() => self.extras[offset],
            _ => [[ABSENT; 2]; 3],
        };
        let positions = self.positions[index];
        [0, 1, 2].map(|k| [positions[k], extras[k][0], extras[k][1]])
    }
}

impl ObjText {
    /// How many triangles the faces make.
    pub fn triangle_count(&self) -> usize {
        self.ranges.iter().map(|range| range.triangles.len()).sum()
    }

    /// Every `v`, divided by its `w`, in file order.
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// The triangles' position indices, range by range, in file order.
    pub fn triangle_positions(&self) -> Vec<&[[u32; 3]]> {
        self.ranges
            .iter()
            .map(|range| range.triangles.positions.as_slice())
            .collect()
    }
}

/// What the first pass learns about a range of lines.
#[derive(Debug, Clone, Copy, Default)]
struct RangeCounts {
    /// Line ends (`\n`) in the range.
    line_ends: usize,
    /// `v`, `vt` and `vn` statements.
    elements: [usize; 3],
    /// `f` statements: at least as many triangles.
    faces: usize,
}

/// Parses and checks the OBJ file `bytes` (module documentation, steps 1 and 2). The bytes
/// are read as UTF-8 with invalid sequences replaced, as `String::from_utf8_lossy` does (OBJ
/// is ASCII in practice; a stray Latin-1 byte in a comment or name should not reject the file).
pub(super) fn parse_obj_text(bytes: &[u8]) -> Result<ObjText, ScanError> {
    parse_in_ranges(bytes, RANGE_BYTES)
}

/// [`parse_obj_text`] with ranges of about `range_bytes`: the result is the same for any size.
fn parse_in_ranges(bytes: &[u8], range_bytes: usize) -> Result<ObjText, ScanError> {
    // Each range is converted to text on its own: a line end is never part of a multi-byte
    // sequence, so the ranges' replacements are the whole file's.
    let ranges: Vec<(Cow<str>, RangeCounts)> = line_ranges(bytes, range_bytes)
        .into_par_iter()
        .map(|range| {
            let bytes = &bytes[range];
            // `from_utf8` checks ASCII a word at a time; the lossy conversion walks every byte.
            let text = match std::str::from_utf8(bytes) {
                Ok(text) => Cow::Borrowed(text),
                Err(_) => String::from_utf8_lossy(bytes),
            };
            let counts = count_range(&text);
            (text, counts)
        })
        .collect();
    // Each range's first line number and the elements defined above it.
    let mut starts = Vec::with_capacity(ranges.len());
    let (mut line, mut defined) = (1, [0usize; 3]);
    for (_, range_counts) in &ranges {
        starts.push((line, defined));
        line += range_counts.line_ends;
        for (total, count) in defined.iter_mut().zip(range_counts.elements) {
            *total += count;
        }
    }
    let parsed: Vec<Result<ParsedRange, ScanError>> = ranges
        .par_iter()
        .zip(&starts)
        .map(|((text, counts), &(first_line, defined))| parse_range(text, first_line, defined, counts))
        .collect();

    let mut text = ObjText {
        positions: Vec::with_capacity(defined[0]),
        texcoords: Vec::with_capacity(defined[1]),
        normals: Vec::with_capacity(defined[2]),
        ranges: Vec::with_capacity(parsed.len()),
        polyline_lines: Vec::new(),
        material_uses: Vec::new(),
    };
    // The first error in file order wins: every range before it parsed cleanly, so the
    // element counts it was checked against are right. Later ranges may have been checked
    // against counts that include the failing line; their errors are never reported.
    for range in parsed {
        let range = range?;
        text.positions.extend_from_slice(&range.positions);
        text.texcoords.extend_from_slice(&range.texcoords);
        text.normals.extend_from_slice(&range.normals);
        text.ranges.push(RangeFaces {
            triangles: range.triangles,
            statements: range.statements,
        });
        text.polyline_lines.extend(range.polyline_lines);
        text.material_uses.extend(range.material_uses);
    }
    Ok(text)
}

/// Cuts `bytes` into ranges of whole lines of about `target` bytes (the last line of a range
/// keeps its `\n`).
fn line_ranges(bytes: &[u8], target: usize) -> Vec<Range<usize>> {
    let mut ranges = Vec::with_capacity(bytes.len() / target + 1);
    let mut start = 0;
    while start < bytes.len() {
        let wanted = (start + target).min(bytes.len());
        let end = bytes[wanted..]
            .iter()
            .position(|&byte| byte == b'\n')
            .map_or(bytes.len(), |offset| wanted + offset + 1);
        ranges.push(start..end);
        start = end;
    }
    ranges
}

/// The first pass over a range (module documentation, step 1).
fn count_range(range: &str) -> RangeCounts {
    let mut counts = RangeCounts::default();
    let mut count = |keyword: Option<&str>| match keyword {
        Some("v") => counts.elements[0] += 1,
        Some("vt") => counts.elements[1] += 1,
        Some("vn") => counts.elements[2] += 1,
        Some("f") => counts.faces += 1,
        _ => {}
    };
    if range.is_ascii() {
        for line in AsciiLines::new(range) {
            // A scan's lines, told by their first two bytes.
            let keyword = match line.as_bytes() {
                [b'v', blank, ..] if is_blank(*blank) => Some("v"),
                [b'f', blank, ..] if is_blank(*blank) => Some("f"),
                _ => AsciiWords::new(line).next(),
            };
            count(keyword);
        }
    } else {
        for line in range.lines() {
            count(line.split_whitespace().next());
        }
    }
    counts.line_ends = memchr::memchr_iter(b'\n', range.as_bytes()).count();
    counts
}

/// The lines of an ASCII text, as `str::lines` cuts them (the `\r` of a `\r\n` is left at
/// the end of its line, where it is whitespace), found with a vectorised search for `\n`.
struct AsciiLines<'a> {
    text: &'a str,
    start: usize,
    line_ends: memchr::Memchr<'a>,
}

impl<'a> AsciiLines<'a> {
    fn new(text: &'a str) -> Self {
        AsciiLines {
            text,
            start: 0,
            line_ends: memchr::memchr_iter(b'\n', text.as_bytes()),
        }
    }
}

impl<'a> Iterator for AsciiLines<'a> {
    type Item = &'a str;

    fn next(&mut self) -> Option<&'a str> {
        let start = self.start;
        let end = match self.line_ends.next() {
            Some(end) => end,
            // A last line without a line end.
            None if start < self.text.len() => self.text.len(),
            None => return None,
        };
        self.start = end + 1;
        // An ASCII text splits at any byte.
        self.text.get(start..end)
    }
}

/// The words of an ASCII line, split at whitespace as `str::split_whitespace` splits them.
struct AsciiWords<'a> {
    line: &'a str,
    position: usize,
}

impl<'a> AsciiWords<'a> {
    fn new(line: &'a str) -> Self {
        AsciiWords { line, position: 0 }
    }
}

/// The ASCII characters `char::is_whitespace` accepts (vertical tab included). Most bytes of a
/// mesh are digits, signs and points, above the space: one comparison tells them apart.
fn is_blank(byte: u8) -> bool {
    byte <= b' ' && matches!(byte, b' ' | b'\t' | b'\n' | b'\x0B' | b'\x0C' | b'\r')
}

impl<'a> Iterator for AsciiWords<'a> {
    type Item = &'a str;

    fn next(&mut self) -> Option<&'a str> {
        let bytes = self.line.as_bytes();
        let mut start = self.position;
        while start < bytes.len() && is_blank(bytes[start]) {
            start += 1;
        }
        let mut end = start;
        while end < bytes.len() && !is_blank(bytes[end]) {
            end += 1;
        }
        self.position = end;
        // An ASCII line splits at any byte.
        (end > start).then(|| self.line.get(start..end)).flatten()
    }
}

/// The rest of `line` after its first word `keyword`, trimmed: a statement's name.
fn rest_after<'a>(line: &'a str, keyword: &str) -> &'a str {
    let offset = keyword.as_ptr() as usize - line.as_ptr() as usize + keyword.len();
    line[offset..].trim()
}

/// The column (1-based, in chars) of `word`, a slice of `line`.
fn column_of(line: &str, word: &str) -> usize {
    let offset = (word.as_ptr() as usize).saturating_sub(line.as_ptr() as usize);
    1 + line.get(..offset).map_or(0, |before| before.chars().count())
}

/// Parses one range of lines (module documentation, step 2): `first_line` is its first
/// line's number and `defined` the positions, texture coordinates and normals defined above
/// it. ASCII ranges (almost all) are cut into lines and words by bytes; others as `str::lines`
/// and `str::split_whitespace` cut them.
fn parse_range(
    range: &str,
    first_line: usize,
    defined: [usize; 3],
    counts: &RangeCounts,
) -> Result<ParsedRange, ScanError> {
    // Sized by the first pass: growing them would allocate (and the kernel zero) about twice
    // the memory.
    let parsed = ParsedRange {
        positions: Vec::with_capacity(counts.elements[0]),
        texcoords: Vec::with_capacity(counts.elements[1]),
        normals: Vec::with_capacity(counts.elements[2]),
        triangles: RangeTriangles {
            positions: Vec::with_capacity(counts.faces),
            ..RangeTriangles::default()
        },
        ..ParsedRange::default()
    };
    let mut parser = RangeParser {
        parsed,
        defined,
        corners: Vec::new(),
    };
    if range.is_ascii() {
        for (index, line) in AsciiLines::new(range).enumerate() {
            // The line and the rest of the range after it.
            let start = line.as_ptr() as usize - range.as_ptr() as usize;
            if parser.plain_statement(&range.as_bytes()[start..], line.len()) {
                continue;
            }
            let mut words = AsciiWords::new(line);
            if let Some(keyword) = words.next() {
                parser.statement(keyword, &mut words, first_line + index, || line)?;
            }
        }
    } else {
        for (index, line) in range.lines().enumerate() {
            let mut words = line.split_whitespace();
            if let Some(keyword) = words.next() {
                parser.statement(keyword, &mut words, first_line + index, || line)?;
            }
        }
    }
    Ok(parser.parsed)
}

/// What [`parse_range`] has parsed so far.
struct RangeParser {
    parsed: ParsedRange,
    /// Positions, texture coordinates and normals defined above the range.
    defined: [usize; 3],
    /// The corners of the face being read.
    corners: Vec<Corner>,
}

impl RangeParser {
    /// The lines a scan is made of, `v x y z` and `f i j k…` with plain numbers and position
    /// indices, read in one pass over their bytes (each number parsed as it is found instead
    /// of cut out as a word first). `false`, with nothing read, for any other line and for one
    /// these do not read exactly as [`RangeParser::statement`] would (an index out of range, a
    /// number [`fast_f32`] leaves to `str::parse`, a `w`, fewer than three corners): it then
    /// takes the general path, which also makes its errors.
    ///
    /// The line is `text[..end]`; the rest of `text` is what follows it in the range (its line
    /// end first, if it has one), so that numbers are read eight bytes at a time up to the
    /// line's end without copying its last bytes. A line end is not part of a number, so the
    /// numbers read are the line's.
    fn plain_statement(&mut self, text: &[u8], end: usize) -> bool {
        let Some(line) = text.get(..end) else {
            return false;
        };
        match line {
            [b'v', blank, ..] if is_blank(*blank) => match plain_numbers(text, 2, end) {
                Some(position) => {
                    self.parsed.positions.push(Vec3::from_array(position));
                    true
                }
                None => false,
            },
            [b'f', blank, ..] if is_blank(*blank) => {
                let defined = self.defined[0] + self.parsed.positions.len();
                self.corners.clear();
                let mut at = 2;
                loop {
                    while at < end && is_blank(text[at]) {
                        at += 1;
                    }
                    if at == end {
                        break;
                    }
                    // One word holds an index of up to seven digits and what ends it.
                    let word = word_at(text, at) ^ (0x30 * ONES);
                    let (digits, index) = match (non_digit_bytes(word).trailing_zeros() / 8) as usize {
                        8 => leading_digits(text, at, 0),
                        digits => (digits, digits_value(word, digits)),
                    };
                    at += digits;
                    let ends_word = at == end || (at < end && is_blank(text[at]));
                    // Longer runs (leading zeros) are left to the general path.
                    if digits == 0 || digits > 18 || !ends_word || !(1..=defined as u64).contains(&index) {
                        return false;
                    }
                    self.corners.push([(index - 1) as u32, ABSENT, ABSENT]);
                }
                if self.corners.len() < 3 {
                    return false;
                }
                let first = self.corners[0];
                for pair in self.corners[1..].windows(2) {
                    self.parsed.triangles.push([first, pair[0], pair[1]]);
                }
                true
            }
            _ => false,
        }
    }

    /// One statement: its `keyword`, the `words` after it, its line's number, and its line's
    /// text (only read for names and errors).
    fn statement<'a>(
        &mut self,
        keyword: &'a str,
        words: &mut impl Iterator<Item = &'a str>,
        line_number: usize,
        line: impl Fn() -> &'a str,
    ) -> Result<(), ScanError> {
        let fail_at = |word: &str, message: String| ScanError {
            line: line_number,
            column: column_of(line(), word),
            message,
        };
        let fail = |message: String| fail_at(keyword, message);
        let parsed = &mut self.parsed;
        match keyword {
            "v" => parsed.positions.push(parse_position(words).map_err(fail)?),
            "vt" => {
                let [u, v] = parse_numbers(words, "texture coordinate").map_err(fail)?;
                parsed.texcoords.push(Vec2::new(u, v));
            }
            "vn" => parsed
                .normals
                .push(Vec3::from_array(parse_numbers(words, "normal").map_err(fail)?)),
            "f" => {
                let so_far = [
                    self.defined[0] + parsed.positions.len(),
                    self.defined[1] + parsed.texcoords.len(),
                    self.defined[2] + parsed.normals.len(),
                ];
                self.corners.clear();
                for word in words {
                    let corner = parse_corner(word, so_far).map_err(|message| fail_at(word, message))?;
                    self.corners.push(corner);
                }
                // A face needs three corners; fewer is what a file cut off in the middle of
                // its last line looks like (`f 1 3 `), so it is an error, not a dropped face.
                if self.corners.len() < 3 {
                    return Err(fail(format!(
                        "a face needs at least 3 vertices, this one has {}: `{}` (is the file truncated?)",
                        self.corners.len(),
                        line().trim()
                    )));
                }
                let first = self.corners[0];
                for pair in self.corners[1..].windows(2) {
                    parsed.triangles.push([first, pair[0], pair[1]]);
                }
            }
            "l" => parsed.polyline_lines.push(line_number),
            "usemtl" => {
                let name = rest_after(line(), keyword);
                if name.is_empty() {
                    return Err(fail("usemtl needs a material name".to_string()));
                }
                parsed.material_uses.push((name.to_string(), line_number));
                let statement = Statement::UseMaterial(name.to_string());
                parsed.statements.push((parsed.triangles.len(), statement));
            }
            "mtllib" => {
                let statement = Statement::MaterialLibrary {
                    file: rest_after(line(), keyword).to_string(),
                    line: line_number,
                };
                parsed.statements.push((parsed.triangles.len(), statement));
            }
            "o" | "g" => {
                let name = match rest_after(line(), keyword) {
                    "" => UNNAMED_MODEL,
                    name => name,
                };
                let statement = Statement::Group(name.to_string());
                parsed.statements.push((parsed.triangles.len(), statement));
            }
            _ => {}
        }
        Ok(())
    }
}

/// A `v` line after the keyword: `x y z`, then nothing, `w`, or an `r g b` colour (which is
/// not used), with finite coordinates and a non-zero `w`; the position divided by `w`.
fn parse_position<'a>(mut words: impl Iterator<Item = &'a str>) -> Result<Vec3, String> {
    let mut coordinates = [0.0f32; 3];
    for coordinate in &mut coordinates {
        *coordinate = words
            .next()
            .and_then(parse_f32)
            .ok_or_else(|| "a vertex position needs three numbers".to_string())?;
    }
    let position = Vec3::from_array(coordinates);
    if !position.is_finite() {
        return Err("vertex position is not finite (NaN or infinity)".to_string());
    }
    let weight = words.next();
    match (weight, words.by_ref().count()) {
        (None, _) | (Some(_), 2) => Ok(position),
        (Some(weight), 0) => match parse_f32(weight) {
            Some(w) if w != 0.0 && (position / w).is_finite() => Ok(position / w),
            Some(_) => Err("vertex weight w must be non-zero and keep the position finite".to_string()),
            None => Err(format!("vertex weight w '{weight}' is not a number")),
        },
        _ => Err("a vertex is x y z, optionally followed by w or by an r g b colour".to_string()),
    }
}

/// The first `N` words as finite numbers (more are allowed and ignored).
fn parse_numbers<'a, const N: usize>(
    mut words: impl Iterator<Item = &'a str>,
    what: &str,
) -> Result<[f32; N], String> {
    let mut numbers = [0.0f32; N];
    for number in &mut numbers {
        *number = words
            .next()
            .and_then(parse_f32)
            .ok_or_else(|| format!("a {what} needs {N} numbers"))?;
    }
    // `1e39` parses as infinity in `f32`; a NaN or infinite normal or texture coordinate is a
    // broken export, rejected like a non-finite position rather than silently repaired.
    if numbers.iter().all(|n| n.is_finite()) {
        Ok(numbers)
    } else {
        Err(format!("{what} is not finite (NaN or infinity)"))
    }
}

/// Exactly three numbers separated by blanks (and blanks around them) in `text[start..end]`, as
/// [`fast_f32`] reads them; `None` for anything else. What follows `end` is read only as
/// [`RangeParser::plain_statement`] says.
fn plain_numbers(text: &[u8], start: usize, end: usize) -> Option<[f32; 3]> {
    let mut numbers = [0.0f32; 3];
    let mut at = start;
    for number in &mut numbers {
        while at < end && is_blank(text[at]) {
            at += 1;
        }
        let (value, length) = fast_f32_prefix(text.get(at..)?)?;
        at += length;
        if at > end || (at < end && !is_blank(text[at])) {
            return None;
        }
        *number = value;
    }
    text.get(at..end)?
        .iter()
        .all(|&byte| is_blank(byte))
        .then_some(numbers)
}

/// One `v`, `v/vt`, `v//vn` or `v/vt/vn` word of a face, resolved against the element counts
/// defined so far (positions, texture coordinates, normals).
fn parse_corner(word: &str, defined: [usize; 3]) -> Result<Corner, String> {
    const KINDS: [(&str, &str); 3] = [
        ("vertex", "vertices"),
        ("texture coordinate", "texture coordinates"),
        ("normal", "normals"),
    ];
    let bytes = word.as_bytes();
    // The usual corner of a scan, a position index alone (`5123`), read directly; anything
    // else (and an index out of range, for its message) takes the general path below.
    if bytes.len() <= 18 {
        // Checked and read in one pass (the value is only used when every byte is a digit).
        let mut index = 0usize;
        let all_digits = bytes.iter().all(|&byte| {
            let digit = byte.wrapping_sub(b'0');
            index = index.wrapping_mul(10).wrapping_add(usize::from(digit));
            digit < 10
        });
        if all_digits && (1..=defined[0]).contains(&index) {
            return Ok([(index - 1) as u32, ABSENT, ABSENT]);
        }
    }
    let malformed = || format!("malformed face vertex '{word}'");
    let mut parts: [&[u8]; 3] = [b""; 3];
    let mut part_count = 0;
    let mut start = 0;
    for (end, &byte) in bytes.iter().enumerate() {
        if byte == b'/' {
            if part_count == 2 {
                return Err(malformed());
            }
            parts[part_count] = &bytes[start..end];
            part_count += 1;
            start = end + 1;
        }
    }
    parts[part_count] = &bytes[start..];
    part_count += 1;
    if parts[0].is_empty() {
        return Err(malformed());
    }
    // `3/` or `3/1/`: tobj read these silently as if the last index were absent; they are
    // what a file cut off in the middle of a face looks like.
    if part_count > 1 && parts[part_count - 1].is_empty() {
        return Err(format!(
            "face vertex '{word}' ends with '/': the file is truncated or malformed"
        ));
    }
    let mut corner = [ABSENT; 3];
    for (k, part) in parts[..part_count].iter().enumerate() {
        if part.is_empty() {
            continue;
        }
        let index = parse_index(part).ok_or_else(malformed)?;
        let ((kind, kinds), count) = (KINDS[k], defined[k]);
        if index == 0 {
            return Err(format!(
                "face index 0 in '{word}' is invalid: OBJ indices start at 1"
            ));
        }
        // Positive indices count from the first element, negative ones back from the last
        // defined so far: either way |index| may not exceed the count.
        if index.unsigned_abs() > count as u64 {
            return Err(format!(
                "face refers to {kind} {index}, but only {count} {kinds} are defined above this line"
            ));
        }
        let resolved = if index > 0 {
            index as usize - 1
        } else {
            count - index.unsigned_abs() as usize
        };
        // Fewer elements than bytes in a file of at most 4 GiB.
        corner[k] = resolved as u32;
    }
    Ok(corner)
}

/// A face index as `i64::from_str` reads it (an optional sign, then decimal digits), without
/// its generality.
fn parse_index(text: &[u8]) -> Option<i64> {
    let (negative, digits) = match text {
        [b'-', rest @ ..] => (true, rest),
        [b'+', rest @ ..] => (false, rest),
        digits => (false, digits),
    };
    if digits.is_empty() {
        return None;
    }
    let mut value: i64 = 0;
    for &digit in digits {
        let digit = match digit {
            b'0'..=b'9' => i64::from(digit - b'0'),
            _ => return None,
        };
        // Accumulated on the side of its sign, so that i64::MIN parses too.
        value = value.checked_mul(10)?;
        value = if negative {
            value.checked_sub(digit)?
        } else {
            value.checked_add(digit)?
        };
    }
    Some(value)
}

/// Parses a decimal number as `str::parse::<f32>` does, bit for bit, with a shortcut for the
/// plain decimals OBJ files are made of (`-0.777853`, `74.009689`, `1e-3`).
///
/// The shortcut reads the digits into an integer `m` and the decimal exponent `e`; when
/// `m < 2⁵³` and `|e| ≤ 22`, both `m` and `10^|e|` are exact in `f64`, so
/// one `f64` multiplication or division gives the correctly rounded `f64` of the number.
/// Rounding that to `f32` gives the correctly rounded `f32` (what `str::parse` returns) unless
/// the `f64` lies exactly halfway between two `f32`s: rounding is monotonic and every such
/// halfway point is an `f64`, so the true value and its `f64` round to the same side of every
/// halfway point except that one. Halfway cases, and everything the shortcut does not read
/// (more digits, larger exponents, `inf`, `nan`, malformed text), go to `str::parse`.
pub(super) fn parse_f32(text: &str) -> Option<f32> {
    fast_f32(text.as_bytes()).or_else(|| text.parse().ok())
}

/// The shortcut of [`parse_f32`]; `None` when the text is not one it reads exactly.
fn fast_f32(bytes: &[u8]) -> Option<f32> {
    match fast_f32_prefix(bytes) {
        Some((value, length)) if length == bytes.len() => Some(value),
        _ => None,
    }
}

/// [`fast_f32`] on the number `bytes` start with: its value and how many bytes it took (the
/// caller checks what follows, which may be the rest of the line and the lines after it).
/// `None` when those bytes are not a number the shortcut reads. Inlined: as a call, saving and
/// restoring registers and returning the pair through memory took a sixth of its time.
#[inline(always)]
fn fast_f32_prefix(bytes: &[u8]) -> Option<(f32, usize)> {
    const POWERS_OF_TEN: [f64; 23] = [
        1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17,
        1e18, 1e19, 1e20, 1e21, 1e22,
    ];
    let (negative, start) = match bytes.first() {
        Some(b'-') => (true, 1),
        Some(b'+') => (false, 1),
        _ => (false, 0),
    };
    // Up to 19 digits fit in a u64 (more, leading zeros included, are left to `str::parse`;
    // the wrapped value of longer runs is never used). The first eight bytes are read as one
    // word: an exporter's `-0.777853` or `74.009689` has its point and all or most of its
    // digits there, read with one conversion.
    let word = word_at(bytes, start);
    let digits = word ^ (0x30 * ONES);
    let non_digits = non_digit_bytes(digits);
    let mut integer_digits = (non_digits.trailing_zeros() / 8) as usize;
    let mut mantissa;
    let mut fraction_digits = 0;
    let mut i;
    if integer_digits < 8 && (word >> (8 * integer_digits)) as u8 == b'.' {
        // The point adds no carry to the bytes above it (`non_digit_bytes`), so the first
        // non-digit after it is found in the same word.
        let after_point = non_digits & ((u64::MAX << (8 * integer_digits)) << 8);
        let end = (after_point.trailing_zeros() / 8) as usize;
        // The digits with the point taken out: those below it as they are, those above it
        // one byte down.
        let below = (1u64 << (8 * integer_digits)) - 1;
        let joined = (digits & below) | ((digits >> 8) & !below);
        mantissa = digits_value(joined, end - 1);
        fraction_digits = end - 1 - integer_digits;
        i = start + end;
        // A number of eight bytes after its sign (`0.777853`) fills the word: the fraction
        // goes on only if a digit follows, usually one or two (`74.009689`, six decimals with
        // two before the point), read one at a time (cheaper than another word for so few).
        if end == 8 {
            while let Some(&digit @ b'0'..=b'9') = bytes.get(i) {
                mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(digit - b'0'));
                fraction_digits += 1;
                i += 1;
            }
        }
    } else {
        mantissa = digits_value(digits, integer_digits);
        if integer_digits == 8 && bytes.get(start + 8).is_some_and(u8::is_ascii_digit) {
            let (more, with_more) = leading_digits(bytes, start + 8, mantissa);
            mantissa = with_more;
            integer_digits += more;
        }
        i = start + integer_digits;
        if bytes.get(i) == Some(&b'.') {
            let (more, with_fraction) = leading_digits(bytes, i + 1, mantissa);
            mantissa = with_fraction;
            fraction_digits = more;
            i += 1 + more;
        }
    }
    let mut exponent = -(fraction_digits as i64);
    let digit_count = integer_digits + exponent.unsigned_abs() as usize;
    if digit_count == 0 || digit_count > 19 {
        return None;
    }
    if let Some(b'e' | b'E') = bytes.get(i) {
        i += 1;
        let exponent_negative = match bytes.get(i) {
            Some(b'-') => {
                i += 1;
                true
            }
            Some(b'+') => {
                i += 1;
                false
            }
            _ => false,
        };
        let exponent_start = i;
        let mut written: i64 = 0;
        while let Some(&digit @ b'0'..=b'9') = bytes.get(i) {
            written = (written * 10 + i64::from(digit - b'0')).min(1 << 20);
            i += 1;
        }
        if i == exponent_start {
            return None;
        }
        exponent += if exponent_negative { -written } else { written };
    }
    if mantissa >= 1 << 53 || exponent.unsigned_abs() > 22 {
        return None;
    }
    let scale = POWERS_OF_TEN[exponent.unsigned_abs() as usize];
    let value = if exponent < 0 {
        mantissa as f64 / scale
    } else {
        mantissa as f64 * scale
    };
    // The 29 bits f64 has beyond f32's 24, exactly halfway: let `str::parse` decide. (With
    // 1 ≤ m < 2⁵³ and |e| ≤ 22 every non-zero result lies in f32's normal range, where that is
    // where the halfway points are.)
    if value.to_bits() & ((1 << 29) - 1) == 1 << 28 {
        return None;
    }
    let value = value as f32;
    Some((if negative { -value } else { value }, i))
}

/// A byte of ones, for bytewise arithmetic on a word of eight bytes.
const ONES: u64 = 0x0101_0101_0101_0101;

/// The run of decimal digits at `bytes[at..]`: how many there are, and `value` with them
/// appended (`10ⁿ · value +` the run's value, wrapping modulo 2⁶⁴ as a digit-by-digit loop
/// would). Read eight bytes at a time.
#[inline(always)]
fn leading_digits(bytes: &[u8], at: usize, mut value: u64) -> (usize, u64) {
    const POWERS_OF_TEN: [u64; 9] = [
        1,
        10,
        100,
        1_000,
        10_000,
        100_000,
        1_000_000,
        10_000_000,
        100_000_000,
    ];
    let mut count = 0;
    loop {
        let digits = word_at(bytes, at + count) ^ (0x30 * ONES);
        let run = (non_digit_bytes(digits).trailing_zeros() / 8) as usize;
        value = value
            .wrapping_mul(POWERS_OF_TEN[run])
            .wrapping_add(digits_value(digits, run));
        count += run;
        if run < 8 {
            return (count, value);
        }
    }
}

/// The eight bytes at `bytes[at..]` as a little-endian word (the first byte lowest), zeros
/// past the end (a zero byte is not a digit).
#[inline(always)]
fn word_at(bytes: &[u8], at: usize) -> u64 {
    match bytes.get(at..at.saturating_add(8)) {
        Some(eight) => u64::from_le_bytes(eight.try_into().unwrap_or_default()),
        None => {
            let rest = bytes.get(at..).unwrap_or_default();
            let mut word = [0u8; 8];
            word[..rest.len()].copy_from_slice(rest);
            u64::from_le_bytes(word)
        }
    }
}

/// For a word of bytes with `0x30` taken out of each (digits 0 to 9), the top bit of each
/// byte that is not a digit: set when the byte is 10 or more (adding 0x76 carries into the top
/// bit) or already has it. The addition carries into the next byte only from a byte at 0x8A or
/// above, already a non-digit, so the bytes up to and including the first non-digit are right
/// (and those after a non-digit below 0x8A, such as a point or a blank).
#[inline(always)]
fn non_digit_bytes(digits: u64) -> u64 {
    (digits.wrapping_add(0x76 * ONES) | digits) & (0x80 * ONES)
}

/// The value of the first `count` (0 to 8) bytes of `digits`, each a digit 0 to 9, the first
/// byte (lowest) the most significant.
#[inline(always)]
fn digits_value(digits: u64, count: usize) -> u64 {
    if count == 0 {
        return 0;
    }
    // The digits as the last `count` of an eight-digit number with leading zeros, then pairs,
    // fours and eights combined with multiplications (as in simdjson and fast_float).
    let digits = digits << (8 * (8 - count));
    let pairs = digits.wrapping_mul(10).wrapping_add(digits >> 8);
    let mask = 0x0000_00FF_0000_00FF;
    ((pairs & mask).wrapping_mul(100 + (1_000_000 << 32)))
        .wrapping_add(((pairs >> 16) & mask).wrapping_mul(1 + (10_000 << 32)))
        >> 32
}

/// Which vertices of the assembled geometry came with a normal.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum FileNormals {
    /// Every vertex, in vertex order.
    All(Vec<Vec3>),
    /// Some but not all.
    Some,
    None,
}

/// The faces of an OBJ text as one indexed triangle list (module documentation, step 3).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct ObjGeometry {
    pub positions: Vec<Vec3>,
    /// File normals: used when every vertex has one.
    pub normals: FileNormals,
    /// One per vertex in the glTF convention (v' = 1 − v, non-finite ones zero), or empty when
    /// no model has texture coordinates. A model where only some vertices have one cannot be
    /// trusted: its coordinates are zeros (and it is named in a warning), as are those of
    /// models without any.
    pub uvs: Vec<Vec2>,
    pub triangles: Vec<[u32; 3]>,
    /// The material of the triangles, as runs: (first triangle, the index of the material among
    /// the libraries' materials), each run lasting until the next.
    pub material_runs: Vec<(usize, Option<usize>)>,
    /// The models (by name) where only some vertices have texture coordinates.
    pub models_with_partial_uvs: Vec<String>,
}

impl ObjGeometry {
    /// The material of each triangle, in order (the runs expanded).
    pub fn triangle_material_ids(&self) -> impl Iterator<Item = Option<usize>> + '_ {
        let ends = self.material_runs.iter().skip(1).map(|&(first, _)| first);
        let ends = ends.chain([self.triangles.len()]);
        self.material_runs
            .iter()
            .zip(ends)
            .flat_map(|(&(first, material), end)| std::iter::repeat_n(material, end - first))
    }
}

/// Groups the faces of `text` into models and merges them (module documentation, step 3).
/// `load_library(file, line)` reads the material library an `mtllib` line names and returns
/// its material names (indices follow on from the libraries loaded before); `None` when it
/// could not be loaded.
pub(super) fn assemble(
    text: &ObjText,
    mut load_library: impl FnMut(&str, usize) -> Option<Vec<String>>,
) -> Result<ObjGeometry, String> {
    if text.triangle_count() > u32::MAX as usize / 3 {
        return Err("too many vertices (more than 2³² after splitting)".to_string());
    }
    let mut models = ModelAssembly::new(text);
    let mut material_by_name: HashMap<String, usize> = HashMap::new();
    let mut material_count = 0;
    let mut material = None;
    for RangeFaces {
        triangles,
        statements,
    } in &text.ranges
    {
        let mut done = 0;
        for (at, statement) in statements {
            models.add_triangles(triangles, done..*at, material);
            done = *at;
            match statement {
                Statement::Group(name) => {
                    models.finish_model();
                    models.name.clone_from(name);
                }
                Statement::UseMaterial(name) => {
                    let named = material_by_name.get(name).copied();
                    if named != material {
                        models.finish_model();
                    }
                    material = named;
                }
                Statement::MaterialLibrary { file, line } => {
                    // Later definitions of a name win, within a library and across them.
                    for name in load_library(file, *line).unwrap_or_default() {
                        material_by_name.insert(name, material_count);
                        material_count += 1;
                    }
                }
            }
        }
        models.add_triangles(triangles, done..triangles.len(), material);
    }
    models.finish_model();
    Ok(models.into_geometry())
}

/// The models of [`assemble`], built triangle by triangle.
struct ModelAssembly<'a> {
    text: &'a ObjText,
    geometry: ObjGeometry,
    /// The name of the model being built (from the last `o` or `g`).
    name: String,
    /// Where the model being built starts: its first vertex and first triangle.
    model_vertices: usize,
    model_triangles: usize,
    /// Its vertices with a texture coordinate and with a normal.
    with_texcoords: usize,
    with_normals: usize,
    /// Per vertex, its normal from the file (zero where it has none).
    file_normals: Vec<Vec3>,
    /// Vertices with a normal and without one, over all models.
    vertices_with_normals: usize,
    vertices_without_normals: usize,
    any_model_with_uvs: bool,
    /// The vertex map of the model being built, keyed by position: for each position index,
    /// the newest vertex of this model at it (valid when `model_of_position` holds the
    /// model's number) ...
    newest_vertex_of_position: Vec<u32>,
    model_of_position: Vec<u32>,
    model_number: u32,
    /// Whether some vertex of the model being built has a texture coordinate or normal index:
    /// until one does, the newest vertex at a position is the one every corner there uses.
    model_has_extras: bool,
    /// ... and for each vertex, the previous vertex of its model at the same position
    /// ([`ABSENT`] at the first) and its texture coordinate and normal indices.
    previous_at_position: Vec<u32>,
    texcoord_and_normal: Vec<[u32; 2]>,
}

impl<'a> ModelAssembly<'a> {
    fn new(text: &'a ObjText) -> Self {
        let position_count = text.positions.len();
        ModelAssembly {
            text,
            geometry: ObjGeometry {
                // Most files have one vertex per position.
                positions: Vec::with_capacity(position_count),
                normals: FileNormals::None,
                uvs: Vec::new(),
                triangles: Vec::with_capacity(text.triangle_count()),
                material_runs: Vec::new(),
                models_with_partial_uvs: Vec::new(),
            },
            name: UNNAMED_MODEL.to_string(),
            model_vertices: 0,
            model_triangles: 0,
            with_texcoords: 0,
            with_normals: 0,
            file_normals: Vec::new(),
            vertices_with_normals: 0,
            vertices_without_normals: 0,
            any_model_with_uvs: false,
            newest_vertex_of_position: vec![ABSENT; position_count],
            model_of_position: vec![u32::MAX; position_count],
            model_number: 0,
            model_has_extras: false,
            previous_at_position: Vec::with_capacity(position_count),
            texcoord_and_normal: Vec::with_capacity(position_count),
        }
    }

    fn add_triangles(&mut self, triangles: &RangeTriangles, range: Range<usize>, material: Option<usize>) {
        if range.is_empty() {
            return;
        }
        let runs = &mut self.geometry.material_runs;
        if runs.last().is_none_or(|&(_, last)| last != material) {
            runs.push((self.geometry.triangles.len(), material));
        }
        // Scans have positions only: their corners skip the search among a position's vertices.
        let with_extras_from = if triangles.extras.is_empty() {
            range.end
        } else {
            triangles.extras_from.clamp(range.start, range.end)
        };
        for &positions in &triangles.positions[range.start..with_extras_from] {
            let vertices = positions.map(|position| self.vertex_without_extras(position));
            self.geometry.triangles.push(vertices);
        }
        for index in with_extras_from..range.end {
            let vertices = triangles.corners(index).map(|corner| self.vertex(corner));
            self.geometry.triangles.push(vertices);
        }
    }

    /// [`Self::vertex`] for a corner with a position only.
    #[inline(always)]
    fn vertex_without_extras(&mut self, position: u32) -> u32 {
        let p = position as usize;
        if !self.model_has_extras && self.model_of_position[p] == self.model_number {
            return self.newest_vertex_of_position[p];
        }
        self.vertex([position, ABSENT, ABSENT])
    }

    /// The vertex of the model being built for `corner`, created when it is new.
    fn vertex(&mut self, [position, texcoord, normal]: Corner) -> u32 {
        let p = position as usize;
        if self.model_of_position[p] == self.model_number {
            let mut vertex = self.newest_vertex_of_position[p];
            while vertex != ABSENT {
                if self.texcoord_and_normal[vertex as usize] == [texcoord, normal] {
                    return vertex;
                }
                vertex = self.previous_at_position[vertex as usize];
            }
        } else {
            self.model_of_position[p] = self.model_number;
            self.newest_vertex_of_position[p] = ABSENT;
        }
        let vertex = self.geometry.positions.len() as u32;
        self.geometry.positions.push(self.text.positions[p]);
        let uv = match self.text.texcoords.get(texcoord as usize) {
            Some(uv) => {
                self.with_texcoords += 1;
                let flipped = Vec2::new(uv.x, 1.0 - uv.y);
                Vec2::select(flipped.is_finite_mask(), flipped, Vec2::ZERO)
            }
            None => Vec2::ZERO,
        };
        // Kept only for files that have texture coordinates or normals at all.
        if !self.text.texcoords.is_empty() {
            self.geometry.uvs.push(uv);
        }
        let file_normal = match self.text.normals.get(normal as usize) {
            Some(&file_normal) => {
                self.with_normals += 1;
                file_normal
            }
            None => Vec3::ZERO,
        };
        if !self.text.normals.is_empty() {
            self.file_normals.push(file_normal);
        }
        self.model_has_extras |= [texcoord, normal] != [ABSENT; 2];
        self.previous_at_position.push(self.newest_vertex_of_position[p]);
        self.texcoord_and_normal.push([texcoord, normal]);
        self.newest_vertex_of_position[p] = vertex;
        vertex
    }

    /// Ends the model being built, if it has triangles; the next triangle starts a new one.
    fn finish_model(&mut self) {
        if self.geometry.triangles.len() == self.model_triangles {
            return;
        }
        let vertex_count = self.geometry.positions.len() - self.model_vertices;
        if self.with_texcoords == vertex_count {
            self.any_model_with_uvs = true;
        } else {
            if self.with_texcoords > 0 {
                self.geometry.models_with_partial_uvs.push(self.name.clone());
            }
            if let Some(model_uvs) = self.geometry.uvs.get_mut(self.model_vertices..) {
                model_uvs.fill(Vec2::ZERO);
            }
        }
        self.vertices_with_normals += self.with_normals;
        self.vertices_without_normals += vertex_count - self.with_normals;
        self.model_vertices = self.geometry.positions.len();
        self.model_triangles = self.geometry.triangles.len();
        self.with_texcoords = 0;
        self.with_normals = 0;
        self.model_number += 1;
        self.model_has_extras = false;
    }

    fn into_geometry(mut self) -> ObjGeometry {
        if !self.any_model_with_uvs {
            self.geometry.uvs = Vec::new();
        }
        self.geometry.normals = match (self.vertices_with_normals, self.vertices_without_normals) {
            (0, _) => FileNormals::None,
            (_, 0) => FileNormals::All(self.file_normals),
            _ => FileNormals::Some,
        };
        self.geometry
    }
}

#[cfg(test)]
mod tests {
    use std::io::Cursor;

    use super::*;

    /// What `tobj` made of an OBJ text before this parser: `tobj::load_obj_buf` with
    /// `triangulate`, `single_index`, `ignore_points` and `ignore_lines` on the text with its
    /// polyline lines blanked, and its models merged as the loader merged them. The oracle the
    /// new parser is held to. `libraries` are the MTL files by name.
    fn tobj_geometry(text: &str, libraries: &[(&str, &str)]) -> ObjGeometry {
        let blanked: Vec<&str> = text
            .lines()
            .map(|line| match line.split_whitespace().next() {
                Some("l") => "",
                _ => line,
            })
            .collect();
        // `..Default::default()` covers tobj's options that exist only under cargo features
        // some other crate could enable (absent in this build, hence the allow).
        #[allow(clippy::needless_update)]
        let options = tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ignore_points: true,
            ignore_lines: true,
            ..Default::default()
        };
        let (models, _) = tobj::load_obj_buf(&mut Cursor::new(blanked.join("\n")), &options, |file| {
            let name = file.to_string_lossy();
            match libraries.iter().find(|(library, _)| *library == name) {
                Some((_, mtl)) => tobj::load_mtl_buf(&mut Cursor::new(mtl.as_bytes())),
                None => Err(tobj::LoadError::OpenFileFailed),
            }
        })
        .unwrap_or_else(|error| panic!("tobj: {error}"));
        let mut geometry = ObjGeometry {
            positions: Vec::new(),
            normals: FileNormals::None,
            uvs: Vec::new(),
            triangles: Vec::new(),
            material_runs: Vec::new(),
            models_with_partial_uvs: Vec::new(),
        };
        let mut normals = Vec::new();
        let (mut with_normals, mut without_normals) = (0, 0);
        let mut model_uvs = Vec::new();
        for model in &models {
            let mesh = &model.mesh;
            let offset = geometry.positions.len() as u32;
            let vertex_count = mesh.positions.len() / 3;
            geometry
                .positions
                .extend(mesh.positions.chunks_exact(3).map(Vec3::from_slice));
            if mesh.texcoords.len() == 2 * vertex_count && vertex_count > 0 {
                let flipped = mesh.texcoords.chunks_exact(2).map(|uv| {
                    let flipped = Vec2::new(uv[0], 1.0 - uv[1]);
                    Vec2::select(flipped.is_finite_mask(), flipped, Vec2::ZERO)
                });
                model_uvs.push((Some(flipped.collect::<Vec<_>>()), vertex_count));
            } else {
                if !mesh.texcoords.is_empty() {
                    geometry.models_with_partial_uvs.push(model.name.clone());
                }
                model_uvs.push((None, vertex_count));
            }
            if mesh.normals.len() == mesh.positions.len() {
                normals.extend(mesh.normals.chunks_exact(3).map(Vec3::from_slice));
                with_normals += vertex_count;
            } else {
                with_normals += mesh.normals.len() / 3;
                without_normals += vertex_count - mesh.normals.len() / 3;
            }
            for corners in mesh.indices.chunks_exact(3) {
                let runs = &mut geometry.material_runs;
                if runs.last().is_none_or(|&(_, last)| last != mesh.material_id) {
                    runs.push((geometry.triangles.len(), mesh.material_id));
                }
                geometry.triangles.push([0, 1, 2].map(|k| offset + corners[k]));
            }
        }
        geometry.normals = match (with_normals, without_normals) {
            (0, _) => FileNormals::None,
            (_, 0) => FileNormals::All(normals),
            _ => FileNormals::Some,
        };
        if model_uvs.iter().any(|(uvs, _)| uvs.is_some()) {
            geometry.uvs = model_uvs
                .into_iter()
                .flat_map(|(uvs, count)| uvs.unwrap_or_else(|| vec![Vec2::ZERO; count]))
                .collect();
        }
        geometry
    }

    /// Parses and assembles `text` with ranges of `range_bytes`, the libraries named as in
    /// [`tobj_geometry`].
    fn geometry(text: &str, libraries: &[(&str, &str)], range_bytes: usize) -> ObjGeometry {
        let parsed =
            parse_in_ranges(text.as_bytes(), range_bytes).unwrap_or_else(|error| panic!("{error:?}"));
        assemble(&parsed, |file, _| {
            let (_, mtl) = libraries.iter().find(|(library, _)| *library == file)?;
            let (materials, _) = tobj::load_mtl_buf(&mut Cursor::new(mtl.as_bytes())).ok()?;
            Some(materials.into_iter().map(|material| material.name).collect())
        })
        .unwrap_or_else(|error| panic!("{error}"))
    }

    /// The parser agrees with `tobj` on `text`, whatever the size of its ranges.
    fn check_against_tobj(text: &str, libraries: &[(&str, &str)]) {
        let expected = tobj_geometry(text, libraries);
        for range_bytes in [1, 7, 64, 1000, RANGE_BYTES] {
            let actual = geometry(text, libraries, range_bytes);
            assert!(
                actual == expected,
                "ranges of {range_bytes} bytes differ from tobj on:\n{}\n{actual:?}\n{expected:?}",
                &text[..text.len().min(400)]
            );
        }
    }

    fn asset(relative: &str) -> String {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/obj")
            .join(relative);
        std::fs::read_to_string(&path).unwrap_or_else(|error| panic!("{}: {error}", path.display()))
    }

    #[test]
    fn the_bundled_obj_files_parse_as_tobj_parsed_them() {
        let cornell_mtl = asset("cornell-box/CornellBox-Original.mtl");
        check_against_tobj(
            &asset("cornell-box/CornellBox-Original.obj"),
            &[("CornellBox-Original.mtl", &cornell_mtl)],
        );
        let fixture_mtl = asset("tobj-fixtures/cornell_box.mtl");
        let fixture_mtl2 = asset("tobj-fixtures/cornell_box2.mtl");
        check_against_tobj(
            &asset("tobj-fixtures/cornell_box.obj"),
            &[
                ("cornell_box.mtl", &fixture_mtl),
                ("cornell_box2.mtl", &fixture_mtl2),
            ],
        );
        for file in [
            "tobj-fixtures/quad.obj",
            "tobj-fixtures/triangle.obj",
            "teapot/teapot.obj",
            "spot/spot_triangulated.obj",
            "spot/spot_quadrangulated.obj",
            "spot/spot_control_mesh.obj",
            "koala/koala.obj",
            "nefertiti/nefertiti-lowres.obj",
        ] {
            check_against_tobj(&asset(file), &[]);
        }
    }

    const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

    #[test]
    fn statements_parse_as_tobj_parsed_them() {
        let mtl = "newmtl red\nKd 1 0 0\nnewmtl green\nKd 0 1 0\nnewmtl red\nKd 0.5 0 0\n";
        let other = "newmtl blue\nKd 0 0 1\nnewmtl green\nKd 0 0.5 0\n";
        let libraries = [("m.mtl", mtl), ("other.mtl", other)];
        let cases = [
            // Negative indices, quads and polygons, w, vertex colours, comments.
            format!("v 9 9 9\n{TRIANGLE}f -3 -2 -1\nv 5 5 5 2\nf 1 2 -1\nf 1 2 3 4 5\n# c\nf 2 3 4 5\n"),
            "v 0 0 0 1 0.5 0.25\nv 1 0 0 0 1 0\nv 0 1 0 1 1 1\nf 1 2 3\n".to_string(),
            // The same position twice, by value and by index; positions shared across models.
            format!("{TRIANGLE}v 0 0 0\nf 1 2 3\nf 4 2 3\nf -4 1 2\no second\nf 1 2 3\nf 1 3 2\n"),
            // Groups with and without faces, unnamed groups, and materials: resolved against
            // the libraries named above, later definitions winning, a change of material
            // starting a model only when the model has faces.
            format!(
                "usemtl red\nmtllib m.mtl\n{TRIANGLE}f 1 2 3\nusemtl red\nf 1 3 2\ng\nusemtl green\n\
                 usemtl red\nf 2 3 1\no named\no\nf 1 2 3\nmtllib other.mtl\nusemtl green\nf 3 2 1\n\
                 usemtl blue\nusemtl missing\nf 1 2 3\nmtllib nowhere.mtl\nusemtl blue\nf 1 2 3\n"
            ),
            // Texture coordinates and normals: every vertex, some, none, per model.
            format!(
                "{TRIANGLE}vt 0 0\nvt 1 0 0\nvt 0.5 1\nvn 0 0 1\nvn 0 0 -1\n\
                 o all\nf 1/1/1 2/2/1 3/3/1\nf 1/2/2 2/2/1 3/3/1\n\
                 o some\nf 1/1 2 3\no none\nf 1 2 3\no normals\nf 1//1 2//2 3//1\n\
                 o mixed\nf 1/1/1 2//1 3/3\n"
            ),
            format!("{TRIANGLE}vn 0 0 1\nf 1//1 2//1 3//1\nf 3//1 2//1 1//1\n"),
            // Faces with positions only before, between and after faces with texture
            // coordinates or normals at the same positions, in one model and across models
            // (the small ranges put them in ranges with and without such faces).
            format!(
                "{TRIANGLE}vt 0 0\nvn 0 0 1\nf 1 2 3\nf 3 2 1\nf 1/1 2 3//1\nf 1 2 3\nf 2 3 1\n\
                 o next\nf 1 2 3\nf 1/1/1 2 3\nf 3 1 2\no last\nf 3 1 2\nf 1 2 3\n"
            ),
            format!("{TRIANGLE}vt 0.25 0.75\nvt 1 1\nvt 0 1\no a\nf 1/1 2/2 3/3\no b\nf 1 3 2\n"),
            // Polylines and points are skipped; CRLF and tab separators, indented lines,
            // Unicode whitespace, a last line without an end.
            format!(
                "{TRIANGLE}l 1 2 3\np 1\nf 1 2 3\r\n\tf\t3 2 1\r\n   f 1 3 2\n\u{a0}f\u{a0}2 1 3\u{2003}\nf 1 2 3"
            ),
        ];
        for text in &cases {
            check_against_tobj(text, &libraries);
        }
    }

    #[test]
    fn invalid_utf8_is_replaced_as_from_utf8_lossy_replaces_it() {
        let mut bytes = b"# caf\xE9\nmtllib m\xFF.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n".to_vec();
        bytes.extend_from_slice(
            b"usemtl \xC3\nf 1 2 3\ng \xE2\x82\n\xE2\x82\xACf 1 3 2\nf 1 2 3\n# \xF0\x9F\n",
        );
        let lossy = String::from_utf8_lossy(&bytes).into_owned();
        let expected = parse_in_ranges(lossy.as_bytes(), RANGE_BYTES).map(|text| {
            let statements: Vec<_> = text
                .ranges
                .iter()
                .flat_map(|range| range.statements.iter().map(|(_, s)| s.clone()))
                .collect();
            (text.material_uses.clone(), statements)
        });
        for range_bytes in [1, 3, 16, RANGE_BYTES] {
            let parsed = parse_in_ranges(&bytes, range_bytes).map(|text| {
                let statements: Vec<_> = text
                    .ranges
                    .iter()
                    .flat_map(|range| range.statements.iter().map(|(_, s)| s.clone()))
                    .collect();
                (text.material_uses.clone(), statements)
            });
            assert_eq!(parsed, expected, "ranges of {range_bytes} bytes");
        }
        let (uses, statements) = expected.unwrap_or_else(|error| panic!("{error:?}"));
        assert_eq!(uses, vec![("\u{FFFD}".to_string(), 6)]);
        assert_eq!(statements.len(), 3, "{statements:?}");
    }

    #[test]
    fn errors_are_the_same_whatever_the_ranges() {
        let cases = [
            format!("{TRIANGLE}f 1 2 3\n{TRIANGLE}f 1 2 7\nf 1 2 9\n"),
            format!("{TRIANGLE}f -1 -2 -3\nv 1 2\nf 1 2 -5\n"),
            format!("{TRIANGLE}vt 0 0\nf 1/1 2/1 3/\n"),
            format!("{TRIANGLE}# é\nvn 0 0 1\n  vt é 0\n"),
            format!("{TRIANGLE}f 1 2 3\nusemtl \nf 1 2\n"),
            format!("{TRIANGLE}{TRIANGLE}{TRIANGLE}f 1 2 10\n"),
        ];
        for text in &cases {
            let whole = parse_in_ranges(text.as_bytes(), RANGE_BYTES).err();
            assert!(whole.is_some(), "{text:?} parsed");
            for range_bytes in [1, 5, 16] {
                assert_eq!(
                    parse_in_ranges(text.as_bytes(), range_bytes).err(),
                    whole,
                    "{text:?}"
                );
            }
        }
    }

    /// `parse_f32` against `str::parse`, bit for bit (or both failing).
    /// Also the shortcut on the text followed by more of a line and the next line, as the
    /// plain lines read it: the same number, ending where the text does.
    fn check_f32(text: &str) {
        let expected = text.parse::<f32>().ok().map(f32::to_bits);
        assert_eq!(parse_f32(text).map(f32::to_bits), expected, "{text:?}");
        let alone = fast_f32(text.as_bytes()).map(f32::to_bits);
        for after in [" 12345678", "\n12345678", "\r\n1", "\t-7.5e3"] {
            let followed = format!("{text}{after}");
            let prefix = fast_f32_prefix(followed.as_bytes())
                .filter(|&(_, length)| length == text.len())
                .map(|(value, _)| value.to_bits());
            assert_eq!(prefix, alone, "{followed:?}");
        }
    }

    /// The lines against `str::split_terminator` (`str::lines` without taking the `\r` of a
    /// `\r\n` off), on every text of up to 10 bytes from a line end, a carriage return, a blank
    /// and a letter, and on longer ones with every byte value.
    #[test]
    fn ascii_lines_are_cut_at_every_line_end() {
        let alphabet = ['\n', '\r', ' ', 'v'];
        for length in 0..=10u32 {
            for code in 0..4usize.pow(length) {
                let text: String = (0..length).map(|k| alphabet[code / 4usize.pow(k) % 4]).collect();
                let lines: Vec<&str> = AsciiLines::new(&text).collect();
                assert_eq!(lines, text.split_terminator('\n').collect::<Vec<_>>(), "{text:?}");
            }
        }
        let every_byte: String = (0..128u8).cycle().take(1000).map(char::from).collect();
        for start in 0..20 {
            let text = &every_byte[start..];
            let lines: Vec<&str> = AsciiLines::new(text).collect();
            assert_eq!(lines, text.split_terminator('\n').collect::<Vec<_>>());
        }
    }

    /// The eight-bytes-at-a-time digit runs against a loop over the bytes, for runs of every
    /// length up to 24 followed by every byte, at every distance from the end of the text.
    #[test]
    fn digit_runs_read_as_a_byte_loop_reads_them() {
        let mut rng = crate::test_support::XorShift64::new(0x9E37_79B9_7F4A_7C15u64);
        let mut random = || rng.next_u64();
        for length in 0..=24 {
            for stop in 0..=255u8 {
                let mut text: Vec<u8> = (0..length).map(|_| b'0' + (random() % 10) as u8).collect();
                text.push(stop);
                text.extend((0..random() % 12).map(|_| random() as u8));
                for at in 0..=text.len() {
                    let start = random();
                    let (mut count, mut value) = (0, start);
                    while let Some(&digit @ b'0'..=b'9') = text.get(at + count) {
                        value = value.wrapping_mul(10).wrapping_add(u64::from(digit - b'0'));
                        count += 1;
                    }
                    assert_eq!(
                        leading_digits(&text, at, start),
                        (count, value),
                        "{text:?} at {at}"
                    );
                }
            }
        }
    }

    #[test]
    fn plain_lines_read_in_one_pass_as_the_general_path_reads_them() {
        let parser = || RangeParser {
            parsed: ParsedRange::default(),
            defined: [4, 2, 0],
            corners: Vec::new(),
        };
        let mut taken = 0;
        for line in [
            "v 1 2 3",
            "v\t-0.777853  74.009689 1e-3\r",
            "v 1 2 3 ",
            "v .5 -2. +3e2",
            "v 1 2 3 0.5",
            "v 1 2 3 1 0 0",
            "v 1 2",
            "v 1 2 3x",
            "v 1e39 0 0",
            "v 0.1000000000000000055511151231257827 0 0",
            "v 1 2 # comment",
            "v nan 0 0",
            " v 1 2 3",
            "vt 1 2",
            "f 1 2 3",
            "f 1 2 3 4 4 3\r",
            "f\t4 1   2 ",
            "f 1 2",
            "f 1 2 5",
            "f 0 1 2",
            "f 1 2 -1",
            "f 1/1 2/2 3/1",
            "f 1 2 3a",
            "f 1 2 0000000000000000003",
            "f 1 2 000000000000000003",
            "f 1 2 00000003",
            "f 12345678 1 2",
            "f 1 2 3 1\t",
            "v -0.777853 2.740647 3.930020",
            "v 12345678.123456789 -123456789.5 0.000000001",
            "v 1234567890123456789 0 0",
            "v 12345678901234567890 0 0",
            "v 1 2 3.",
            "v 1 2 3e",
            "v 1 2 -",
            "g f 1 2 3",
            "",
        ] {
            let mut general = parser();
            let mut words = AsciiWords::new(line);
            let general_result = match words.next() {
                Some(keyword) => general.statement(keyword, &mut words, 1, || line),
                None => Ok(()),
            };
            // Alone, and followed by the next line as in a range (the numbers are read
            // eight bytes at a time across the line end).
            let mut plain = parser();
            let mut followed = parser();
            let taken_alone = plain.plain_statement(line.as_bytes(), line.len());
            let with_next = format!("{line}\n12345678 -0.5 f 1 2 3\n");
            let taken_followed = followed.plain_statement(with_next.as_bytes(), line.len());
            assert_eq!(taken_alone, taken_followed, "{line:?}");
            assert_eq!(plain.parsed.positions, followed.parsed.positions, "{line:?}");
            assert_eq!(
                plain.parsed.triangles.positions, followed.parsed.triangles.positions,
                "{line:?}"
            );
            if taken_alone {
                taken += 1;
                assert!(general_result.is_ok(), "{line:?}");
                let bits = |positions: &[Vec3]| {
                    positions
                        .iter()
                        .map(|p| p.to_array().map(f32::to_bits))
                        .collect::<Vec<_>>()
                };
                assert_eq!(
                    bits(&plain.parsed.positions),
                    bits(&general.parsed.positions),
                    "{line:?}"
                );
                assert_eq!(
                    plain.parsed.triangles.positions, general.parsed.triangles.positions,
                    "{line:?}"
                );
                assert!(general.parsed.triangles.extras.is_empty(), "{line:?}");
            } else {
                assert!(
                    plain.parsed.positions.is_empty() && plain.parsed.triangles.len() == 0,
                    "{line:?}"
                );
            }
        }
        assert_eq!(taken, 12);
    }

    #[test]
    fn numbers_parse_as_str_parse_parses_them() {
        for text in [
            "0",
            "-0",
            "+0",
            "0.0",
            "-0.777853",
            "74.009689",
            "1e-3",
            "1E+3",
            "-.5",
            "5.",
            ".",
            "",
            "-",
            "+",
            "e5",
            "1e",
            "1e+",
            "1.5e-22",
            "1e22",
            "1e23",
            "1e-23",
            "123456789012345678",
            "1234567890123456789",
            "12345678901234567890",
            "0.000000000000000000000000123",
            "00000000000000000000000001",
            "16777217",
            "16777219",
            "33554433",
            "nan",
            "-inf",
            "infinity",
            "1_0",
            "1.2.3",
            "1e1.5",
            "0x10",
            "--1",
            "+-1",
            "1e-0",
            "3.4028236e38",
            "9007199254740993",
            "9007199254740992",
            "8388608.5",
            "8388609.5",
            "0.1",
            "0.2",
            "0.3",
        ] {
            check_f32(text);
        }
        // Every split of up to 12 digits around the point (and none), so that the point
        // falls at every byte of the first eight and past them, with and without a sign and
        // an exponent.
        let mut rng = crate::test_support::XorShift64::new(0x5DEE_CE66_D1CE_4E5Bu64);
        for integer_length in 0..=12 {
            for fraction_length in 0..=12 {
                for _ in 0..20 {
                    let state = rng.next_u64();
                    let mut digits = state;
                    let mut digit = || {
                        let next = char::from(b'0' + (digits % 10) as u8);
                        digits /= 10;
                        next
                    };
                    let integer: String = (0..integer_length).map(|_| digit()).collect();
                    let fraction: String = (0..fraction_length).map(|_| digit()).collect();
                    for text in [
                        format!("{integer}.{fraction}"),
                        format!("-{integer}.{fraction}"),
                        format!("{integer}{fraction}"),
                        format!("+{integer}.{fraction}e-{}", state % 25),
                        format!("{integer}.{fraction}E{}", state % 25),
                    ] {
                        check_f32(&text);
                    }
                }
            }
        }
        // Halfway cases between f32 neighbours written with few digits, and many values in
        // the formats exporters write.
        let mut rng = crate::test_support::XorShift64::new(0x2545_F491_4F6C_DD1Du64);
        let mut random = || rng.next_u64();
        for _ in 0..200_000 {
            let bits = random();
            let value = f32::from_bits(bits as u32);
            if !value.is_finite() {
                continue;
            }
            let decimals = (bits >> 32) as usize % 10;
            check_f32(&format!("{value:.decimals$}"));
            check_f32(&format!("{value}"));
            check_f32(&format!("{value:e}"));
            check_f32(&format!(
                "{}",
                f64::from(value) + f64::from(value) * f64::EPSILON * 3.0
            ));
            check_f32(&format!("{}e-{}", bits >> 45, (bits >> 20) % 30));
            // The halfway point between an f32 and the next, and decimals of 15 and 16
            // significant digits next to it that round onto it in f64: the one case where
            // rounding through f64 would go wrong.
            let magnitude = f32::from_bits(0x3000_0000 + (bits as u32 % 0x1F00_0000));
            let halfway = (f64::from(magnitude) + f64::from(magnitude.next_up())) / 2.0;
            for text in [
                format!("{halfway}"),
                format!("{halfway:.15e}"),
                format!("{halfway:.14e}"),
            ] {
                check_f32(&text);
                check_f32(&format!("-{text}"));
            }
        }
    }

    #[test]
    fn face_indices_parse_as_i64_from_str() {
        for text in [
            "1",
            "-1",
            "+1",
            "0",
            "-0",
            "",
            "-",
            "+",
            "1a",
            "9223372036854775807",
            "9223372036854775808",
            "-9223372036854775808",
            "-9223372036854775809",
            "99999999999999999999",
            "٣",
        ] {
            assert_eq!(parse_index(text.as_bytes()), text.parse::<i64>().ok(), "{text:?}");
        }
    }
}
