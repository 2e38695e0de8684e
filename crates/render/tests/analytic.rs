//! Analytic shadow tests: a square occluder over a plane, one light of each type. The test
//! computes the exact shadow itself (ray from the camera to the first surface, then a segment
//! from that point to the light against the occluder box) and the renderer's hard visibility
//! mask must agree everywhere except within two pixels of an edge (the shadow outline, the
//! occluder's silhouette, the spot cone).

mod common;

use manyshadows::scene::builtin::{self, BuiltinOptions};
use manyshadows::scene::light_space::PointShadows;
use manyshadows::{Pcf, RenderSettings, Renderer, Technique};

const SIZE: u32 = 256;
const EDGE_BAND_PX: i32 = 2;

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
    let truth = common::analytic_truth(&scene, SIZE);
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
