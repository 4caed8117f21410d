//! Where a running `lampshade watch --serve` can be found by the language server of an editor
//! that has the same scene open (`lampshade lsp` sends it the unsaved text, see `watch::view`).
//!
//! Each serving watch writes one small file, `lampshade/watch-<hash>.json` under
//! `$XDG_RUNTIME_DIR` (else the system temporary folder), named by a hash of the scene's
//! canonical path and holding that path, the preview's port and the process id; it removes the
//! file when it ends. The language server reads the file for the document's path. A file left by
//! a watch that was killed names a port nobody answers on (or that answers with another scene,
//! which the server refuses): the buffer is simply not shown.
//!
//! Rejected: a fixed port (two watches would collide, and the preview already falls back to a
//! free port); scanning ports (slow, and it would talk to whatever listens there); an option
//! every editor configuration would have to repeat.

use std::io;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::check::select::fnv1a_64;

/// What the registry file holds.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Entry {
    /// The scene's canonical path.
    pub scene: PathBuf,
    /// The preview's port on 127.0.0.1.
    pub port: u16,
    pub pid: u32,
}

/// The registry file of `scene` and the scene's canonical path (its folder's, for a scene not
/// created yet); `None` when not even the folder exists.
pub fn registry_file(scene: &Path) -> Option<(PathBuf, PathBuf)> {
    let canonical = scene.canonicalize().ok().or_else(|| {
        let folder = match scene.parent() {
            Some(parent) if !parent.as_os_str().is_empty() => parent,
            _ => Path::new("."),
        };
        Some(folder.canonicalize().ok()?.join(scene.file_name()?))
    })?;
    let folder = std::env::var_os("XDG_RUNTIME_DIR")
        .map(PathBuf::from)
        .filter(|dir| dir.is_dir())
        .unwrap_or_else(std::env::temp_dir)
        .join("lampshade");
    let name = format!(
        "watch-{:016x}.json",
        fnv1a_64(canonical.as_os_str().as_encoded_bytes())
    );
    Some((folder.join(name), canonical))
}

/// A watch's registry file, removed when dropped.
pub struct Registration {
    file: PathBuf,
}

impl Drop for Registration {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.file);
    }
}

/// Says that the preview of `scene` is served on `port`.
pub fn register(scene: &Path, port: u16) -> io::Result<Registration> {
    let (file, canonical) =
        registry_file(scene).ok_or_else(|| io::Error::other("the scene has no canonical path"))?;
    let entry = Entry {
        scene: canonical,
        port,
        pid: std::process::id(),
    };
    if let Some(folder) = file.parent() {
        std::fs::create_dir_all(folder)?;
    }
    let json = serde_json::to_vec(&entry).map_err(io::Error::other)?;
    crate::output::write_atomically(&file, |writer| {
        io::Write::write_all(writer, &json).map_err(|source| crate::output::OutputError::Io {
            path: file.clone(),
            source,
        })
    })
    .map_err(io::Error::other)?;
    Ok(Registration { file })
}

/// The port of the watch serving `scene`'s preview, if one registered.
pub fn lookup(scene: &Path) -> Option<u16> {
    let (file, canonical) = registry_file(scene)?;
    let entry: Entry = serde_json::from_slice(&std::fs::read(file).ok()?).ok()?;
    (entry.scene == canonical).then_some(entry.port)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_registration_is_found_by_any_path_to_the_scene_and_removed_when_dropped() {
        let folder = tempfile::tempdir().unwrap();
        let scene = folder.path().join("scene.ron");
        std::fs::write(&scene, "()").unwrap();
        let other = folder.path().join("other.ron");
        std::fs::write(&other, "()").unwrap();
        let registration = register(&scene, 45678).unwrap();
        let roundabout = folder.path().join(".").join("scene.ron");
        assert_eq!(lookup(&roundabout), Some(45678));
        assert_eq!(lookup(&other), None);
        drop(registration);
        assert_eq!(lookup(&scene), None);
    }
}
