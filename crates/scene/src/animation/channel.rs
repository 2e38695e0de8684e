//! A channel of a clip: one node's translation, rotation or scale over time, its keys joined
//! as glTF 2.0 §3.11.6 says (`STEP`, `LINEAR` with rotations by spherical interpolation along
//! the shorter arc, `CUBICSPLINE`), and the checks that refuse a channel that cannot play.

use glam::{Quat, Vec4};

/// How a channel's keys are joined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Each key's value holds until the next key.
    Step,
    /// Linear between keys; rotations along the shorter great arc.
    Linear,
    /// Cubic Hermite spline through the keys with their in and out tangents.
    CubicSpline,
}

/// What a channel drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Property {
    /// The node's translation (xyz).
    Translation,
    /// The node's rotation, a unit quaternion (xyzw).
    Rotation,
    /// The node's scale (xyz).
    Scale,
}

impl Property {
    /// The glTF name (`translation`, `rotation`, `scale`).
    pub fn name(self) -> &'static str {
        match self {
            Property::Translation => "translation",
            Property::Rotation => "rotation",
            Property::Scale => "scale",
        }
    }
}

/// One animated property of one node.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The node it drives (an index into [`Animations::nodes`]).
    pub node: usize,
    /// What it drives.
    pub property: Property,
    /// How its keys are joined.
    pub interpolation: Interpolation,
    /// Key times in seconds: finite, strictly increasing, at least one.
    pub times: Vec<f32>,
    /// The keys' values (xyz for translation and scale, xyzw for rotation), one per key, or
    /// three per key for [`Interpolation::CubicSpline`]: in-tangent, value, out-tangent.
    pub values: Vec<Vec4>,
}

impl Channel {
    /// Why this channel cannot be played, if it cannot: the checks the loader drops a channel
    /// for (`None`: it plays).
    pub fn problem(&self, nodes: usize) -> Option<String> {
        let per_key = match self.interpolation {
            Interpolation::CubicSpline => 3,
            _ => 1,
        };
        if self.node >= nodes {
            return Some(format!("node {} is not in the scene's tree", self.node));
        }
        if self.times.is_empty() {
            return Some("it has no keys".into());
        }
        if self.values.len() != per_key * self.times.len() {
            return Some(format!(
                "it has {} key times but {} values ({} expected)",
                self.times.len(),
                self.values.len(),
                per_key * self.times.len()
            ));
        }
        if let Some(t) = self.times.iter().find(|t| !t.is_finite()) {
            return Some(format!("a key time is not finite ({t})"));
        }
        if self.times.windows(2).any(|w| w[1] <= w[0]) {
            return Some("its key times do not increase".into());
        }
        if self.values.iter().any(|v| !v.is_finite()) {
            return Some("a key value is not finite".into());
        }
        if self.property == Property::Rotation
            && self
                .values
                .iter()
                .skip(usize::from(per_key == 3))
                .step_by(per_key)
                .any(|q| q.length_squared() < 1e-12)
        {
            return Some("a rotation key is the zero quaternion".into());
        }
        None
    }

    /// The channel's value at `t` seconds (xyz or xyzw), held at its ends.
    pub fn sample(&self, t: f32) -> Vec4 {
        let n = self.times.len();
        let cubic = self.interpolation == Interpolation::CubicSpline;
        let value = |k: usize| {
            if cubic {
                self.values[3 * k + 1]
            } else {
                self.values[k]
            }
        };
        let rotation = self.property == Property::Rotation;
        let unit = |v: Vec4| if rotation { v.normalize() } else { v };
        // The key at or before `t`.
        let after = self.times.partition_point(|&k| k <= t);
        if after == 0 {
            return unit(value(0));
        }
        if after >= n {
            return unit(value(n - 1));
        }
        let (k, (t0, t1)) = (after - 1, (self.times[after - 1], self.times[after]));
        let dt = t1 - t0;
        let u = ((t - t0) / dt).clamp(0.0, 1.0);
        match self.interpolation {
            Interpolation::Step => unit(value(k)),
            Interpolation::Linear if rotation => {
                let a = Quat::from_vec4(value(k)).normalize();
                let b = Quat::from_vec4(value(k + 1)).normalize();
                Vec4::from(slerp_shorter(a, b, u))
            }
            Interpolation::Linear => value(k).lerp(value(k + 1), u),
            Interpolation::CubicSpline => {
                let (u2, u3) = (u * u, u * u * u);
                let p0 = self.values[3 * k + 1];
                let m0 = self.values[3 * k + 2] * dt;
                let p1 = self.values[3 * (k + 1) + 1];
                let m1 = self.values[3 * (k + 1)] * dt;
                let v = (2.0 * u3 - 3.0 * u2 + 1.0) * p0
                    + (u3 - 2.0 * u2 + u) * m0
                    + (-2.0 * u3 + 3.0 * u2) * p1
                    + (u3 - u2) * m1;
                unit(v)
            }
        }
    }
}

/// `a` to `b` by `u` along the shorter great arc (a quaternion and its negation are one
/// rotation), normalized.
fn slerp_shorter(a: Quat, b: Quat, u: f32) -> Quat {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    let cos = a.dot(b).clamp(-1.0, 1.0);
    if cos > 0.9995 {
        // Nearly the same rotation: linear, then normalized (slerp's limit).
        return Quat::from_vec4(Vec4::from(a).lerp(Vec4::from(b), u)).normalize();
    }
    let angle = cos.acos();
    let s = angle.sin();
    let wa = ((1.0 - u) * angle).sin() / s;
    let wb = (u * angle).sin() / s;
    Quat::from_vec4(Vec4::from(a) * wa + Vec4::from(b) * wb).normalize()
}
