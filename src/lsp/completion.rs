//! Completion: field names valid where the cursor is (with their type, default and meaning
//! from the reference, [`crate::scene::field_docs`]), enum variants, material names (the scene's
//! table, its includes, the presets) and file paths relative to the scene.

use std::path::Path;

use lsp_types::{
    CompletionItem, CompletionItemKind, CompletionTextEdit, Documentation, MarkupContent, MarkupKind,
    TextEdit,
};

use crate::lsp::cursor::{Cursor, Role, TokenKind, typing_at};
use crate::lsp::documents::{Document, range_of};
use crate::scene::field_docs;
use crate::scene::format::SCENE_SCHEMA;
use crate::scene::load::{LoadOptions, NamedMaterial, scene_materials};
use crate::scene::locate::fields_in_group;

/// At most this many files are offered from one folder.
const MAX_PATHS: usize = 500;

/// The completions at byte `offset` of `document`.
pub fn complete(document: &Document, offset: usize) -> Vec<CompletionItem> {
    let text = &document.text;
    let cursor = typing_at(text, offset);
    if cursor.token_kind == TokenKind::Str {
        return complete_in_string(document, &cursor, offset);
    }
    // What is replaced: the identifier being typed, or nothing.
    let replaced = match (&cursor.token, cursor.token_kind) {
        (Some(token), TokenKind::Ident) => token.start..offset,
        _ => offset..offset,
    };
    let edit = |insert: String| {
        Some(CompletionTextEdit::Edit(TextEdit::new(
            range_of(text, replaced.clone()),
            insert,
        )))
    };
    match &cursor.role {
        Role::FieldName => {
            let Some(fields) = (SCENE_SCHEMA.fields)(cursor.holder.as_deref(), cursor.name.as_deref()) else {
                return Vec::new();
            };
            // Fields already written are not offered again (a field may be given once).
            let written = cursor
                .group_open
                .and_then(|open| fields_in_group(text, open))
                .unwrap_or_default();
            fields
                .iter()
                .filter(|field| !written.iter().any(|w| w == *field))
                .map(|field| {
                    let doc = field_docs::field_doc(cursor.holder.as_deref(), cursor.name.as_deref(), field);
                    CompletionItem {
                        label: (*field).to_owned(),
                        kind: Some(CompletionItemKind::FIELD),
                        detail: doc.map(|doc| format!("{} (default: {})", doc.kind, doc.default)),
                        documentation: doc.map(|doc| markdown(doc.to_markdown())),
                        text_edit: edit(format!("{field}: ")),
                        ..CompletionItem::default()
                    }
                })
                .collect()
        }
        Role::Value(field) if field == "material" || field == "base" => materials(document)
            .into_iter()
            .map(|material| CompletionItem {
                text_edit: edit(format!("\"{}\"", material.name)),
                ..material_item(&material)
            })
            .collect(),
        Role::Value(field) if field == "shadows" => ["true", "false"]
            .into_iter()
            .map(|value| CompletionItem {
                label: value.to_owned(),
                kind: Some(CompletionItemKind::VALUE),
                text_edit: edit(value.to_owned()),
                ..CompletionItem::default()
            })
            .collect(),
        Role::Value(field) => (SCENE_SCHEMA.variants)(field)
            .unwrap_or_default()
            .iter()
            .map(|variant| CompletionItem {
                label: (*variant).to_owned(),
                kind: Some(CompletionItemKind::ENUM_MEMBER),
                text_edit: edit((*variant).to_owned()),
                ..CompletionItem::default()
            })
            .collect(),
        Role::MeshPath | Role::Other => Vec::new(),
    }
}

fn complete_in_string(document: &Document, cursor: &Cursor, offset: usize) -> Vec<CompletionItem> {
    let text = &document.text;
    let Some((content_start, _)) = cursor.string_content(text) else {
        return Vec::new();
    };
    let typed = text.get(content_start..offset).unwrap_or("");
    match &cursor.role {
        Role::Value(field) if field == "material" || field == "base" => {
            let replaced = range_of(text, content_start..offset);
            materials(document)
                .into_iter()
                .map(|material| CompletionItem {
                    text_edit: Some(CompletionTextEdit::Edit(TextEdit::new(
                        replaced,
                        material.name.clone(),
                    ))),
                    ..material_item(&material)
                })
                .collect()
        }
        role => {
            let Some(extensions) = path_extensions(role, cursor.name.as_deref()) else {
                return Vec::new();
            };
            let folder = document.path.parent().unwrap_or(Path::new(""));
            let typed_folder_len = typed.rfind('/').map_or(0, |slash| slash + 1);
            let replaced = range_of(text, content_start + typed_folder_len..offset);
            paths(&folder.join(&typed[..typed_folder_len]), extensions)
                .into_iter()
                .map(|(name, is_folder)| CompletionItem {
                    label: name.clone(),
                    kind: Some(if is_folder {
                        CompletionItemKind::FOLDER
                    } else {
                        CompletionItemKind::FILE
                    }),
                    text_edit: Some(CompletionTextEdit::Edit(TextEdit::new(replaced, name))),
                    ..CompletionItem::default()
                })
                .collect()
        }
    }
}

/// The file extensions a string in `role` names, when it names a file.
pub fn path_extensions(role: &Role, name: Option<&str>) -> Option<&'static [&'static str]> {
    match role {
        Role::Value(field) if field == "include" => Some(&["ron"]),
        Role::Value(field) if field == "texture" || field == "normal_map" => Some(&["png", "jpg", "jpeg"]),
        Role::MeshPath if name == Some("Obj") => Some(&["obj"]),
        Role::MeshPath => Some(&["gltf", "glb"]),
        _ => None,
    }
}

/// The folders (named with a trailing `/`) and files with one of `extensions` in `folder`,
/// sorted; hidden ones left out.
fn paths(folder: &Path, extensions: &[&str]) -> Vec<(String, bool)> {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return Vec::new();
    };
    let mut found: Vec<(String, bool)> = entries
        .flatten()
        .filter_map(|entry| {
            let name = entry.file_name().into_string().ok()?;
            if name.starts_with('.') {
                return None;
            }
            let is_folder = entry.file_type().ok()?.is_dir()
                || (entry.file_type().ok()?.is_symlink() && entry.path().is_dir());
            if is_folder {
                return Some((format!("{name}/"), true));
            }
            let extension = Path::new(&name).extension()?.to_str()?.to_ascii_lowercase();
            extensions.contains(&extension.as_str()).then_some((name, false))
        })
        .take(MAX_PATHS)
        .collect();
    found.sort();
    found
}

fn materials(document: &Document) -> Vec<NamedMaterial> {
    scene_materials(&document.path, document.materials_text(), &LoadOptions::default())
}

fn material_item(material: &NamedMaterial) -> CompletionItem {
    let detail = match &material.defined_at {
        Some((path, _)) => format!(
            "material from {}",
            path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into_owned()
            )
        ),
        None => "built-in material".to_owned(),
    };
    CompletionItem {
        label: material.name.clone(),
        kind: Some(CompletionItemKind::COLOR),
        detail: Some(detail),
        documentation: Some(markdown(crate::lsp::hover::material_markdown(material))),
        ..CompletionItem::default()
    }
}

pub fn markdown(value: String) -> Documentation {
    Documentation::MarkupContent(MarkupContent {
        kind: MarkupKind::Markdown,
        value,
    })
}
