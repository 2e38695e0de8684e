//! How the frame estimate prices a technique (`Renderer::estimate_frame`): the work of a
//! frame counted in units ([`EstimatedWork`]), and each technique's own price list, declared
//! with it ([`Cost`] in its `TechniqueInfo`): how its lighting pass reads shadows (which row of
//! the lighting pass's costs applies) and the milliseconds of its shadow stage for a frame's
//! work, from costs per unit measured on lavapipe (`manyshadows bench estimate` measures them
//! against real frames; docs/benchmarks.md, "What a frame will cost: `bench estimate`", has
//! its table).

/// The work of the next frame, counted before it is drawn
/// ([`Renderer::estimated_work`](crate::Renderer::estimated_work)).
#[non_exhaustive]
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct EstimatedWork {
    /// Pixels of the frame.
    pub pixels: u64,
    /// Triangles the camera draws (every instance; with stereo, once per eye).
    pub triangles: u64,
    /// Triangles of the instances that cast shadows.
    pub caster_triangles: u64,
    /// Instances.
    pub instances: usize,
    /// Lights.
    pub lights: usize,
    /// (pixel, light) pairs in reach, estimated from a coarse grid of camera rays.
    pub pixel_lights: u64,
    /// (pixel, light) pairs the clustered light loop visits: lights whose reach meets the
    /// pixel's cluster (estimated from the same grid).
    pub cluster_lights: u64,
    /// (caster triangle, view) pairs the shadow stage takes on (0 without views; for virtual
    /// maps, after culling whole instances per face).
    pub triangle_views: u64,
    /// (caster triangle, view) pairs left after culling whole instances per view by bounding
    /// sphere.
    pub after_instance_culling: u64,
    /// Every caster triangle in every view.
    pub all_pairs: u64,
    /// (caster instance, view) pairs left after culling whole instances per view: the draws
    /// of the techniques that draw per instance and view.
    pub instance_views: u64,
    /// Shadow views (atlas tiles, virtual faces, irregular light views).
    pub views: usize,
    /// Atlas texels the views' tiles cover (atlas techniques).
    pub atlas_texels: u64,
    /// Texels of the whole atlas texture (atlas techniques).
    pub atlas_area: u64,
    /// Depth taps per (pixel, light) pair beyond one comparison: a sized light's blocker
    /// search and filter, or a 3×3 PCF.
    pub taps: u32,
    /// Shadow rays the lighting pass traces (ray-traced shadows).
    pub rays: u64,
    /// Mean triangles a shadow ray tests before it is done (on a CPU BVH of the scene, from
    /// a few lights in reach of each grid point).
    pub ray_weight: f64,
}

impl EstimatedWork {
    /// The units an atlas technique's shadow stage is priced by: (triangle, view) pairs taken
    /// on, (instance, view) pairs, texels of the tiles, texels of the whole atlas, views, 1.
    pub fn atlas_units(&self) -> [f64; 6] {
        [
            self.triangle_views as f64,
            self.instance_views as f64,
            self.atlas_texels as f64,
            self.atlas_area as f64,
            self.views as f64,
            1.0,
        ]
    }

    /// (pixel, light) pairs in reach times the extra depth taps each pays.
    pub fn tap_pairs(&self) -> f64 {
        self.pixel_lights as f64 * f64::from(self.taps)
    }
}

/// How a technique's lighting pass reads its shadows, which decides the lighting pass's price
/// per (pixel, light) pair.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightingRead {
    /// A depth comparison in a shadow map (an atlas tile, a virtual page), with the soft
    /// filter's taps for sized lights.
    Maps,
    /// A bit of a visibility mask the source computed.
    Mask,
    /// Shadow rays traced by the lighting pass.
    Rays,
}

/// A technique's price list for the frame estimate.
#[derive(Clone, Copy, Debug)]
pub struct Cost {
    /// How its lighting pass reads shadows.
    pub lighting: LightingRead,
    /// Milliseconds of its shadow stage (pages and acceleration structures included) for a
    /// frame's work, at lavapipe's measured costs per unit.
    pub shadows_ms: fn(&EstimatedWork) -> f64,
}

/// `Σ kᵢ·xᵢ`: a linear price.
pub fn price(k: &[f64], x: &[f64]) -> f64 {
    k.iter().zip(x).map(|(k, x)| k * x).sum()
}
