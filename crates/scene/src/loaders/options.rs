//! What a caller may change about loading a model file: whether the file may reach files
//! outside its own folder, and whether a ground plane is added under a model without a floor.
//! The CLI fills these from `--allow-outside-paths` and `--ground`.

/// Options of [`load_scene_with`](super::dispatch::load_scene_with) and
/// [`load_mesh_with`](super::dispatch::load_mesh_with); [`Default`] (paths stay inside the
/// model's folder, no ground plane) is what [`load_scene`](super::dispatch::load_scene) and
/// [`load_mesh`](super::dispatch::load_mesh) use. The CLI's defaults differ in one place: its
/// `--ground` is `auto`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Let the paths a file names (glTF buffer and image URIs, OBJ `mtllib`, MTL texture
    /// statements) be absolute or leave the model's folder through `..` or a symbolic link.
    /// Off by default: a model file is untrusted input, and without this a file could make the
    /// loader read any file the user can (`"uri": "/etc/passwd"`). The CLI's
    /// `--allow-outside-paths`.
    pub allow_outside_paths: bool,
    /// Whether [`load_scene_with`](super::dispatch::load_scene_with) adds a ground plane under
    /// the model (the CLI's `--ground`, `auto` there; [`Ground::Off`] here, so a library
    /// caller gets the file's own scene unless it asks).
    pub ground: Ground,
}

/// When a loaded scene gets a ground plane (a large, shadow-catching square under the model).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Ground {
    /// Only for a model without a floor of its own (see the module documentation of
    /// [`super`] for how a floor is recognised): the CLI's default.
    Auto,
    /// Always.
    On,
    /// Never: the library's default.
    #[default]
    Off,
}

impl std::str::FromStr for Ground {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(Self::Auto),
            "on" | "yes" | "true" => Ok(Self::On),
            "off" | "no" | "false" => Ok(Self::Off),
            other => Err(format!(
                "'{other}' is not a ground setting: use auto (a ground plane only under a model \
                 without a floor), on or off"
            )),
        }
    }
}
