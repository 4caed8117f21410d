//! Hover: a field's row of the reference (type and unit, default, meaning); a material name's
//! resolved coefficients and where it is defined; a mesh file's triangle count, bounds and
//! attributes, from the meshes the checker has loaded.

use std::path::Path;
use std::sync::Mutex;

use lsp_types::{Hover, HoverContents, MarkupContent, MarkupKind};

use crate::lsp::cursor::{Role, TokenKind, pointing_at};
use crate::lsp::documents::{Document, range_of};
use crate::mesh::Mesh;
use crate::scene::field_docs;
use crate::scene::load::{LoadOptions, MeshCache, NamedMaterial, scene_materials};
use crate::scene::{LightingModel, presets};

/// The hover at byte `offset` of `document`, if there is something to say.
pub fn hover(document: &Document, offset: usize, meshes: &Mutex<MeshCache>) -> Option<Hover> {
    let text = &document.text;
    let cursor = pointing_at(text, offset);
    let token = cursor.token.clone()?;
    let value = match (cursor.token_kind, &cursor.role) {
        (TokenKind::Ident, Role::FieldName) => {
            let field = text.get(token.clone())?;
            field_docs::field_doc(cursor.holder.as_deref(), cursor.name.as_deref(), field)?.to_markdown()
        }
        // A variant, `true`...: the documentation of the field it is the value of.
        (TokenKind::Ident, Role::Value(field)) => {
            field_docs::field_doc(cursor.holder.as_deref(), cursor.name.as_deref(), field)?.to_markdown()
        }
        (TokenKind::Str, Role::Value(field)) if field == "material" || field == "base" => {
            let (_, name) = cursor.string_content(text)?;
            let wanted = presets::normalize_name(name);
            let materials =
                scene_materials(&document.path, document.materials_text(), &LoadOptions::default());
            let material = materials
                .iter()
                .find(|m| presets::normalize_name(&m.name) == wanted)?;
            material_markdown(material)
        }
        (TokenKind::Str, Role::MeshPath) => {
            let (_, file) = cursor.string_content(text)?;
            let path = document.path.parent().unwrap_or(Path::new("")).join(file);
            // The checker may be loading a large mesh right now: say so rather than wait.
            let mesh = match meshes.try_lock() {
                Ok(cache) => cache.mesh_of_file(&path),
                Err(_) => None,
            };
            match mesh {
                Some(mesh) => mesh_markdown(file, &mesh),
                None => format!("`{file}`: not loaded yet (it is described once the scene has been checked)"),
            }
        }
        _ => return None,
    };
    Some(Hover {
        contents: HoverContents::Markup(MarkupContent {
            kind: MarkupKind::Markdown,
            value,
        }),
        range: Some(range_of(text, token)),
    })
}

/// A material's resolved coefficients and where it comes from.
pub fn material_markdown(material: &NamedMaterial) -> String {
    let m = &material.material;
    let rgb = |v: glam::Vec3| format!("({}, {}, {})", v.x, v.y, v.z);
    let origin = match &material.defined_at {
        Some((path, _)) => format!("defined in `{}`", path.display()),
        None => "built-in".to_owned(),
    };
    let model = match m.model {
        LightingModel::Phong => "Phong".to_owned(),
        LightingModel::BlinnPhong => "BlinnPhong".to_owned(),
        LightingModel::Lambert => "Lambert".to_owned(),
        LightingModel::Unlit => "Unlit".to_owned(),
        LightingModel::CookTorrance(microfacet) => format!(
            "CookTorrance (roughness {}, fresnel {}, {:?})",
            microfacet.roughness,
            rgb(microfacet.fresnel),
            microfacet.distribution
        ),
    };
    format!(
        "material `{}`, {origin}\n\n| | |\n|---|---|\n| ambient | {} |\n| diffuse | {} |\n| specular | {} |\n| shininess | {} |\n| emission | {} |\n| model | {model} |",
        material.name,
        rgb(m.ambient),
        rgb(m.diffuse),
        rgb(m.specular),
        m.shininess,
        rgb(m.emission),
    )
}

fn mesh_markdown(file: &str, mesh: &Mesh) -> String {
    let yes_no = |present: bool| if present { "yes" } else { "no" };
    let bounds = match mesh.bounds() {
        Some((lo, hi)) => format!("({}, {}, {}) to ({}, {}, {})", lo.x, lo.y, lo.z, hi.x, hi.y, hi.z),
        None => "empty".to_owned(),
    };
    format!(
        "`{file}`: {} triangles, {} vertices\n\nbounds: {bounds}\n\nnormals: yes (the file's, or computed)\n\ntexture coordinates: {}\n\nvertex colours: {}\n\nmaterials: {}\n\nclosed: {}",
        mesh.triangle_count(),
        mesh.positions.len(),
        yes_no(!mesh.uvs.is_empty()),
        yes_no(!mesh.colors.is_empty()),
        mesh.materials.len(),
        yes_no(mesh.closed),
    )
}
