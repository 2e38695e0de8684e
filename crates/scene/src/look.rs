//! How a scene means to be seen: the units of its lights and the shading model of its
//! materials ([`Lighting`]), and the physically based parameters of a material ([`Pbr`]).
//!
//! The seeds' scenes (built-in and TOML) are Phong scenes in arbitrary light units: a light's
//! diffuse colour is what a white surface facing it reflects, before a fixed exposure and an
//! exponential tone map. glTF files are physical: `KHR_lights_punctual` gives candela (point
//! and spot lights) and lux (directional), and materials are metallic-roughness. The renderer
//! picks its default shading, exposure and tone map from [`Scene::lighting`](crate::Scene);
//! every choice can be overridden (`manyshadows::Look`).

/// The units of a scene's lights and the shading its author meant.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Lighting {
    /// Seed 004's Phong lighting: light colours in arbitrary units, shown through a fixed
    /// exposure and an exponential tone map. The built-in scenes, TOML scenes, OBJ and PLY.
    #[default]
    Phong,
    /// Physical light: a point or spot light's colour is its luminous intensity in candela, a
    /// directional light's its illuminance in lux (glTF's `color × intensity`); materials are
    /// shaded with the glTF BRDF, seen through an exposure (EV100) and a tone map.
    Physical,
}

impl Lighting {
    /// Its name in messages and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Lighting::Phong => "phong",
            Lighting::Physical => "physical",
        }
    }
}

/// glTF's metallic-roughness parameters of a material. The base colour is the material's
/// diffuse colour (times its base-colour texture).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pbr {
    /// 0 = dielectric, 1 = metal (glTF `metallicFactor`).
    pub metallic: f32,
    /// Perceptual roughness, 0 = mirror, 1 = fully rough (glTF `roughnessFactor`); the GGX
    /// α is its square.
    pub roughness: f32,
}

impl Pbr {
    /// The parameters a Phong material stands for when it is shaded with the glTF BRDF: a
    /// dielectric whose GGX α gives the Blinn-Phong exponent `shininess` (`α = √(2 / (s + 2))`,
    /// the inverse of the loaders' `s = 2/α² − 2`), metallic when its specular colour is
    /// brighter than a dielectric's 4 % (`metallic = (max(specular) − 0.04) / 0.96`).
    pub fn from_phong(shininess: f32, specular: glam::Vec3) -> Self {
        let alpha = (2.0 / (shininess.max(0.0) + 2.0)).sqrt();
        let metallic = ((specular.max_element() - 0.04) / 0.96).clamp(0.0, 1.0);
        Pbr {
            metallic: if metallic.is_finite() { metallic } else { 0.0 },
            roughness: alpha.sqrt().clamp(0.0, 1.0),
        }
    }

    /// Whether both parameters lie in 0..=1.
    pub fn is_valid(&self) -> bool {
        (0.0..=1.0).contains(&self.metallic) && (0.0..=1.0).contains(&self.roughness)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn phong_roughness_inverts_the_loaders_shininess() {
        for r in [0.2f32, 0.5, 0.8, 1.0] {
            let a = r * r;
            let s = 2.0 / (a * a) - 2.0;
            let p = Pbr::from_phong(s, Vec3::splat(0.04));
            assert!(
                (p.roughness - r).abs() < 1e-4,
                "{r} -> {s} -> {}",
                p.roughness
            );
            assert_eq!(p.metallic, 0.0);
        }
        assert_eq!(Pbr::from_phong(1.0, Vec3::ONE).metallic, 1.0);
        assert!(Pbr::from_phong(f32::NAN, Vec3::splat(f32::NAN)).metallic == 0.0);
    }
}
