//! The documents an editor has open: their unsaved text, and positions in it.
//!
//! LSP positions are (line, UTF-16 code unit in the line), both from 0; the loader's are byte
//! offsets. Converting is a walk over the text, clamped at every step, so a position past the
//! end of a line or of the file lands at that end instead of failing.

use std::collections::HashMap;
use std::path::PathBuf;

use lsp_types::{Position, Range, TextDocumentContentChangeEvent, Url};

/// One open document.
#[derive(Debug, Clone)]
pub struct Document {
    /// The file the document is (includes and meshes are relative to its folder).
    pub path: PathBuf,
    pub text: String,
    pub version: i32,
    /// The last text of this document that parsed: what material names are read from while
    /// the text being typed does not parse (`material: "b` is half a string).
    pub parsed_text: Option<String>,
}

impl Document {
    /// The text to read the scene's materials from: the current one, or the last that parsed.
    pub fn materials_text(&self) -> &str {
        self.parsed_text.as_deref().unwrap_or(&self.text)
    }
}

impl Document {
    /// Applies the changes of one `didChange`, in order: a change without a range replaces
    /// the whole text, one with a range replaces that range.
    pub fn apply(&mut self, changes: Vec<TextDocumentContentChangeEvent>, version: i32) {
        for change in changes {
            match change.range {
                Some(range) => {
                    let start = offset_of(&self.text, range.start);
                    let end = offset_of(&self.text, range.end).max(start);
                    self.text.replace_range(start..end, &change.text);
                }
                None => self.text = change.text,
            }
        }
        self.version = version;
    }
}

/// The open documents by URI.
#[derive(Debug, Default)]
pub struct Documents {
    open: HashMap<Url, Document>,
}

impl Documents {
    /// Opens `uri`; `None` when it is not a `file:` URI (lampshade reads scenes from files).
    pub fn open(&mut self, uri: Url, text: String, version: i32) -> Option<&Document> {
        let path = uri.to_file_path().ok()?;
        self.open.insert(
            uri.clone(),
            Document {
                path,
                text,
                version,
                parsed_text: None,
            },
        );
        self.open.get(&uri)
    }

    pub fn get(&self, uri: &Url) -> Option<&Document> {
        self.open.get(uri)
    }

    pub fn get_mut(&mut self, uri: &Url) -> Option<&mut Document> {
        self.open.get_mut(uri)
    }

    pub fn close(&mut self, uri: &Url) {
        self.open.remove(uri);
    }
}

/// The LSP position of byte `offset` of `text` (clamped to the text and back to a char
/// boundary).
pub fn position_of(text: &str, offset: usize) -> Position {
    let offset = text.floor_char_boundary(offset.min(text.len()));
    let before = &text[..offset];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let line = before.bytes().filter(|&b| b == b'\n').count();
    let character = before[line_start..].encode_utf16().count();
    Position::new(saturate(line), saturate(character))
}

/// The LSP range of bytes `span` of `text`.
pub fn range_of(text: &str, span: std::ops::Range<usize>) -> Range {
    Range::new(position_of(text, span.start), position_of(text, span.end))
}

/// The byte offset of LSP `position` in `text`: a line past the last is the end of the text,
/// a character past the end of its line is the end of that line.
pub fn offset_of(text: &str, position: Position) -> usize {
    let mut line_start = 0;
    for _ in 0..position.line {
        match text[line_start..].find('\n') {
            Some(newline) => line_start += newline + 1,
            None => return text.len(),
        }
    }
    let line_end = text[line_start..]
        .find('\n')
        .map_or(text.len(), |i| line_start + i);
    let mut units = 0;
    for (index, c) in text[line_start..line_end].char_indices() {
        if units >= position.character as usize {
            return line_start + index;
        }
        units += c.len_utf16();
    }
    line_end
}

fn saturate(value: usize) -> u32 {
    u32::try_from(value).unwrap_or(u32::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_count_utf16_units_and_round_trip() {
        let text = "ab\n→x𝄞y\n";
        assert_eq!(position_of(text, 0), Position::new(0, 0));
        assert_eq!(position_of(text, 3), Position::new(1, 0));
        // `→` is one UTF-16 unit, `𝄞` two.
        let y = text.find('y').unwrap();
        assert_eq!(position_of(text, y), Position::new(1, 4));
        for offset in [0, 1, 2, 3, 6, 7, y, text.len()] {
            assert_eq!(offset_of(text, position_of(text, offset)), offset, "{offset}");
        }
        // Clamped, never a panic.
        assert_eq!(offset_of(text, Position::new(1, 99)), text.len() - 1);
        assert_eq!(offset_of(text, Position::new(9, 0)), text.len());
        assert_eq!(position_of(text, 999), Position::new(2, 0));
        assert_eq!(
            position_of(text, 5),
            position_of(text, 4),
            "inside `→`: back to its start"
        );
    }

    #[test]
    fn ranged_changes_splice_and_others_replace() {
        let mut document = Document {
            path: PathBuf::from("/s.ron"),
            text: "(objects: [])".into(),
            version: 1,
            parsed_text: None,
        };
        document.apply(
            vec![TextDocumentContentChangeEvent {
                range: Some(Range::new(Position::new(0, 11), Position::new(0, 11))),
                range_length: None,
                text: "(mesh: Cube)".into(),
            }],
            2,
        );
        assert_eq!(document.text, "(objects: [(mesh: Cube)])");
        assert_eq!(document.version, 2);
        document.apply(
            vec![TextDocumentContentChangeEvent {
                range: None,
                range_length: None,
                text: "()".into(),
            }],
            3,
        );
        assert_eq!(document.text, "()");
    }
}
