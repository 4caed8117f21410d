//! glTF 2.0 meshes (`.gltf` with external or `data:` buffers, and `.glb`), baked into one
//! [`Mesh`] in the file's scene space.
//!
//! # Design
//!
//! * **Parsing.** `gltf::Gltf::from_slice` parses and validates the document; buffers are
//!   then loaded one by one (the loop `gltf::import_buffers` runs, inlined so that each
//!   external `.bin` file is recorded in `files_read` and named in errors). Images are never
//!   decoded: `gltf::import` would decode every texture, which is slow and unused here.
//!   A required extension the loader does not support is an error naming it.
//! * **No panics.** `gltf` can panic on malformed input (out-of-range accessors, bad
//!   percent-encoding in a URI); every accessor is checked before it is read (component
//!   type, element size, stride, count) and every index against the vertex count, and the
//!   whole load also runs under `catch_unwind`, reported as "malformed glTF". The node
//!   hierarchy is walked with an explicit stack and a visited set, so a cyclic or shared
//!   hierarchy (invalid glTF) is an error instead of a stack overflow.
//! * **Scene.** The default scene is drawn, else scene 0, else (a file without scenes) every
//!   root node. Each node's world matrix is `parent · local`, composed in `f64`. Every
//!   TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN primitive of every node instance is baked:
//!   positions by the world matrix, normals by its inverse transpose (computed as the
//!   cofactor matrix, which stays finite for singular matrices) and renormalised; when
//!   the matrix mirrors (negative determinant) every triangle's winding is reversed so the
//!   front stays counter-clockwise. Strips and fans follow the glTF spec's vertex order,
//!   which keeps alternate strip triangles facing the same way. POINTS and LINES
//!   primitives are skipped with a warning. A mesh used by two nodes is baked twice, so
//!   the triangle count is per node instance.
//! * **Normals** are handled per primitive instance: file normals are repaired
//!   ([`normals::repair_normals`]), missing ones computed with the crease angle
//!   ([`normals::compute_vertex_normals`]) after the transform, so the crease angle applies
//!   to what is drawn.
//!
//! # Metallic-roughness to [`Material`]
//!
//! glTF's `pbrMetallicRoughness` maps onto the Cook-Torrance model with the GGX distribution
//! (the BRDF the glTF specification describes), not onto a Phong approximation:
//!
//! * roughness `α = r²` from the perceptual roughness `r` (floored at 10⁻³: a perfect mirror
//!   has no finite distribution);
//! * `F0 = lerp(0.04, baseColor, metallic)`: 4 % for dielectrics, the base colour for metals;
//! * diffuse = `baseColor·(1 − metallic)` (metals have no diffuse term), further weighted by
//!   `1 − F` when lit (the seed's energy conservation `k_s + k_d = 1`);
//! * ambient = `baseColor`, specular (used only by the debug views of other models) = `F0`;
//! * shininess = [`blinn_phong_exponent`] (used if the scene switches the model to Phong);
//! * emission = `emissiveFactor` × `KHR_materials_emissive_strength` (default 1).
//!
//! Textures are not sampled (a warning says so). Factors then stand for the whole
//! material, except one case: with a `metallicRoughnessTexture`, `metallicFactor` only
//! scales the texture and its default of 1 would turn every textured model into a metal, so
//! metallic is taken as 0 there. A primitive without a material uses the glTF default
//! material (base colour 1, metallic 1, roughness 1: a white rough metal), appended after
//! the file's materials when some primitive needs it.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use glam::{DMat3, DMat4, DVec3, Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use super::{LoadedMesh, Mesh, MeshError, MeshOptions, io_error_text, normals};
use crate::scene::{LightingModel, Material, Microfacet, MicrofacetDistribution};

/// Required extensions a file may list and still load: both are understood by the `gltf`
/// crate as built here, and neither changes the geometry (`KHR_lights_punctual` adds lights,
/// which are not part of a mesh and are ignored).
const SUPPORTED_REQUIRED_EXTENSIONS: [&str; 2] = ["KHR_materials_emissive_strength", "KHR_lights_punctual"];

/// The Blinn-Phong exponent equivalent to a glTF perceptual roughness (clamped to [0, 1]):
/// with `α = r²` (the GGX remapping glTF uses), the Beckmann-matched exponent
/// `n = 2/α² − 2`, clamped to [1, 1000] (α² is floored at 1e-4 first so a mirror does
/// not divide by zero).
pub fn blinn_phong_exponent(roughness: f32) -> f32 {
    let r = if roughness.is_finite() {
        roughness.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let alpha = r * r;
    (2.0 / (alpha * alpha).max(1e-4) - 2.0).clamp(1.0, 1000.0)
}

/// A glTF material's factors as a [`Material`] (module documentation). `metallic` and
/// `roughness` are clamped to [0, 1]; non-finite inputs fall back to the glTF defaults.
pub fn material_from_factors(base_color: Vec3, metallic: f32, roughness: f32, emission: Vec3) -> Material {
    let base_color = if base_color.is_finite() {
        base_color
    } else {
        Vec3::ONE
    };
    let metallic = if metallic.is_finite() {
        metallic.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let roughness = if roughness.is_finite() {
        roughness.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let fresnel = Vec3::splat(0.04).lerp(base_color, metallic);
    Material {
        ambient: base_color,
        diffuse: base_color * (1.0 - metallic),
        specular: fresnel,
        shininess: blinn_phong_exponent(roughness),
        emission: if emission.is_finite() {
            emission
        } else {
            Vec3::ZERO
        },
        model: LightingModel::CookTorrance(Microfacet {
            roughness: (roughness * roughness).max(1e-3),
            fresnel,
            distribution: MicrofacetDistribution::Ggx,
        }),
    }
}

/// The material of primitives that have none: glTF's default material (base colour 1,
/// metallic 1, roughness 1, no emission) through [`material_from_factors`].
pub fn default_material() -> Material {
    material_from_factors(Vec3::ONE, 1.0, 1.0, Vec3::ZERO)
}

/// Loads a `.gltf` or `.glb` file into one [`Mesh`]; see the module documentation.
pub fn load_gltf(path: &Path, options: &MeshOptions) -> Result<LoadedMesh, MeshError> {
    let bytes = std::fs::read(path).map_err(|error| MeshError::cannot_read(path, &error))?;
    catch_unwind(AssertUnwindSafe(|| load_gltf_bytes(path, &bytes, options))).unwrap_or_else(|panic| {
        let reason = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "the glTF reader gave up on this file".to_string());
        Err(MeshError::new(path, format!("malformed glTF: {reason}")))
    })
}

fn load_gltf_bytes(path: &Path, bytes: &[u8], options: &MeshOptions) -> Result<LoadedMesh, MeshError> {
    let fail = |message: String| MeshError::new(path, message);
    let (document, blob) = parse_document(bytes).map_err(fail)?;
    let mut files_read = vec![path.to_path_buf()];
    let directory = path.parent().unwrap_or(Path::new(""));
    let buffers = load_buffers(&document, blob, directory, &mut files_read).map_err(fail)?;

    let mut baker = Baker {
        buffers: &buffers,
        crease_angle_degrees: options.crease_angle_degrees,
        default_material_index: document.materials().len() as u32,
        mesh: Mesh::default(),
        skipped_primitives: Vec::new(),
        repaired_normals: 0,
        warnings: Vec::new(),
    };
    for (node, world) in scene_instances(&document).map_err(fail)? {
        if let Some(mesh) = node.mesh() {
            for primitive in mesh.primitives() {
                baker.bake(&mesh, &primitive, world).map_err(fail)?;
            }
        }
    }
    if baker.mesh.triangles.is_empty() {
        return Err(fail("contains no triangles".to_string()));
    }

    let Baker {
        mut mesh,
        mut warnings,
        skipped_primitives,
        repaired_normals,
        default_material_index,
        ..
    } = baker;
    if !skipped_primitives.is_empty() {
        warnings.push(format!(
            "skipped {} point or line primitives (mesh, primitive: {}): only triangles are drawn",
            skipped_primitives.len(),
            skipped_primitives
                .iter()
                .map(|(mesh, primitive)| format!("{mesh}, {primitive}"))
                .collect::<Vec<_>>()
                .join("; ")
        ));
    }
    if repaired_normals > 0 {
        warnings.push(format!(
            "{repaired_normals} vertex normals in the file were zero or not finite and were recomputed"
        ));
    }

    mesh.materials = document.materials().map(|m| material_from_gltf(&m)).collect();
    if mesh.triangle_materials.contains(&default_material_index) {
        mesh.materials.push(default_material());
    }
    let textured: Vec<String> = document
        .materials()
        .filter(|m| m.pbr_metallic_roughness().base_color_texture().is_some())
        .map(|m| {
            m.name().map_or_else(
                || format!("#{}", m.index().unwrap_or_default()),
                |n| format!("'{n}'"),
            )
        })
        .collect();
    if !textured.is_empty() {
        warnings.push(format!(
            "textures are not sampled; these materials use their base colour factor only: {}",
            textured.join(", ")
        ));
    }

    Ok(LoadedMesh {
        mesh,
        files_read,
        warnings,
    })
}

/// Parses and validates the document, returning it with the .glb binary chunk if any. An
/// unsupported required extension is named.
fn parse_document(bytes: &[u8]) -> Result<(gltf::Document, Option<Vec<u8>>), String> {
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|error| format!("malformed glTF: {error}"))?;
    let json = document.into_json();
    // Checked before validation, which reports an unknown required extension tersely.
    if let Some(name) = json
        .extensions_required
        .iter()
        .find(|name| !SUPPORTED_REQUIRED_EXTENSIONS.contains(&name.as_str()))
    {
        return Err(format!(
            "requires the glTF extension {name}, which is not supported"
        ));
    }
    // gltf-json 1.4's validation indexes a primitive's POSITION accessor before checking
    // that it exists, and panics; check attribute indices first.
    for (mesh_index, mesh) in json.meshes.iter().enumerate() {
        for (primitive_index, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(index) = primitive
                .attributes
                .values()
                .find(|index| index.value() >= json.accessors.len())
            {
                return Err(format!(
                    "malformed glTF: mesh {mesh_index} primitive {primitive_index} refers to accessor {}, but there are {}",
                    index.value(),
                    json.accessors.len()
                ));
            }
        }
    }
    let document = gltf::Document::from_json(json).map_err(|error| format!("malformed glTF: {error}"))?;
    Ok((document, blob))
}

/// The bytes of every buffer, in document order. External files are read relative to
/// `directory` and recorded in `files_read`.
fn load_buffers(
    document: &gltf::Document,
    mut blob: Option<Vec<u8>>,
    directory: &Path,
    files_read: &mut Vec<PathBuf>,
) -> Result<Vec<Vec<u8>>, String> {
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let index = buffer.index();
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                format!("buffer {index} refers to the binary chunk of a .glb, and there is none")
            })?,
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                gltf::buffer::Data::from_source(buffer.source(), None)
                    .map_err(|error| format!("buffer {index}: cannot decode its data URI: {error}"))?
                    .0
            }
            gltf::buffer::Source::Uri(uri) => {
                let relative =
                    percent_decode(uri).ok_or_else(|| format!("buffer {index}: malformed URI '{uri}'"))?;
                if relative.contains(':') {
                    return Err(format!(
                        "buffer {index}: unsupported URI '{uri}' (only relative paths and data: URIs)"
                    ));
                }
                let file = directory.join(relative);
                files_read.push(file.clone());
                std::fs::read(&file).map_err(|error| {
                    format!(
                        "cannot read buffer file {}: {}",
                        file.display(),
                        io_error_text(&error)
                    )
                })?
            }
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {index} has {} bytes but the file declares {}",
                data.len(),
                buffer.length()
            ));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// Decodes `%XX` escapes of a URI path; `None` for a malformed escape or non-UTF-8 result.
fn percent_decode(uri: &str) -> Option<String> {
    let bytes = uri.as_bytes();
    let mut decoded = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            decoded.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            decoded.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(decoded).ok()
}

/// Every node of the drawn scene with its world matrix, in depth-first order.
fn scene_instances(document: &gltf::Document) -> Result<Vec<(gltf::Node<'_>, DMat4)>, String> {
    let roots: Vec<gltf::Node> = match document.default_scene().or_else(|| document.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut is_child = vec![false; document.nodes().len()];
            for child in document.nodes().flat_map(|node| node.children()) {
                is_child[child.index()] = true;
            }
            document.nodes().filter(|node| !is_child[node.index()]).collect()
        }
    };
    let mut visited = vec![false; document.nodes().len()];
    let mut instances = Vec::new();
    let mut stack: Vec<(gltf::Node, DMat4)> = roots
        .into_iter()
        .rev()
        .map(|node| (node, DMat4::IDENTITY))
        .collect();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            return Err(format!(
                "malformed glTF: node {} is reached twice from the scene (node hierarchies must be trees)",
                node.index()
            ));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4();
        let world = parent * local;
        let children: Vec<gltf::Node> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|child| (child, world)));
        instances.push((node, world));
    }
    Ok(instances)
}

/// Accumulates baked primitives into one mesh.
struct Baker<'a> {
    buffers: &'a [Vec<u8>],
    crease_angle_degrees: f32,
    /// Material index of primitives without a material: one past the file's materials.
    default_material_index: u32,
    mesh: Mesh,
    /// (mesh, primitive) indices of point and line primitives.
    skipped_primitives: Vec<(usize, usize)>,
    repaired_normals: usize,
    warnings: Vec<String>,
}

impl Baker<'_> {
    /// Appends one primitive of one node instance, transformed by `world`.
    fn bake(&mut self, mesh: &gltf::Mesh, primitive: &gltf::Primitive, world: DMat4) -> Result<(), String> {
        let mode = primitive.mode();
        let here = format!("mesh {} primitive {}", mesh.index(), primitive.index());
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            self.skipped_primitives.push((mesh.index(), primitive.index()));
            return Ok(());
        }
        let buffers = self.buffers;
        let reader = primitive.reader(|buffer| buffers.get(buffer.index()).map(Vec::as_slice));

        let Some(position_accessor) = primitive.get(&gltf::Semantic::Positions) else {
            self.warnings
                .push(format!("{here} has no POSITION attribute and was skipped"));
            return Ok(());
        };
        check_accessor(&position_accessor, DataType::F32, Dimensions::Vec3)
            .map_err(|e| format!("{here}: POSITION {e}"))?;
        let vertex_count = position_accessor.count();
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or_else(|| format!("{here}: POSITION data lies outside its buffer"))?
            .map(|p| world.transform_point3(Vec3::from(p).as_dvec3()).as_vec3())
            .collect();
        if positions.len() != vertex_count {
            return Err(format!(
                "{here}: POSITION has {} of its {vertex_count} entries",
                positions.len()
            ));
        }
        if !positions.iter().all(|p| p.is_finite()) {
            return Err(format!(
                "{here}: a vertex position is not finite after the node transforms"
            ));
        }

        let indices: Vec<u32> = match primitive.indices() {
            None => (0..vertex_count as u32).collect(),
            Some(accessor) => {
                check_index_accessor(&accessor).map_err(|e| format!("{here}: indices {e}"))?;
                let indices: Vec<u32> = reader
                    .read_indices()
                    .ok_or_else(|| format!("{here}: index data lies outside its buffer"))?
                    .into_u32()
                    .collect();
                if let Some(&bad) = indices.iter().find(|&&i| i as usize >= vertex_count) {
                    return Err(format!(
                        "{here}: index {bad} is out of range ({vertex_count} vertices)"
                    ));
                }
                indices
            }
        };
        let mut triangles = assemble_triangles(mode, &indices);
        if mode == Mode::Triangles && !indices.len().is_multiple_of(3) {
            self.warnings.push(format!(
                "{here}: ignored {} indices after the last whole triangle",
                indices.len() % 3
            ));
        }
        let linear = DMat3::from_mat4(world);
        let mirrored = linear.determinant() < 0.0;
        if mirrored {
            for triangle in &mut triangles {
                triangle.swap(1, 2);
            }
        }

        let file_normals = match primitive.get(&gltf::Semantic::Normals) {
            None => None,
            Some(accessor) => {
                check_accessor(&accessor, DataType::F32, Dimensions::Vec3)
                    .map_err(|e| format!("{here}: NORMAL {e}"))?;
                // Inverse transpose of the linear part, up to the positive factor |det|:
                // the cofactor matrix, sign-corrected, which stays finite when det = 0.
                let cofactor = DMat3::from_cols(
                    linear.y_axis.cross(linear.z_axis),
                    linear.z_axis.cross(linear.x_axis),
                    linear.x_axis.cross(linear.y_axis),
                ) * if mirrored { -1.0 } else { 1.0 };
                let normals: Vec<Vec3> = reader
                    .read_normals()
                    .ok_or_else(|| format!("{here}: NORMAL data lies outside its buffer"))?
                    .map(|n| normals::unit_or_zero((cofactor * DVec3::from(n.map(f64::from))).as_vec3()))
                    .collect();
                if normals.len() == vertex_count {
                    Some(normals)
                } else {
                    self.warnings.push(format!(
                        "{here}: NORMAL has {} entries for {vertex_count} vertices; normals were computed",
                        normals.len()
                    ));
                    None
                }
            }
        };

        let baked = match file_normals {
            Some(file_normals) => {
                let repaired =
                    normals::repair_normals(&positions, &file_normals, &triangles, self.crease_angle_degrees);
                self.repaired_normals += repaired.replaced_count;
                repaired.mesh
            }
            None => normals::compute_vertex_normals(&positions, &triangles, self.crease_angle_degrees),
        };
        self.append(
            baked,
            primitive
                .material()
                .index()
                .map_or(self.default_material_index, |i| i as u32),
        )
    }

    fn append(&mut self, part: Mesh, material: u32) -> Result<(), String> {
        let offset = u32::try_from(self.mesh.positions.len())
            .ok()
            .filter(|offset| offset.checked_add(part.positions.len() as u32).is_some())
            .ok_or_else(|| "too many vertices (more than 2³²)".to_string())?;
        self.mesh.positions.extend(part.positions);
        self.mesh.normals.extend(part.normals);
        self.mesh
            .triangles
            .extend(part.triangles.iter().map(|triangle| triangle.map(|v| v + offset)));
        self.mesh
            .triangle_materials
            .extend(std::iter::repeat_n(material, part.triangles.len()));
        Ok(())
    }
}

/// Triangles from a primitive's index list, in the glTF spec's vertex order: strip triangle
/// `i` is `(v_i, v_{i+1+i%2}, v_{i+2−i%2})`, fan triangle `i` is `(v_{i+1}, v_{i+2}, v_0)`.
fn assemble_triangles(mode: Mode, indices: &[u32]) -> Vec<[u32; 3]> {
    let spans = indices.len().saturating_sub(2);
    match mode {
        Mode::TriangleStrip => (0..spans)
            .map(|i| [indices[i], indices[i + 1 + i % 2], indices[i + 2 - i % 2]])
            .collect(),
        Mode::TriangleFan => (0..spans)
            .map(|i| [indices[i + 1], indices[i + 2], indices[0]])
            .collect(),
        _ => indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    }
}

/// Checks what `gltf`'s reader assumes (and would panic or misread on): the element type,
/// a count of at least one, and a stride no smaller than an element.
fn check_accessor(
    accessor: &gltf::Accessor,
    data_type: DataType,
    dimensions: Dimensions,
) -> Result<(), String> {
    if accessor.data_type() != data_type || accessor.dimensions() != dimensions {
        return Err(format!(
            "accessor {} holds {:?} {:?}; expected {:?} {:?}",
            accessor.index(),
            accessor.dimensions(),
            accessor.data_type(),
            dimensions,
            data_type
        ));
    }
    check_layout(accessor)
}

fn check_index_accessor(accessor: &gltf::Accessor) -> Result<(), String> {
    let integer = matches!(accessor.data_type(), DataType::U8 | DataType::U16 | DataType::U32);
    if !integer || accessor.dimensions() != Dimensions::Scalar {
        return Err(format!(
            "accessor {} holds {:?} {:?}; expected unsigned integer scalars",
            accessor.index(),
            accessor.dimensions(),
            accessor.data_type()
        ));
    }
    check_layout(accessor)
}

fn check_layout(accessor: &gltf::Accessor) -> Result<(), String> {
    if accessor.count() == 0 {
        return Err(format!("accessor {} is empty", accessor.index()));
    }
    let too_narrow = accessor
        .view()
        .and_then(|view| view.stride())
        .filter(|&stride| stride < accessor.size());
    if let Some(stride) = too_narrow {
        return Err(format!(
            "accessor {}: stride {stride} is smaller than an element ({} bytes)",
            accessor.index(),
            accessor.size()
        ));
    }
    if accessor.view().is_none() && accessor.sparse().is_none() {
        return Err(format!("accessor {} has no data", accessor.index()));
    }
    Ok(())
}

/// One glTF material as a [`Material`] (module documentation).
fn material_from_gltf(material: &gltf::Material) -> Material {
    let pbr = material.pbr_metallic_roughness();
    let [r, g, b, _alpha] = pbr.base_color_factor();
    let metallic = if pbr.metallic_roughness_texture().is_some() {
        0.0
    } else {
        pbr.metallic_factor()
    };
    let emission = Vec3::from(material.emissive_factor()) * material.emissive_strength().unwrap_or(1.0);
    material_from_factors(Vec3::new(r, g, b), metallic, pbr.roughness_factor(), emission)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn asset(relative: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/gltf")
            .join(relative)
    }

    fn load(path: &Path) -> Result<LoadedMesh, MeshError> {
        load_gltf(path, &MeshOptions::default())
    }

    /// Loads an asset, checks the module invariant and the triangle count per node
    /// instance, and returns it.
    fn check_asset(relative: &str, triangles: usize) -> LoadedMesh {
        let loaded = load(&asset(relative)).unwrap_or_else(|e| panic!("{relative}: {e:?}"));
        check_invariant(&loaded.mesh);
        assert_eq!(loaded.mesh.triangle_count(), triangles, "{relative}");
        loaded
    }

    fn check_invariant(mesh: &Mesh) {
        assert_eq!(mesh.positions.len(), mesh.normals.len());
        assert!(mesh.positions.iter().all(|p| p.is_finite()));
        assert!(
            mesh.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-5),
            "unit normals"
        );
        let vertex_count = mesh.positions.len() as u32;
        assert!(mesh.triangles.iter().flatten().all(|&v| v < vertex_count));
        assert_eq!(mesh.triangle_materials.len(), mesh.triangles.len());
        assert!(
            mesh.triangle_materials
                .iter()
                .all(|&m| (m as usize) < mesh.materials.len())
        );
    }

    /// Expects loading `path` to fail with a message containing `message`.
    fn check_error(path: &Path, message: &str) {
        match load(path) {
            Ok(loaded) => panic!(
                "expected an error, loaded {} triangles",
                loaded.mesh.triangle_count()
            ),
            Err(error) => assert!(
                error.message.contains(message),
                "{error:?} should contain {message:?}"
            ),
        }
    }

    #[test]
    fn triangle_counts_per_node_instance() {
        // assets/LICENSES.md counts triangles per mesh; these count per node instance of
        // the drawn scene, so they differ where a mesh is used twice or a scene is skipped:
        check_asset("Avocado/glTF/Avocado.gltf", 682);
        check_asset("Box/glTF/Box.gltf", 12);
        check_asset("Box/glTF-Binary/Box.glb", 12);
        check_asset("Box/glTF-Embedded/Box.gltf", 12);
        check_asset("BoxInterleaved/glTF/BoxInterleaved.gltf", 12);
        check_asset("BoxInterleaved/glTF-Binary/BoxInterleaved.glb", 12);
        check_asset("BoxTextured/glTF/BoxTextured.gltf", 12);
        check_asset("BoxTextured/glTF-Binary/BoxTextured.glb", 12);
        // Mesh 0 (a square) under a rotated node; the cameras carry no mesh.
        check_asset("Cameras/glTF/Cameras.gltf", 2);
        check_asset("Duck/glTF/Duck.gltf", 4212);
        check_asset("Duck/glTF-Binary/Duck.glb", 4212);
        // The default scene is scene 1 ("scene": 1), holding only the square (2
        // triangles); the table's 3 adds the triangle of scene 0, which is not drawn.
        check_asset("MultipleScenes/glTF/MultipleScenes.gltf", 2);
        // 13 nodes, each with its own mesh: per instance equals per mesh.
        check_asset("OrientationTest/glTF/OrientationTest.gltf", 524);
        check_asset("OrientationTest/glTF-Binary/OrientationTest.glb", 524);
        // One 1-triangle mesh used by two nodes: 2 instances.
        check_asset("SimpleMeshes/glTF/SimpleMeshes.gltf", 2);
        // 5 nodes, each with its own 2-triangle mesh.
        check_asset("TextureCoordinateTest/glTF-Binary/TextureCoordinateTest.glb", 10);
        check_asset(
            "TextureCoordinateTest/glTF-Embedded/TextureCoordinateTest.gltf",
            10,
        );
        check_asset("Triangle/glTF/Triangle.gltf", 1);
        check_asset("Triangle/glTF-Embedded/Triangle.gltf", 1);
        check_asset("TriangleWithoutIndices/glTF/TriangleWithoutIndices.gltf", 1);
        check_asset(
            "TriangleWithoutIndices/glTF-Embedded/TriangleWithoutIndices.gltf",
            1,
        );
    }

    #[test]
    fn box_variants_give_identical_meshes() {
        let external = check_asset("Box/glTF/Box.gltf", 12);
        for other in ["Box/glTF-Binary/Box.glb", "Box/glTF-Embedded/Box.gltf"] {
            assert_eq!(check_asset(other, 12).mesh, external.mesh, "{other}");
        }
        assert_eq!(
            check_asset("BoxInterleaved/glTF/BoxInterleaved.gltf", 12)
                .mesh
                .bounds(),
            external.mesh.bounds()
        );
    }

    #[test]
    fn files_read_lists_external_buffers_only() {
        let external = check_asset("Box/glTF/Box.gltf", 12);
        assert_eq!(
            external.files_read,
            vec![asset("Box/glTF/Box.gltf"), asset("Box/glTF/Box0.bin")]
        );
        let binary = check_asset("Box/glTF-Binary/Box.glb", 12);
        assert_eq!(binary.files_read, vec![asset("Box/glTF-Binary/Box.glb")]);
        let embedded = check_asset("Box/glTF-Embedded/Box.gltf", 12);
        assert_eq!(embedded.files_read, vec![asset("Box/glTF-Embedded/Box.gltf")]);
    }

    #[test]
    fn box_material_maps_metallic_roughness() {
        let loaded = check_asset("Box/glTF/Box.gltf", 12);
        // "Red": baseColorFactor 0.8 0 0, metallic 0, roughness 1 (default).
        assert_eq!(loaded.mesh.materials.len(), 1, "every primitive has a material");
        let red = loaded.mesh.materials[0];
        assert_eq!(
            (red.diffuse, red.ambient),
            (Vec3::new(0.8, 0.0, 0.0), Vec3::new(0.8, 0.0, 0.0))
        );
        assert!(red.specular.distance(Vec3::splat(0.04)) < 1e-7);
        let expected = Microfacet {
            roughness: 1.0,
            fresnel: Vec3::splat(0.04),
            distribution: MicrofacetDistribution::Ggx,
        };
        assert_eq!(red.model, LightingModel::CookTorrance(expected));
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    }

    #[test]
    fn primitives_without_material_use_the_gltf_default() {
        let loaded = check_asset("Triangle/glTF/Triangle.gltf", 1);
        assert_eq!(loaded.mesh.materials, vec![default_material()]);
        let white_metal = default_material();
        // A metal: no diffuse term, F0 = the base colour.
        assert_eq!(
            (white_metal.diffuse, white_metal.specular, white_metal.ambient),
            (Vec3::ZERO, Vec3::ONE, Vec3::ONE)
        );
    }

    #[test]
    fn textured_materials_warn_and_are_not_metals() {
        let loaded = check_asset("Avocado/glTF/Avocado.gltf", 682);
        let avocado = loaded.mesh.materials[0];
        assert!(
            avocado.specular.distance(Vec3::splat(0.04)) < 1e-7,
            "metallicRoughnessTexture: metallic 0"
        );
        assert!(
            loaded
                .warnings
                .iter()
                .any(|w| w.contains("textures are not sampled")),
            "{:?}",
            loaded.warnings
        );
    }

    #[test]
    fn roughness_maps_to_blinn_phong_exponent() {
        assert_eq!(blinn_phong_exponent(1.0), 1.0, "2/1 - 2 = 0, clamped up");
        assert_eq!(blinn_phong_exponent(0.5), 30.0, "α = 0.25, 2/0.0625 - 2");
        assert_eq!(blinn_phong_exponent(0.0), 1000.0);
        assert_eq!(blinn_phong_exponent(f32::NAN), 1.0);
        assert!(blinn_phong_exponent(0.3) > blinn_phong_exponent(0.4));
    }

    #[test]
    fn node_transforms_are_applied() {
        // Duck: the root node scales by 0.01; the raw positions reach about ±100.
        let duck = check_asset("Duck/glTF/Duck.gltf", 4212);
        let (lo, hi) = duck.mesh.bounds().unwrap_or_default();
        assert!(lo.min_element() > -2.0 && hi.max_element() < 2.0, "{lo} {hi}");
        assert!(hi.max_element() > 0.5, "{lo} {hi}");
        // SimpleMeshes: the triangle spans [0, 1]² in XY, and the second node moves it by +1 in x.
        let simple = check_asset("SimpleMeshes/glTF/SimpleMeshes.gltf", 2);
        assert_eq!(simple.mesh.bounds(), Some((Vec3::ZERO, Vec3::new(2.0, 1.0, 0.0))));
    }

    #[test]
    fn duck_normals_point_away_from_its_body() {
        let duck = check_asset("Duck/glTF-Binary/Duck.glb", 4212);
        let mesh = &duck.mesh;
        let agreeing = mesh
            .triangles
            .iter()
            .filter(|t| {
                let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
                let face = normals::face_normal(a, b, c);
                t.iter().all(|&v| mesh.normals[v as usize].dot(face) > 0.0)
            })
            .count();
        assert!(
            agreeing * 100 > mesh.triangles.len() * 95,
            "{agreeing} of {}",
            mesh.triangles.len()
        );
    }

    #[test]
    fn broken_binary_files_are_errors_not_panics() {
        let dir = scratch_dir();
        let header_only = write(dir.path(), "header.glb", b"glTF\x02\x00\x00\x00\xff\xff\x00\x00");
        check_error(&header_only, "malformed glTF");
        let glb = std::fs::read(asset("Box/glTF-Binary/Box.glb")).unwrap_or_default();
        let truncated = write(dir.path(), "truncated.glb", &glb[..glb.len() / 2]);
        check_error(&truncated, "malformed glTF");
        let not_gltf = write(dir.path(), "text.gltf", b"solid cube\nendsolid\n");
        check_error(&not_gltf, "malformed glTF");
        check_error(
            &dir.path().join("missing.glb"),
            "cannot read mesh file: No such file or directory",
        );
    }

    // Synthetic files: one mesh with the given primitives, accessor i holding data block i,
    // written with an external .bin.

    fn scratch_dir() -> tempfile::TempDir {
        tempfile::Builder::new()
            .prefix("lampshade-gltf-test")
            .tempdir()
            .unwrap_or_else(|e| panic!("cannot create a temporary directory: {e}"))
    }

    fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
        path
    }

    /// One accessor's data.
    enum Block<'a> {
        Vec3(&'a [[f32; 3]]),
        Indices(&'a [u32]),
    }

    /// Writes `fixture.gltf` and `fixture.bin`, each block in its own buffer view and
    /// accessor. `primitives` and `nodes` are JSON arrays; `extra` is more top-level JSON
    /// members, each followed by a comma.
    fn write_fixture(dir: &Path, blocks: &[Block], primitives: &str, nodes: &str, extra: &str) -> PathBuf {
        let mut bin = Vec::new();
        let mut views = Vec::new();
        let mut accessors = Vec::new();
        for (index, block) in blocks.iter().enumerate() {
            let offset = bin.len();
            let accessor = match block {
                Block::Vec3(vectors) => {
                    bin.extend(vectors.iter().flatten().flat_map(|c| c.to_le_bytes()));
                    let (lo, hi) = vectors
                        .iter()
                        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), p| {
                            (
                                [0, 1, 2].map(|k| lo[k].min(p[k])),
                                [0, 1, 2].map(|k| hi[k].max(p[k])),
                            )
                        });
                    format!(
                        r#"{{"bufferView": {index}, "componentType": 5126, "count": {}, "type": "VEC3", "min": {lo:?}, "max": {hi:?}}}"#,
                        vectors.len()
                    )
                }
                Block::Indices(indices) => {
                    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
                    format!(
                        r#"{{"bufferView": {index}, "componentType": 5125, "count": {}, "type": "SCALAR"}}"#,
                        indices.len()
                    )
                }
            };
            views.push(format!(
                r#"{{"buffer": 0, "byteOffset": {offset}, "byteLength": {}}}"#,
                bin.len() - offset
            ));
            accessors.push(accessor);
        }
        write(dir, "fixture.bin", &bin);
        let json = format!(
            r#"{{
  "asset": {{"version": "2.0"}}, {extra}
  "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": {nodes},
  "meshes": [{{"primitives": {primitives}}}],
  "buffers": [{{"uri": "fixture.bin", "byteLength": {}}}],
  "bufferViews": [{}],
  "accessors": [{}]
}}"#,
            bin.len(),
            views.join(", "),
            accessors.join(", "),
        );
        write(dir, "fixture.gltf", json.as_bytes())
    }

    const SQUARE: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    const ONE_NODE: &str = r#"[{"mesh": 0}]"#;
    const TRIANGLES: &str = r#"[{"attributes": {"POSITION": 0}, "indices": 1}]"#;

    /// Loads a fixture and checks that every triangle faces +Z (geometric and vertex
    /// normals), returning the mesh.
    fn check_faces_up(path: &Path, triangles: usize) -> LoadedMesh {
        let loaded = load(path).unwrap_or_else(|e| panic!("{e:?}"));
        check_invariant(&loaded.mesh);
        let mesh = &loaded.mesh;
        assert_eq!(mesh.triangle_count(), triangles);
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            assert_eq!(normals::face_normal(a, b, c), Vec3::Z, "triangle {t:?}");
            assert!(t.iter().all(|&v| mesh.normals[v as usize] == Vec3::Z));
        }
        loaded
    }

    #[test]
    fn strips_keep_alternate_triangles_counter_clockwise() {
        let dir = scratch_dir();
        // Strip 0 1 2 3 over the square: (0 1 2) then (2 1 3) in spec order, both facing +Z.
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&SQUARE), Block::Indices(&[0, 1, 2, 3])],
            r#"[{"attributes": {"POSITION": 0}, "indices": 1, "mode": 5}]"#,
            ONE_NODE,
            "",
        );
        check_faces_up(&path, 2);
    }

    #[test]
    fn fans_become_triangles() {
        let dir = scratch_dir();
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&SQUARE), Block::Indices(&[0, 1, 3, 2])],
            r#"[{"attributes": {"POSITION": 0}, "indices": 1, "mode": 6}]"#,
            ONE_NODE,
            "",
        );
        check_faces_up(&path, 2);
    }

    #[test]
    fn non_indexed_triangles_and_skipped_points() {
        let dir = scratch_dir();
        let positions = [SQUARE[0], SQUARE[1], SQUARE[3]];
        let primitives = r#"[{"attributes": {"POSITION": 0}}, {"attributes": {"POSITION": 0}, "mode": 0}]"#;
        let loaded = check_faces_up(
            &write_fixture(dir.path(), &[Block::Vec3(&positions)], primitives, ONE_NODE, ""),
            1,
        );
        assert!(
            loaded
                .warnings
                .iter()
                .any(|w| w.contains("skipped 1 point or line")),
            "{:?}",
            loaded.warnings
        );
        assert_eq!(
            loaded.files_read,
            vec![dir.path().join("fixture.gltf"), dir.path().join("fixture.bin")]
        );
    }

    #[test]
    fn mirroring_node_keeps_front_faces_counter_clockwise() {
        let dir = scratch_dir();
        let facing_down = [SQUARE[0], SQUARE[2], SQUARE[1]];
        let primitive = r#"[{"attributes": {"POSITION": 0}}]"#;
        // A mirror in z turns the triangle to face +Z: the winding must be reversed and
        // the computed normals follow.
        let mirror_z = r#"[{"mesh": 0, "scale": [1, 1, -1]}]"#;
        check_faces_up(
            &write_fixture(dir.path(), &[Block::Vec3(&facing_down)], primitive, mirror_z, ""),
            1,
        );
        // The same with file normals, which go through the inverse transpose.
        let down = [[0.0, 0.0, -1.0]; 3];
        let with_normals = r#"[{"attributes": {"POSITION": 0, "NORMAL": 1}}]"#;
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&facing_down), Block::Vec3(&down)],
            with_normals,
            mirror_z,
            "",
        );
        check_faces_up(&path, 1);
        // A mirror in x leaves z alone: the triangle keeps facing -Z once rewound.
        let mirror_x = r#"[{"mesh": 0, "scale": [-1, 1, 1]}]"#;
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&facing_down), Block::Vec3(&down)],
            with_normals,
            mirror_x,
            "",
        );
        let loaded = load(&path).unwrap_or_else(|e| panic!("{e:?}"));
        let [a, b, c] = loaded.mesh.triangles[0].map(|v| loaded.mesh.positions[v as usize]);
        assert_eq!(normals::face_normal(a, b, c), -Vec3::Z);
        assert!(loaded.mesh.normals.iter().all(|&n| n == -Vec3::Z));
    }

    #[test]
    fn out_of_range_index_is_an_error() {
        let dir = scratch_dir();
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&SQUARE), Block::Indices(&[0, 1, 7])],
            TRIANGLES,
            ONE_NODE,
            "",
        );
        check_error(&path, "index 7 is out of range (4 vertices)");
    }

    #[test]
    fn unsupported_required_extension_is_named() {
        let dir = scratch_dir();
        let extra = r#""extensionsUsed": ["KHR_draco_mesh_compression"], "extensionsRequired": ["KHR_draco_mesh_compression"],"#;
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&SQUARE), Block::Indices(&[0, 1, 2])],
            TRIANGLES,
            ONE_NODE,
            extra,
        );
        check_error(&path, "requires the glTF extension KHR_draco_mesh_compression");
    }

    #[test]
    fn cyclic_node_hierarchy_is_an_error() {
        let dir = scratch_dir();
        let nodes = r#"[{"children": [1]}, {"children": [0], "mesh": 0}]"#;
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&SQUARE), Block::Indices(&[0, 1, 2])],
            TRIANGLES,
            nodes,
            "",
        );
        check_error(&path, "node");
    }

    #[test]
    fn attribute_naming_a_missing_accessor_is_an_error_not_a_panic() {
        // gltf-json's own validation would index past the end here.
        let dir = scratch_dir();
        let json =
            r#"{"asset": {"version": "2.0"}, "meshes": [{"primitives": [{"attributes": {"POSITION": 5}}]}]}"#;
        let path = write(dir.path(), "missing-accessor.gltf", json.as_bytes());
        check_error(&path, "mesh 0 primitive 0 refers to accessor 5, but there are 0");
    }

    #[test]
    fn missing_buffer_file_is_named() {
        let dir = scratch_dir();
        let path = write_fixture(
            dir.path(),
            &[Block::Vec3(&SQUARE), Block::Indices(&[0, 1, 2])],
            TRIANGLES,
            ONE_NODE,
            "",
        );
        std::fs::remove_file(dir.path().join("fixture.bin")).unwrap_or_else(|e| panic!("{e}"));
        check_error(&path, "cannot read buffer file");
        check_error(&path, "fixture.bin: No such file or directory");
    }

    #[test]
    fn percent_encoded_uris_are_decoded() {
        assert_eq!(percent_decode("my%20model.bin").as_deref(), Some("my model.bin"));
        assert_eq!(percent_decode("plain.bin").as_deref(), Some("plain.bin"));
        assert_eq!(percent_decode("bad%2").as_deref(), None);
        assert_eq!(percent_decode("bad%FF.bin").as_deref(), None, "not UTF-8");
    }
}
