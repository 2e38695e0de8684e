//! Mesh loader tests: every file is generated here, in a temporary directory.
//!
//! By subject: OBJ and its materials (`obj`), PLY (`ply`), glTF geometry and conformance
//! (`gltf_geometry`), whole glTF scenes with materials, images, lights and camera, and the
//! defaults of files without lights or camera (`gltf_scene`), the glTF writer (`gltf_writer`),
//! crease-angle normals (`crease_normals`) and bad input (`bad_input`); paths that leave the
//! model's folder (`safe_paths`), files exporters write that used to be refused (`gaps`), glTF
//! extensions (`gltf_extensions`), compressed geometry (`compressed`), and the camera and
//! ground plane of a bare model (`defaults`); the helpers they share (temporary files, mesh
//! assertions, glTF documents) are in `common`.

mod bad_input;
mod common;
mod compressed;
mod crease_normals;
mod defaults;
mod gaps;
mod gltf_animation;
mod gltf_extensions;
mod gltf_geometry;
mod gltf_scene;
mod gltf_writer;
mod memory_files;
mod obj;
mod ply;
mod safe_paths;
