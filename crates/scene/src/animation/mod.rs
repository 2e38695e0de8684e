//! Keyframe animation of a scene's node tree (glTF 2.0 §3.11): what moves, and where it
//! stands at a time.
//!
//! A glTF file's meshes are loaded with their node's world transform baked into the vertices
//! (see [`loaders`](crate::loaders)), so an animated node does not move vertices: it moves the
//! instances drawn from it. At time `t` such an instance's transform is
//! `W(t) · W₀⁻¹ · P`, where `W(t)` is its node's world transform at `t` (the parents' local
//! transforms times its own, each channel of the playing clips overriding its node's
//! translation, rotation or scale), `W₀` that world transform at rest (the file's own node
//! transforms, baked into the vertices) and `P` the instance's transform as loaded. So the
//! rest pose is drawn exactly as before, and the renderer sees instances that move — which
//! every shadow technique already follows (`Renderer::set_instance_transform`).
//!
//! Samplers are evaluated on the CPU, as glTF defines them: `STEP` holds the earlier key,
//! `LINEAR` interpolates (rotations by spherical interpolation along the shorter arc, as
//! three.js and the Khronos sample viewer do), `CUBICSPLINE` is the cubic Hermite spline of
//! the keys and their in and out tangents scaled by the key interval (§3.11.6), a rotation
//! normalized after it. Before the first key a channel holds its first value, after the last
//! its last. Playback loops: a time past the clip's end is taken modulo its duration (a time
//! equal to the duration shows the last keys), as a looping player shows it.
//!
//! No scene type is named here (the model holds an [`Animations`] and imports this module):
//! [`Animations::pose`] hands back the instances' transforms, which the caller sets.

use glam::{Mat4, Quat, Vec3};

mod channel;
mod deform;

pub use channel::{Channel, Interpolation, Property};
pub use deform::{Bending, Morph, Skin};

/// One animation: channels played together.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Clip {
    /// Its name in the file (`animation N` where it has none).
    pub name: String,
    /// What it drives; every channel plays (the loader drops those that cannot).
    pub channels: Vec<Channel>,
    /// The morph-target weights it drives.
    pub weights: Vec<WeightChannel>,
}

impl Clip {
    /// Seconds from 0 to its last key (0 for a clip of one key per channel).
    pub fn duration(&self) -> f32 {
        self.channels
            .iter()
            .filter_map(|c| c.times.last().copied())
            .chain(self.weights.iter().filter_map(|c| c.times.last().copied()))
            .fold(0.0, f32::max)
    }
}

/// A node of the file's tree, as it stands at rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// Its parent (an index into [`Animations::nodes`]); `None` for a root.
    pub parent: Option<usize>,
    /// Its local transform at rest (the file's `matrix`, or its translation, rotation and
    /// scale).
    pub rest: Mat4,
    /// The rest transform as translation, rotation, scale: what a channel's property replaces.
    pub translation: Vec3,
    /// Rotation at rest.
    pub rotation: Quat,
    /// Scale at rest.
    pub scale: Vec3,
}

/// An instance that an animated node moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moving {
    /// The scene's instance.
    pub instance: usize,
    /// The node it is drawn at (its mesh's node).
    pub node: usize,
    /// `W₀⁻¹ · P`: the inverse of the node's world transform at rest times the instance's
    /// transform as loaded.
    pub from_rest: Mat4,
}

/// A node's morph-target weights over time: `targets` weights per key (three times that for a
/// cubic spline: in-tangents, values, out-tangents).
#[derive(Clone, Debug, PartialEq)]
pub struct WeightChannel {
    /// The node.
    pub node: usize,
    /// How its keys are joined.
    pub interpolation: Interpolation,
    /// Key times in seconds: finite, strictly increasing, at least one.
    pub times: Vec<f32>,
    /// Weights per key.
    pub targets: usize,
    /// The keys' weights, `targets` per key (per part of a cubic key).
    pub values: Vec<f32>,
}

impl WeightChannel {
    /// Why this channel cannot be played, if it cannot.
    pub fn problem(&self, nodes: usize) -> Option<String> {
        let per_key = if self.interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
        if self.node >= nodes {
            return Some(format!("node {} is not in the scene's tree", self.node));
        }
        if self.times.is_empty() || self.targets == 0 {
            return Some("it has no keys or no targets".into());
        }
        if self.values.len() != per_key * self.targets * self.times.len() {
            return Some(format!(
                "it has {} key times but {} weights ({} expected for {} targets)",
                self.times.len(),
                self.values.len(),
                per_key * self.targets * self.times.len(),
                self.targets
            ));
        }
        if self.times.iter().any(|t| !t.is_finite()) || self.values.iter().any(|v| !v.is_finite()) {
            return Some("a key time or weight is not finite".into());
        }
        if self.times.windows(2).any(|w| w[1] <= w[0]) {
            return Some("its key times do not increase".into());
        }
        None
    }

    /// The weights at `t`, held at the ends.
    pub fn sample(&self, t: f32) -> Vec<f32> {
        let (n, m) = (self.times.len(), self.targets);
        let cubic = self.interpolation == Interpolation::CubicSpline;
        let part = |k: usize, which: usize| -> &[f32] {
            let at = if cubic { (3 * k + which) * m } else { k * m };
            &self.values[at..at + m]
        };
        let value = |k: usize| part(k, 1).to_vec();
        let after = self.times.partition_point(|&k| k <= t);
        if after == 0 {
            return value(0);
        }
        if after >= n {
            return value(n - 1);
        }
        let k = after - 1;
        let dt = self.times[after] - self.times[k];
        let u = ((t - self.times[k]) / dt).clamp(0.0, 1.0);
        match self.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear => part(k, 1)
                .iter()
                .zip(part(k + 1, 1))
                .map(|(a, b)| a + (b - a) * u)
                .collect(),
            Interpolation::CubicSpline => {
                let (u2, u3) = (u * u, u * u * u);
                (0..m)
                    .map(|i| {
                        (2.0 * u3 - 3.0 * u2 + 1.0) * part(k, 1)[i]
                            + (u3 - 2.0 * u2 + u) * dt * part(k, 2)[i]
                            + (-2.0 * u3 + 3.0 * u2) * part(k + 1, 1)[i]
                            + (u3 - u2) * dt * part(k + 1, 0)[i]
                    })
                    .collect()
            }
        }
    }
}

/// Which clips play.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Playing {
    /// One clip, by index.
    One(usize),
    /// Every clip at once, a later clip's channel winning where two drive one property.
    All,
}

/// A scene's animations: the node tree, the clips, and the instances they move. Empty (the
/// default) for a scene that does not move.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Animations {
    /// The file's nodes (by their index in the file).
    pub nodes: Vec<Node>,
    /// The clips, in the file's order.
    pub clips: Vec<Clip>,
    /// The instances under an animated node.
    pub moving: Vec<Moving>,
    /// The meshes joints bend.
    pub skins: Vec<Skin>,
    /// The meshes morph targets shape.
    pub morphs: Vec<Morph>,
    /// Meshes bent away from their vertices in `Scene::meshes` (a renderer bends them on the
    /// GPU and keeps the vertices as loaded): per mesh, a box `(min, max)` around it as it is
    /// bent now, in its own coordinates, which [`Scene::world_bounds`](crate::Scene) takes
    /// instead of its vertices. Empty as loaded.
    pub bent_bounds: std::collections::BTreeMap<usize, (Vec3, Vec3)>,
}

impl Animations {
    /// True when nothing moves (no clip, or no instance under an animated node and no skin).
    pub fn is_empty(&self) -> bool {
        self.clips.is_empty()
            || (self.moving.is_empty() && self.skins.is_empty() && self.morphs.is_empty())
    }

    /// What `--animation` names: a clip's name, its index from 0, or `all`. The error lists
    /// the clips.
    pub fn choose(&self, asked: &str) -> Result<Playing, String> {
        if asked.eq_ignore_ascii_case("all") {
            return Ok(Playing::All);
        }
        if let Some(k) = self.clips.iter().position(|c| c.name == asked) {
            return Ok(Playing::One(k));
        }
        match asked.parse::<usize>() {
            Ok(k) if k < self.clips.len() => Ok(Playing::One(k)),
            _ => Err(format!(
                "no animation named or numbered '{asked}'; the file has {}, and `all` plays \
                 every one",
                self.list()
            )),
        }
    }

    /// The clips, numbered, with their durations: `0 'Walk' (1.20 s), 1 'Run' (0.80 s)`.
    pub fn list(&self) -> String {
        if self.clips.is_empty() {
            return "none".into();
        }
        self.clips
            .iter()
            .enumerate()
            .map(|(k, c)| format!("{k} '{}' ({:.2} s)", c.name, c.duration()))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Seconds `playing` lasts (the longest clip for [`Playing::All`]).
    pub fn duration(&self, playing: Playing) -> f32 {
        self.playing(playing)
            .map(Clip::duration)
            .fold(0.0, f32::max)
    }

    /// Its name for messages: the clip's, or `all N animations`.
    pub fn describe(&self, playing: Playing) -> String {
        match playing {
            Playing::One(k) => format!(
                "'{}' ({} of {})",
                self.clips.get(k).map_or("?", |c| c.name.as_str()),
                k + 1,
                self.clips.len()
            ),
            Playing::All => format!("all {} animations", self.clips.len()),
        }
    }

    fn playing(&self, playing: Playing) -> impl Iterator<Item = &Clip> {
        let range = match playing {
            Playing::One(k) => k..(k + 1).min(self.clips.len()),
            Playing::All => 0..self.clips.len(),
        };
        self.clips[range].iter()
    }

    /// `t` as a looping player shows it: taken modulo the duration past the end (the end
    /// itself stays), 0 before 0 or where nothing lasts.
    pub fn wrap(&self, playing: Playing, t: f32) -> f32 {
        let d = self.duration(playing);
        // NaN compares false: it lands here too.
        if t.is_nan() || d.is_nan() || t <= 0.0 || d <= 0.0 {
            0.0
        } else if t <= d {
            t
        } else {
            t % d
        }
    }

    /// Every node's local transform at `t` (wrapped as [`Self::wrap`] says).
    pub fn locals(&self, playing: Playing, t: f32) -> Vec<Mat4> {
        let t = self.wrap(playing, t);
        let mut trs: Vec<Option<(Vec3, Quat, Vec3)>> = vec![None; self.nodes.len()];
        for clip in self.playing(playing) {
            for c in &clip.channels {
                let Some(node) = self.nodes.get(c.node) else {
                    continue;
                };
                let slot = trs[c.node].get_or_insert((node.translation, node.rotation, node.scale));
                let v = c.sample(t);
                match c.property {
                    Property::Translation => slot.0 = v.truncate(),
                    Property::Rotation => slot.1 = Quat::from_vec4(v),
                    Property::Scale => slot.2 = v.truncate(),
                }
            }
        }
        self.nodes
            .iter()
            .zip(trs)
            .map(|(n, trs)| match trs {
                Some((t, r, s)) => Mat4::from_scale_rotation_translation(s, r, t),
                None => n.rest,
            })
            .collect()
    }

    /// World transforms of every node given their locals (a parent's before its child's
    /// whatever the order of the list; a cycle, which the loader refuses, is cut at the root).
    pub fn worlds(&self, locals: &[Mat4]) -> Vec<Mat4> {
        let n = self.nodes.len();
        let mut world: Vec<Option<Mat4>> = vec![None; n];
        for start in 0..n {
            // The chain up to a node already known (or a root), then down again.
            let mut chain = vec![start];
            while let Some(&k) = chain.last() {
                match self.nodes[k].parent {
                    Some(p) if p < n && world[p].is_none() && chain.len() <= n => chain.push(p),
                    _ => break,
                }
            }
            for &k in chain.iter().rev() {
                if world[k].is_some() {
                    continue;
                }
                let parent = self.nodes[k]
                    .parent
                    .and_then(|p| world.get(p).copied().flatten())
                    .unwrap_or(Mat4::IDENTITY);
                world[k] = Some(parent * locals[k]);
            }
        }
        world
            .into_iter()
            .map(|w| w.unwrap_or(Mat4::IDENTITY))
            .collect()
    }

    /// The rest world transforms (every node's file transform, no clip playing).
    pub fn rest_worlds(&self) -> Vec<Mat4> {
        let locals: Vec<Mat4> = self.nodes.iter().map(|n| n.rest).collect();
        self.worlds(&locals)
    }

    /// Nodes that a clip drives, or whose ancestor one drives.
    pub fn animated_nodes(&self) -> Vec<bool> {
        let n = self.nodes.len();
        let mut driven = vec![false; n];
        for c in self.clips.iter().flat_map(|c| &c.channels) {
            if c.node < n {
                driven[c.node] = true;
            }
        }
        (0..n)
            .map(|mut k| {
                for _ in 0..=n {
                    if driven[k] {
                        return true;
                    }
                    match self.nodes[k].parent {
                        Some(p) if p < n => k = p,
                        _ => return false,
                    }
                }
                false
            })
            .collect()
    }

    /// The moving instances' transforms at `t`: `(instance, W(t) · W₀⁻¹ · P)`. A transform
    /// that a clip scales to nothing (a common way to hide a part) is clamped to a scale of
    /// 10⁻⁴ of the rest, which the renderer accepts (it refuses singular transforms), and
    /// which draws nothing visible.
    pub fn pose(&self, playing: Playing, t: f32) -> Vec<(usize, Mat4)> {
        let worlds = self.worlds(&self.locals(playing, t));
        self.moving
            .iter()
            .filter_map(|m| {
                let w = *worlds.get(m.node)?;
                let mut out = w * m.from_rest;
                if !out.is_finite() || out.determinant().abs() < 1e-12 {
                    let (s, r, t) = w.to_scale_rotation_translation();
                    let s = Vec3::select(s.abs().cmplt(Vec3::splat(1e-4)), Vec3::splat(1e-4), s);
                    out = Mat4::from_scale_rotation_translation(s, r.normalize(), t) * m.from_rest;
                    if !out.is_finite() || out.determinant().abs() < 1e-12 {
                        out = Mat4::from_translation(t) * Mat4::from_scale(Vec3::splat(1e-4));
                    }
                }
                Some((m.instance, out))
            })
            .collect()
    }
}

impl Animations {
    /// What bends the meshes at `t` (wrapped as [`Animations::wrap`] says): every node's
    /// world transform, and the morph weights the playing clips drive.
    pub fn bending(&self, playing: Playing, t: f32) -> Bending {
        let worlds = self.worlds(&self.locals(playing, t));
        let t = self.wrap(playing, t);
        let mut weights: Vec<(usize, Vec<f32>)> = Vec::new();
        for c in self.playing(playing).flat_map(|clip| &clip.weights) {
            weights.retain(|(n, _)| *n != c.node);
            weights.push((c.node, c.sample(t)));
        }
        Bending { worlds, weights }
    }

    /// What bends the meshes at rest: the joints where the file's nodes put them, the
    /// default morph weights.
    pub fn bending_at_rest(&self) -> Bending {
        Bending {
            worlds: self.rest_worlds(),
            weights: Vec::new(),
        }
    }

    /// Every deformed mesh's vertices and normals at `t`: `(mesh, positions, normals)`.
    pub fn deformed(&self, playing: Playing, t: f32) -> Vec<(usize, Vec<Vec3>, Vec<Vec3>)> {
        if self.skins.is_empty() && self.morphs.is_empty() {
            return Vec::new();
        }
        self.bend(&self.bending(playing, t))
    }

    /// Every deformed mesh at rest.
    pub fn deformed_at_rest(&self) -> Vec<(usize, Vec<Vec3>, Vec<Vec3>)> {
        self.bend(&self.bending_at_rest())
    }

    /// Every deformed mesh bent by `bending`: `(mesh, positions, normals)`.
    pub fn bend(&self, bending: &Bending) -> Vec<(usize, Vec<Vec3>, Vec<Vec3>)> {
        self.bend_where(bending, |_| true)
    }

    /// [`Animations::bend`] for the meshes `keep` keeps alone (`deform::bend_meshes`).
    pub fn bend_where(
        &self,
        bending: &Bending,
        keep: impl Fn(usize) -> bool,
    ) -> Vec<(usize, Vec<Vec3>, Vec<Vec3>)> {
        deform::bend_meshes(&self.skins, &self.morphs, bending, keep)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec4;

    fn channel(
        property: Property,
        interpolation: Interpolation,
        times: &[f32],
        values: &[Vec4],
    ) -> Channel {
        Channel {
            node: 0,
            property,
            interpolation,
            times: times.to_vec(),
            values: values.to_vec(),
        }
    }

    #[test]
    fn linear_and_step_hold_their_ends_and_join_their_keys() {
        let v = [
            Vec4::new(0.0, 0.0, 0.0, 0.0),
            Vec4::new(2.0, 4.0, -2.0, 0.0),
        ];
        let lin = channel(
            Property::Translation,
            Interpolation::Linear,
            &[1.0, 3.0],
            &v,
        );
        assert_eq!(lin.sample(0.0), v[0]);
        assert_eq!(lin.sample(2.0), Vec4::new(1.0, 2.0, -1.0, 0.0));
        assert_eq!(lin.sample(9.0), v[1]);
        let step = channel(Property::Translation, Interpolation::Step, &[1.0, 3.0], &v);
        assert_eq!(step.sample(2.9), v[0]);
        assert_eq!(step.sample(3.0), v[1]);
    }

    #[test]
    fn rotations_turn_along_the_shorter_arc() {
        // 0° and 350° about y, the second stored negated: halfway is 355°, i.e. -5°, not 175°.
        let a = Quat::IDENTITY;
        let b = -Quat::from_rotation_y(350f32.to_radians());
        let c = channel(
            Property::Rotation,
            Interpolation::Linear,
            &[0.0, 1.0],
            &[Vec4::from(a), Vec4::from(b)],
        );
        let half = Quat::from_vec4(c.sample(0.5));
        let want = Quat::from_rotation_y((-5f32).to_radians());
        assert!(half.dot(want).abs() > 0.99999, "{half:?} vs {want:?}");
        // A quarter of 90°: 22.5° (a linear blend of the quaternions would be off).
        let c = channel(
            Property::Rotation,
            Interpolation::Linear,
            &[0.0, 1.0],
            &[
                Vec4::from(Quat::IDENTITY),
                Vec4::from(Quat::from_rotation_x(1.5707964)),
            ],
        );
        let q = Quat::from_vec4(c.sample(0.25));
        let (axis, angle) = q.to_axis_angle();
        assert!((angle - 22.5f32.to_radians()).abs() < 1e-5, "{angle}");
        assert!(axis.abs_diff_eq(Vec3::X, 1e-5));
    }

    #[test]
    fn cubic_spline_reproduces_a_cubic() {
        // f(t) = t³ − 2t + 1 over keys 0, 0.5, 2 with tangents f'(t) = 3t² − 2: a Hermite
        // spline through values and derivatives is exact for a cubic.
        let f = |t: f32| t * t * t - 2.0 * t + 1.0;
        let d = |t: f32| 3.0 * t * t - 2.0;
        let times = [0.0, 0.5, 2.0];
        let values: Vec<Vec4> = times
            .iter()
            .flat_map(|&t| [Vec4::splat(d(t)), Vec4::splat(f(t)), Vec4::splat(d(t))])
            .collect();
        let c = channel(Property::Scale, Interpolation::CubicSpline, &times, &values);
        for t in [0.0, 0.1, 0.3, 0.5, 0.7, 1.2, 1.9, 2.0] {
            let got = c.sample(t).x;
            assert!((got - f(t)).abs() < 1e-4, "t {t}: {got} vs {}", f(t));
        }
    }

    #[test]
    fn weights_join_their_keys_target_by_target() {
        // Two targets: (0, 1) at 0 s, (1, 0) at 2 s.
        let c = WeightChannel {
            node: 0,
            interpolation: Interpolation::Linear,
            times: vec![0.0, 2.0],
            targets: 2,
            values: vec![0.0, 1.0, 1.0, 0.0],
        };
        assert_eq!(c.problem(1), None);
        assert_eq!(c.sample(0.5), vec![0.25, 0.75]);
        assert_eq!(c.sample(3.0), vec![1.0, 0.0]);
        let short = WeightChannel {
            values: vec![0.0, 1.0, 1.0],
            ..c.clone()
        };
        assert!(short
            .problem(1)
            .unwrap()
            .contains("4 expected for 2 targets"));
        // The shape: base plus each target's displacement times its weight.
        let m = Morph {
            mesh: 0,
            node: 0,
            base_positions: vec![Vec3::ZERO],
            base_normals: vec![Vec3::Y],
            position_deltas: vec![vec![Vec3::X], vec![Vec3::Z]],
            normal_deltas: vec![vec![Vec3::ZERO], vec![Vec3::ZERO]],
            default_weights: vec![0.0, 0.0],
        };
        let (p, n) = m.shape(&c.sample(0.5));
        assert_eq!(p, vec![Vec3::new(0.25, 0.0, 0.75)]);
        assert_eq!(n, vec![Vec3::Y]);
    }

    #[test]
    fn channels_that_cannot_play_say_why() {
        let one = [Vec4::ZERO];
        let bad = channel(
            Property::Translation,
            Interpolation::Linear,
            &[f32::NAN],
            &one,
        );
        assert!(bad.problem(1).unwrap().contains("not finite"));
        let two = [Vec4::ZERO, Vec4::ONE];
        let back = channel(
            Property::Translation,
            Interpolation::Linear,
            &[1.0, 0.5],
            &two,
        );
        assert!(back.problem(1).unwrap().contains("do not increase"));
        let short = channel(
            Property::Translation,
            Interpolation::CubicSpline,
            &[0.0, 1.0],
            &two,
        );
        assert!(short.problem(1).unwrap().contains("6 expected"));
        let zero = channel(Property::Rotation, Interpolation::Step, &[0.0], &one);
        assert!(zero.problem(1).unwrap().contains("zero quaternion"));
        let fine = channel(
            Property::Translation,
            Interpolation::Linear,
            &[0.0, 1.0],
            &two,
        );
        assert_eq!(fine.problem(1), None);
        assert!(fine.problem(0).unwrap().contains("node 0"));
    }

    #[test]
    fn a_child_follows_its_turning_parent() {
        // Root turns about y by 90° per second; its child stands 2 along x.
        let node = |parent, t: Vec3| Node {
            parent,
            rest: Mat4::from_translation(t),
            translation: t,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
        };
        let anim = Animations {
            bent_bounds: Default::default(),
            nodes: vec![
                node(None, Vec3::ZERO),
                node(Some(0), Vec3::new(2.0, 0.0, 0.0)),
            ],
            clips: vec![Clip {
                weights: Vec::new(),
                name: "turn".into(),
                channels: vec![channel(
                    Property::Rotation,
                    Interpolation::Linear,
                    &[0.0, 1.0],
                    &[
                        Vec4::from(Quat::IDENTITY),
                        Vec4::from(Quat::from_rotation_y(1.5707964)),
                    ],
                )],
            }],
            moving: vec![Moving {
                instance: 7,
                node: 1,
                from_rest: Mat4::from_translation(Vec3::new(-2.0, 0.0, 0.0)),
            }],
            skins: Vec::new(),
            morphs: Vec::new(),
        };
        assert_eq!(anim.animated_nodes(), vec![true, true]);
        let pose = anim.pose(Playing::One(0), 1.0);
        assert_eq!(pose.len(), 1);
        assert_eq!(pose[0].0, 7);
        // The vertex baked at (2, 0, 0) + (0, 1, 0) ends at (0, 1, -2) after 90° about y.
        let p = pose[0].1.transform_point3(Vec3::new(2.0, 1.0, 0.0));
        assert!(p.abs_diff_eq(Vec3::new(0.0, 1.0, -2.0), 1e-5), "{p}");
        // Looping: 1.5 s of a 1 s clip is 0.5 s; the end itself stays.
        assert_eq!(anim.wrap(Playing::All, 1.5), 0.5);
        assert_eq!(anim.wrap(Playing::All, 1.0), 1.0);
        assert_eq!(anim.choose("turn"), Ok(Playing::One(0)));
        assert_eq!(anim.choose("0"), Ok(Playing::One(0)));
        assert_eq!(anim.choose("ALL"), Ok(Playing::All));
        assert!(anim
            .choose("walk")
            .unwrap_err()
            .contains("0 'turn' (1.00 s)"));
    }
}
