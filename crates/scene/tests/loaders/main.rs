//! Mesh loader tests: every file is generated here, in a temporary directory.
//!
//! By subject: OBJ and its materials (`obj`), PLY (`ply`), glTF geometry and conformance
//! (`gltf_geometry`), whole glTF scenes with materials, images, lights and camera, and the
//! defaults of files without lights or camera (`gltf_scene`), the glTF writer (`gltf_writer`),
//! crease-angle normals (`crease_normals`) and bad input (`bad_input`); the helpers they share
//! (temporary files, mesh assertions, glTF documents) are in `common`.

mod bad_input;
mod common;
mod crease_normals;
mod gltf_geometry;
mod gltf_scene;
mod gltf_writer;
mod obj;
mod ply;
