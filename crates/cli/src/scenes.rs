//! Loading the scene a command asks for: a built-in name, a TOML scene or a model file, with
//! seeded lights and a camera; the viewer loads its scenes the same way.

use std::path::{Path, PathBuf};

use crate::args::{LightSizeArgs, ModelArgs, RenderArgs};
use anyhow::{bail, Result};
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::scene::Scene;

/// What the viewer asks of its scene, as `render`'s flags of the same names.
#[derive(Clone, Debug)]
pub struct ViewScene {
    /// A built-in name, a TOML file or a model file.
    pub scene: String,
    /// Mesh file for the dragon scene.
    pub mesh: Option<PathBuf>,
    /// Seeded lights instead of the scene's own.
    pub lights: Option<usize>,
    /// Seed of the light layout.
    pub seed: u64,
    /// The lights' sizes.
    pub light_sizes: LightSizeArgs,
    /// The camera, `PX,PY,PZ,TX,TY,TZ`.
    pub camera: Option<[f32; 6]>,
    /// How a model file is loaded (paths outside its folder, the ground plane).
    pub model: ModelArgs,
    /// Seeded reflection probes instead of the scene's own (0: none).
    pub probes: Option<usize>,
}

/// Loads a scene as `render` does: a built-in name, a TOML file or a model file (loaded as
/// `v.model` asks), with seeded lights instead of its own when given, the light sizes asked
/// for, the camera when given and seeded probes when asked (what the viewer shows).
pub fn load_scene_for_view(v: ViewScene) -> Result<Scene> {
    load_scene(&RenderArgs {
        scene: v.scene,
        mesh: v.mesh,
        lights: v.lights,
        seed: v.seed,
        light_sizes: v.light_sizes,
        camera: v.camera,
        model: v.model,
        probes: v.probes,
        ..RenderArgs::default()
    })
}

/// Loads a built-in scene or a TOML file, applying `--lights`/`--seed`/`--light-types` and
/// `--light-size`/`--sun-size`.
pub(crate) fn load_scene(args: &RenderArgs) -> Result<Scene> {
    let mut scene = load_scene_unsubdivided(args)?;
    if let Some(n) = args.probes {
        if n > manyshadows::scene::Probe::MAX_COUNT {
            bail!(
                "--probes {n} is more than the supported {}",
                manyshadows::scene::Probe::MAX_COUNT
            );
        }
        scene.probes = scene.seeded_probes(n, args.probe_resolution);
    } else {
        for p in &mut scene.probes {
            p.resolution = args.probe_resolution;
        }
    }
    if args.subdivide > 0 {
        scene.subdivide(args.subdivide)?;
    }
    if !args.shadows {
        for l in &mut scene.lights {
            l.casts_shadows = false;
        }
    }
    if let Some(c) = args.camera {
        scene.camera.position = glam::Vec3::new(c[0], c[1], c[2]);
        scene.camera.target = glam::Vec3::new(c[3], c[4], c[5]);
    }
    // A file's animation: its instances where the clock stands at the first frame.
    if let Some(clock) = args.animation.clock(&scene, args.frames)? {
        scene.set_time(clock.playing, clock.start);
    }
    Ok(scene)
}

/// The file endings read as model files (the rest as TOML scenes).
const MODEL_EXTENSIONS: [&str; 5] = [".obj", ".gltf", ".glb", ".ply", ".ply.gz"];

pub(crate) fn load_scene_unsubdivided(args: &RenderArgs) -> Result<Scene> {
    let mix: LightMix = args.light_types.parse()?;
    let light_sizes = args.light_sizes.sizes()?;
    let path = Path::new(&args.scene);
    let lower = args.scene.to_ascii_lowercase();
    let model = MODEL_EXTENSIONS.iter().any(|ext| lower.ends_with(ext));
    // A built-in name wins over a same-named file in the working directory.
    let builtin_name = builtin::SCENE_NAMES.contains(&args.scene.as_str());
    let is_file = lower.ends_with(".toml") || model || (path.is_file() && !builtin_name);
    if !builtin_name && path.is_dir() {
        bail!(
            "--scene {}: that is a folder; give a scene file (.toml), a model file ({}) or a \
             built-in scene ({})",
            args.scene,
            MODEL_EXTENSIONS.join(", "),
            builtin::SCENE_NAMES.join(", ")
        );
    }
    if is_file && !model && !lower.ends_with(".toml") {
        if let Some(ext) = path.extension() {
            bail!(
                "--scene {}: manyshadows reads no '.{}' files; a scene file is TOML (.toml), \
                 a model {}",
                args.scene,
                ext.to_string_lossy(),
                MODEL_EXTENSIONS.join(", ")
            );
        }
    }
    let load_options = args.model.options();
    if is_file {
        let mut scene = if model {
            // A model file is a scene of its own: its materials, textures, lights and camera
            // (defaults added where it has none, and said).
            let loaded = manyshadows::scene::loaders::load_scene_with(path, &load_options)?;
            for note in &loaded.notes {
                eprintln!("note: {}: {note}", path.display());
            }
            loaded.scene
        } else {
            manyshadows::scene::scene_file::load_scene_file(path)?
        };
        if let Some(n) = args.lights {
            if n > builtin::MAX_LIGHTS {
                bail!(
                    "--lights {n} is more than the supported {}",
                    builtin::MAX_LIGHTS
                );
            }
            manyshadows::scene::loaders::seed_lights(
                &mut scene,
                n,
                args.seed,
                mix,
                args.shadow_resolution,
            )?;
        } else if let Some(r) = args.shadow_resolution {
            for l in &mut scene.lights {
                l.shadow_resolution = r;
            }
        }
        add_lights(&mut scene, args, mix)?;
        light_sizes.apply(&mut scene.lights);
        return Ok(scene);
    }
    let mesh = match &args.mesh {
        Some(p) => {
            let meshes = manyshadows::scene::loaders::load_mesh_with(p, &load_options)?;
            Some(manyshadows::scene::primitives::merge(
                &meshes
                    .into_iter()
                    .map(|m| (m, glam::Mat4::IDENTITY))
                    .collect::<Vec<_>>(),
            ))
        }
        None => None,
    };
    let opts = BuiltinOptions {
        lights: args.lights,
        seed: args.seed,
        mix,
        mesh,
        shadow_resolution: args.shadow_resolution,
        light_sizes,
        default_probes: args.probes.is_none(),
    };
    let mut scene = builtin::build(&args.scene, &opts)?;
    if args.add_lights.is_some() {
        add_lights(&mut scene, args, mix)?;
        light_sizes.apply(&mut scene.lights);
    }
    Ok(scene)
}

/// `--add-lights N`: the seeded layout added to the scene's own lights.
fn add_lights(scene: &mut Scene, args: &RenderArgs, mix: LightMix) -> Result<()> {
    if let Some(n) = args.add_lights {
        manyshadows::scene::loaders::add_seeded_lights(
            scene,
            n,
            args.seed,
            mix,
            args.shadow_resolution,
        )?;
    }
    Ok(())
}
