//! The reference against geometry whose shadow is known in closed form: the analytic scenes
//! (`plane-spot`, `plane-point`, `plane-directional`), a thin box over a floor.
//!
//! The exact shadow on the floor is the convex hull of the box's eight corners projected from
//! the light onto `y = 0` (the box is convex and wholly below the light). These tests compute
//! that polygon independently of the reference (no BVH, no ray/triangle test) and require the
//! reference to agree at every floor point farther than `MARGIN` from the outline. `MARGIN` is
//! not a tolerance for sloppiness: the reference starts its rays `ray_offset(p)` (1 mm at
//! |p| = 10 m) above the floor, which moves the outline it sees by at most a few times that;
//! 1 cm covers it with room to spare and is still 5 times finer than a pixel of the 256-pixel
//! test frames.

use std::sync::atomic::AtomicBool;

use glam::{Vec2, Vec3};
use manyshadows_reference::visibility::point_visible;
use manyshadows_reference::{
    in_reach, ray_offset, reference_visibility, SurfacePoint, Surfaces, Tracer,
};
use manyshadows_scene::builtin::{self, BuiltinOptions};
use manyshadows_scene::{LightKind, Scene};

const MARGIN: f32 = 0.01;
const GRID: u32 = 200;

fn scene(name: &str) -> Scene {
    builtin::build(name, &BuiltinOptions::default()).expect("builtin scene")
}

fn box_corners() -> Vec<Vec3> {
    let c = builtin::OCCLUDER_CENTER;
    let h = Vec3::new(
        builtin::OCCLUDER_HALF_SIZE,
        builtin::OCCLUDER_THICKNESS * 0.5,
        builtin::OCCLUDER_HALF_SIZE,
    );
    (0..8)
        .map(|i| {
            c + Vec3::new(
                if i & 1 == 0 { -h.x } else { h.x },
                if i & 2 == 0 { -h.y } else { h.y },
                if i & 4 == 0 { -h.z } else { h.z },
            )
        })
        .collect()
}

/// The exact shadow polygon on `y = 0`, counter-clockwise in (x, z).
fn shadow_polygon(scene: &Scene) -> Vec<Vec2> {
    let pts: Vec<Vec2> = box_corners()
        .into_iter()
        .map(|c| {
            let p = match scene.lights[0].kind {
                LightKind::Directional { direction, .. } => c - direction * (c.y / direction.y),
                LightKind::Spot { position: l, .. } | LightKind::Point { position: l, .. } => {
                    l + (c - l) * (l.y / (l.y - c.y))
                }
            };
            Vec2::new(p.x, p.z)
        })
        .collect();
    convex_hull(pts)
}

/// Andrew's monotone chain.
fn convex_hull(mut pts: Vec<Vec2>) -> Vec<Vec2> {
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: Vec2, a: Vec2, b: Vec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<Vec2> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &Vec2>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// Signed distance from `p` to the polygon's outline: negative inside.
fn signed_distance(poly: &[Vec2], p: Vec2) -> f32 {
    let mut d = f32::INFINITY;
    let mut inside = true;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let e = b - a;
        let t = ((p - a).dot(e) / e.length_squared()).clamp(0.0, 1.0);
        d = d.min((a + e * t - p).length());
        if e.perp_dot(p - a) < 0.0 {
            inside = false;
        }
    }
    if inside {
        -d
    } else {
        d
    }
}

/// Distance (radians) of `p` from the light's cone boundary; infinite for other lights.
fn cone_distance(scene: &Scene, p: Vec3) -> f32 {
    match scene.lights[0].kind {
        LightKind::Spot {
            position,
            direction,
            cutoff_deg,
            ..
        } => {
            let angle = (p - position).angle_between(direction);
            (angle - cutoff_deg.to_radians()).abs()
        }
        _ => f32::INFINITY,
    }
}

/// Floor points on a grid covering the whole floor, normal up.
fn floor_grid() -> Surfaces {
    let half = builtin::FLOOR_SIZE * 0.5;
    let points = (0..GRID * GRID)
        .map(|i| {
            let (x, z) = (i % GRID, i / GRID);
            let s = |k: u32| -half + (k as f32 + 0.5) / GRID as f32 * 2.0 * half;
            Some(SurfacePoint {
                position: Vec3::new(s(x), 0.0, s(z)),
                normal: Vec3::Y,
            })
        })
        .collect();
    Surfaces::new(GRID, GRID, points).unwrap()
}

fn check_floor(name: &str) {
    let scene = scene(name);
    let tracer = Tracer::new(&scene).unwrap();
    let poly = shadow_polygon(&scene);
    let surfaces = floor_grid();
    let vis = reference_visibility(
        &tracer,
        &scene.lights,
        &surfaces,
        &|| {},
        &AtomicBool::new(false),
    )
    .unwrap();
    let (mut checked, mut skipped, mut shadowed, mut lit, mut wrong) = (0, 0, 0, 0, Vec::new());
    for (i, sp) in surfaces.points.iter().enumerate() {
        let p = sp.unwrap().position;
        let d = signed_distance(&poly, Vec2::new(p.x, p.z));
        // 1e-4 rad at the spot's distance (< 1 cm) covers float rounding of the cone test.
        if d.abs() < MARGIN || cone_distance(&scene, p) < 1e-4 {
            skipped += 1;
            continue;
        }
        let reach = in_reach(&scene.lights[0], p);
        let expected = reach && d > 0.0;
        checked += 1;
        if expected {
            lit += 1;
        } else if reach {
            shadowed += 1;
        }
        if vis.lit.get(i, 0) != expected {
            wrong.push((p, expected));
        }
        assert_eq!(vis.reach.get(i, 0), reach, "{name}: reach bit at {p}");
    }
    assert!(
        shadowed > 300 && lit > 3000,
        "{name}: degenerate test ({shadowed} shadowed, {lit} lit)"
    );
    assert!(
        skipped < checked / 50,
        "{name}: {skipped} points skipped near edges"
    );
    assert!(
        wrong.is_empty(),
        "{name}: {} of {checked} floor points disagree with the exact outline, e.g. {:?}",
        wrong.len(),
        &wrong[..wrong.len().min(5)]
    );
}

#[test]
fn spot_reference_matches_exact_outline() {
    check_floor("plane-spot");
}

#[test]
fn point_reference_matches_exact_outline() {
    check_floor("plane-point");
}

#[test]
fn directional_reference_matches_exact_outline() {
    check_floor("plane-directional");
}

/// Straddling the outline: just inside every hull edge is shadow, just outside is light, at
/// `MARGIN` on either side, at 16 places along each edge. This pins the outline's position to
/// within 1 cm everywhere, not only where the grid happens to fall.
#[test]
fn outline_is_exact_to_a_centimetre() {
    for name in ["plane-spot", "plane-point", "plane-directional"] {
        let scene = scene(name);
        let tracer = Tracer::new(&scene).unwrap();
        let light = &scene.lights[0];
        let poly = shadow_polygon(&scene);
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            let outward = -(b - a).perp().normalize();
            for k in 1..16 {
                let on = a + (b - a) * (k as f32 / 16.0);
                for (sign, lit) in [(1.0, true), (-1.0, false)] {
                    let q = on + outward * (sign * 2.0 * MARGIN);
                    let p = Vec3::new(q.x, 0.0, q.y);
                    if cone_distance(&scene, p) < 1e-3 {
                        continue;
                    }
                    assert_eq!(
                        point_visible(&tracer, light, p, Vec3::Y),
                        lit && in_reach(light, p),
                        "{name}: at {p} ({} the outline)",
                        if lit { "outside" } else { "inside" }
                    );
                }
            }
        }
    }
}

#[test]
fn occluder_top_is_lit_and_casters_are_two_sided() {
    for name in ["plane-spot", "plane-point", "plane-directional"] {
        let scene = scene(name);
        let tracer = Tracer::new(&scene).unwrap();
        let light = &scene.lights[0];
        let top = builtin::OCCLUDER_CENTER.y + builtin::OCCLUDER_THICKNESS * 0.5;
        for (x, z) in [(0.0, 0.0), (0.9, -0.9), (-0.5, 0.7)] {
            let p = Vec3::new(x, top, z);
            assert!(
                point_visible(&tracer, light, p, Vec3::Y),
                "{name}: top at {p}"
            );
            // The same point seen from inside the box (normal down) is behind the top face.
            assert!(
                !point_visible(&tracer, light, p, Vec3::NEG_Y),
                "{name}: the top face must block its own underside at {p}"
            );
        }
        // A floor point seen from below (normal down) is shadowed by the floor itself.
        let p = Vec3::new(6.0, 0.0, -6.0);
        if in_reach(light, p) {
            assert!(!point_visible(&tracer, light, p, Vec3::NEG_Y), "{name}");
        }
    }
}

#[test]
fn ray_offset_is_small_and_scales() {
    assert_eq!(ray_offset(Vec3::ZERO), 1e-4);
    assert!((ray_offset(Vec3::new(0.0, -30.0, 5.0)) - 3e-3).abs() < 1e-9);
}

#[test]
fn reach_follows_range_and_cone() {
    let scene = scene("plane-spot");
    let light = &scene.lights[0];
    let LightKind::Spot {
        position,
        direction,
        cutoff_deg,
        range,
    } = light.kind
    else {
        unreachable!()
    };
    // Rotate the axis by the cutoff ± 0.1° around X.
    let at = |deg: f32, dist: f32| {
        let r = glam::Quat::from_rotation_x(deg.to_radians());
        position + r * direction * dist
    };
    assert!(in_reach(light, at(cutoff_deg - 0.1, 3.0)));
    assert!(!in_reach(light, at(cutoff_deg + 0.1, 3.0)));
    assert!(in_reach(light, at(0.0, range * 0.999)));
    assert!(!in_reach(light, at(0.0, range * 1.001)));
}

#[test]
fn lights_and_instances_without_shadows_cast_none() {
    let mut s = scene("plane-spot");
    let under = Vec3::new(0.0, 0.0, 0.0);
    let tracer = Tracer::new(&s).unwrap();
    assert!(!point_visible(&tracer, &s.lights[0], under, Vec3::Y));
    // A light that casts no shadow lights everything it reaches.
    s.lights[0].casts_shadows = false;
    assert!(point_visible(&tracer, &s.lights[0], under, Vec3::Y));
    // An instance that casts no shadow is not in the BVH.
    s.lights[0].casts_shadows = true;
    s.instances[1].casts_shadows = false;
    let tracer = Tracer::new(&s).unwrap();
    assert_eq!(tracer.triangle_count(), 2, "only the floor's two triangles");
    assert!(point_visible(&tracer, &s.lights[0], under, Vec3::Y));
}

#[test]
fn bad_input_is_an_error() {
    let e = Surfaces::new(2, 2, vec![None; 3]).unwrap_err();
    assert!(e.to_string().contains("expected 4"), "{e}");
    let nan = Some(SurfacePoint {
        position: Vec3::NAN,
        normal: Vec3::Y,
    });
    let e = Surfaces::new(1, 1, vec![nan]).unwrap_err();
    assert!(e.to_string().contains("non-finite"), "{e}");
    let mut s = scene("plane-spot");
    s.instances[0].mesh = 7;
    let e = Tracer::new(&s).err().expect("invalid scene");
    assert!(e.to_string().contains("mesh 7"), "{e}");
}
