//! Analytic shadow tests: a square occluder over a plane, one light of each type. The test
//! computes the exact shadow itself (ray from the camera to the first surface, then a segment
//! from that point to the light against the occluder box) and the renderer's hard visibility
//! mask must agree everywhere except within two pixels of an edge (the shadow outline, the
//! occluder's silhouette, the spot cone).

mod common;

use glam::{Vec3, Vec4Swizzles};
use manyshadows::scene::builtin::{self, BuiltinOptions};
use manyshadows::scene::light_space::PointShadows;
use manyshadows::scene::{LightKind, Scene};
use manyshadows::{Pcf, RenderSettings, Renderer, Technique};

const SIZE: u32 = 256;
const EDGE_BAND_PX: i32 = 2;

/// Ray/box slab test; returns the entry distance.
fn ray_box(o: Vec3, d: Vec3, lo: Vec3, hi: Vec3) -> Option<f32> {
    let inv = d.recip();
    let t0 = (lo - o) * inv;
    let t1 = (hi - o) * inv;
    let tmin = t0.min(t1).max_element();
    let tmax = t0.max(t1).min_element();
    (tmax >= tmin.max(0.0)).then_some(tmin.max(0.0))
}

/// Truth per pixel: `None` = sky, `Some(lit)`.
fn truth(scene: &Scene) -> Vec<Option<bool>> {
    let c = builtin::OCCLUDER_CENTER;
    let half = Vec3::new(
        builtin::OCCLUDER_HALF_SIZE,
        builtin::OCCLUDER_THICKNESS * 0.5,
        builtin::OCCLUDER_HALF_SIZE,
    );
    let (lo, hi) = (c - half, c + half);
    let cam = &scene.camera;
    let inv = (cam.projection(1.0) * cam.view()).inverse();
    let light = scene.lights[0];
    let mut out = Vec::new();
    for y in 0..SIZE {
        for x in 0..SIZE {
            let ndc_x = (x as f32 + 0.5) / SIZE as f32 * 2.0 - 1.0;
            let ndc_y = 1.0 - (y as f32 + 0.5) / SIZE as f32 * 2.0;
            let near = inv * glam::Vec4::new(ndc_x, ndc_y, 0.0, 1.0);
            let far = inv * glam::Vec4::new(ndc_x, ndc_y, 1.0, 1.0);
            let o = near.xyz() / near.w;
            let d = (far.xyz() / far.w - o).normalize();
            let t_floor = if d.y < 0.0 { -o.y / d.y } else { f32::INFINITY };
            let t_box = ray_box(o, d, lo, hi).unwrap_or(f32::INFINITY);
            let t = t_floor.min(t_box);
            if !t.is_finite()
                || (o + d * t).x.abs() > 10.0
                || (o + d * t).z.abs() > 10.0 && t == t_floor
            {
                out.push(None);
                continue;
            }
            let p = o + d * t;
            if t_box <= t_floor {
                // The occluder's top face: nothing is above it.
                out.push(Some(true));
                continue;
            }
            let lit = match light.kind {
                LightKind::Directional { direction, .. } => {
                    ray_box(p, -direction, lo, hi).is_none()
                }
                LightKind::Spot {
                    position,
                    direction,
                    cutoff_deg,
                    range,
                } => {
                    let to_p = p - position;
                    let in_cone = to_p.normalize().dot(direction.normalize())
                        >= cutoff_deg.to_radians().cos();
                    in_cone
                        && to_p.length() <= range
                        && ray_box(p, -to_p.normalize(), lo, hi).is_none_or(|t| t > to_p.length())
                }
                LightKind::Point { position, range } => {
                    let to_p = p - position;
                    to_p.length() <= range
                        && ray_box(p, -to_p.normalize(), lo, hi).is_none_or(|t| t > to_p.length())
                }
            };
            out.push(Some(lit));
        }
    }
    out
}

fn check(name: &str) {
    let wrong = wrong_pixels(name, Technique::Traditional, PointShadows::Cube, 0);
    assert_eq!(
        wrong, 0,
        "{name}: {wrong} pixels away from edges disagree with the exact shadow"
    );
}

/// Pixels more than [`EDGE_BAND_PX`] from an edge whose visibility disagrees with the exact
/// shadow (a difference image goes to target/test-artifacts).
fn wrong_pixels(name: &str, technique: Technique, points: PointShadows, subdivide: u32) -> usize {
    let ctx = common::context();
    let mut scene = builtin::build(name, &BuiltinOptions::default()).expect("builtin scene");
    scene.subdivide(subdivide).expect("subdivide");
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        pcf: Pcf::Off,
        visibility: true,
        technique,
        point_shadows: points,
        ..Default::default()
    };
    let mut r = Renderer::new(&ctx, &scene, settings).expect("renderer");
    let frame = r.render().expect("frame");
    let vis = frame.visibility.expect("visibility mask");
    let truth = truth(&scene);
    let at = |x: i32, y: i32| truth[(y as u32 * SIZE + x as u32) as usize];
    let (mut compared, mut wrong, mut shadowed, mut lit) = (0, 0, 0, 0);
    let mut diff = vec![0u8; (SIZE * SIZE * 3) as usize];
    for y in 0..SIZE as i32 {
        for x in 0..SIZE as i32 {
            let Some(expected) = at(x, y) else { continue };
            let near_edge = (-EDGE_BAND_PX..=EDGE_BAND_PX).any(|dy| {
                (-EDGE_BAND_PX..=EDGE_BAND_PX).any(|dx| {
                    let (nx, ny) = (x + dx, y + dy);
                    nx < 0
                        || ny < 0
                        || nx >= SIZE as i32
                        || ny >= SIZE as i32
                        || at(nx, ny) != Some(expected)
                })
            });
            let got = vis.lit(x as u32, y as u32, 0);
            let i = ((y as u32 * SIZE + x as u32) * 3) as usize;
            diff[i..i + 3].copy_from_slice(&match (expected, got) {
                (true, true) => [200, 200, 200],
                (false, false) => [40, 40, 40],
                (true, false) => [255, 0, 0],
                (false, true) => [0, 255, 0],
            });
            if near_edge {
                continue;
            }
            compared += 1;
            if expected {
                lit += 1
            } else {
                shadowed += 1
            }
            if got != expected {
                wrong += 1;
            }
        }
    }
    let path = common::artifacts_dir().join(format!(
        "analytic-{name}-{technique}-{}-sub{subdivide}.png",
        points.name()
    ));
    image::save_buffer(&path, &diff, SIZE, SIZE, image::ExtendedColorType::Rgb8).unwrap();
    assert!(
        shadowed > 200 && lit > 200,
        "{name}: degenerate test ({shadowed} shadowed, {lit} lit pixels)"
    );
    eprintln!(
        "{name} {technique} {} subdivided {subdivide}x: {wrong} of {compared} pixels away from \
         edges disagree with the exact shadow (red = false shadow, green = false light: {})",
        points.name(),
        path.display()
    );
    wrong
}

#[test]
fn spot_light_shadow_matches_exact_outline() {
    check("plane-spot");
}

#[test]
fn point_light_shadow_matches_exact_outline() {
    check("plane-point");
}

#[test]
fn directional_light_shadow_matches_exact_outline() {
    check("plane-directional");
}

/// Dual-paraboloid maps on geometry fine enough for the warp (every triangle split 4 times:
/// the occluder's edges become 16 segments each, short enough that the straight segments the
/// rasterizer draws in paraboloid space stay within a texel of the true curves): exact away
/// from edges, with both techniques that support the mode.
#[test]
fn point_light_dual_paraboloid_matches_exact_outline_on_fine_geometry() {
    for t in [Technique::Traditional, Technique::Layered] {
        let wrong = wrong_pixels("plane-point", t, PointShadows::DualParaboloid, 4);
        assert_eq!(
            wrong, 0,
            "{t}: dual-paraboloid shadow disagrees in {wrong} pixels"
        );
    }
}

/// The known weakness (seed 003): on the unsubdivided scene the occluder's edges are single
/// triangles, drawn straight in paraboloid space where the true outline curves, so the shadow
/// outline is visibly wrong. If this ever passes with zero errors, the warp is not being
/// exercised.
#[test]
fn dual_paraboloid_bends_outlines_of_coarse_geometry() {
    let wrong = wrong_pixels(
        "plane-point",
        Technique::Traditional,
        PointShadows::DualParaboloid,
        0,
    );
    assert!(
        wrong > 20,
        "coarse geometry should show the paraboloid's error ({wrong} pixels)"
    );
    let cube = wrong_pixels("plane-point", Technique::Traditional, PointShadows::Cube, 0);
    assert_eq!(
        cube, 0,
        "cube maps are exact on the same coarse geometry ({cube} pixels)"
    );
}
