//! What single-sided surfaces shadow (`SingleSidedShadows`, docs/decisions.md "What a
//! single-sided surface shadows"): every technique and the CPU reference follow one rule.
//!
//! Under the default rule (`front`) a single-sided surface blocks a shadow ray only where the
//! light sees its front: the ray ignores single-sided triangles whose front faces the ray's
//! origin. The truth here is traced through scenes that have no single-sided surface at all,
//! so it does not rest on the rule's code:
//! - a closed single-sided box casts as the same box made double-sided;
//! - an inverted outline shell 5 % larger than a cube (fronts facing in): a point inside it
//!   (the cube's own surface, the floor under it, the shell's inner walls) sees the light as if
//!   there were no shell, since every wall its rays cross shows them its front; a point outside
//!   sees it as a solid box 5 % larger, since a ray from outside that crosses the shell enters
//!   through a wall whose front faces the light (the far wall a camera at the light would see,
//!   the shell's outline);
//! - a single-sided floor (a patch facing up) lit from below casts nothing.
//!
//! Every technique's mask must agree with that truth: irregular and ray-traced shadows exactly
//! (0 pairs away from the edges), the shadow maps within 0.2 % (`compare`'s budget for real
//! content); where the camera sees the same surfaces as in the plain twin (the floor lit from
//! below), each technique's mask must equal its own mask of the twin bit for bit. Under the
//! other rule (`both`) every technique must match the reference traced with `both`, which
//! differs from the truth of `front` by hundreds of pixels: the scenes tell the rules apart in
//! every configuration.

mod common;

use glam::{Mat4, Vec3};
use manyshadows::scene::light_space::PointShadows;
use manyshadows::scene::{
    primitives, Attenuation, Camera, Instance, Light, LightKind, Material, Mesh, Scene,
};
use manyshadows::{
    CasterOptions, Pcf, RenderSettings, Renderer, ShadowOptions, SingleSidedShadows, Technique,
};

const WIDTH: u32 = 192;
const HEIGHT: u32 = 144;
const EDGE_BAND_PX: u32 = 2;
/// Misclassified pairs outside the edge band allowed to the shadow-map techniques.
const MAP_BUDGET: f64 = 0.002;
/// The centre of the cube in the shell (a unit cube on the floor).
const SHELL_CENTRE: Vec3 = Vec3::new(1.4, 0.5, -0.2);

/// `mesh` turned inside out: fronts facing in (an inverted hull).
fn inverted(mut mesh: Mesh) -> Mesh {
    for t in mesh.indices.chunks_mut(3) {
        t.swap(1, 2);
    }
    for n in &mut mesh.normals {
        *n = -*n;
    }
    mesh.name = format!("inverted {}", mesh.name);
    mesh
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Stage {
    /// A floor, a closed single-sided box and a cube inside a single-sided shell 5 % larger,
    /// lit from above, seen from above.
    Shells,
    /// A single-sided patch facing up, lit from below, under a ceiling, seen from below.
    FloorFromBelow,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Lamp {
    Spot,
    Point,
    Directional,
}

fn light(kind: LightKind, range: f32) -> Light {
    Light {
        kind,
        ambient: Vec3::ZERO,
        diffuse: Vec3::ONE,
        specular: Vec3::ZERO,
        attenuation: Attenuation::for_range(range),
        casts_shadows: true,
        shadow_resolution: 1024,
        size: 0.0,
    }
}

/// Where a shell stands: its box, as a solid twin to trace points outside it through.
struct Shell {
    lo: Vec3,
    hi: Vec3,
    solid: Scene,
}

/// A stage under a lamp: the scene, its plain twin (no shell, no patch, the box double-sided)
/// and, for the shells, the solid twin (the shell a plain double-sided box).
struct Case {
    scene: Scene,
    plain: Scene,
    shell: Option<Shell>,
}

impl Case {
    /// The truth under `front` at `surfaces`, traced through the twins only.
    fn truth(
        &self,
        surfaces: &manyshadows_reference::Surfaces,
    ) -> manyshadows_reference::ReferenceVisibility {
        let mut truth = common::trace_reference(&self.plain, surfaces, SingleSidedShadows::Both);
        if let Some(shell) = &self.shell {
            let solid = common::trace_reference(&shell.solid, surfaces, SingleSidedShadows::Both);
            // Points on the shell's walls count as inside (they face its interior).
            let margin = Vec3::splat(1e-3);
            for (i, p) in surfaces.points.iter().enumerate() {
                let Some(p) = p else { continue };
                let inside = p.position.cmpge(shell.lo - margin).all()
                    && p.position.cmple(shell.hi + margin).all();
                if !inside {
                    truth.lit.words[i] = solid.lit.words[i];
                }
            }
        }
        truth
    }
}

/// The stage under `lamp`.
fn case(stage: Stage, lamp: Lamp) -> Case {
    let single_sided = Material {
        cull_back_faces: true,
        diffuse: Vec3::new(0.8, 0.5, 0.3),
        ..Material::default()
    };
    let plain = Material::default();
    let at = Mat4::from_translation;
    let (meshes, mut instances, lamp_light, camera) = match stage {
        Stage::Shells => {
            let cube = primitives::cuboid(Vec3::ONE);
            let shell = inverted(cube.clone());
            let instances = vec![
                Instance::caster(0, 0, Mat4::IDENTITY),
                // The closed single-sided box.
                Instance::caster(1, 1, at(Vec3::new(-1.6, 0.5, 0.3))),
                // The plain cube and its shell, 5 % larger.
                Instance::caster(1, 0, at(SHELL_CENTRE)),
                Instance::caster(2, 1, at(SHELL_CENTRE) * Mat4::from_scale(Vec3::splat(1.05))),
            ];
            let l = match lamp {
                Lamp::Spot => light(
                    LightKind::Spot {
                        position: Vec3::new(0.6, 5.0, 1.2),
                        direction: Vec3::new(-0.1, -1.0, -0.25).normalize(),
                        cutoff_deg: 45.0,
                        range: 12.0,
                    },
                    12.0,
                ),
                Lamp::Point => light(
                    LightKind::Point {
                        position: Vec3::new(0.4, 3.5, 1.5),
                        range: 12.0,
                    },
                    12.0,
                ),
                Lamp::Directional => light(
                    LightKind::Directional {
                        direction: Vec3::new(-0.35, -1.0, -0.25).normalize(),
                        cascades: 2,
                        split_lambda: 0.5,
                        cascade_resolution_scale: 1.0,
                    },
                    1.0,
                ),
            };
            let meshes = vec![primitives::plane(9.0, 7.0, 4), cube, shell];
            (
                meshes,
                instances,
                l,
                Camera::look_at(Vec3::new(0.0, 5.5, 5.0), Vec3::new(0.0, 0.3, 0.0)),
            )
        }
        Stage::FloorFromBelow => {
            let instances = vec![
                // The ceiling (double-sided, as every plain surface).
                Instance::caster(0, 0, at(Vec3::new(0.0, 3.0, 0.0))),
                // The single-sided patch, its front up, the light below it.
                Instance::caster(1, 1, at(Vec3::new(0.2, 1.5, -0.1))),
            ];
            let l = match lamp {
                Lamp::Spot => light(
                    LightKind::Spot {
                        position: Vec3::new(0.0, 0.3, 0.0),
                        direction: Vec3::new(0.05, 1.0, 0.1).normalize(),
                        cutoff_deg: 60.0,
                        range: 10.0,
                    },
                    10.0,
                ),
                Lamp::Point => light(
                    LightKind::Point {
                        position: Vec3::new(0.0, 0.3, 0.0),
                        range: 10.0,
                    },
                    10.0,
                ),
                Lamp::Directional => light(
                    LightKind::Directional {
                        direction: Vec3::new(0.15, 1.0, 0.1).normalize(),
                        cascades: 2,
                        split_lambda: 0.5,
                        cascade_resolution_scale: 1.0,
                    },
                    1.0,
                ),
            };
            let meshes = vec![
                primitives::plane(12.0, 12.0, 4),
                primitives::plane(2.0, 2.0, 16),
            ];
            let camera = Camera::look_at(Vec3::new(0.0, -1.0, 4.5), Vec3::new(0.0, 2.2, 0.0));
            (meshes, instances, l, camera)
        }
    };
    let scene = Scene {
        textures: Vec::new(),
        name: format!("{stage:?} under a {lamp:?} light"),
        meshes: meshes.clone(),
        materials: vec![plain, single_sided],
        instances: instances.clone(),
        lights: vec![lamp_light],
        camera,
        lighting: Default::default(),
        probes: Vec::new(),
        animations: Default::default(),
    };
    scene.validate().expect("valid scene");
    // Every single-sided instance made plain: the shell a solid box.
    for i in &mut instances {
        i.material = 0;
    }
    let solid = Scene {
        name: format!("{} (solid twin)", scene.name),
        materials: vec![plain],
        instances: instances.clone(),
        ..scene.clone()
    };
    // No shell, no patch.
    instances.retain(|i| match stage {
        Stage::Shells => i.mesh != 2,
        Stage::FloorFromBelow => i.mesh != 1,
    });
    let plain = Scene {
        name: format!("{} (plain twin)", scene.name),
        instances,
        ..solid.clone()
    };
    plain.validate().expect("valid twin");
    let shell = (stage == Stage::Shells).then(|| {
        let (lo, hi) = (
            SHELL_CENTRE - Vec3::splat(0.525),
            SHELL_CENTRE + Vec3::splat(0.525),
        );
        Shell { lo, hi, solid }
    });
    Case {
        scene,
        plain,
        shell,
    }
}

fn settings(technique: Technique, point: PointShadows, rule: SingleSidedShadows) -> RenderSettings {
    RenderSettings::default()
        .with_width(WIDTH)
        .with_height(HEIGHT)
        .with_pcf(Pcf::Off)
        .with_visibility(true)
        .with_technique(technique)
        .with_point_shadows(point)
        .with_shadow(
            ShadowOptions::default().with_casters(CasterOptions::default().with_single_sided(rule)),
        )
}

/// Visibility bits that differ between two masks of the same size.
fn differing_bits(a: &manyshadows::VisibilityMask, b: &manyshadows::VisibilityMask) -> u32 {
    a.words
        .iter()
        .zip(&b.words)
        .map(|(x, y)| (x ^ y).count_ones())
        .sum()
}

fn misclassified(e: &common::ReferenceErrors) -> f64 {
    let c = &e.counts;
    (c.false_shadow + c.false_light) as f64 / c.in_reach.max(1) as f64
}

/// Every technique on `stage` under `lamp` (point lights: each kind of point shadow a
/// technique renders), under both rules.
fn check(stage: Stage, lamp: Lamp) {
    let ctx = common::context();
    let case = case(stage, lamp);
    let name = &case.scene.name;
    let mut ran = 0;
    let mut seen_reference = false;
    for technique in Technique::all() {
        let info = technique.info();
        let points: Vec<PointShadows> = if lamp == Lamp::Point {
            info.point_shadows.to_vec()
        } else {
            vec![PointShadows::default()]
        };
        let exact = matches!(
            info.fills,
            manyshadows::Fills::Mask | manyshadows::Fills::Rays
        );
        for point in points {
            let label = if lamp == Lamp::Point {
                format!("{name} / {technique} ({point:?})")
            } else {
                format!("{name} / {technique}")
            };
            let front = settings(technique, point, SingleSidedShadows::Front);
            let Some(mut r) = common::renderer_or_refusal(&ctx, &case.scene, front.clone()) else {
                continue;
            };
            let vis = r.render().expect("frame").visibility.expect("mask");
            let surfaces = common::gbuffer_surfaces(&r);
            let truth = case.truth(&surfaces);

            if !seen_reference {
                // The CPU reference itself: under `front` it is the truth at every pixel;
                // under `both` it is not.
                let pixels = (WIDTH * HEIGHT) as usize;
                let count = |v: &manyshadows_reference::ReferenceVisibility| {
                    (0..pixels)
                        .filter(|&p| v.lit.get(p, 0) != truth.lit.get(p, 0))
                        .count()
                };
                let got =
                    common::trace_reference(&case.scene, &surfaces, SingleSidedShadows::Front);
                let both =
                    common::trace_reference(&case.scene, &surfaces, SingleSidedShadows::Both);
                let lit = (0..pixels).filter(|&p| truth.lit.get(p, 0)).count();
                eprintln!(
                    "{name}: the reference under front differs from the truth at {} pixels, \
                     under both at {} ({lit} of {pixels} lit)",
                    count(&got),
                    count(&both)
                );
                assert_eq!(count(&got), 0, "{name}: the CPU reference breaks the rule");
                assert!(
                    lit > 2000 && pixels - lit > 2000,
                    "{name}: degenerate ({lit} lit)"
                );
                assert!(count(&both) > 300, "{name}: the rules look alike here");
                seen_reference = true;
            }

            let e = common::errors_against(&truth, &surfaces, &vis, EDGE_BAND_PX);
            eprintln!(
                "{label}, front: {} pairs away from edges differ from the truth ({:.4} % \
                 misclassified)",
                e.wrong,
                misclassified(&e) * 100.0
            );
            if exact {
                assert_eq!(e.wrong, 0, "{label}: breaks the rule (front)");
            } else {
                assert!(
                    misclassified(&e) <= MAP_BUDGET,
                    "{label}: {:.4} % misclassified (front)",
                    misclassified(&e) * 100.0
                );
            }
            if stage == Stage::FloorFromBelow {
                // The camera sees what it sees in the plain twin: the same mask, bit for bit.
                let mut plain = Renderer::new(&ctx, &case.plain, front).expect("the twin renders");
                let plain_vis = plain.render().expect("frame").visibility.expect("mask");
                let same = differing_bits(&vis, &plain_vis);
                eprintln!("{label}: {same} bits differ from its own mask of the twin");
                assert_eq!(same, 0, "{label}: the mask differs from the twin's");
            }

            // The other rule: against the reference traced with it.
            let both = settings(technique, point, SingleSidedShadows::Both);
            let mut r = Renderer::new(&ctx, &case.scene, both).expect("renderer (both)");
            let vis = r.render().expect("frame").visibility.expect("mask");
            let e = common::reference_errors_with(
                &r,
                &case.scene,
                &vis,
                EDGE_BAND_PX,
                SingleSidedShadows::Both,
            );
            let off = common::errors_against(&truth, &surfaces, &vis, EDGE_BAND_PX);
            eprintln!(
                "{label}, both: {} pairs away from edges differ from the reference ({:.4} % \
                 misclassified); {} from the truth of front",
                e.wrong,
                misclassified(&e) * 100.0,
                off.wrong
            );
            if exact {
                assert_eq!(e.wrong, 0, "{label}: wrong under rule both");
            } else if stage == Stage::Shells {
                // The shell lies 2.5 cm off the cube, within the maps' receiver bias of its
                // surface: under `both` no map can shadow the cube by it (what lit such models
                // "by accident" before the rule), so only the exact techniques are held to it.
            } else {
                assert!(
                    misclassified(&e) <= MAP_BUDGET,
                    "{label}: {:.4} % misclassified (both)",
                    misclassified(&e) * 100.0
                );
            }
            if exact || stage != Stage::Shells {
                assert!(off.wrong > 300, "{label}: rule both looks like front");
            }
            ran += 1;
        }
    }
    assert!(ran >= 6, "only {ran} configurations ran");
}

#[test]
fn outline_shells_and_closed_boxes_under_a_spot() {
    check(Stage::Shells, Lamp::Spot);
}

#[test]
fn outline_shells_and_closed_boxes_under_a_point_light() {
    check(Stage::Shells, Lamp::Point);
}

#[test]
fn outline_shells_and_closed_boxes_under_the_sun() {
    check(Stage::Shells, Lamp::Directional);
}

#[test]
fn a_floor_lit_from_below_under_a_spot() {
    check(Stage::FloorFromBelow, Lamp::Spot);
}

#[test]
fn a_floor_lit_from_below_under_a_point_light() {
    check(Stage::FloorFromBelow, Lamp::Point);
}

#[test]
fn a_floor_lit_from_below_under_the_sun() {
    check(Stage::FloorFromBelow, Lamp::Directional);
}
