//! A pass's bindings from one definition. Each binding is declared once, as a [`Binding`]: the
//! name its WGSL uses and what it is. A [`BindingList`] numbers a pass's bindings in order and
//! gives, from the same list, the WGSL declarations the pass's shader starts with, the
//! bind-group layout's entries and, with the resources in the same order, the bind group's
//! entries. So a pass's Rust side and its WGSL never spell a binding number: a part that
//! plugs into a pass (a shadow source's lookup, the reflection probes, the denoiser) brings its
//! bindings as declarations and its WGSL without them.

/// What a binding holds, as WGSL declares it and as the layout describes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// `var<uniform> name: T`, `T` the WGSL type.
    Uniform(&'static str),
    /// `var<storage, read> name: T`.
    Storage(&'static str),
    /// `var<storage, read_write> name: T`.
    StorageRw(&'static str),
    /// A sampled 2D texture: `texture_2d<u32>` (unsigned), `texture_2d<f32>` (float) or
    /// `texture_depth_2d` (depth).
    Texture(wgpu::TextureSampleType),
    /// A 2D array texture of filterable floats: `texture_2d_array<f32>`.
    TextureArray,
    /// `sampler` (filtering) or `sampler_comparison`.
    Sampler(wgpu::SamplerBindingType),
    /// `acceleration_structure` (ray queries).
    AccelerationStructure,
}

/// One binding of a pass: its WGSL name and its kind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Binding {
    /// The variable's name in WGSL.
    pub name: &'static str,
    /// What it holds.
    pub kind: Kind,
}

impl Binding {
    /// A uniform buffer of WGSL type `ty`.
    pub const fn uniform(name: &'static str, ty: &'static str) -> Self {
        Binding {
            name,
            kind: Kind::Uniform(ty),
        }
    }

    /// A read-only storage buffer of WGSL type `ty`.
    pub const fn storage(name: &'static str, ty: &'static str) -> Self {
        Binding {
            name,
            kind: Kind::Storage(ty),
        }
    }

    /// A read-write storage buffer of WGSL type `ty`.
    pub const fn storage_rw(name: &'static str, ty: &'static str) -> Self {
        Binding {
            name,
            kind: Kind::StorageRw(ty),
        }
    }

    /// A 2D texture of unsigned integers.
    pub const fn texture_u32(name: &'static str) -> Self {
        Binding {
            name,
            kind: Kind::Texture(wgpu::TextureSampleType::Uint),
        }
    }

    /// A 2D texture of floats read without filtering (`textureLoad`).
    pub const fn texture_f32(name: &'static str) -> Self {
        Binding {
            name,
            kind: Kind::Texture(wgpu::TextureSampleType::Float { filterable: false }),
        }
    }

    /// A depth texture (comparison sampling).
    pub const fn texture_depth(name: &'static str) -> Self {
        Binding {
            name,
            kind: Kind::Texture(wgpu::TextureSampleType::Depth),
        }
    }

    /// A 2D array texture of filterable floats.
    pub const fn texture_array(name: &'static str) -> Self {
        Binding {
            name,
            kind: Kind::TextureArray,
        }
    }

    /// A filtering sampler.
    pub const fn sampler(name: &'static str) -> Self {
        Binding {
            name,
            kind: Kind::Sampler(wgpu::SamplerBindingType::Filtering),
        }
    }

    /// A comparison sampler.
    pub const fn sampler_comparison(name: &'static str) -> Self {
        Binding {
            name,
            kind: Kind::Sampler(wgpu::SamplerBindingType::Comparison),
        }
    }

    /// A ray-query acceleration structure.
    pub const fn acceleration_structure(name: &'static str) -> Self {
        Binding {
            name,
            kind: Kind::AccelerationStructure,
        }
    }

    /// Its WGSL declaration at `binding` of group 0.
    pub fn wgsl(&self, binding: u32) -> String {
        let name = self.name;
        let var = match self.kind {
            Kind::Uniform(ty) => format!("var<uniform> {name}: {ty}"),
            Kind::Storage(ty) => format!("var<storage, read> {name}: {ty}"),
            Kind::StorageRw(ty) => format!("var<storage, read_write> {name}: {ty}"),
            Kind::Texture(wgpu::TextureSampleType::Uint) => format!("var {name}: texture_2d<u32>"),
            Kind::Texture(wgpu::TextureSampleType::Sint) => format!("var {name}: texture_2d<i32>"),
            Kind::Texture(wgpu::TextureSampleType::Depth) => {
                format!("var {name}: texture_depth_2d")
            }
            Kind::Texture(wgpu::TextureSampleType::Float { .. }) => {
                format!("var {name}: texture_2d<f32>")
            }
            Kind::TextureArray => format!("var {name}: texture_2d_array<f32>"),
            Kind::Sampler(wgpu::SamplerBindingType::Comparison) => {
                format!("var {name}: sampler_comparison")
            }
            Kind::Sampler(_) => format!("var {name}: sampler"),
            Kind::AccelerationStructure => format!("var {name}: acceleration_structure"),
        };
        format!("@group(0) @binding({binding}) {var};")
    }

    /// Its bind-group layout entry at `binding`, seen by `visibility`.
    pub fn layout(
        &self,
        binding: u32,
        visibility: wgpu::ShaderStages,
    ) -> wgpu::BindGroupLayoutEntry {
        let buffer = |ty| wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let ty = match self.kind {
            Kind::Uniform(_) => buffer(wgpu::BufferBindingType::Uniform),
            Kind::Storage(_) => buffer(wgpu::BufferBindingType::Storage { read_only: true }),
            Kind::StorageRw(_) => buffer(wgpu::BufferBindingType::Storage { read_only: false }),
            Kind::Texture(sample_type) => wgpu::BindingType::Texture {
                sample_type,
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            Kind::TextureArray => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: wgpu::TextureViewDimension::D2Array,
                multisampled: false,
            },
            Kind::Sampler(s) => wgpu::BindingType::Sampler(s),
            Kind::AccelerationStructure => wgpu::BindingType::AccelerationStructure {
                vertex_return: false,
            },
        };
        wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty,
            count: None,
        }
    }
}

/// A pass's bindings in order: binding `i` is the `i`-th pushed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BindingList {
    bindings: Vec<Binding>,
}

impl BindingList {
    /// A list of `bindings`.
    #[cfg(test)]
    pub fn new(bindings: &[Binding]) -> Self {
        let mut list = Self::default();
        list.extend(bindings);
        list
    }

    /// Appends `bindings` after those already listed.
    pub fn extend(&mut self, bindings: &[Binding]) {
        for b in bindings {
            assert!(
                !self.bindings.iter().any(|x| x.name == b.name),
                "binding `{}` declared twice in one pass ({:?})",
                b.name,
                self.bindings.iter().map(|x| x.name).collect::<Vec<_>>()
            );
            self.bindings.push(*b);
        }
    }

    /// The names of the storage buffers listed (read-only and read-write): a stage may bind
    /// `max_storage_buffers_per_shader_stage` of them (10 in Chromium's WebGPU on SwiftShader,
    /// 8 in WebGPU's defaults).
    pub fn storage_buffers(&self) -> Vec<&'static str> {
        self.bindings
            .iter()
            .filter(|b| matches!(b.kind, Kind::Storage(_) | Kind::StorageRw(_)))
            .map(|b| b.name)
            .collect()
    }

    /// The WGSL declarations, one per line, numbered in order.
    pub fn wgsl(&self) -> String {
        (0u32..)
            .zip(&self.bindings)
            .map(|(i, b)| b.wgsl(i) + "\n")
            .collect()
    }

    /// The bind-group layout's entries, every binding seen by `visibility`.
    pub fn layout(&self, visibility: wgpu::ShaderStages) -> Vec<wgpu::BindGroupLayoutEntry> {
        (0u32..)
            .zip(&self.bindings)
            .map(|(i, b)| b.layout(i, visibility))
            .collect()
    }

    /// The bind group's entries for `resources`, given in the list's order (one per binding).
    pub fn entries<'a>(
        &self,
        resources: Vec<wgpu::BindingResource<'a>>,
    ) -> Vec<wgpu::BindGroupEntry<'a>> {
        assert_eq!(
            resources.len(),
            self.bindings.len(),
            "one resource per binding ({:?})",
            self.bindings.iter().map(|b| b.name).collect::<Vec<_>>()
        );
        (0u32..)
            .zip(resources)
            .map(|(binding, resource)| wgpu::BindGroupEntry { binding, resource })
            .collect()
    }
}

/// What plugs into a pass beside its own WGSL: constants and functions (with no binding
/// declarations), its bindings and their resources in the same order, and the fragment entry
/// points it adds to a full-screen pass: drawn right after the pass's own in its timing span
/// (`follow`), or left to its owner to draw when it wants (`own`).
pub struct Part<'a> {
    /// Its WGSL.
    pub wgsl: String,
    /// Its bindings.
    pub bindings: &'static [Binding],
    /// Their resources, in order.
    pub resources: Vec<wgpu::BindingResource<'a>>,
    /// Entry points drawn right after the pass's own.
    pub follow: &'static [&'static str],
    /// Entry points its owner draws.
    pub own: &'static [&'static str],
}

impl Part<'_> {
    /// A part of WGSL alone: no bindings, no entry points.
    pub fn wgsl(wgsl: String) -> Self {
        Part {
            wgsl,
            bindings: &[],
            resources: Vec::new(),
            follow: &[],
            own: &[],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn declarations_are_numbered_in_order_and_match_the_layout() {
        let mut list = BindingList::new(&[
            Binding::uniform("frame", "FrameUniforms"),
            Binding::storage("lights", "array<LightData>"),
        ]);
        list.extend(&[
            Binding::texture_depth("atlas"),
            Binding::sampler_comparison("cmp"),
            Binding::storage_rw("out", "array<u32>"),
        ]);
        let wgsl = list.wgsl();
        assert!(wgsl.contains("@group(0) @binding(0) var<uniform> frame: FrameUniforms;"));
        assert!(wgsl.contains("@group(0) @binding(2) var atlas: texture_depth_2d;"));
        assert!(wgsl.contains("@group(0) @binding(4) var<storage, read_write> out: array<u32>;"));
        let layout = list.layout(wgpu::ShaderStages::FRAGMENT);
        assert_eq!(layout.len(), 5);
        assert_eq!(layout[3].binding, 3);
        assert!(matches!(
            layout[3].ty,
            wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison)
        ));
        assert!(matches!(
            layout[4].ty,
            wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                ..
            }
        ));
    }

    #[test]
    #[should_panic(expected = "declared twice")]
    fn a_name_declared_twice_is_refused() {
        BindingList::new(&[Binding::texture_u32("g"), Binding::texture_f32("g")]);
    }
}
