//! A `.zip` of a model's files into a [`MemoryFiles`] set: what a web page is given when a
//! user drops an archive (the `zip` crate reads it; deflate through flate2, as `.ply.gz`).
//!
//! The archive is untrusted input, held to the limits of files on disk: entry names that
//! climb out of the archive's folder are refused by name, every entry is read with at most
//! the bytes left under [`MAX_DECOMPRESSED_BYTES`] (whatever its header claims), and at most
//! [`MAX_ZIP_ENTRIES`] entries are taken.

use std::io::Read;

use super::common::MAX_DECOMPRESSED_BYTES;
use super::files::MemoryFiles;

/// The most entries an archive may have.
pub const MAX_ZIP_ENTRIES: usize = 65_536;

impl MemoryFiles {
    /// Adds the files of the zip archive `bytes` (named `name`, for messages), each under its
    /// path in the archive, in the folder `name` lies in (`models/car.zip`'s `scene.gltf`
    /// becomes `models/scene.gltf`). Folders are skipped. Returns how many files were added.
    /// Errors, naming the archive (and the entry): not a zip archive, an entry that climbs
    /// above the archive's folder, encrypted or unsupported compression, more than
    /// [`MAX_ZIP_ENTRIES`] entries or [`MAX_DECOMPRESSED_BYTES`] in all.
    pub fn insert_zip(&mut self, name: &str, bytes: &[u8]) -> Result<usize, String> {
        let mut archive = zip::ZipArchive::new(std::io::Cursor::new(bytes))
            .map_err(|e| format!("{name}: not a zip archive we can read ({e})"))?;
        if archive.len() > MAX_ZIP_ENTRIES {
            return Err(format!(
                "{name}: {} entries; the limit is {MAX_ZIP_ENTRIES}",
                archive.len()
            ));
        }
        let folder = match name.replace('\\', "/").rsplit_once('/') {
            Some((dir, _)) => format!("{dir}/"),
            None => String::new(),
        };
        let mut left = MAX_DECOMPRESSED_BYTES;
        let mut added = 0;
        for i in 0..archive.len() {
            let mut entry = archive
                .by_index(i)
                .map_err(|e| format!("{name}: entry {i}: {e}"))?;
            if entry.is_dir() {
                continue;
            }
            let path = entry
                .name()
                .map_err(|e| format!("{name}: entry {i}: its name: {e}"))?
                .into_owned();
            let mut data = Vec::new();
            (&mut entry)
                .take(left + 1)
                .read_to_end(&mut data)
                .map_err(|e| format!("{name}: {path}: {e}"))?;
            if data.len() as u64 > left {
                return Err(format!(
                    "{name}: its files hold more than {MAX_DECOMPRESSED_BYTES} bytes (4 GiB) \
                     unpacked"
                ));
            }
            left -= data.len() as u64;
            self.insert(&format!("{folder}{path}"), data)
                .map_err(|_| format!("{name}: entry '{path}' climbs above the archive's folder"))?;
            added += 1;
        }
        Ok(added)
    }
}
