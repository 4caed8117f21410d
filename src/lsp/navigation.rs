//! Go to definition (a material name to its table entry, in the scene or an included library;
//! a mesh, texture or include path to the file) and the document's outline (objects, lights,
//! materials).

use std::path::Path;

use lsp_types::{DocumentSymbol, Location, Position, Range, SymbolKind};

use crate::lsp::completion::path_extensions;
use crate::lsp::cursor::{Role, TokenKind, pointing_at};
use crate::lsp::diagnostics::file_url;
use crate::lsp::documents::{Document, range_of};
use crate::ron_path;
use crate::scene::format::{self, LightFile, MeshFile, SceneFile};
use crate::scene::load::{LoadOptions, scene_materials};
use crate::scene::locate::{PathSegment, locate, locate_key};
use crate::scene::presets;

/// Where the name or path at byte `offset` of `document` is defined.
pub fn definition(document: &Document, offset: usize) -> Option<Location> {
    let text = &document.text;
    let cursor = pointing_at(text, offset);
    if cursor.token_kind != TokenKind::Str {
        return None;
    }
    let (_, value) = cursor.string_content(text)?;
    match &cursor.role {
        Role::Value(field) if field == "material" || field == "base" => {
            let wanted = presets::normalize_name(value);
            let materials =
                scene_materials(&document.path, document.materials_text(), &LoadOptions::default());
            let material = materials
                .iter()
                .find(|m| presets::normalize_name(&m.name) == wanted)?;
            let (path, span) = material.defined_at.clone()?;
            let range = if path == document.path {
                range_of(document.materials_text(), span)
            } else {
                range_of(&std::fs::read_to_string(&path).ok()?, span)
            };
            Some(Location::new(file_url(&path)?, range))
        }
        role => {
            path_extensions(role, cursor.name.as_deref())?;
            let path = document.path.parent().unwrap_or(Path::new("")).join(value);
            if !path.is_file() {
                return None;
            }
            let start = Position::new(0, 0);
            Some(Location::new(file_url(&path)?, Range::new(start, start)))
        }
    }
}

/// The outline: the scene's materials, lights and objects (a library's materials), each at
/// its value with its name or key selected. Empty while the text does not parse.
pub fn symbols(document: &Document) -> Vec<DocumentSymbol> {
    let text = &document.text;
    let Ok(scene) = format::ron_options().from_str::<SceneFile>(text) else {
        return library_symbols(text);
    };
    let mut symbols = material_symbols(text, scene.materials.0.iter().map(|(name, _)| name.as_str()));
    for (index, light) in scene.lights.iter().flatten().enumerate() {
        let kind = match light {
            LightFile::Directional { .. } => "Directional",
            LightFile::Point { .. } => "Point",
            LightFile::Spot { .. } => "Spot",
        };
        if let Some(span) = locate(text, &ron_path!["lights", index]) {
            symbols.push(symbol(
                format!("light {index}"),
                kind,
                SymbolKind::EVENT,
                text,
                span.clone(),
                span,
            ));
        }
    }
    for (index, object) in scene.objects.iter().enumerate() {
        let mesh = match &object.mesh {
            MeshFile::Sphere { .. } => "Sphere".to_owned(),
            MeshFile::Plane => "Plane".to_owned(),
            MeshFile::Cube => "Cube".to_owned(),
            MeshFile::Obj(path) => format!("Obj(\"{path}\")"),
            MeshFile::Gltf(path) => format!("Gltf(\"{path}\")"),
        };
        let name = object
            .name
            .clone()
            .unwrap_or_else(|| format!("object {}", index + 1));
        if let Some(span) = locate(text, &ron_path!["objects", index]) {
            let selection = locate(text, &ron_path!["objects", index, "name"]).unwrap_or(span.clone());
            symbols.push(symbol(name, &mesh, SymbolKind::OBJECT, text, span, selection));
        }
    }
    symbols
}

fn library_symbols(text: &str) -> Vec<DocumentSymbol> {
    match format::ron_options().from_str::<format::MaterialLibraryFile>(text) {
        Ok(library) => material_symbols(text, library.materials.0.iter().map(|(name, _)| name.as_str())),
        Err(_) => Vec::new(),
    }
}

fn material_symbols<'n>(text: &str, names: impl Iterator<Item = &'n str>) -> Vec<DocumentSymbol> {
    names
        .filter_map(|name| {
            let span = locate(text, &ron_path!["materials", PathSegment::key(name)])?;
            let key = locate_key(text, &ron_path!["materials"], name)?;
            Some(symbol(
                name.to_owned(),
                "material",
                SymbolKind::CONSTANT,
                text,
                key.start..span.end,
                key,
            ))
        })
        .collect()
}

fn symbol(
    name: String,
    detail: &str,
    kind: SymbolKind,
    text: &str,
    span: std::ops::Range<usize>,
    selection: std::ops::Range<usize>,
) -> DocumentSymbol {
    // `deprecated` is a field of the struct that the protocol replaced by `tags`.
    #[allow(deprecated)]
    DocumentSymbol {
        name,
        detail: Some(detail.to_owned()),
        kind,
        tags: None,
        deprecated: None,
        range: range_of(text, span),
        selection_range: range_of(text, selection),
        children: None,
    }
}
