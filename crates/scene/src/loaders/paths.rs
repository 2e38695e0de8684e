//! The paths a model file names (glTF buffer and image URIs, OBJ `mtllib`, MTL texture
//! statements), resolved so that they stay inside the model's folder.
//!
//! Why: a model file is untrusted input. Without this check a downloaded `.gltf` whose buffer
//! URI is `/etc/passwd` or `../../../../home/you/.ssh/id_rsa` makes the loader read that file
//! (and parse it as geometry, or report what it found in a note). So an absolute path, a `..`
//! that climbs above the model's folder, and a symbolic link that leads out of it are refused
//! by name, unless [`LoadOptions::allow_outside_paths`](super::options::LoadOptions) (the
//! CLI's `--allow-outside-paths`) lets them through.

use std::path::{Component, Path, PathBuf};

/// The flag that lets a path through, as the messages name it.
pub(crate) const ALLOW_FLAG: &str = "--allow-outside-paths";

/// Resolves `name` (a relative path as the file gives it, `/` or `\` separated, already
/// percent-decoded for URIs) against `dir`, which lies in `root` (the model's folder), and
/// checks that the result stays inside `root`. `what` names the reference as the file writes
/// it, for the message (`"URI 'a%20b.bin'"`). The error is a sentence naming it and the flag.
pub(crate) fn resolve(
    root: &Path,
    dir: &Path,
    name: &str,
    what: &str,
    allow_outside: bool,
) -> Result<PathBuf, String> {
    let unified = name.replace('\\', "/");
    let as_path = Path::new(&unified);
    let joined = dir.join(as_path);
    if allow_outside {
        return Ok(joined);
    }
    let refuse = |why: &str| {
        format!(
            "{what} {why}, outside the model's folder: refused (a model may only read \
             files in its own folder and below; {ALLOW_FLAG} allows it)"
        )
    };
    if as_path.has_root() || is_drive_path(&unified) {
        return Err(refuse("is an absolute path"));
    }
    // Lexically: `dir` relative to `root`, then each component of the name.
    let mut depth: Vec<std::ffi::OsString> = match dir.strip_prefix(root) {
        Ok(rel) => rel
            .components()
            .filter_map(|c| match c {
                Component::Normal(n) => Some(n.to_os_string()),
                _ => None,
            })
            .collect(),
        Err(_) => return Err(refuse("is resolved in a folder")),
    };
    for c in as_path.components() {
        match c {
            Component::Normal(n) => depth.push(n.to_os_string()),
            Component::CurDir => {}
            Component::ParentDir => {
                if depth.pop().is_none() {
                    return Err(refuse("climbs above the model's folder with '..'"));
                }
            }
            Component::RootDir | Component::Prefix(_) => return Err(refuse("is an absolute path")),
        }
    }
    // Through symbolic links: where the file really is (a missing file is left for the
    // caller's read to report).
    if let (Ok(real_root), Ok(real)) = (
        super::files::canonicalize(root),
        super::files::canonicalize(&joined),
    ) {
        if !real.starts_with(&real_root) {
            return Err(refuse(&format!(
                "leads through a symbolic link to {}",
                real.display()
            )));
        }
    }
    Ok(joined)
}

/// `C:/…` or `C:…`: a Windows drive path, absolute wherever the file is read.
fn is_drive_path(p: &str) -> bool {
    let b = p.as_bytes();
    b.len() >= 2 && b[0].is_ascii_alphabetic() && b[1] == b':'
}

/// The folder a model file's own relative paths are resolved in: the folder it lies in.
pub(crate) fn model_folder(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_are_refused_by_name() {
        let root = Path::new("/models/car");
        let ok = |n: &str| resolve(root, root, n, &format!("URI '{n}'"), false);
        assert_eq!(ok("a.bin").unwrap(), root.join("a.bin"));
        assert_eq!(ok("sub/../a.bin").unwrap(), root.join("sub/../a.bin"));
        assert_eq!(ok("./t\\x.png").unwrap(), root.join("./t/x.png"));
        for bad in [
            "/etc/passwd",
            "../a.bin",
            "sub/../../a.bin",
            "C:/x.bin",
            "\\x.bin",
        ] {
            let e = ok(bad).unwrap_err();
            assert!(e.contains(bad) && e.contains(ALLOW_FLAG), "{e}");
        }
        assert!(resolve(root, root, "/etc/passwd", "URI", true).is_ok());
        // A texture of an MTL in a subfolder may climb back to the model's folder, not above.
        let sub = root.join("mtl");
        assert!(resolve(root, &sub, "../tex.png", "map_Kd", false).is_ok());
        assert!(resolve(root, &sub, "../../tex.png", "map_Kd", false).is_err());
    }
}
