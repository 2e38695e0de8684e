//! Compressed glTF geometry: files compressed here with the same libraries the loader decodes
//! with (`draco-core`'s encoder, meshoptimizer's) give the same triangles as their
//! uncompressed source.

use glam::Vec3;
use manyshadows_scene::loaders::load_mesh;
use manyshadows_scene::Mesh;
use serde_json::{json, Value};

use crate::common::{base64, pyramid, save_json, temp_dir};

/// A one-primitive glTF document over `buffers` (data URIs, or a meshopt fallback for `None`
/// with that length), with `views`, `accessors` and the POSITION / indices accessors given.
fn doc(
    buffers: &[(Option<&[u8]>, usize)],
    views: Value,
    accessors: Value,
    primitive: Value,
) -> Value {
    let buffers: Vec<Value> = buffers
        .iter()
        .map(|(data, len)| match data {
            Some(d) => {
                json!({ "uri": format!("data:application/octet-stream;base64,{}", base64(d)),
                               "byteLength": d.len() })
            }
            None => json!({ "byteLength": len,
                            "extensions": { "EXT_meshopt_compression": { "fallback": true } } }),
        })
        .collect();
    json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "name": "p", "primitives": [primitive] }],
        "buffers": buffers,
        "bufferViews": views,
        "accessors": accessors
    })
}

fn bytes_of<T: bytemuck::Pod>(v: &[T]) -> Vec<u8> {
    bytemuck::cast_slice(v).to_vec()
}

/// The pyramid as a plain glTF (positions and u32 indices, normals computed by the loader).
fn uncompressed(source: &Mesh) -> Value {
    let mut data = bytes_of(
        &source
            .positions
            .iter()
            .map(|p| p.to_array())
            .collect::<Vec<_>>(),
    );
    let at = data.len();
    data.extend(bytes_of(&source.indices));
    doc(
        &[(Some(&data), data.len())],
        json!([{ "buffer": 0, "byteLength": at }, { "buffer": 0, "byteOffset": at, "byteLength": data.len() - at }]),
        json!([
            { "bufferView": 0, "componentType": 5126, "count": source.positions.len(), "type": "VEC3",
              "min": [-1, 0, -1], "max": [1, 1.7, 1] },
            { "bufferView": 1, "componentType": 5125, "count": source.indices.len(), "type": "SCALAR" }
        ]),
        json!({ "attributes": { "POSITION": 0 }, "indices": 1 }),
    )
}

/// Every triangle of `a` is a triangle of `b` (same corners, same winding, within `tol`), and
/// both have as many.
fn same_triangles(a: &Mesh, b: &Mesh, tol: f32) {
    let tris = |m: &Mesh| -> Vec<[Vec3; 3]> {
        m.indices
            .chunks_exact(3)
            .map(|t| [0, 1, 2].map(|k| m.positions[t[k] as usize]))
            .collect()
    };
    let (ta, tb) = (tris(a), tris(b));
    assert_eq!(ta.len(), tb.len());
    for t in &ta {
        let found = tb
            .iter()
            .any(|u| (0..3).any(|r| (0..3).all(|k| (t[k] - u[(k + r) % 3]).length() <= tol)));
        assert!(found, "triangle {t:?} is missing");
    }
}

#[test]
fn draco_primitives_decode_to_their_source_triangles() {
    use draco_core::{
        DataType, EncoderBuffer, EncoderOptions, FaceIndex, GeometryAttributeType, MeshEncoder,
        PointAttribute, PointIndex,
    };
    let dir = temp_dir("draco");
    let source = pyramid();
    let mut mesh = draco_core::Mesh::new();
    let mut positions = PointAttribute::new();
    positions.init(
        GeometryAttributeType::Position,
        3,
        DataType::Float32,
        false,
        source.positions.len(),
    );
    positions.buffer_mut().write(
        0,
        &bytes_of(
            &source
                .positions
                .iter()
                .map(|p| p.to_array())
                .collect::<Vec<_>>(),
        ),
    );
    let position_id = mesh.add_attribute(positions);
    mesh.set_num_faces(source.triangle_count());
    for (f, t) in source.indices.chunks_exact(3).enumerate() {
        mesh.set_face(
            FaceIndex(f as u32),
            [PointIndex(t[0]), PointIndex(t[1]), PointIndex(t[2])],
        );
    }
    let unique_id = mesh.attribute(position_id).unique_id();
    let mut options = EncoderOptions::new();
    options.set_attribute_int(position_id, "quantization_bits", 16);
    let mut encoder = MeshEncoder::new();
    encoder.set_mesh(mesh);
    let mut encoded = EncoderBuffer::new();
    encoder.encode(&options, &mut encoded).unwrap();
    let data = encoded.data().to_vec();

    let file = doc(
        &[(Some(&data), data.len())],
        json!([{ "buffer": 0, "byteLength": data.len() }]),
        json!([
            { "componentType": 5126, "count": source.positions.len(), "type": "VEC3",
              "min": [-1, 0, -1], "max": [1, 1.7, 1] },
            { "componentType": 5125, "count": source.indices.len(), "type": "SCALAR" }
        ]),
        json!({ "attributes": { "POSITION": 0 }, "indices": 1, "extensions": {
            "KHR_draco_mesh_compression": { "bufferView": 0, "attributes": { "POSITION": unique_id } }
        }}),
    );
    let mut file = file;
    file["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    file["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let decoded =
        load_mesh(&save_json(&dir, "draco.gltf", &file)).unwrap_or_else(|e| panic!("{e}"));
    let plain = load_mesh(&save_json(&dir, "plain.gltf", &uncompressed(&source))).unwrap();
    assert_eq!(decoded.len(), 1);
    // 16-bit quantization of a 2-unit box: within 1e-4.
    same_triangles(&plain[0], &decoded[0], 1e-4);
    same_triangles(&decoded[0], &plain[0], 1e-4);

    // Damaged Draco data is a clear error naming the extension.
    let mut broken = file.clone();
    let garbage = vec![7u8; data.len()];
    broken["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        base64(&garbage)
    ));
    let e = load_mesh(&save_json(&dir, "broken.gltf", &broken))
        .unwrap_err()
        .to_string();
    assert!(e.contains("KHR_draco_mesh_compression"), "{e}");
}

#[test]
fn meshopt_views_decode_to_their_source_bytes() {
    let dir = temp_dir("meshopt");
    let source = pyramid();
    let positions: Vec<[f32; 3]> = source.positions.iter().map(|p| p.to_array()).collect();
    let vertices = meshopt::encode_vertex_buffer(&positions).unwrap();
    let triangles = meshopt::encode_index_buffer(&source.indices, positions.len()).unwrap();
    let sequence = meshopt::encode_index_sequence(&source.indices, positions.len()).unwrap();
    for (mode, indices) in [("TRIANGLES", &triangles), ("INDICES", &sequence)] {
        let mut compressed = vertices.clone();
        compressed.resize(compressed.len().next_multiple_of(4), 0);
        let at = compressed.len();
        compressed.extend_from_slice(indices);
        let vertex_bytes = positions.len() * 12;
        let index_bytes = source.indices.len() * 4;
        let mut file = doc(
            &[
                (Some(&compressed), compressed.len()),
                (None, vertex_bytes + index_bytes),
            ],
            json!([
                { "buffer": 1, "byteLength": vertex_bytes, "byteStride": 12, "extensions": {
                    "EXT_meshopt_compression": { "buffer": 0, "byteLength": vertices.len(),
                        "byteStride": 12, "count": positions.len(), "mode": "ATTRIBUTES" } } },
                { "buffer": 1, "byteOffset": vertex_bytes, "byteLength": index_bytes, "extensions": {
                    "EXT_meshopt_compression": { "buffer": 0, "byteOffset": at,
                        "byteLength": indices.len(), "byteStride": 4,
                        "count": source.indices.len(), "mode": mode } } }
            ]),
            json!([
                { "bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3",
                  "min": [-1, 0, -1], "max": [1, 1.7, 1] },
                { "bufferView": 1, "componentType": 5125, "count": source.indices.len(), "type": "SCALAR" }
            ]),
            json!({ "attributes": { "POSITION": 0 }, "indices": 1 }),
        );
        file["extensionsUsed"] = json!(["EXT_meshopt_compression"]);
        file["extensionsRequired"] = json!(["EXT_meshopt_compression"]);
        let decoded = load_mesh(&save_json(&dir, &format!("{mode}.gltf"), &file))
            .unwrap_or_else(|e| panic!("{mode}: {e}"));
        let plain = load_mesh(&save_json(&dir, "plain.gltf", &uncompressed(&source))).unwrap();
        // Lossless: the very same triangles (the triangle codec may start a triangle at
        // another corner, keeping its winding; the sequence codec keeps the very indices).
        same_triangles(&decoded[0], &plain[0], 0.0);
        same_triangles(&plain[0], &decoded[0], 0.0);
        if mode == "INDICES" {
            assert_eq!(decoded[0].positions, plain[0].positions);
            assert_eq!(decoded[0].indices, plain[0].indices);
            assert_eq!(decoded[0].normals, plain[0].normals);
        }
    }
}

#[test]
fn meshopt_filtered_quantized_normals_decode_as_gltfpack_writes_them() {
    // Octahedral-filtered 8-bit normals (stride 4) on a triangle, as gltfpack writes them with
    // KHR_mesh_quantization: they decode to within 8-bit precision of the source normals.
    let dir = temp_dir("meshopt_oct");
    let source = [
        Vec3::X,
        Vec3::new(0.0, 0.6, 0.8),
        Vec3::new(0.48, 0.6, 0.64),
    ];
    let four: Vec<[f32; 4]> = source.iter().map(|n| [n.x, n.y, n.z, 0.0]).collect();
    let filtered: Vec<[i8; 4]> = meshopt::encode_filter_oct(&four, 8);
    let encoded = meshopt::encode_vertex_buffer(&filtered).unwrap();
    let positions: Vec<[f32; 3]> = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let mut data = bytes_of(&positions);
    let at = data.len();
    data.extend_from_slice(&encoded);
    let mut file = doc(
        &[(Some(&data), data.len()), (None, 12)],
        json!([
            { "buffer": 0, "byteLength": 36 },
            { "buffer": 1, "byteLength": 12, "byteStride": 4, "extensions": {
                "EXT_meshopt_compression": { "buffer": 0, "byteOffset": at,
                    "byteLength": encoded.len(), "byteStride": 4, "count": 3,
                    "mode": "ATTRIBUTES", "filter": "OCTAHEDRAL" } } }
        ]),
        json!([
            { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
              "min": [0, 0, 0], "max": [1, 1, 0] },
            { "bufferView": 1, "componentType": 5120, "normalized": true, "count": 3,
              "type": "VEC3" }
        ]),
        json!({ "attributes": { "POSITION": 0, "NORMAL": 1 } }),
    );
    file["extensionsUsed"] = json!(["EXT_meshopt_compression", "KHR_mesh_quantization"]);
    file["extensionsRequired"] = json!(["EXT_meshopt_compression", "KHR_mesh_quantization"]);
    let meshes = load_mesh(&save_json(&dir, "oct.gltf", &file)).unwrap_or_else(|e| panic!("{e}"));
    for (got, want) in meshes[0].normals.iter().zip(source) {
        assert!((*got - want).length() < 0.02, "{got} vs {want}");
    }
}
