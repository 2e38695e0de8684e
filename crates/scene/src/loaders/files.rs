//! Where the loaders read files: the disk, or a set of files held in memory ([`MemoryFiles`]:
//! what a web page was given by a drop, a file picker or a download, where there is no file
//! system).
//!
//! Every read of the loaders (the model file, a glTF buffer or image URI, an OBJ material
//! library and its textures, a PLY file) goes through this module. While
//! [`load_scene_from_memory`](super::dispatch::load_scene_from_memory) runs, the set it was
//! given answers instead of the disk: a path names a file of the set by its name relative to
//! the set's root, `..` and `.` resolved lexically, and a path that names no file of the set
//! is not found ("not among the files given", with their names), so a model's URIs resolve
//! only among those files. The set is installed for the calling thread for the duration of
//! that call only (the loaders' work runs on it), so every loader keeps its signature and the
//! disk path is unchanged.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::io::{self, Read};
use std::path::{Component, Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;

/// Files held in memory, by their names relative to the set's root (`/`-separated, as a
/// folder dropped on a web page gives them: `car/scene.gltf`, `car/textures/paint.png`).
#[derive(Clone, Debug, Default)]
pub struct MemoryFiles {
    files: BTreeMap<String, Arc<[u8]>>,
}

impl MemoryFiles {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a file under `name` (`\` taken as `/`; `.` and `..` resolved; a leading `/`
    /// ignored). Errors: an empty name, or one that climbs above the root.
    pub fn insert(&mut self, name: &str, bytes: impl Into<Arc<[u8]>>) -> Result<(), String> {
        let key = normalize(Path::new(&name.replace('\\', "/")))
            .filter(|k| !k.is_empty())
            .ok_or_else(|| format!("'{name}' is not a file name inside the set"))?;
        self.files.insert(key, bytes.into());
        Ok(())
    }

    /// The names of the files, sorted.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.files.keys().map(String::as_str)
    }

    /// The number of files.
    pub fn len(&self) -> usize {
        self.files.len()
    }

    /// Whether the set holds no file.
    pub fn is_empty(&self) -> bool {
        self.files.is_empty()
    }

    /// The bytes of the file `name` names, if the set holds it.
    pub fn get(&self, name: &str) -> Option<&[u8]> {
        let key = normalize(Path::new(&name.replace('\\', "/")))?;
        self.files.get(&key).map(|b| &b[..])
    }

    fn lookup(&self, path: &Path) -> io::Result<Arc<[u8]>> {
        normalize(path)
            .and_then(|k| self.files.get(&k).cloned())
            .ok_or_else(|| {
                const SHOWN: usize = 12;
                let mut names: Vec<&str> = self.names().take(SHOWN).collect();
                if self.files.len() > SHOWN {
                    names.push("…");
                }
                io::Error::new(
                    io::ErrorKind::NotFound,
                    format!(
                        "not among the files given ({})",
                        if names.is_empty() {
                            "none".to_string()
                        } else {
                            names.join(", ")
                        }
                    ),
                )
            })
    }
}

/// `path` as a key of a [`MemoryFiles`]: its normal components joined by `/`, `.` dropped and
/// `..` taken back; `None` if it climbs above the root. A root or drive prefix is ignored.
fn normalize(path: &Path) -> Option<String> {
    let mut parts: Vec<String> = Vec::new();
    for c in path.components() {
        match c {
            Component::Normal(n) => parts.push(n.to_string_lossy().into_owned()),
            Component::CurDir | Component::RootDir | Component::Prefix(_) => {}
            Component::ParentDir => {
                parts.pop()?;
            }
        }
    }
    Some(parts.join("/"))
}

thread_local! {
    static MEMORY: RefCell<Option<Rc<MemoryFiles>>> = const { RefCell::new(None) };
}

/// Runs `f` with `files` answering this thread's reads instead of the disk; the previous
/// source is back afterwards, also when `f` panics.
pub(crate) fn with_memory<R>(files: &MemoryFiles, f: impl FnOnce() -> R) -> R {
    struct Restore(Option<Rc<MemoryFiles>>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let previous = self.0.take();
            MEMORY.with(|m| *m.borrow_mut() = previous);
        }
    }
    let previous = MEMORY.with(|m| m.borrow_mut().replace(Rc::new(files.clone())));
    let _restore = Restore(previous);
    f()
}

fn memory() -> Option<Rc<MemoryFiles>> {
    MEMORY.with(|m| m.borrow().clone())
}

/// The size of the file at `path`, in bytes.
pub(crate) fn len(path: &Path) -> io::Result<u64> {
    match memory() {
        Some(m) => m.lookup(path).map(|b| b.len() as u64),
        None => std::fs::metadata(path).map(|m| m.len()),
    }
}

/// Opens the file at `path` for reading.
pub(crate) fn open(path: &Path) -> io::Result<Box<dyn Read>> {
    match memory() {
        Some(m) => Ok(Box::new(io::Cursor::new(m.lookup(path)?))),
        None => Ok(Box::new(std::fs::File::open(path)?)),
    }
}

/// Where `path` really is, for the check that a model's paths stay in its folder: through
/// symbolic links on disk; in memory, where there are none, the path itself (lexically
/// resolved), if the set holds a file or a folder there.
pub(crate) fn canonicalize(path: &Path) -> io::Result<PathBuf> {
    match memory() {
        Some(m) => {
            let key = normalize(path)
                .ok_or_else(|| io::Error::new(io::ErrorKind::NotFound, "above the root"))?;
            let exists = key.is_empty()
                || m.files.contains_key(&key)
                || m.names().any(|n| n.starts_with(&format!("{key}/")));
            if exists {
                Ok(PathBuf::from(format!("/{key}")))
            } else {
                Err(io::Error::new(io::ErrorKind::NotFound, "no such file"))
            }
        }
        None => path.canonicalize(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_normalized_and_missing_files_name_the_set() {
        let mut m = MemoryFiles::new();
        m.insert("car\\scene.gltf", vec![1]).unwrap();
        m.insert("./car/tex/../paint.png", vec![2, 3]).unwrap();
        assert!(m.insert("../x.bin", vec![0]).is_err());
        assert!(m.insert("", vec![0]).is_err());
        assert_eq!(
            m.names().collect::<Vec<_>>(),
            ["car/paint.png", "car/scene.gltf"]
        );
        assert_eq!(m.models(), ["car/scene.gltf"]);
        with_memory(&m, || {
            assert_eq!(len(Path::new("car/./paint.png")).unwrap(), 2);
            let mut b = Vec::new();
            open(Path::new("car/sub/../scene.gltf"))
                .unwrap()
                .read_to_end(&mut b)
                .unwrap();
            assert_eq!(b, [1]);
            let e = open(Path::new("car/other.bin")).err().unwrap();
            assert_eq!(e.kind(), io::ErrorKind::NotFound);
            assert!(
                e.to_string().contains("car/paint.png, car/scene.gltf"),
                "{e}"
            );
            assert!(canonicalize(Path::new("car")).is_ok());
            assert!(canonicalize(Path::new("bike")).is_err());
        });
        // Outside the call the disk answers again.
        assert!(len(Path::new("car/paint.png")).is_err());
    }
}
