//! Procedural meshes: the building blocks of the built-in scenes and of the TOML scene format's
//! `primitive = "..."` meshes.
//!
//! Why generate geometry instead of shipping asset files: the built-in scenes must run on a fresh
//! checkout with nothing downloaded, be exactly reproducible (the analytic shadow tests know
//! every vertex), and be tunable in size (tessellation) for benchmarks. A handful of shapes
//! covers it: planes and height fields, boxes, spheres, cylinders and cones, surfaces of
//! revolution ([`lathe`]) for columns, urns and fountains, tubes along closed curves for a
//! torus knot with real self-shadowing, and an [`arch`] for arcades.
//!
//! Conventions every function here keeps, and which the tests check:
//!
//! - right-handed, Y up, metres;
//! - every triangle is **counter-clockwise seen from outside** (front face = CCW), so the
//!   geometric normal `(b − a) × (c − a)` points outwards, the same way as the vertex normals;
//! - normals are unit length; sharp edges (box edges, cylinder rims) get split vertices so
//!   shading stays flat across a face;
//! - no zero-area triangles are emitted (poles of spheres and cones get one triangle per
//!   segment, not a degenerate quad);
//! - every returned mesh passes [`Mesh::validate`].
//!
//! Tessellation arguments are clamped to the smallest sensible value (3 segments around,
//! 1 subdivision, ...) rather than rejected, so a caller can never get an invalid mesh.

use std::f32::consts::{PI, TAU};

use glam::{Mat3, Mat4, Vec2, Vec3};

use crate::error::SceneError;
use crate::model::{Mesh, Scene};

/// Collects vertices and triangles; orients triangles from the normals it is given so every
/// generator gets the counter-clockwise-outside rule right by construction.
struct Builder {
    mesh: Mesh,
}

impl Builder {
    fn new(name: &str) -> Self {
        Self {
            mesh: Mesh {
                name: name.to_string(),
                ..Mesh::default()
            },
        }
    }

    fn vertex(&mut self, position: Vec3, normal: Vec3) -> u32 {
        self.mesh.positions.push(position);
        self.mesh.normals.push(normal);
        (self.mesh.positions.len() - 1) as u32
    }

    fn geometric_normal(&self, a: u32, b: u32, c: u32) -> Vec3 {
        let p = &self.mesh.positions;
        let (a, b, c) = (p[a as usize], p[b as usize], p[c as usize]);
        (b - a).cross(c - a)
    }

    /// Adds triangle `a b c`, reversing it if its geometric normal points against `outward`.
    /// Zero-area triangles are dropped.
    fn tri_facing(&mut self, a: u32, b: u32, c: u32, outward: Vec3) {
        let n = self.geometric_normal(a, b, c);
        if n.length_squared() <= f32::MIN_POSITIVE {
            return;
        }
        if n.dot(outward) < 0.0 {
            self.mesh.indices.extend_from_slice(&[a, c, b]);
        } else {
            self.mesh.indices.extend_from_slice(&[a, b, c]);
        }
    }

    /// Adds triangle `a b c` oriented by the sum of its vertex normals.
    fn tri_auto(&mut self, a: u32, b: u32, c: u32) {
        let n = &self.mesh.normals;
        let outward = n[a as usize] + n[b as usize] + n[c as usize];
        self.tri_facing(a, b, c, outward);
    }

    /// Adds a planar quad with its own four vertices; `corners` go round the perimeter in either
    /// direction.
    fn flat_quad(&mut self, corners: [Vec3; 4], normal: Vec3) {
        let i: Vec<u32> = corners.iter().map(|&p| self.vertex(p, normal)).collect();

        self.tri_facing(i[0], i[1], i[2], normal);
        self.tri_facing(i[0], i[2], i[3], normal);
    }

    fn finish(self) -> Mesh {
        self.mesh
    }
}

/// A flat rectangle in the XZ plane, centred at the origin, facing +Y, split into
/// `subdivisions × subdivisions` quads (two triangles each).
///
/// Vertex `(i, j)` (i along X, j along Z, both `0..=subdivisions`) has index
/// `i·(subdivisions+1) + j`.
pub fn plane(size_x: f32, size_z: f32, subdivisions: u32) -> Mesh {
    let mut mesh = heightfield(size_x, size_z, subdivisions, |_, _| 0.0);
    mesh.name = "plane".into();
    mesh.normals.fill(Vec3::Y); // exact, not re-normalised sums
    mesh
}

/// A height field over a rectangle in the XZ plane centred at the origin: the vertex at `(x, z)`
/// is raised to `height(x, z)`. `subdivisions` quads per side, so `(subdivisions+1)²` vertices
/// and `2·subdivisions²` triangles; normals are area-weighted from the triangles.
///
/// Vertex `(i, j)` (i along X, j along Z) has index `i·(subdivisions+1) + j`, and each quad is
/// split along the diagonal from `(i, j+1)` to `(i+1, j)`; [`heightfield_height`] interpolates
/// exactly on these triangles.
pub fn heightfield(
    size_x: f32,
    size_z: f32,
    subdivisions: u32,
    height: impl Fn(f32, f32) -> f32,
) -> Mesh {
    let s = subdivisions.max(1);
    let n = s + 1;
    let mut b = Builder::new("heightfield");
    for i in 0..n {
        let x = -0.5 * size_x + size_x * i as f32 / s as f32;
        for j in 0..n {
            let z = -0.5 * size_z + size_z * j as f32 / s as f32;
            b.vertex(Vec3::new(x, height(x, z), z), Vec3::Y);
            b.mesh
                .uvs
                .push(Vec2::new(i as f32 / s as f32, j as f32 / s as f32));
        }
    }
    b.mesh.indices.reserve((s * s * 6) as usize);
    for i in 0..s {
        for j in 0..s {
            let v00 = i * n + j;
            let v01 = v00 + 1;
            let v10 = v00 + n;
            let v11 = v10 + 1;
            // (x0,z0) → (x0,z1) → (x1,z0) is counter-clockwise seen from +Y.
            b.mesh
                .indices
                .extend_from_slice(&[v00, v01, v10, v10, v01, v11]);
        }
    }
    let mut mesh = b.finish();
    mesh.compute_normals();
    mesh
}

/// The height of the triangulated surface [`heightfield`] builds, at `(x, z)`, given the heights
/// at the grid vertices `h(i, j)`. Points outside the rectangle are clamped onto its edge.
///
/// Objects placed with this sit exactly on the rendered surface, not on the smooth function
/// the grid samples.
pub fn heightfield_height(
    size_x: f32,
    size_z: f32,
    subdivisions: u32,
    h: impl Fn(u32, u32) -> f32,
    x: f32,
    z: f32,
) -> f32 {
    let s = subdivisions.max(1);
    let fx = ((x / size_x + 0.5) * s as f32).clamp(0.0, s as f32);
    let fz = ((z / size_z + 0.5) * s as f32).clamp(0.0, s as f32);
    let i = (fx.floor() as u32).min(s - 1);
    let j = (fz.floor() as u32).min(s - 1);
    let (u, v) = (fx - i as f32, fz - j as f32);
    let (h00, h01, h10, h11) = (h(i, j), h(i, j + 1), h(i + 1, j), h(i + 1, j + 1));
    if u + v <= 1.0 {
        h00 + u * (h10 - h00) + v * (h01 - h00)
    } else {
        h11 + (1.0 - u) * (h01 - h11) + (1.0 - v) * (h10 - h11)
    }
}

/// An axis-aligned box centred at the origin, flat-shaded: 24 vertices (4 per face, so edges
/// stay sharp) and 12 triangles.
pub fn cuboid(size: Vec3) -> Mesh {
    let h = size * 0.5;
    let mut b = Builder::new("cuboid");
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for sign in [-1.0f32, 1.0] {
            let normal = Vec3::AXES[axis] * sign;
            let center = normal * h[axis];
            let du = Vec3::AXES[u] * h[u];
            let dv = Vec3::AXES[v] * h[v];
            b.flat_quad(
                [
                    center - du - dv,
                    center + du - dv,
                    center + du + dv,
                    center - du + dv,
                ],
                normal,
            );
        }
    }
    let mut mesh = b.finish();
    // Four vertices per face, in `flat_quad`'s corner order: each face spans the texture.
    let corner = [
        Vec2::new(0.0, 1.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(0.0, 0.0),
    ];
    mesh.uvs = (0..mesh.positions.len()).map(|k| corner[k % 4]).collect();
    mesh
}

/// A flat card: a `width` × `height` rectangle standing in the XY plane on the X axis
/// (x from −width/2 to width/2, y from 0 to height), facing +Z, one quad of two triangles.
/// Texture coordinates span `uv_scale` copies of the texture: (0, 0) at the top-left corner
/// (glTF's convention: v runs down the image), (uv_scale.x, uv_scale.y) at the bottom-right.
/// Foliage, banners and lattices of the built-in scenes are cards with alpha-masked textures.
pub fn card(width: f32, height: f32, uv_scale: Vec2) -> Mesh {
    let h = 0.5 * width;
    let mut mesh = Mesh {
        name: "card".into(),
        positions: vec![
            Vec3::new(-h, height, 0.0),
            Vec3::new(h, height, 0.0),
            Vec3::new(h, 0.0, 0.0),
            Vec3::new(-h, 0.0, 0.0),
        ],
        normals: vec![Vec3::Z; 4],
        uvs: vec![
            Vec2::ZERO,
            Vec2::new(uv_scale.x, 0.0),
            uv_scale,
            Vec2::new(0.0, uv_scale.y),
        ],
        indices: vec![0, 2, 1, 0, 3, 2],
    };
    if width <= 0.0 || height <= 0.0 {
        mesh.indices.clear();
    }
    mesh
}

/// A UV sphere centred at the origin: `segments` around the Y axis (≥ 3), `rings` from pole to
/// pole (≥ 2); `2·segments·(rings−1)` triangles, smooth radial normals.
pub fn uv_sphere(radius: f32, segments: u32, rings: u32) -> Mesh {
    let segs = segments.max(3);
    let rings = rings.max(2);
    let mut b = Builder::new("uv_sphere");
    for k in 0..=rings {
        let theta = PI * k as f32 / rings as f32;
        let (st, ct) = theta.sin_cos();
        for i in 0..=segs {
            let phi = TAU * (i % segs) as f32 / segs as f32;
            let (sp, cp) = phi.sin_cos();
            // Exact zeros at the poles, so the pole is one point.
            let st = if k == 0 || k == rings { 0.0 } else { st };
            let n = Vec3::new(st * sp, -ct, st * cp);
            b.vertex(n * radius, n);
        }
    }
    let row = segs + 1;
    for k in 0..rings {
        for i in 0..segs {
            let a = k * row + i;
            let (bb, c, d) = (a + 1, a + 1 + row, a + row);
            if k > 0 {
                b.tri_auto(a, bb, c);
            }
            if k + 1 < rings {
                b.tri_auto(a, c, d);
            }
        }
    }
    b.finish()
}

/// A surface of revolution around the Y axis.
///
/// `profile` is a polyline of `(radius, y)` points (radius ≥ 0), traversed so that the solid is
/// on its **left**: for a closed solid go from the axis at the bottom, outwards, up the outside
/// and back to the axis at the top. The outward normal of a profile step `(dr, dy)` is
/// `(dy, −dr)`. Where consecutive steps turn by more than 35° the edge is kept sharp (split
/// vertices); elsewhere normals are averaged so curved profiles shade smoothly. Points on the
/// axis (radius 0) become poles with one triangle per segment.
pub fn lathe(profile: &[Vec2], segments: u32) -> Mesh {
    const CREASE_COS: f32 = 0.819; // cos 35°
    let segs = segments.max(3);
    let mut b = Builder::new("lathe");
    // Drop points that (nearly) repeat the previous one: a zero-length step has no normal and
    // would only add slivers.
    let scale = profile
        .iter()
        .fold(0.0f32, |s, p| s.max(p.abs().max_element()));
    let mut points: Vec<Vec2> = Vec::with_capacity(profile.len());
    for &p in profile {
        if points
            .last()
            .is_none_or(|&q| q.distance(p) > 1e-5 * scale.max(1e-6))
        {
            points.push(p);
        }
    }
    let profile = &points[..];
    let m = profile.len();
    if m < 2 {
        return b.finish();
    }
    let seg_normal: Vec<Option<Vec2>> = profile
        .windows(2)
        .map(|w| {
            let d = w[1] - w[0];
            Vec2::new(d.y, -d.x).try_normalize()
        })
        .collect();
    let add_ring = |b: &mut Builder, p: Vec2, n: Vec2| -> u32 {
        let first = b.mesh.positions.len() as u32;
        let r = p.x.max(0.0);
        for i in 0..=segs {
            let phi = TAU * (i % segs) as f32 / segs as f32;
            let (s, c) = phi.sin_cos();
            b.vertex(
                Vec3::new(r * s, p.y, r * c),
                Vec3::new(n.x * s, n.y, n.x * c).normalize_or(Vec3::Y),
            );
        }
        first
    };
    // For each profile point: the ring its outgoing step starts from and the ring its incoming
    // step ends on (the same ring unless the point is a crease).
    let mut ring_out = vec![u32::MAX; m];
    let mut ring_in = vec![u32::MAX; m];
    for k in 0..m {
        let n_in = if k > 0 { seg_normal[k - 1] } else { None };
        let n_out = if k + 1 < m { seg_normal[k] } else { None };
        match (n_in, n_out) {
            (Some(a), Some(c)) if a.dot(c) >= CREASE_COS => {
                let r = add_ring(&mut b, profile[k], (a + c).normalize_or(a));
                ring_in[k] = r;
                ring_out[k] = r;
            }
            (a, c) => {
                if let Some(a) = a {
                    ring_in[k] = add_ring(&mut b, profile[k], a);
                }
                if let Some(c) = c {
                    ring_out[k] = add_ring(&mut b, profile[k], c);
                }
            }
        }
    }
    for k in 0..m - 1 {
        if seg_normal[k].is_none() {
            continue;
        }
        let (lo, hi) = (ring_out[k], ring_in[k + 1]);
        let lo_pole = profile[k].x <= 0.0;
        let hi_pole = profile[k + 1].x <= 0.0;
        for i in 0..segs {
            let (a, bb, c, d) = (lo + i, lo + i + 1, hi + i + 1, hi + i);
            if !lo_pole {
                b.tri_auto(a, bb, c);
            }
            if !hi_pole {
                b.tri_auto(a, c, d);
            }
        }
    }
    b.finish()
}

/// A capped cylinder around the Y axis, base at `y = 0`, top at `y = height`; `4·segments`
/// triangles (sides smooth, caps flat).
pub fn cylinder(radius: f32, height: f32, segments: u32) -> Mesh {
    let mut mesh = lathe(
        &[
            Vec2::new(0.0, 0.0),
            Vec2::new(radius, 0.0),
            Vec2::new(radius, height),
            Vec2::new(0.0, height),
        ],
        segments,
    );
    mesh.name = "cylinder".into();
    mesh
}

/// A capped cone around the Y axis, base at `y = 0`, apex at `y = height`; `2·segments`
/// triangles.
pub fn cone(radius: f32, height: f32, segments: u32) -> Mesh {
    let mut mesh = lathe(
        &[
            Vec2::new(0.0, 0.0),
            Vec2::new(radius, 0.0),
            Vec2::new(0.0, height),
        ],
        segments,
    );
    mesh.name = "cone".into();
    mesh
}

/// A closed tube of varying radius swept along a closed curve given as `points` (the last
/// point connects back to the first; don't repeat it).
///
/// Frames are rotation-minimising (parallel transport) with the leftover twist spread evenly
/// round the loop, so the tube has no seam and no sudden twist whatever the curve.
/// `radius(k, angle)` gives the tube radius at curve point `k` and angle `angle` (radians)
/// around it, which is how bumps and ridges are made. Produces `2·points·sides` triangles;
/// normals are area-weighted from the surface.
pub fn tube(points: &[Vec3], sides: u32, radius: impl Fn(usize, f32) -> f32) -> Mesh {
    let mut b = Builder::new("tube");
    let n = points.len();
    let sides = sides.max(3);
    if n < 3 {
        return b.finish();
    }
    let tangent = |k: usize| (points[(k + 1) % n] - points[(k + n - 1) % n]).normalize_or(Vec3::X);
    let tangents: Vec<Vec3> = (0..n).map(tangent).collect();
    // Parallel transport of a normal round the loop.
    let mut normals = Vec::with_capacity(n + 1);
    normals.push(tangents[0].any_orthonormal_vector());
    for k in 1..=n {
        let t = tangents[k % n];
        let prev: Vec3 = normals[k - 1];
        let projected = prev - t * prev.dot(t);
        normals.push(
            projected
                .try_normalize()
                .unwrap_or_else(|| t.any_orthonormal_vector()),
        );
    }
    // Twist left over when the transported frame comes back to the start.
    let t0 = tangents[0];
    let (n0, nn) = (normals[0], normals[n]);
    let twist = t0.dot(n0.cross(nn)).atan2(n0.dot(nn));
    normals.truncate(n);
    for (k, nk) in normals.iter_mut().enumerate() {
        let angle = -twist * k as f32 / n as f32;
        *nk = glam::Quat::from_axis_angle(tangents[k], angle) * *nk;
    }
    for (k, &c) in points.iter().enumerate() {
        let t = tangents[k];
        let nk = normals[k];
        let bk = t.cross(nk);
        for j in 0..sides {
            let angle = TAU * j as f32 / sides as f32;
            let (s, co) = angle.sin_cos();
            let dir = nk * co + bk * s;
            b.vertex(c + dir * radius(k, angle), dir);
        }
    }
    let s = sides;
    for k in 0..n as u32 {
        let k1 = (k + 1) % n as u32;
        for j in 0..s {
            let j1 = (j + 1) % s;
            let (a, bb, c, d) = (k * s + j, k1 * s + j, k1 * s + j1, k * s + j1);
            b.tri_auto(a, bb, c);
            b.tri_auto(a, c, d);
        }
    }
    let mut mesh = b.finish();
    mesh.compute_normals();
    mesh
}

/// A torus lying in the XZ plane, centred at the origin: `segments` round the ring, `sides`
/// round the tube; `2·segments·sides` triangles.
pub fn torus(major_radius: f32, minor_radius: f32, segments: u32, sides: u32) -> Mesh {
    let segs = segments.max(3);
    let points: Vec<Vec3> = (0..segs)
        .map(|k| {
            let a = TAU * k as f32 / segs as f32;
            Vec3::new(a.cos(), 0.0, a.sin()) * major_radius
        })
        .collect();
    let mut mesh = tube(&points, sides, |_, _| minor_radius);
    mesh.name = "torus".into();
    mesh
}

/// A `(p, q)` torus knot tube lying roughly in the XZ plane, centred at the origin, reaching
/// out to about `knot_radius` (plus the tube): the curve winds `p` times round the Y axis and
/// `q` times through the hole. `(2, 3)` is the trefoil. `2·segments·sides` triangles.
///
/// Its crossings make a closed shape that shadows itself from every side, which is why the
/// dragon scene's stand-in uses it.
pub fn torus_knot(
    p: u32,
    q: u32,
    knot_radius: f32,
    tube_radius: f32,
    segments: u32,
    sides: u32,
) -> Mesh {
    let points = torus_knot_curve(p, q, knot_radius, segments);
    let mut mesh = tube(&points, sides, |_, _| tube_radius);
    mesh.name = format!("torus_knot_{p}_{q}");
    mesh
}

/// Points along the centre line of a `(p, q)` torus knot (see [`torus_knot`]).
pub fn torus_knot_curve(p: u32, q: u32, knot_radius: f32, segments: u32) -> Vec<Vec3> {
    let segs = segments.max(3);
    let (p, q) = (p.max(1) as f32, q.max(1) as f32);
    (0..segs)
        .map(|k| {
            let t = TAU * k as f32 / segs as f32;
            let r = 2.0 + (q * t).cos();
            Vec3::new(r * (p * t).cos(), -(q * t).sin(), r * (p * t).sin()) * (knot_radius / 3.0)
        })
        .collect()
}

/// A semicircular arch block: the wall between two piers with a round opening.
///
/// Local frame: width along X (`−width/2..width/2`), height along Y (`0..height`), depth along Z
/// (`−depth/2..depth/2`). The opening is a half circle of `radius` centred at the origin, so the
/// arch springs at `y = 0` and its two legs are `width/2 − radius` wide at the bottom. Place one
/// between two column capitals and its legs sit on them. `radius` is clamped to
/// `(0, min(width/2, height)]`. `segments` steps round the half circle (≥ 4, rounded to a
/// multiple of 4) give about `6·segments + 10` triangles.
pub fn arch(width: f32, height: f32, radius: f32, depth: f32, segments: u32) -> Mesh {
    let n = segments.max(4).div_ceil(4) * 4;
    let hw = 0.5 * width;
    let r = radius.clamp(1e-4, hw.min(height));
    let hd = 0.5 * depth;
    let mut b = Builder::new("arch");
    // Inner half circle from the left springing point over the top to the right one, and the
    // matching outer path: up the left side, across the top, down the right side.
    let n1 = n / 4;
    let n2 = n - 2 * n1;
    let inner: Vec<Vec2> = (0..=n)
        .map(|i| {
            let a = PI * (1.0 - i as f32 / n as f32);
            Vec2::new(r * a.cos(), r * a.sin())
        })
        .collect();
    let outer: Vec<Vec2> = (0..=n)
        .map(|i| {
            if i <= n1 {
                Vec2::new(-hw, height * i as f32 / n1 as f32)
            } else if i <= n1 + n2 {
                Vec2::new(-hw + width * (i - n1) as f32 / n2 as f32, height)
            } else {
                Vec2::new(hw, height * (1.0 - (i - n1 - n2) as f32 / n1 as f32))
            }
        })
        .collect();
    // Front and back faces.
    for (z, normal) in [(hd, Vec3::Z), (-hd, Vec3::NEG_Z)] {
        let first = b.mesh.positions.len() as u32;
        for (p_in, p_out) in inner.iter().zip(&outer) {
            b.vertex(p_in.extend(z), normal);
            b.vertex(p_out.extend(z), normal);
        }
        for i in 0..n {
            let (ia, oa, ib, ob) = (
                first + 2 * i,
                first + 2 * i + 1,
                first + 2 * i + 2,
                first + 2 * i + 3,
            );
            b.tri_facing(ia, ib, ob, normal);
            b.tri_facing(ia, ob, oa, normal);
        }
    }
    // Intrados: the curved underside, normals towards the opening's centre.
    let first = b.mesh.positions.len() as u32;
    for p in &inner {
        let nrm = (-*p).normalize_or(Vec2::NEG_Y).extend(0.0);
        b.vertex(p.extend(hd), nrm);
        b.vertex(p.extend(-hd), nrm);
    }
    for i in 0..n {
        let (fa, ba, fb, bb) = (
            first + 2 * i,
            first + 2 * i + 1,
            first + 2 * i + 2,
            first + 2 * i + 3,
        );
        b.tri_auto(fa, fb, bb);
        b.tri_auto(fa, bb, ba);
    }
    // Top, outer sides, and the legs' bottoms.
    let quad_xy = |b: &mut Builder, p0: Vec2, p1: Vec2, normal: Vec3| {
        b.flat_quad(
            [p0.extend(hd), p1.extend(hd), p1.extend(-hd), p0.extend(-hd)],
            normal,
        );
    };
    quad_xy(
        &mut b,
        Vec2::new(-hw, height),
        Vec2::new(hw, height),
        Vec3::Y,
    );
    quad_xy(
        &mut b,
        Vec2::new(-hw, 0.0),
        Vec2::new(-hw, height),
        Vec3::NEG_X,
    );
    quad_xy(&mut b, Vec2::new(hw, 0.0), Vec2::new(hw, height), Vec3::X);
    if hw - r > 1e-5 {
        quad_xy(&mut b, Vec2::new(-hw, 0.0), Vec2::new(-r, 0.0), Vec3::NEG_Y);
        quad_xy(&mut b, Vec2::new(r, 0.0), Vec2::new(hw, 0.0), Vec3::NEG_Y);
    }
    b.finish()
}

/// A classical column standing on `y = 0`, `height` tall, with shaft radius `radius`: a square
/// plinth, a rounded base moulding, a shaft with entasis (it swells slightly and tapers to
/// 85 %), a neck ring, a flared capital (echinus) and a square abacus `3·radius` wide on top.
/// `segments` around (≥ 8); about `110·segments` triangles, so a well-tessellated column is
/// a few thousand triangles: the atrium gets its triangle count from many of these.
pub fn column(radius: f32, height: f32, segments: u32) -> Mesh {
    let (r, h) = (radius, height);
    let segs = segments.max(8);
    let plinth_h = 0.07 * h;
    let abacus_h = 0.07 * h;
    let mut profile = vec![Vec2::new(0.0, plinth_h), Vec2::new(1.3 * r, plinth_h)];
    // Base moulding: a half round (torus) bulging out to 1.45 r.
    let base_h = 0.05 * h;
    for k in 0..=8 {
        let a = -PI / 2.0 + PI * k as f32 / 8.0;
        profile.push(Vec2::new(
            1.3 * r + 0.15 * r * a.cos(),
            plinth_h + base_h * (0.5 + 0.5 * a.sin()),
        ));
    }
    // Shaft with entasis.
    let (s0, s1) = (plinth_h + base_h, 0.86 * h);
    profile.push(Vec2::new(r, s0));
    for k in 1..=28 {
        let t = k as f32 / 28.0;
        let swell = 0.02 * (PI * t).sin();
        profile.push(Vec2::new(
            r * (1.0 - 0.15 * t * t + swell),
            s0 + (s1 - s0) * t,
        ));
    }
    // Neck ring.
    let top = 0.85 * r;
    let ring_h = 0.012 * h;
    for k in 0..=6 {
        let a = -PI / 2.0 + PI * k as f32 / 6.0;
        profile.push(Vec2::new(
            top + 0.08 * r * a.cos(),
            s1 + ring_h * (0.5 + 0.5 * a.sin()),
        ));
    }
    // Echinus: a quarter-round flare up to the abacus.
    let (e0, e1) = (s1 + ring_h, h - abacus_h);
    for k in 0..=10 {
        let a = PI / 2.0 * k as f32 / 10.0;
        profile.push(Vec2::new(
            top + (1.45 * r - top) * (1.0 - a.cos()),
            e0 + (e1 - e0) * a.sin(),
        ));
    }
    profile.push(Vec2::new(0.0, e1));
    let body = lathe(&profile, segs);
    let plinth = cuboid(Vec3::new(3.2 * r, plinth_h, 3.2 * r));
    let abacus = cuboid(Vec3::new(3.0 * r, abacus_h, 3.0 * r));
    let mut mesh = merge(&[
        (
            plinth,
            Mat4::from_translation(Vec3::new(0.0, 0.5 * plinth_h, 0.0)),
        ),
        (body, Mat4::IDENTITY),
        (
            abacus,
            Mat4::from_translation(Vec3::new(0.0, h - 0.5 * abacus_h, 0.0)),
        ),
    ]);
    mesh.name = "column".into();
    mesh
}

/// Bakes each mesh's transform into its vertices and concatenates them into one mesh.
///
/// Normals are transformed by the inverse transpose (so non-uniform scales shade correctly) and
/// re-normalised; a mirroring transform (negative determinant) has its triangles reversed so
/// they stay counter-clockwise seen from outside.
pub fn merge(meshes: &[(Mesh, Mat4)]) -> Mesh {
    let mut out = Mesh {
        name: "merged".into(),
        ..Mesh::default()
    };
    let any_uvs = meshes.iter().any(|(m, _)| !m.uvs.is_empty());
    for (mesh, transform) in meshes {
        let base = out.positions.len() as u32;
        if any_uvs {
            if mesh.uvs.len() == mesh.positions.len() {
                out.uvs.extend_from_slice(&mesh.uvs);
            } else {
                out.uvs
                    .resize(out.uvs.len() + mesh.positions.len(), Vec2::ZERO);
            }
        }
        let linear = Mat3::from_mat4(*transform);
        let normal_matrix = linear.inverse().transpose();
        let normal_matrix = if normal_matrix.is_finite() {
            normal_matrix
        } else {
            linear
        };
        out.positions.extend(
            mesh.positions
                .iter()
                .map(|&p| transform.transform_point3(p)),
        );
        out.normals.extend(
            mesh.normals
                .iter()
                .map(|&n| (normal_matrix * n).normalize_or(Vec3::Y)),
        );
        let mirrored = linear.determinant() < 0.0;
        for tri in mesh.indices.chunks_exact(3) {
            if mirrored {
                out.indices
                    .extend_from_slice(&[base + tri[0], base + tri[2], base + tri[1]]);
            } else {
                out.indices
                    .extend_from_slice(&[base + tri[0], base + tri[1], base + tri[2]]);
            }
        }
    }
    out
}

/// Splits every triangle into four at its edge midpoints, `levels` times (4^levels as many
/// triangles; shared edges get one midpoint, so closed meshes stay closed). Normals of new
/// vertices are the normalised mean of the edge's ends. For non-linear shadow projections
/// (dual paraboloid) that need finely tessellated geometry.
pub fn subdivide(mesh: &Mesh, levels: u32) -> Mesh {
    let mut m = mesh.clone();
    if m.normals.len() != m.positions.len() {
        m.compute_normals();
    }
    for _ in 0..levels {
        let mut mids: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
        let mut indices = Vec::with_capacity(m.indices.len() * 4);
        for t in m.indices.clone().chunks_exact(3) {
            let mut mid = |a: u32, b: u32, m: &mut Mesh| -> u32 {
                *mids.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    let p = (m.positions[a as usize] + m.positions[b as usize]) * 0.5;
                    let n = (m.normals[a as usize] + m.normals[b as usize]).normalize_or_zero();
                    m.positions.push(p);
                    m.normals.push(n);
                    if !m.uvs.is_empty() {
                        let uv = (m.uvs[a as usize] + m.uvs[b as usize]) * 0.5;
                        m.uvs.push(uv);
                    }
                    (m.positions.len() - 1) as u32
                })
            };
            let (a, b, c) = (t[0], t[1], t[2]);
            let ab = mid(a, b, &mut m);
            let bc = mid(b, c, &mut m);
            let ca = mid(c, a, &mut m);
            indices.extend([a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca]);
        }
        m.indices = indices;
    }
    m
}

impl Scene {
    /// Splits every mesh's triangles `levels` times ([`subdivide`]: 4^levels
    /// as many triangles). Fails past 20 million triangles over all instances.
    pub fn subdivide(&mut self, levels: u32) -> Result<(), SceneError> {
        const MAX: u64 = 20_000_000;
        let after = (self.triangle_count() as u64).saturating_mul(4u64.saturating_pow(levels));
        if levels > 12 || after > MAX {
            // (4^levels times the triangles; said as a power of ten past u64's reach.)
            let count = if levels > 12 || after == u64::MAX {
                format!(
                    "about 10^{:.0}",
                    (self.triangle_count().max(1) as f64).log10() + levels as f64 * 4f64.log10()
                )
            } else {
                after.to_string()
            };
            return Err(SceneError::InvalidRequest(format!(
                "subdividing {levels} times would make {count} triangles (at most {MAX})"
            )));
        }
        for m in &mut self.meshes {
            *m = subdivide(m, levels);
        }
        Ok(())
    }
}
