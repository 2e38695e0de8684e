//! Loading the scene a command asks for: a built-in name, a TOML scene or a model file, with
//! seeded lights and a camera; the viewer loads its scenes the same way.

use std::path::{Path, PathBuf};

use crate::args::{LightSizeArgs, ModelArgs, RenderArgs};
use anyhow::{bail, Result};
use manyshadows::scene::builtin::{self, BuiltinOptions, LightMix};
use manyshadows::scene::Scene;

/// Loads a scene as `render` does: a built-in name, a TOML file or a model file (loaded as
/// `model` asks: paths outside its folder, the ground plane), with `lights` seeded lights
/// instead of its own when given, the light sizes `light_sizes` asks for and the camera at
/// `camera` (`PX,PY,PZ,TX,TY,TZ`) when given (what the viewer shows).
pub fn load_scene_for_view(
    scene: &str,
    mesh: Option<PathBuf>,
    lights: Option<usize>,
    seed: u64,
    light_sizes: LightSizeArgs,
    camera: Option<[f32; 6]>,
    model: ModelArgs,
) -> Result<Scene> {
    load_scene(&RenderArgs {
        scene: scene.to_string(),
        mesh,
        lights,
        seed,
        light_sizes,
        camera,
        model,
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
    Ok(scene)
}

pub(crate) fn load_scene_unsubdivided(args: &RenderArgs) -> Result<Scene> {
    let mix: LightMix = args.light_types.parse()?;
    let light_sizes = args.light_sizes.sizes()?;
    let path = Path::new(&args.scene);
    let lower = args.scene.to_ascii_lowercase();
    let model = [".obj", ".gltf", ".glb", ".ply", ".ply.gz"]
        .iter()
        .any(|ext| lower.ends_with(ext));
    // A built-in name wins over a same-named file in the working directory.
    let is_file = lower.ends_with(".toml")
        || model
        || (path.is_file() && !builtin::SCENE_NAMES.contains(&args.scene.as_str()));
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
            scene.lights =
                builtin::scatter_lights(&scene, n, args.seed, mix, args.shadow_resolution);
            if scene.lighting == manyshadows::scene::Lighting::Physical {
                // The layout's lights are in Phong units: 10 cd (or lx) each, as a model
                // file's seeded lights.
                let k = 1.0 / manyshadows::scene::loaders::PHONG_PER_LUX;
                for l in &mut scene.lights {
                    l.ambient *= k;
                    l.diffuse *= k;
                    l.specular *= k;
                }
            }
        } else if let Some(r) = args.shadow_resolution {
            for l in &mut scene.lights {
                l.shadow_resolution = r;
            }
        }
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
    Ok(builtin::build(&args.scene, &opts)?)
}
