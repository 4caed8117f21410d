//! Reading glTF accessors into plain arrays (glTF 2.0 specification, §3.6 "Buffers, buffer
//! views and accessors", §3.6.2.3 "Sparse accessors", §3.11 "Implementation note" on
//! normalized integers).
//!
//! # Design
//!
//! * **Bulk reads.** The common case, an accessor whose elements lie tightly packed in its
//!   buffer view (no `byteStride`, or one equal to the element size) of `f32`, `u16` or `u32`
//!   components, is one copy of the byte range into the typed array (`bytemuck`; a buffer
//!   whose range is not aligned for the type is copied byte-wise, which gives the same
//!   values). Everything else (a stride wider than an element, 8- and 16-bit attribute
//!   components, sparse accessors) is read element by element from little-endian bytes.
//!   Both paths give the same values; the bulk path is taken on little-endian machines only.
//! * **Normalized integers** become floats by the specification's formulas, correctly
//!   rounded: `c / 255` and `c / 65535` for unsigned bytes and shorts, `max(c / 127, −1)` and
//!   `max(c / 32767, −1)` for signed ones. (The `gltf` crate's reader multiplies by the
//!   reciprocal, which is one unit in the last place off for 150 of the 256 byte values.)
//!   Integers that are not normalized are converted exactly.
//! * **Sparse accessors** start from the base view's elements, or zeros when there is none,
//!   and replace the elements their indices name by their values. The specification wants
//!   the indices strictly increasing; they are applied in the order given (a later
//!   duplicate wins), and an index past the accessor's count is an error.
//! * **No panics, clear errors.** Every byte range is computed with checked arithmetic and
//!   checked against its buffer view, and every view against its buffer: an accessor that
//!   reaches past either is an error saying which accessor, view and buffer (with the
//!   buffer's file) and how many bytes it needs and has. The caller names the glTF file and
//!   decides whether the attribute is required (an error) or optional (a warning).
//!
//! Rejected: the `gltf` crate's `utils` reader, used before. It reads every element
//! through a `split_at` and a little-endian read per component (about ten times the
//! instructions of a copy on large meshes), rounds normalized integers differently from the
//! specification, silently skips sparse indices that are out of order or out of range,
//! and only says "outside its buffer" (through `None`) when data is missing.

use bytemuck::Pod;
use gltf::accessor::DataType;
use gltf::accessor::sparse::IndexType;

/// The elements of a float attribute accessor with `N` components each: `f32` as stored,
/// integers normalized or converted (module documentation). Unsigned 32-bit components are
/// for indices only and give an error here.
pub fn read_floats<const N: usize>(
    accessor: &gltf::Accessor,
    buffers: &[Vec<u8>],
) -> Result<Vec<[f32; N]>, String>
where
    [f32; N]: Pod,
{
    let normalized = accessor.normalized();
    match accessor.data_type() {
        DataType::F32 => read_elements(
            accessor,
            buffers,
            Component::new(4, f32_le),
            cast_tight::<[f32; N]>,
        ),
        DataType::U8 => read_elements(
            accessor,
            buffers,
            Component::new(1, move |bytes| integer_to_float(u8_le(bytes), 255.0, normalized)),
            no_bulk,
        ),
        DataType::I8 => read_elements(
            accessor,
            buffers,
            Component::new(1, move |bytes| {
                integer_to_float(u8_le(bytes) as i8, 127.0, normalized)
            }),
            no_bulk,
        ),
        DataType::U16 => read_elements(
            accessor,
            buffers,
            Component::new(2, move |bytes| {
                integer_to_float(u16_le(bytes), 65535.0, normalized)
            }),
            no_bulk,
        ),
        DataType::I16 => read_elements(
            accessor,
            buffers,
            Component::new(2, move |bytes| {
                integer_to_float(u16_le(bytes) as i16, 32767.0, normalized)
            }),
            no_bulk,
        ),
        DataType::U32 => Err(format!(
            "accessor {} holds unsigned int components, which glTF allows for indices only",
            accessor.index()
        )),
    }
}

/// The elements of an index accessor (unsigned byte, short or int scalars) as `u32`.
pub fn read_indices(accessor: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<u32>, String> {
    let elements: Vec<[u32; 1]> = match accessor.data_type() {
        DataType::U8 => read_elements(
            accessor,
            buffers,
            Component::new(1, |b| u32::from(u8_le(b))),
            no_bulk,
        ),
        DataType::U16 => read_elements(
            accessor,
            buffers,
            Component::new(2, |b| u32::from(u16_le(b))),
            |bytes| {
                cast_tight::<u16>(bytes).map(|indices| indices.into_iter().map(|i| [u32::from(i)]).collect())
            },
        ),
        DataType::U32 => read_elements(
            accessor,
            buffers,
            Component::new(4, u32_le),
            cast_tight::<[u32; 1]>,
        ),
        other => {
            return Err(format!(
                "accessor {} holds {other:?} indices; glTF allows unsigned byte, short and int",
                accessor.index()
            ));
        }
    }?;
    Ok(elements.into_iter().map(|[index]| index).collect())
}

/// How one component is stored: its size in bytes and how its little-endian bytes (at least
/// that many) become a `T`.
struct Component<T, D: Fn(&[u8]) -> T> {
    bytes: usize,
    decode: D,
}

impl<T, D: Fn(&[u8]) -> T> Component<T, D> {
    fn new(bytes: usize, decode: D) -> Self {
        Component { bytes, decode }
    }
}

/// The bulk read of a tightly packed run for a component type without one.
fn no_bulk<E>(_: &[u8]) -> Option<Vec<E>> {
    None
}

/// A tightly packed run of elements copied into a typed array: `None` on big-endian machines,
/// where the bytes would need swapping (the element-wise read does that).
fn cast_tight<E: Pod>(bytes: &[u8]) -> Option<Vec<E>> {
    if cfg!(target_endian = "big") {
        return None;
    }
    Some(match bytemuck::try_cast_slice::<u8, E>(bytes) {
        Ok(aligned) => aligned.to_vec(),
        // Unaligned for `E` (or a length that is not a whole number of elements, which the
        // caller's ranges rule out): copied byte-wise.
        Err(_) => bytemuck::allocation::pod_collect_to_vec(bytes),
    })
}

/// Reads an accessor with `N` components of `component` per element: the base elements
/// (bulk when tightly packed, through `bulk`), then the sparse substitution.
fn read_elements<T, D, const N: usize>(
    accessor: &gltf::Accessor,
    buffers: &[Vec<u8>],
    component: Component<T, D>,
    bulk: impl Fn(&[u8]) -> Option<Vec<[T; N]>>,
) -> Result<Vec<[T; N]>, String>
where
    T: Copy + Default,
    D: Fn(&[u8]) -> T,
{
    let count = accessor.count();
    let element_bytes = component.bytes * N;
    if element_bytes != accessor.size() {
        return Err(format!(
            "accessor {} has {}-byte elements, expected {N} components of {} bytes",
            accessor.index(),
            accessor.size(),
            component.bytes
        ));
    }
    let what = || format!("accessor {}", accessor.index());
    let mut elements = match accessor.view() {
        Some(view) => {
            let run = Run::new(&view, accessor.offset(), count, element_bytes, buffers, what)?;
            match run.is_tight().then(|| bulk(run.bytes)).flatten() {
                Some(elements) => elements,
                None => run.decode(&component),
            }
        }
        None => vec![[T::default(); N]; count],
    };
    if let Some(sparse) = accessor.sparse() {
        let substitutes = sparse.count();
        let indices = sparse.indices();
        let index_component_bytes = match indices.index_type() {
            IndexType::U8 => 1,
            IndexType::U16 => 2,
            IndexType::U32 => 4,
        };
        let index_run = Run::new(
            &indices.view(),
            indices.offset(),
            substitutes,
            index_component_bytes,
            buffers,
            || format!("the sparse indices of accessor {}", accessor.index()),
        )?;
        let index_decode = |bytes: &[u8]| match index_component_bytes {
            1 => u32::from(u8_le(bytes)),
            2 => u32::from(u16_le(bytes)),
            _ => u32_le(bytes),
        };
        let values = sparse.values();
        let value_run = Run::new(
            &values.view(),
            values.offset(),
            substitutes,
            element_bytes,
            buffers,
            || format!("the sparse values of accessor {}", accessor.index()),
        )?;
        let index_elements =
            index_run.decode::<u32, _, 1>(&Component::new(index_component_bytes, index_decode));
        for ([index], value) in index_elements.into_iter().zip(value_run.decode(&component)) {
            let slot = elements.get_mut(index as usize).ok_or_else(|| {
                format!(
                    "accessor {}: sparse index {index} is out of range ({count} elements)",
                    accessor.index()
                )
            })?;
            *slot = value;
        }
    }
    Ok(elements)
}

/// `count` elements of `element_bytes` bytes, `stride` bytes apart, checked to lie in their
/// buffer view and buffer.
struct Run<'b> {
    /// From the first element's first byte to the last element's last.
    bytes: &'b [u8],
    stride: usize,
    count: usize,
    element_bytes: usize,
}

impl<'b> Run<'b> {
    /// The run of `count` elements starting `offset` bytes into `view`; `what` names the
    /// reader in errors.
    fn new(
        view: &gltf::buffer::View,
        offset: usize,
        count: usize,
        element_bytes: usize,
        buffers: &'b [Vec<u8>],
        what: impl Fn() -> String,
    ) -> Result<Run<'b>, String> {
        let view_bytes = view_bytes(view, buffers)?;
        let stride = view.stride().unwrap_or(element_bytes);
        if stride < element_bytes || element_bytes == 0 {
            return Err(format!(
                "{}: buffer view {} has a stride of {stride} bytes, less than an element ({element_bytes} bytes)",
                what(),
                view.index()
            ));
        }
        let end = match count.checked_sub(1) {
            None => Some(offset),
            Some(last) => last
                .checked_mul(stride)
                .and_then(|start| start.checked_add(offset))
                .and_then(|start| start.checked_add(element_bytes)),
        };
        let bytes = end
            .and_then(|end| view_bytes.get(offset.min(end)..end))
            .ok_or_else(|| {
                format!(
                    "{}: {count} elements of {element_bytes} bytes every {stride} bytes from byte {offset} need {} bytes, but buffer view {} has {}: the data is truncated",
                    what(),
                    end.map_or_else(|| "more than 2⁶⁴".to_string(), |end| end.to_string()),
                    view.index(),
                    view_bytes.len()
                )
            })?;
        Ok(Run {
            bytes,
            stride,
            count,
            element_bytes,
        })
    }

    /// Whether the elements follow each other without gaps (a bulk copy reads them).
    fn is_tight(&self) -> bool {
        self.stride == self.element_bytes
    }

    /// The elements read one by one, each component decoded from its bytes.
    fn decode<T, D, const N: usize>(&self, component: &Component<T, D>) -> Vec<[T; N]>
    where
        T: Copy + Default,
        D: Fn(&[u8]) -> T,
    {
        self.bytes
            .chunks(self.stride)
            .take(self.count)
            .map(|element| {
                std::array::from_fn(|k| {
                    element
                        .get(k * component.bytes..)
                        .map_or_else(T::default, |bytes| (component.decode)(bytes))
                })
            })
            .collect()
    }
}

/// The bytes of a buffer view, checked to lie in its buffer's declared length (the buffer
/// loader checked that the data has at least that many bytes).
fn view_bytes<'b>(view: &gltf::buffer::View, buffers: &'b [Vec<u8>]) -> Result<&'b [u8], String> {
    let buffer = view.buffer();
    let data = buffers.get(buffer.index()).ok_or_else(|| {
        format!(
            "buffer view {} refers to buffer {}, which was not loaded",
            view.index(),
            buffer.index()
        )
    })?;
    let declared = buffer.length().min(data.len());
    let start = view.offset();
    let end = start.checked_add(view.length());
    end.and_then(|end| data.get(start..end).filter(|_| end <= declared))
        .ok_or_else(|| {
            let name = match buffer.source() {
                gltf::buffer::Source::Uri(uri) if !uri.starts_with("data:") => format!(" (`{uri}`)"),
                gltf::buffer::Source::Uri(_) => " (a data URI)".to_string(),
                gltf::buffer::Source::Bin => " (the GLB binary chunk)".to_string(),
            };
            format!(
                "buffer view {} covers bytes {start}..{} of buffer {}{name}, which has {declared}: the buffer is truncated or the view is wrong",
                view.index(),
                end.map_or_else(|| "2⁶⁴".to_string(), |end| end.to_string()),
                buffer.index()
            )
        })
}

/// An integer component as a float: normalized by the specification's formula (division by
/// the type's largest value, clamped at −1 for signed types, whose smallest value would give
/// slightly less), or converted as it is.
fn integer_to_float(value: impl Into<f32>, largest: f32, normalized: bool) -> f32 {
    let value = value.into();
    if normalized {
        (value / largest).max(-1.0)
    } else {
        value
    }
}

fn u8_le(bytes: &[u8]) -> u8 {
    bytes.first().copied().unwrap_or_default()
}

fn u16_le(bytes: &[u8]) -> u16 {
    bytes.first_chunk().map_or(0, |b| u16::from_le_bytes(*b))
}

fn u32_le(bytes: &[u8]) -> u32 {
    bytes.first_chunk().map_or(0, |b| u32::from_le_bytes(*b))
}

fn f32_le(bytes: &[u8]) -> f32 {
    f32::from_bits(u32_le(bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A document with one buffer of `buffer_length` bytes and the given buffer views and
    /// accessors (JSON arrays).
    fn document(buffer_length: usize, views: &str, accessors: &str) -> gltf::Document {
        let json = format!(
            r#"{{"asset": {{"version": "2.0"}},
                "buffers": [{{"uri": "data.bin", "byteLength": {buffer_length}}}],
                "bufferViews": {views}, "accessors": {accessors}}}"#
        );
        gltf::Gltf::from_slice(json.as_bytes())
            .unwrap_or_else(|e| panic!("{e}"))
            .document
    }

    fn accessor(document: &gltf::Document, index: usize) -> gltf::Accessor<'_> {
        document
            .accessors()
            .nth(index)
            .unwrap_or_else(|| panic!("accessor {index}"))
    }

    fn le_bytes<const K: usize, V: Copy>(values: &[V], to_bytes: impl Fn(V) -> [u8; K]) -> Vec<u8> {
        values.iter().flat_map(|&v| to_bytes(v)).collect()
    }

    /// Bulk-read floats, aligned and not (a view starting one byte into the buffer), equal
    /// the values written.
    #[test]
    fn tight_floats_are_read_exactly_aligned_or_not() {
        let values = [1.5f32, -0.0, 3.25e-7, f32::MAX, -2.0, 0.1];
        for start in [0, 1] {
            let mut bytes = vec![0xAB; start];
            bytes.extend(le_bytes(&values, f32::to_le_bytes));
            let doc = document(
                bytes.len(),
                &format!(r#"[{{"buffer": 0, "byteOffset": {start}, "byteLength": 24}}]"#),
                r#"[{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC2"}]"#,
            );
            let read = read_floats::<2>(&accessor(&doc, 0), &[bytes]).unwrap_or_else(|e| panic!("{e}"));
            let bits: Vec<u32> = read.iter().flatten().map(|v| v.to_bits()).collect();
            assert_eq!(bits, values.map(f32::to_bits), "start {start}");
        }
    }

    /// Interleaved attributes: a stride wider than the element, with an accessor offset
    /// inside it, reads every element from its own place.
    #[test]
    fn strided_elements_are_read_from_their_own_place() {
        // Per vertex: position (3 × f32), then uv as normalized u16 × 2, then 4 bytes of padding.
        let mut bytes = Vec::new();
        for vertex in 0..3u16 {
            let p = f32::from(vertex);
            bytes.extend(le_bytes(&[p, p + 0.5, -p], f32::to_le_bytes));
            bytes.extend(le_bytes(&[vertex * 1000 + 257, 65535 - vertex], u16::to_le_bytes));
            bytes.extend([0xFF; 4]);
        }
        let doc = document(
            bytes.len(),
            r#"[{"buffer": 0, "byteLength": 60, "byteStride": 20}]"#,
            r#"[{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
                {"bufferView": 0, "byteOffset": 12, "componentType": 5123, "normalized": true, "count": 3, "type": "VEC2"}]"#,
        );
        let buffers = [bytes];
        let positions = read_floats::<3>(&accessor(&doc, 0), &buffers).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(positions, [[0.0, 0.5, -0.0], [1.0, 1.5, -1.0], [2.0, 2.5, -2.0]]);
        let uvs = read_floats::<2>(&accessor(&doc, 1), &buffers).unwrap_or_else(|e| panic!("{e}"));
        let expected: Vec<[f32; 2]> = (0..3u16)
            .map(|v| {
                [
                    f32::from(v * 1000 + 257) / 65535.0,
                    f32::from(65535 - v) / 65535.0,
                ]
            })
            .collect();
        assert_eq!(uvs, expected);
    }

    /// Each integer component type, normalized by the specification's formula (correctly
    /// rounded division, not multiplication by the reciprocal: 3 / 255 and 257 / 65535 differ
    /// between the two) and unnormalized as the integer itself.
    #[test]
    fn normalized_integers_follow_the_specification() {
        let bytes: Vec<u8> = vec![3, 255, 0x80, 0x7F, 0xF7, 0x00];
        let shorts: Vec<u8> = le_bytes(&[257u16, 65535, 0x8000, 0x7FFF], u16::to_le_bytes);
        let mut buffer = bytes.clone();
        buffer.resize(8, 0);
        buffer.extend(&shorts);
        let doc = document(
            buffer.len(),
            r#"[{"buffer": 0, "byteLength": 6}, {"buffer": 0, "byteOffset": 8, "byteLength": 8}]"#,
            r#"[{"bufferView": 0, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC2"},
                {"bufferView": 0, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC2"},
                {"bufferView": 1, "componentType": 5123, "normalized": true, "count": 2, "type": "VEC2"},
                {"bufferView": 1, "componentType": 5122, "normalized": true, "count": 2, "type": "VEC2"},
                {"bufferView": 0, "componentType": 5120, "count": 3, "type": "VEC2"},
                {"bufferView": 1, "componentType": 5123, "count": 2, "type": "VEC2"}]"#,
        );
        let buffers = [buffer];
        let read = |index| -> Vec<f32> {
            read_floats::<2>(&accessor(&doc, index), &buffers)
                .unwrap_or_else(|e| panic!("{e}"))
                .into_iter()
                .flatten()
                .collect()
        };
        assert_eq!(
            read(0),
            [3.0 / 255.0, 1.0, 128.0 / 255.0, 127.0 / 255.0, 247.0 / 255.0, 0.0]
        );
        assert_ne!(
            3.0f32 / 255.0,
            3.0 * (1.0f32 / 255.0),
            "the case that tells the formulas apart"
        );
        // i8: −128 clamps to −1, 0x7F is 1, 0xF7 is −9.
        assert_eq!(read(1), [3.0 / 127.0, -1.0 / 127.0, -1.0, 1.0, -9.0 / 127.0, 0.0]);
        assert_eq!(
            read(2),
            [257.0 / 65535.0, 1.0, 32768.0 / 65535.0, 32767.0 / 65535.0]
        );
        assert_eq!(read(3), [257.0 / 32767.0, -1.0 / 32767.0, -1.0, 1.0]);
        assert_eq!(read(4), [3.0, -1.0, -128.0, 127.0, -9.0, 0.0]);
        assert_eq!(read(5), [257.0, 65535.0, 32768.0, 32767.0]);
    }

    /// Unsigned byte, short and int indices, tight and (for bytes) at an odd offset.
    #[test]
    fn indices_of_every_width() {
        let mut buffer = vec![9, 0, 1, 2, 250];
        buffer.resize(8, 0);
        buffer.extend(le_bytes(&[0u16, 65535, 7], u16::to_le_bytes));
        buffer.resize(16, 0);
        buffer.extend(le_bytes(&[0u32, 4_000_000_000, 5], u32::to_le_bytes));
        let doc = document(
            buffer.len(),
            r#"[{"buffer": 0, "byteLength": 5}, {"buffer": 0, "byteOffset": 8, "byteLength": 6}, {"buffer": 0, "byteOffset": 16, "byteLength": 12}]"#,
            r#"[{"bufferView": 0, "byteOffset": 1, "componentType": 5121, "count": 4, "type": "SCALAR"},
                {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
                {"bufferView": 2, "componentType": 5125, "count": 3, "type": "SCALAR"}]"#,
        );
        let buffers = [buffer];
        let read = |index| read_indices(&accessor(&doc, index), &buffers).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(read(0), [0, 1, 2, 250]);
        assert_eq!(read(1), [0, 65535, 7]);
        assert_eq!(read(2), [0, 4_000_000_000, 5]);
    }

    /// Sparse accessors over a base view and over zeros; the indices as u8, u16 and u32.
    #[test]
    fn sparse_values_replace_the_base_or_zeros() {
        let base = le_bytes(&[1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0], f32::to_le_bytes);
        let values = le_bytes(&[-1.0f32, -2.0, -3.0, -4.0], f32::to_le_bytes);
        let mut buffer = base.clone();
        buffer.extend(&values); // bytes 32..48
        buffer.extend(le_bytes(&[1u32, 3], u32::to_le_bytes)); // 48..56
        buffer.extend(le_bytes(&[0u16, 2], u16::to_le_bytes)); // 56..60
        buffer.extend([3u8, 1]); // 60..62
        let doc = document(
            buffer.len(),
            r#"[{"buffer": 0, "byteLength": 32}, {"buffer": 0, "byteOffset": 32, "byteLength": 16},
                {"buffer": 0, "byteOffset": 48, "byteLength": 8}, {"buffer": 0, "byteOffset": 56, "byteLength": 4},
                {"buffer": 0, "byteOffset": 60, "byteLength": 2}]"#,
            r#"[{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC2",
                 "sparse": {"count": 2, "indices": {"bufferView": 2, "componentType": 5125}, "values": {"bufferView": 1}}},
                {"componentType": 5126, "count": 4, "type": "VEC2",
                 "sparse": {"count": 2, "indices": {"bufferView": 3, "componentType": 5123}, "values": {"bufferView": 1}}},
                {"componentType": 5126, "count": 4, "type": "VEC2",
                 "sparse": {"count": 2, "indices": {"bufferView": 4, "componentType": 5121}, "values": {"bufferView": 1, "byteOffset": 0}}},
                {"componentType": 5126, "count": 3, "type": "VEC2",
                 "sparse": {"count": 2, "indices": {"bufferView": 4, "componentType": 5121}, "values": {"bufferView": 1}}}]"#,
        );
        let buffers = [buffer];
        let read = |index| read_floats::<2>(&accessor(&doc, index), &buffers);
        let ok = |index| read(index).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(ok(0), [[1.0, 2.0], [-1.0, -2.0], [5.0, 6.0], [-3.0, -4.0]]);
        assert_eq!(ok(1), [[-1.0, -2.0], [0.0, 0.0], [-3.0, -4.0], [0.0, 0.0]]);
        // Indices out of order are applied as given.
        assert_eq!(ok(2), [[0.0, 0.0], [-3.0, -4.0], [0.0, 0.0], [-1.0, -2.0]]);
        let error = read(3).err().unwrap_or_default();
        assert!(
            error.contains("accessor 3: sparse index 3 is out of range (3 elements)"),
            "{error}"
        );
    }

    /// An accessor reaching past its view, and a view reaching past its buffer, are errors
    /// that say so (never a panic, never short data).
    #[test]
    fn truncated_data_is_an_error_with_the_sizes() {
        let doc = document(
            40,
            r#"[{"buffer": 0, "byteLength": 30}, {"buffer": 0, "byteOffset": 16, "byteLength": 32}]"#,
            r#"[{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
                {"bufferView": 0, "byteOffset": 8, "componentType": 5123, "count": 12, "type": "SCALAR"},
                {"bufferView": 1, "componentType": 5126, "count": 1, "type": "VEC2"}]"#,
        );
        let buffers = [vec![0u8; 40]];
        let error = read_floats::<3>(&accessor(&doc, 0), &buffers)
            .err()
            .unwrap_or_default();
        assert!(
            error.contains("accessor 0: 3 elements of 12 bytes every 12 bytes from byte 0 need 36 bytes, but buffer view 0 has 30"),
            "{error}"
        );
        let error = read_indices(&accessor(&doc, 1), &buffers)
            .err()
            .unwrap_or_default();
        assert!(
            error.contains("need 32 bytes, but buffer view 0 has 30"),
            "{error}"
        );
        let error = read_floats::<2>(&accessor(&doc, 2), &buffers)
            .err()
            .unwrap_or_default();
        assert!(
            error.contains("buffer view 1 covers bytes 16..48 of buffer 0 (`data.bin`), which has 40"),
            "{error}"
        );
    }
}
