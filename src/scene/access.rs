//! Every file a scene makes lampshade read goes through [`FileAccess::read`]: the scene
//! itself, included material libraries, OBJ and glTF meshes, MTL libraries, textures, and glTF
//! buffers and images.
//!
//! It does two things the plain `std::fs::read` did not:
//!
//! * **Only regular files.** A path naming a directory, a FIFO or a device (`/dev/zero`,
//!   `/dev/stdin`) is refused before it is opened: reading one would fail late, block forever,
//!   or never end. Files larger than [`MAX_FILE_BYTES`] are refused before they are read.
//! * **The sandbox** (`--sandbox DIR`). With one, a path is read only when it resolves, after
//!   following every symbolic link and `..`, to a place inside `DIR` (itself resolved the
//!   same way). A path that does not exist is judged by where it would be: its deepest
//!   existing ancestor resolved, the rest appended with `..` applied, so "outside" is
//!   reported the same whether or not the file exists (no probing for files outside).
//!
//! What is not guarded: a symbolic link inside the sandbox swapped for one pointing out
//! between the check and the read (the check and the open are two system calls). CI systems
//! rendering untrusted checkouts write the checkout before lampshade runs, so nothing swaps
//! links during the run; a hostile process running beside lampshade is out of scope.
//! Outputs are not read and are not subject to the sandbox: their paths come from the
//! command line only.

use std::fmt;
use std::io::Read;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Larger input files are refused unread: no scene, mesh or texture this renderer can draw
/// within its memory limits comes near it, and it stops `/proc`-like endless files.
pub const MAX_FILE_BYTES: u64 = 4 << 30;

/// How files named by a scene may be read. The default reads anything the process can.
#[derive(Debug, Clone, Default)]
pub struct FileAccess {
    /// The sandbox folder, resolved (absolute, no symlinks); `None` without `--sandbox`.
    sandbox: Option<Arc<PathBuf>>,
    /// Where every path asked for is noted, in a copy made by [`FileAccess::recording`].
    attempts: Option<AttemptedReads>,
}

/// Two accesses are equal when they allow the same reads; recording changes nothing read.
impl PartialEq for FileAccess {
    fn eq(&self, other: &Self) -> bool {
        self.sandbox == other.sandbox
    }
}

impl Eq for FileAccess {}

/// The paths a recording [`FileAccess`] was asked to read or inspect, in order, without repeats:
/// found or not, allowed or not.
#[derive(Debug, Clone, Default)]
pub struct AttemptedReads(Arc<Mutex<Vec<PathBuf>>>);

impl AttemptedReads {
    fn note(&self, path: &Path) {
        // A panic while holding the lock cannot leave the list half-updated (one push).
        let mut paths = self.0.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if !paths.iter().any(|p| p == path) {
            paths.push(path.to_path_buf());
        }
    }

    /// The paths noted so far.
    pub fn paths(&self) -> Vec<PathBuf> {
        self.0
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .clone()
    }
}

/// Why a file was not read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ReadError {
    /// Refused by the sandbox: where the path resolves to.
    OutsideSandbox {
        resolved: PathBuf,
        sandbox: PathBuf,
    },
    NotFound,
    IsDirectory,
    /// A device, FIFO or socket.
    NotRegularFile,
    TooLarge {
        bytes: u64,
    },
    /// Any other I/O error, as the operating system words it.
    Io(String),
}

impl ReadError {
    /// Whether the sandbox refused the read (always an error, even where a missing file is
    /// only a warning, such as an MTL library or a texture).
    pub fn is_sandbox(&self) -> bool {
        matches!(self, ReadError::OutsideSandbox { .. })
    }
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReadError::OutsideSandbox { resolved, sandbox } => write!(
                f,
                "outside the sandbox {}: it resolves to {}",
                sandbox.display(),
                resolved.display()
            ),
            ReadError::NotFound => f.write_str("no such file"),
            ReadError::IsDirectory => f.write_str("is a directory, not a file"),
            ReadError::NotRegularFile => f.write_str("is not a regular file (a device, FIFO or socket)"),
            ReadError::TooLarge { bytes } => write!(
                f,
                "is {bytes} bytes, more than the {MAX_FILE_BYTES} bytes an input file may have"
            ),
            ReadError::Io(text) => f.write_str(text),
        }
    }
}

impl FileAccess {
    /// Reads any file the process can read.
    pub fn unrestricted() -> Self {
        FileAccess::default()
    }

    /// This access, noting every path it is asked for in the returned list: for a reader whose
    /// failure must still say which files it tried (a mesh whose `.bin` is missing: a watcher
    /// follows it to notice when it comes back).
    pub fn recording(&self) -> (FileAccess, AttemptedReads) {
        let attempts = AttemptedReads::default();
        let access = FileAccess {
            sandbox: self.sandbox.clone(),
            attempts: Some(attempts.clone()),
        };
        (access, attempts)
    }

    /// Reads only files inside `folder` (after resolving symlinks and `..`).
    pub fn sandboxed(folder: &Path) -> Result<Self, String> {
        let resolved = std::fs::canonicalize(folder)
            .map_err(|error| format!("--sandbox {}: {}", folder.display(), io_text(&error)))?;
        if !resolved.is_dir() {
            return Err(format!("--sandbox {}: not a folder", folder.display()));
        }
        Ok(FileAccess {
            sandbox: Some(Arc::new(resolved)),
            attempts: None,
        })
    }

    /// The sandbox folder, resolved, if there is one.
    pub fn sandbox(&self) -> Option<&Path> {
        self.sandbox.as_deref().map(PathBuf::as_path)
    }

    /// `Ok` when the sandbox (if any) allows reading `path`.
    pub fn check(&self, path: &Path) -> Result<(), ReadError> {
        let Some(sandbox) = self.sandbox() else {
            return Ok(());
        };
        let resolved = resolve(path);
        if resolved.starts_with(sandbox) {
            Ok(())
        } else {
            Err(ReadError::OutsideSandbox {
                resolved,
                sandbox: sandbox.to_path_buf(),
            })
        }
    }

    /// Whether `path` is a regular file that may be read (for "does the mesh exist" checks).
    pub fn metadata(&self, path: &Path) -> Result<std::fs::Metadata, ReadError> {
        if let Some(attempts) = &self.attempts {
            attempts.note(path);
        }
        self.check(path)?;
        let metadata = std::fs::metadata(path).map_err(|error| io_error(&error))?;
        if metadata.is_dir() {
            return Err(ReadError::IsDirectory);
        }
        if !metadata.is_file() {
            return Err(ReadError::NotRegularFile);
        }
        Ok(metadata)
    }

    /// Reads the whole regular file at `path`, if the sandbox allows it.
    pub fn read(&self, path: &Path) -> Result<Vec<u8>, ReadError> {
        let metadata = self.metadata(path)?;
        if metadata.len() > MAX_FILE_BYTES {
            return Err(ReadError::TooLarge {
                bytes: metadata.len(),
            });
        }
        let file = std::fs::File::open(path).map_err(|error| io_error(&error))?;
        let mut bytes = Vec::with_capacity(metadata.len() as usize);
        // `take`: a file that grows while it is read still stops at the limit.
        file.take(MAX_FILE_BYTES + 1)
            .read_to_end(&mut bytes)
            .map_err(|error| io_error(&error))?;
        if bytes.len() as u64 > MAX_FILE_BYTES {
            return Err(ReadError::TooLarge {
                bytes: bytes.len() as u64,
            });
        }
        Ok(bytes)
    }
}

fn io_error(error: &std::io::Error) -> ReadError {
    match error.kind() {
        std::io::ErrorKind::NotFound => ReadError::NotFound,
        std::io::ErrorKind::IsADirectory => ReadError::IsDirectory,
        _ => ReadError::Io(io_text(error)),
    }
}

/// An I/O error as a user reads it, without Rust's "(os error N)" suffix.
fn io_text(error: &std::io::Error) -> String {
    if error.kind() == std::io::ErrorKind::PermissionDenied {
        return "permission denied".into();
    }
    let text = error.to_string();
    match text.find(" (os error") {
        Some(end) => text[..end].to_string(),
        None => text,
    }
}

/// Where `path` leads: resolved by the file system as far as it exists, then lexically.
fn resolve(path: &Path) -> PathBuf {
    if let Ok(resolved) = std::fs::canonicalize(path) {
        return resolved;
    }
    let absolute = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir().unwrap_or_default().join(path)
    };
    // The deepest ancestor that exists, resolved; the remaining components applied lexically
    // (a `..` after a missing folder removes that folder, as the kernel would once it exists).
    let components: Vec<Component> = absolute.components().collect();
    for split in (0..components.len()).rev() {
        let ancestor: PathBuf = components[..split].iter().collect();
        if let Ok(mut resolved) = std::fs::canonicalize(&ancestor) {
            for component in &components[split..] {
                match component {
                    Component::ParentDir => {
                        resolved.pop();
                    }
                    Component::CurDir => {}
                    other => resolved.push(other),
                }
            }
            return resolved;
        }
    }
    absolute
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sandbox_with_outside_file() -> (tempfile::TempDir, PathBuf, FileAccess) {
        let root = tempfile::tempdir().unwrap();
        let inside = root.path().join("inside");
        std::fs::create_dir(&inside).unwrap();
        std::fs::write(root.path().join("secret.txt"), "secret").unwrap();
        std::fs::write(inside.join("ok.txt"), "ok").unwrap();
        let access = FileAccess::sandboxed(&inside).unwrap();
        (root, inside, access)
    }

    #[test]
    fn a_recording_access_notes_every_path_asked_for_found_or_not() {
        let folder = tempfile::tempdir().unwrap();
        let present = folder.path().join("mesh.gltf");
        std::fs::write(&present, "{}").unwrap();
        let missing = folder.path().join("mesh.bin");
        let plain = FileAccess::unrestricted();
        let (recording, attempts) = plain.recording();
        assert_eq!(recording, plain, "recording changes nothing read");
        recording.read(&present).unwrap();
        assert_eq!(recording.read(&missing), Err(ReadError::NotFound));
        recording.clone().metadata(&present).unwrap();
        assert_eq!(attempts.paths(), [present.clone(), missing]);
        // Only the recording copy notes anything.
        plain.read(&present).unwrap();
        assert_eq!(attempts.paths().len(), 2);

        let (sandboxed, refused) = FileAccess::sandboxed(folder.path()).unwrap().recording();
        assert!(sandboxed.read(Path::new("/etc/hostname")).is_err());
        assert_eq!(refused.paths(), [PathBuf::from("/etc/hostname")]);
    }

    #[test]
    fn inside_is_read_and_every_way_out_is_refused() {
        let (root, inside, access) = sandbox_with_outside_file();
        assert_eq!(access.read(&inside.join("ok.txt")).unwrap(), b"ok");
        assert_eq!(
            access.read(&inside.join("./sub/../ok.txt")),
            Err(ReadError::NotFound)
        );
        for way_out in [
            inside.join("../secret.txt"),
            root.path().join("secret.txt"),
            inside.join("missing/../../secret.txt"),
            inside.join("../missing.txt"),
            PathBuf::from("/etc/passwd"),
        ] {
            let error = access.read(&way_out).unwrap_err();
            assert!(error.is_sandbox(), "{}: {error}", way_out.display());
        }
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(root.path().join("secret.txt"), inside.join("link.txt")).unwrap();
            std::os::unix::fs::symlink(root.path(), inside.join("up")).unwrap();
            assert!(access.read(&inside.join("link.txt")).unwrap_err().is_sandbox());
            assert!(
                access
                    .read(&inside.join("up/secret.txt"))
                    .unwrap_err()
                    .is_sandbox()
            );
            assert!(
                access
                    .read(&inside.join("up/missing.txt"))
                    .unwrap_err()
                    .is_sandbox()
            );
        }
    }

    #[test]
    fn directories_and_devices_are_not_read() {
        let access = FileAccess::unrestricted();
        let folder = tempfile::tempdir().unwrap();
        assert_eq!(access.read(folder.path()), Err(ReadError::IsDirectory));
        #[cfg(unix)]
        assert_eq!(
            access.read(Path::new("/dev/zero")),
            Err(ReadError::NotRegularFile)
        );
        assert_eq!(access.read(&folder.path().join("nope")), Err(ReadError::NotFound));
    }
}
