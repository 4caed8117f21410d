//! What is at a position of a scene's text: the token there, the struct it is in and what goes
//! there (a field name, the value of some field, a mesh file's path), read with
//! [`crate::scene::locate::surroundings`], the tolerant reader the loader rewords syntax errors
//! with, so it works on the half-written text of a buffer being typed in.

use std::ops::Range;

use crate::scene::locate::surroundings;

/// What goes at the cursor.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Role {
    /// A field name of the struct `holder`/`name` (as [`crate::diag::Schema::fields`] takes them).
    FieldName,
    /// The value of this field, or an element of the list it holds.
    Value(String),
    /// The path of a mesh file: `Obj("…")` or `Gltf("…")` as a `mesh`.
    MeshPath,
    /// Nothing lampshade knows how to help with (a number, a vector, a map key...).
    Other,
}

/// The token at a position and its place in the scene.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Cursor {
    pub role: Role,
    /// The field holding the innermost struct (see [`crate::scene::locate::OpenGroup::holder`]).
    pub holder: Option<String>,
    /// The name written before the innermost `(`: `Spot`, `Sphere`, `Scene`...
    pub name: Option<String>,
    /// Where the innermost open bracket is.
    pub group_open: Option<usize>,
    /// The token under the cursor, if any: an identifier or a string (possibly not closed yet).
    pub token: Option<Range<usize>>,
    pub token_kind: TokenKind,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TokenKind {
    None,
    Ident,
    /// A string; its range includes the quotes (the closing one only when written).
    Str,
    Other,
}

impl Cursor {
    /// The text of a string token without its quotes, and where that text starts.
    pub fn string_content<'t>(&self, text: &'t str) -> Option<(usize, &'t str)> {
        let token = self.token.clone().filter(|_| self.token_kind == TokenKind::Str)?;
        let raw = text.get(token.clone())?;
        let open = raw.find('"')? + 1;
        let inner = &raw[open..];
        let inner = inner.strip_suffix('"').unwrap_or(inner);
        Some((token.start + open, inner))
    }
}

/// Where the cursor is while typing at byte `offset`: the token is the one that ends at the
/// cursor (an identifier being typed) or the string the cursor is inside.
pub fn typing_at(text: &str, offset: usize) -> Cursor {
    let offset = text.floor_char_boundary(offset.min(text.len()));
    let before = surroundings(text, offset);
    let token = match before.previous {
        Some(previous)
            if previous.end > offset || (previous.end == offset && !ends_string(text, &previous)) =>
        {
            Some(previous)
        }
        previous => unclosed_string(text, previous.map_or(0, |p| p.end), offset),
    };
    cursor(text, token, offset)
}

/// Where the cursor is when pointing at byte `offset` (hover, go to definition): the token
/// that contains it, or else the one that ends there.
pub fn pointing_at(text: &str, offset: usize) -> Cursor {
    let offset = text.floor_char_boundary(offset.min(text.len()));
    let next = text.ceil_char_boundary(offset + 1);
    let around = surroundings(text, next);
    match around.previous {
        Some(token) if token.start <= offset && offset < token.end => cursor(text, Some(token), offset),
        _ => typing_at(text, offset),
    }
}

/// Whether `token` is a string whose closing quote is its last character (so a cursor right
/// after it is outside).
fn ends_string(text: &str, token: &Range<usize>) -> bool {
    text.get(token.clone())
        .is_some_and(|t| t.len() >= 2 && t.ends_with('"') && t.contains('"'))
}

/// A string opened between `from` and `offset` and not closed before `offset` (the reader
/// stops at a string that is never closed).
fn unclosed_string(text: &str, from: usize, offset: usize) -> Option<Range<usize>> {
    let between = text.get(from..offset)?;
    let quote = between.find('"')?;
    if between[..quote].trim().is_empty() && !between[quote + 1..].contains(['"', '\n']) {
        Some(from + quote..offset)
    } else {
        None
    }
}

fn cursor(text: &str, token: Option<Range<usize>>, offset: usize) -> Cursor {
    let token_kind = match token.as_ref().and_then(|t| text.get(t.clone())) {
        None => TokenKind::None,
        Some(t) if t.starts_with('"') => TokenKind::Str,
        Some(t) if t.starts_with(|c: char| c.is_alphabetic() || c == '_') => TokenKind::Ident,
        Some(_) => TokenKind::Other,
    };
    let context = surroundings(text, token.as_ref().map_or(offset, |t| t.start));
    let group = context.group;
    let holder = group.as_ref().and_then(|g| g.holder.clone());
    let name = group.as_ref().and_then(|g| g.name.clone());
    let bracket = group.as_ref().map(|g| g.bracket);
    let group_open = group.as_ref().map(|g| g.open);
    let role = match (bracket, context.value_of) {
        (Some('('), None)
            if holder.as_deref() == Some("mesh") && matches!(name.as_deref(), Some("Obj" | "Gltf")) =>
        {
            Role::MeshPath
        }
        (_, Some(field)) => Role::Value(field),
        (Some('('), None) => Role::FieldName,
        _ => Role::Other,
    };
    Cursor {
        role,
        holder,
        name,
        group_open,
        token,
        token_kind,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cursor at the `|` of `marked`.
    fn typing(marked: &str) -> (String, Cursor) {
        let offset = marked.find('|').unwrap();
        let text = marked.replacen('|', "", 1);
        let cursor = typing_at(&text, offset);
        (text, cursor)
    }

    #[test]
    fn field_names_values_and_strings_while_typing() {
        let (_, c) = typing("(objects: [(mesh: Cube, sha|)])");
        assert_eq!(c.role, Role::FieldName);
        assert_eq!(c.holder.as_deref(), Some("objects"));
        assert_eq!(c.token_kind, TokenKind::Ident);

        let (_, c) = typing("(objects: [(mesh: Cube, shading: |)])");
        assert_eq!(c.role, Role::Value("shading".into()));
        assert_eq!(c.token_kind, TokenKind::None);

        let (_, c) = typing("(lights: [Spot(cut|)])");
        assert_eq!(
            (c.holder.as_deref(), c.name.as_deref()),
            (Some("lights"), Some("Spot"))
        );
        assert_eq!(c.role, Role::FieldName);

        let (text, c) = typing(r#"(objects: [(mesh: Cube, material: "ru|"#);
        assert_eq!(c.role, Role::Value("material".into()));
        assert_eq!(c.string_content(&text).map(|(_, s)| s), Some("ru"));

        let (text, c) = typing(r#"(objects: [(mesh: Cube, material: "ru|by")])"#);
        assert_eq!(c.string_content(&text).map(|(_, s)| s), Some("ruby"));

        let (_, c) = typing(r#"(objects: [(mesh: Obj("meshes/|"#);
        assert_eq!(c.role, Role::MeshPath);

        let (_, c) = typing(r#"(materials: {"a": (mod|)})"#);
        assert_eq!(
            (c.holder.as_deref(), c.role),
            (Some("materials"), Role::FieldName)
        );
    }

    #[test]
    fn the_fields_written_in_the_cursor_s_group_are_found() {
        let (text, c) = typing("(objects: [(mesh: Cube, r#shading: Flat, sha|)])");
        let written = crate::scene::locate::fields_in_group(&text, c.group_open.unwrap());
        assert_eq!(written, Some(vec!["mesh".to_owned(), "shading".to_owned()]));
        assert_eq!(crate::scene::locate::fields_in_group("(mesh: \"a", 0), None);
        assert_eq!(crate::scene::locate::fields_in_group("[1]", 0), None);
    }

    #[test]
    fn pointing_finds_the_token_under_the_cursor() {
        let text = "(image: (width: 640))";
        let cursor = pointing_at(text, text.find("idth").unwrap());
        assert_eq!(cursor.token.map(|t| &text[t]), Some("width"));
        assert_eq!(
            (cursor.role, cursor.holder.as_deref()),
            (Role::FieldName, Some("image"))
        );
        // Any position, however odd, gives an answer.
        for offset in 0..=text.len() + 2 {
            pointing_at(text, offset);
            typing_at(text, offset);
        }
    }
}
