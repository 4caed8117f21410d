//! The documentation of every field of the scene format, read from `docs/scene-format.md`
//! itself: the reference's field tables (`| field | type | default | meaning |`) are compiled
//! into the binary and parsed on first use, so what an editor shows on completion and hover is
//! the reference, word for word, and cannot drift from it.
//!
//! The other direction is held by a test: every field the serde types of [`super::format`]
//! accept (asked of the types themselves, through [`super::format::SCENE_SCHEMA`]) has a row
//! in the table of its place, and every row names a field that exists.
//!
//! Rejected: a table of field docs in code with the Markdown generated from it (the reference's
//! tables sit among prose, examples and other tables, and generating parts of a hand-written
//! page is more machinery than reading it); doc comments on the serde types (serde keeps none
//! at run time).

use std::sync::OnceLock;

/// The reference page, as compiled in.
const REFERENCE: &str = include_str!("../../docs/scene-format.md");

/// One row of a field table of the reference.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FieldDoc {
    /// Which table: the heading above it, or the table's own first header cell when that names
    /// the holder (`` `shadow_map` field ``).
    pub table: String,
    pub name: String,
    /// The "type" column: kind, unit and range (`integer, pixels`, `degrees in [0, 90]`).
    pub kind: String,
    pub default: String,
    pub meaning: String,
}

impl FieldDoc {
    /// The row as Markdown for a hover: name and type, default, meaning.
    pub fn to_markdown(&self) -> String {
        let mut text = format!("`{}`: {}\n\ndefault: {}", self.name, self.kind, self.default);
        if !self.meaning.is_empty() {
            text.push_str("\n\n");
            text.push_str(&self.meaning);
        }
        text
    }
}

/// Every field row of the reference, in page order.
pub fn all() -> &'static [FieldDoc] {
    static DOCS: OnceLock<Vec<FieldDoc>> = OnceLock::new();
    DOCS.get_or_init(|| parse_tables(REFERENCE))
}

/// The tables that document the fields of the struct that the value of field `holder` is, or
/// of the struct variant `name` written there; the same arguments as
/// [`crate::diag::Schema::fields`]. The first table listing a field wins (a light's own table
/// before the table of what every light has).
pub fn tables_for(holder: Option<&str>, name: Option<&str>) -> &'static [&'static str] {
    match (holder, name) {
        (None, None | Some("Scene" | "Materials")) => &["Top level: `Scene`"],
        (Some("image"), _) => &["`image`"],
        (Some("camera") | None, Some("Perspective" | "Orthographic")) => &["Camera"],
        (Some("camera") | None, Some("Gltf")) => &["`Gltf`: a camera from a glTF file"],
        (Some("lights") | None, Some("Directional")) => &["`Directional`", "Lights"],
        (Some("lights") | None, Some("Point")) => &["`Point`", "Lights"],
        (Some("lights") | None, Some("Spot")) => &["`Spot`", "Lights"],
        (Some("shadow_map"), _) => &["`shadow_map` field"],
        (Some("attenuation"), _) => &["`attenuation` field"],
        (Some("material" | "materials"), _) => &["Materials"],
        (Some("objects"), _) => &["Objects"],
        (Some("mesh") | None, Some("Sphere")) => &["`Sphere` field"],
        _ => &[],
    }
}

/// The documentation of field `field` of the struct that `holder`/`name` locate (see
/// [`tables_for`]).
pub fn field_doc(holder: Option<&str>, name: Option<&str>, field: &str) -> Option<&'static FieldDoc> {
    tables_for(holder, name)
        .iter()
        .find_map(|table| all().iter().find(|doc| doc.table == *table && doc.name == field))
}

/// The field rows of `markdown`'s tables whose header starts `| field |` or ``| `x` field |``.
fn parse_tables(markdown: &str) -> Vec<FieldDoc> {
    let mut docs = Vec::new();
    let mut heading = String::new();
    // The table being read, if the lines are in a field table.
    let mut table: Option<String> = None;
    for line in markdown.lines() {
        let line = line.trim();
        if let Some(title) = line.strip_prefix('#') {
            heading = title.trim_start_matches('#').trim().to_owned();
            table = None;
            continue;
        }
        if !line.starts_with('|') {
            table = None;
            continue;
        }
        let cells = table_cells(line);
        match (&table, cells.as_slice()) {
            (None, [first, kind, default, meaning])
                if *kind == "type" && *default == "default" && *meaning == "meaning" =>
            {
                table = match *first {
                    "field" => Some(heading.clone()),
                    first if first.ends_with(" field") => Some(first.to_owned()),
                    _ => None,
                };
            }
            (Some(table), [name, kind, default, meaning]) => {
                let Some(name) = name.strip_prefix('`').and_then(|n| n.strip_suffix('`')) else {
                    continue; // the `|---|` line
                };
                docs.push(FieldDoc {
                    table: table.clone(),
                    name: name.to_owned(),
                    kind: (*kind).to_owned(),
                    default: (*default).to_owned(),
                    meaning: (*meaning).to_owned(),
                });
            }
            _ => {}
        }
    }
    docs
}

/// The cells of a Markdown table row, trimmed, without the outer pipes.
fn table_cells(line: &str) -> Vec<&str> {
    let inner = line.trim().trim_start_matches('|').trim_end_matches('|');
    inner.split('|').map(str::trim).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::format::SCENE_SCHEMA;

    /// Every place a struct of fields can be written, as the schema names them.
    const PLACES: &[(Option<&str>, Option<&str>)] = &[
        (None, None),
        (None, Some("Materials")),
        (Some("image"), None),
        (Some("camera"), Some("Perspective")),
        (Some("camera"), Some("Orthographic")),
        (Some("camera"), Some("Gltf")),
        (Some("lights"), Some("Directional")),
        (Some("lights"), Some("Point")),
        (Some("lights"), Some("Spot")),
        (Some("shadow_map"), None),
        (Some("attenuation"), None),
        (Some("materials"), None),
        (Some("objects"), None),
        (Some("mesh"), Some("Sphere")),
    ];

    #[test]
    fn every_field_of_the_format_is_documented_in_its_table() {
        for &(holder, name) in PLACES {
            let fields = (SCENE_SCHEMA.fields)(holder, name).expect("the schema knows the place");
            for field in fields {
                let doc = field_doc(holder, name, field);
                assert!(
                    doc.is_some_and(|doc| !doc.kind.is_empty() && !doc.default.is_empty()),
                    "docs/scene-format.md documents no `{field}` (type and default) for {holder:?} {name:?}"
                );
            }
        }
    }

    #[test]
    fn every_documented_field_exists() {
        for doc in all() {
            let exists = PLACES.iter().any(|&(holder, name)| {
                tables_for(holder, name).contains(&doc.table.as_str())
                    && (SCENE_SCHEMA.fields)(holder, name)
                        .is_some_and(|fields| fields.contains(&doc.name.as_str()))
            });
            assert!(
                exists,
                "docs/scene-format.md documents `{}` in `{}`, which the format has not",
                doc.name, doc.table
            );
        }
    }

    #[test]
    fn rows_are_read_word_for_word() {
        let width = field_doc(Some("image"), None, "width").unwrap();
        assert_eq!(width.kind, "integer, pixels");
        assert_eq!(width.default, "`800`");
        let cutoff = field_doc(Some("lights"), Some("Spot"), "cutoff").unwrap();
        assert_eq!(cutoff.kind, "degrees in [0, 90]");
        // A light's own table first, then what every light has.
        assert_eq!(
            field_doc(Some("lights"), Some("Spot"), "intensity")
                .unwrap()
                .table,
            "Lights"
        );
        assert_eq!(field_doc(Some("lights"), Some("Directional"), "cutoff"), None);
    }
}
