//! Fuzzing the loaders on stable Rust (proptest; `cargo fuzz` needs a nightly toolchain):
//! every mesh format (OBJ, glTF, GLB, PLY ascii and binary, `.ply.gz`) and the TOML scene
//! format get generated and mutated inputs, and every input must end in a scene or mesh, or in
//! a clear error — no panic, no hang, no allocation driven by a count the file merely claims.
//! Whole-scene loading (`load_scene`) gets its own inputs: glTF and GLB files written by
//! `write_gltf` with an embedded PNG texture, an alpha mask, every light type and a camera, and
//! OBJ material libraries (texture statements, a PNG beside them).
//!
//! The inputs are valid seed files (built here) put through 1–8 mutations each: bytes flipped
//! or overwritten, "interesting" tokens inserted (huge and negative counts, NaN, infinities,
//! NUL), ranges deleted or duplicated, truncation; plus pure noise behind each format's magic.
//!
//! `MANYSHADOWS_FUZZ_CASES` sets the cases per batch (default 300: the bounded run of `cargo
//! test`, under a second); `MANYSHADOWS_FUZZ_SECONDS` repeats batches until that long has
//! passed. The long run in the README: `MANYSHADOWS_FUZZ_SECONDS=3600
//! MANYSHADOWS_FUZZ_CASES=1000 cargo test --release -p manyshadows-scene --test fuzz --
//! --nocapture --test-threads 5` (five threads, so every format gets its hour at once).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use glam::{Mat4, Vec2, Vec3};
use manyshadows_scene::loaders::{load_mesh, load_scene, write_gltf, write_obj, write_ply_ascii};
use manyshadows_scene::scene_file::load_scene_file;
use manyshadows_scene::{
    primitives, Attenuation, Camera, Instance, Light, LightKind, Material, Scene, SceneError,
    Texture, TextureRef, Wrap,
};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

/// Inputs on which a third-party parser panicked: the loaders catch that and report a parse
/// error (so no input takes the process down), and the fuzz run counts them as findings.
static CAUGHT_PANICS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// Longest any single input may take to load or be refused.
const MAX_CASE_TIME: Duration = Duration::from_secs(10);

/// `MANYSHADOWS_FUZZ_SECONDS`: keep generating batches of [`cases`] until this long has passed
/// (per format; the formats run in parallel).
fn seconds() -> Option<u64> {
    std::env::var("MANYSHADOWS_FUZZ_SECONDS")
        .ok()
        .and_then(|v| v.parse().ok())
}

fn cases() -> u32 {
    std::env::var("MANYSHADOWS_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(300)
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("manyshadows-fuzz-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Tokens that break parsers: counts past every integer type, negatives, non-finite floats.
const TOKENS: &[&[u8]] = &[
    b"4294967295",
    b"4294967296",
    b"18446744073709551615",
    b"1099511627776",
    b"-1",
    b"-2147483648",
    b"0",
    b"nan",
    b"inf",
    b"-inf",
    b"1e39",
    b"1e-45",
    b"\0",
    b"\n",
    b" ",
    b"\xff\xff\xff\xff",
    b"\"",
    b"[",
    b"{",
];

/// One mutation: (kind, position seed, value seed).
type Mutation = (u8, u32, u32);

fn mutate(seed: &[u8], mutations: &[Mutation]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for &(kind, at, v) in mutations {
        let len = b.len().max(1);
        let at = at as usize % len;
        match kind % 6 {
            0 => {
                if let Some(x) = b.get_mut(at) {
                    *x ^= 1 << (v % 8);
                }
            }
            1 => {
                if let Some(x) = b.get_mut(at) {
                    *x = v as u8;
                }
            }
            2 => {
                let t = TOKENS[v as usize % TOKENS.len()];
                let at = at.min(b.len());
                b.splice(at..at, t.iter().copied());
            }
            3 => {
                let end = (at + 1 + v as usize % 64).min(b.len());
                if at < end {
                    b.drain(at..end);
                }
            }
            4 => {
                let end = (at + 1 + v as usize % 64).min(b.len());
                if at < end {
                    let copy: Vec<u8> = b[at..end].to_vec();
                    let to = (v as usize) % (b.len() + 1);
                    b.splice(to..to, copy);
                }
            }
            _ => b.truncate(at),
        }
    }
    b
}

/// Loads `bytes` as `name` and checks the outcome is a result, in time.
fn check(path: &Path, bytes: &[u8], load: &dyn Fn(&Path) -> Result<usize, SceneError>) {
    std::fs::write(path, bytes).unwrap();
    let started = Instant::now();
    let outcome = load(path);
    let took = started.elapsed();
    assert!(
        took < MAX_CASE_TIME,
        "{} took {took:?} ({} bytes)",
        path.display(),
        bytes.len()
    );
    if let Err(e) = outcome {
        // Every error names what went wrong; an empty message is not a clear error.
        let message = e.to_string();
        assert!(!message.trim().is_empty());
        if message.contains("the parser failed on malformed data") {
            let n = CAUGHT_PANICS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            if n < 20 {
                eprintln!("caught parser panic: {message}");
            }
        }
    }
}

fn fuzz(
    name: &str,
    file: &str,
    seeds: Vec<Vec<u8>>,
    magic: &[u8],
    load: &dyn Fn(&Path) -> Result<usize, SceneError>,
) {
    let d = dir(name);
    let path = d.join(file);
    // The seeds themselves must load: the mutations start from valid files.
    for s in &seeds {
        std::fs::write(&path, s).unwrap();
        load(&path).unwrap_or_else(|e| panic!("{name}: a seed does not load: {e}"));
    }
    let config = Config {
        cases: cases(),
        failure_persistence: None,
        ..Config::default()
    };
    // Each batch gets a fresh runner with its own random stream (a runner runs its cases
    // once).
    let mut streams = TestRunner::new(config.clone());
    let strategy = (
        0..seeds.len(),
        prop::collection::vec((any::<u8>(), any::<u32>(), any::<u32>()), 1..8),
        prop::collection::vec(any::<u8>(), 0..256),
        any::<bool>(),
    );
    let panics_before = CAUGHT_PANICS.load(std::sync::atomic::Ordering::Relaxed);
    let started = Instant::now();
    let mut total = 0u64;
    loop {
        TestRunner::new_with_rng(config.clone(), streams.new_rng())
            .run(&strategy, |(seed, mutations, noise, noisy)| {
                let bytes = if noisy {
                    [magic, noise.as_slice()].concat()
                } else {
                    mutate(&seeds[seed], &mutations)
                };
                check(&path, &bytes, load);
                Ok(())
            })
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        total += u64::from(cases());
        if seconds().is_none_or(|s| started.elapsed() >= Duration::from_secs(s)) {
            break;
        }
    }
    let panics = CAUGHT_PANICS.load(std::sync::atomic::Ordering::Relaxed) - panics_before;
    eprintln!(
        "{name}: {total} cases in {:.0} s, {panics} parser panics caught",
        started.elapsed().as_secs_f64()
    );
    // The loaders turn a parser panic into an error, but a panic is still a bug to fix (the
    // one found so far, in gltf-json's validation, is now checked before it can happen).
    assert_eq!(
        panics, 0,
        "{name}: inputs made a parser panic (shown above)"
    );
    let _ = std::fs::remove_dir_all(&d);
}

fn meshes(path: &Path) -> Result<usize, SceneError> {
    load_mesh(path).map(|m| m.len())
}

fn scenes(path: &Path) -> Result<usize, SceneError> {
    load_scene(path).map(|s| s.scene.meshes.len())
}

/// A small scene with a texture, an alpha-masked material, every light type and a camera.
fn textured_scene() -> Scene {
    let texture = Texture::from_fn("t", 4, 4, |x, y| {
        [
            x as u8 * 60,
            y as u8 * 60,
            128,
            if x == y { 0 } else { 255 },
        ]
    });
    let light = |kind| Light {
        kind,
        ambient: Vec3::ZERO,
        diffuse: Vec3::new(1.0, 0.8, 0.6),
        specular: Vec3::new(1.0, 0.8, 0.6),
        attenuation: Attenuation::NONE,
        casts_shadows: true,
        shadow_resolution: 256,
        size: 0.0,
    };
    Scene {
        name: "fuzz".into(),
        meshes: vec![
            primitives::card(1.0, 1.0, Vec2::ONE),
            primitives::cuboid(Vec3::ONE),
        ],
        materials: vec![
            Material {
                base_color_texture: Some(TextureRef {
                    texture: 0,
                    wrap_s: Wrap::ClampToEdge,
                    wrap_t: Wrap::MirroredRepeat,
                }),
                ..Material::default().masked(0.5)
            },
            Material::default(),
        ],
        textures: vec![texture],
        instances: vec![
            Instance::caster(0, 0, Mat4::IDENTITY),
            Instance::caster(1, 1, Mat4::from_translation(Vec3::X * 2.0)),
        ],
        lights: vec![
            light(LightKind::Spot {
                position: Vec3::new(0.0, 3.0, 0.0),
                direction: Vec3::NEG_Y,
                cutoff_deg: 30.0,
                range: 10.0,
            }),
            light(LightKind::Point {
                position: Vec3::new(1.0, 2.0, 1.0),
                range: 5.0,
            }),
            light(LightKind::Directional {
                direction: Vec3::new(0.3, -1.0, 0.2),
                cascades: 2,
                split_lambda: 0.5,
                cascade_resolution_scale: 1.0,
            }),
        ],
        camera: Camera::look_at(Vec3::new(3.0, 2.0, 4.0), Vec3::ZERO),
        lighting: Default::default(),
        probes: Vec::new(),
        animations: Default::default(),
    }
}

/// [`textured_scene`] written as `name` (`.gltf` or `.glb`), as bytes.
fn written(name: &str) -> Vec<u8> {
    let d = dir(&format!("written-{name}"));
    let path = d.join(name);
    write_gltf(&textured_scene(), &path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let _ = std::fs::remove_dir_all(&d);
    bytes
}

fn png(t: &Texture) -> Vec<u8> {
    let mut out = Vec::new();
    image::RgbaImage::from_raw(t.width, t.height, t.rgba.to_vec())
        .unwrap()
        .write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

fn obj_seeds() -> Vec<Vec<u8>> {
    let mut cube = Vec::new();
    write_obj(&primitives::cuboid(glam::Vec3::ONE), &mut cube).unwrap();
    let quads = b"o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\n\
                  o b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf -3 -2 -1\n"
        .to_vec();
    vec![cube, quads]
}

fn ply_ascii() -> Vec<u8> {
    let mut b = Vec::new();
    write_ply_ascii(&primitives::uv_sphere(1.0, 6, 4), &mut b).unwrap();
    b
}

fn ply_binary() -> Vec<u8> {
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n\
                  property float y\nproperty float z\nelement face 2\n\
                  property list uchar int vertex_indices\nend_header\n"
        .to_vec();
    for p in [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]] {
        for c in p {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    for f in [[0i32, 1, 2], [0, 2, 3]] {
        b.push(3);
        for i in f {
            b.extend_from_slice(&i.to_le_bytes());
        }
    }
    b
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

/// A one-triangle glTF: 3 positions and 3 u16 indices in one buffer.
fn gltf_parts() -> (String, Vec<u8>) {
    let mut bin = Vec::new();
    for p in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    bin.extend_from_slice(&[0, 0]);
    let json = |uri: &str| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0,"translation":[0,1,0]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"buffers":[{{{uri}"byteLength":{}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#,
            bin.len()
        )
    };
    // The buffer embedded as base64.
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut b64 = String::new();
    for c in bin.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            b64.push(if k <= c.len() {
                A[(n >> (18 - 6 * k) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    let embedded = json(&format!(
        "\"uri\":\"data:application/octet-stream;base64,{b64}\","
    ));
    (embedded, bin)
}

fn glb() -> Vec<u8> {
    let (_, bin) = gltf_parts();
    let mut json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"buffers":[{{"byteLength":{}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#,
        bin.len()
    )
    .into_bytes();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

#[test]
fn obj_inputs_load_or_fail_cleanly() {
    fuzz("obj", "m.obj", obj_seeds(), b"v ", &meshes);
}

#[test]
fn ply_inputs_load_or_fail_cleanly() {
    fuzz(
        "ply",
        "m.ply",
        vec![ply_ascii(), ply_binary()],
        b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n",
        &meshes,
    );
}

#[test]
fn ply_gz_inputs_load_or_fail_cleanly() {
    // Mutating the compressed stream tests the decoder; compressing mutated text tests the
    // parser behind it: both.
    let seeds = vec![gzip(&ply_ascii()), gzip(&ply_binary())];
    fuzz("plygz", "m.ply.gz", seeds, &[0x1f, 0x8b, 8, 0], &meshes);
    let d = dir("plygz-inner");
    let path = d.join("m.ply.gz");
    let mut runner = TestRunner::new(Config {
        cases: cases(),
        failure_persistence: None,
        ..Config::default()
    });
    runner
        .run(
            &prop::collection::vec((any::<u8>(), any::<u32>(), any::<u32>()), 1..8),
            |m| {
                check(&path, &gzip(&mutate(&ply_binary(), &m)), &meshes);
                Ok(())
            },
        )
        .unwrap();
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn gltf_and_glb_inputs_load_or_fail_cleanly() {
    let (embedded, _) = gltf_parts();
    fuzz(
        "gltf",
        "m.gltf",
        vec![embedded.into_bytes()],
        b"{\"asset\":{\"version\":\"2.0\"},",
        &meshes,
    );
    fuzz("glb", "m.glb", vec![glb()], b"glTF\x02\0\0\0", &meshes);
}

#[test]
fn whole_gltf_scenes_load_or_fail_cleanly() {
    let (embedded, _) = gltf_parts();
    fuzz(
        "scene-gltf",
        "s.gltf",
        vec![written("s.gltf"), embedded.into_bytes()],
        b"{\"asset\":{\"version\":\"2.0\"},",
        &scenes,
    );
    fuzz(
        "scene-glb",
        "s.glb",
        vec![written("s.glb"), glb()],
        b"glTF\x02\0\0\0",
        &scenes,
    );
}

#[test]
fn obj_material_libraries_load_or_fail_cleanly() {
    // The OBJ and its textures stay; the material library is mutated.
    let d = dir("mtl");
    let texture = textured_scene().textures[0].clone();
    std::fs::create_dir_all(d.join("tex")).unwrap();
    std::fs::write(d.join("tex/leaf.png"), png(&texture)).unwrap();
    std::fs::write(
        d.join("m.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
         usemtl leaf\nf 1/1 2/2 3/3\nusemtl stone\nf 2/2 4/1 3/3\n",
    )
    .unwrap();
    let mtl = b"newmtl leaf\nKa 0 0 0\nKd 0.5 0.6 0.7\nKs 0.1 0.1 0.1\nNs 20\n\
        map_Kd -bm 1.0 tex\\leaf.png\nmap_d -clamp on tex/leaf.png\n\
        newmtl stone\nKd 0.4 0.4 0.4\nmap_Bump -bm 0.5 tex/leaf.png\nnorm tex/leaf.png\n"
        .to_vec();
    let obj = d.join("m.obj");
    fuzz("mtl", "m.mtl", vec![mtl], b"newmtl ", &|_| scenes(&obj));
    // And OBJ files loaded as scenes (materials missing: defaults).
    fuzz("obj-scene", "m.obj", obj_seeds(), b"v ", &scenes);
}

#[test]
fn scene_files_load_or_fail_cleanly() {
    let example =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/example_scene.toml"))
            .unwrap();
    fuzz(
        "toml",
        "s.toml",
        vec![example],
        b"name = \"x\"\n[camera]\n",
        &|p| load_scene_file(p).map(|s| s.instances.len()),
    );
}

/// Headers that claim far more than the file holds are refused before anything that size is
/// allocated (a 2^40-vertex PLY would need 12 TiB).
#[test]
fn claimed_counts_do_not_allocate() {
    let d = dir("claims");
    let ply = d.join("claims.ply");
    for count in ["1099511627776", "4294967295", "18446744073709551615"] {
        let text = format!(
            "ply\nformat binary_little_endian 1.0\nelement vertex {count}\nproperty float x\n\
             property float y\nproperty float z\nelement face 1\n\
             property list uchar int vertex_indices\nend_header\n\0\0\0\0"
        );
        check(&ply, text.as_bytes(), &meshes);
        assert!(load_mesh(&ply).is_err());
    }
    let glb_path = d.join("claims.glb");
    let mut g = glb();
    // Claim 2^32 - 1 bytes of total length and of JSON.
    g[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    check(&glb_path, &g, &meshes);
    g[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    check(&glb_path, &g, &meshes);
    let _ = std::fs::remove_dir_all(&d);
}

/// The panic the fuzzing found: a primitive whose POSITION names an accessor the file does not
/// have made gltf-json 1.4.1's validation index out of bounds. Now a parse error that says so.
#[test]
fn dangling_gltf_accessor_is_a_clear_error() {
    let (embedded, _) = gltf_parts();
    let d = dir("dangling");
    let path = d.join("dangling.gltf");
    std::fs::write(&path, embedded.replace("\"POSITION\":0", "\"POSITION\":7")).unwrap();
    let e = load_mesh(&path).unwrap_err().to_string();
    assert!(e.contains("uses accessor 7, but the file has 2"), "{e}");
    assert!(!e.contains("the parser failed"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}
