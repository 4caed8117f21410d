//! Which files `watch` follows, which folders it asks the operating system to watch for them, and
//! which file-system events concern them.
//!
//! Design:
//! - The followed files are exactly the ones the last build read, whether it succeeded or not
//!   (`files_read` of the loader: the scene, its includes, meshes and what they reference,
//!   including files that were named but do not exist yet). Nothing else in their folders
//!   matters.
//! - A file is followed through a non-recursive watch on its *folder*, never on the file itself.
//!   Editors that save by writing a temporary file and renaming it over the original (vim,
//!   JetBrains "safe write", Sublime) replace the file's inode, and a watch on the old inode goes
//!   silent; a delete-and-recreate does the same; and a missing file cannot be watched at all. A
//!   folder watch sees all of these as events on the file's path.
//! - Events are matched by full path against the followed files, so the rest of the folder is
//!   ignored: unrelated files, and in particular our own output and the temporary file it is
//!   written through (which also gets an explicit rule, in case the output is given a name the
//!   scene reads: without it, each image written would trigger the next render).
//! - Paths are compared with the folder part canonical (symlinks and `..` resolved): notify reports
//!   an event as `<watched folder>/<name>`, and watching the canonical folder makes those paths
//!   comparable with ours whatever way the scene spelled them. When the file itself is a symlink,
//!   its target is followed too, since edits happen there.
//! - A file whose folder does not exist yet is followed through its nearest existing ancestor.
//!   Creating the missing folder is an event on a path leading to the file, which is enough to
//!   trigger a rebuild; after it, [`FolderWatches::sync`] moves the watch down to the new folder.
//! - Only events that can change a file's contents count: creation, removal, modification,
//!   renames, and the end of a write. Opening and reading a file is reported by inotify too, and
//!   the build itself reads every followed file: counting those would make each build trigger
//!   the next.
//!
//! Known limit: a file is only seen changing once its folder is watched; if a build names a file
//! in a folder no earlier build used, an edit to it *during* that build (between the read and the
//! watch) is noticed on its next change, not at once.
//!
//! Rejected: a watch per file (goes silent on rename-on-save, cannot see a file that does not
//! exist yet); a recursive watch of the scene's folder (follows unrelated files, costs a watch per
//! subfolder, and misses includes and meshes outside that folder).

use std::collections::{BTreeMap, BTreeSet};
use std::ffi::OsStr;
use std::path::{Component, Path, PathBuf};

use notify::event::{AccessKind, AccessMode, EventKind, ModifyKind, RenameMode};
use notify::{RecommendedWatcher, RecursiveMode, Watcher};

/// Prefix and suffix of the temporary file `output::write_atomically` writes beside an output
/// before renaming it into place.
const OUTPUT_TEMPORARY_PREFIX: &str = ".lampshade-";
const OUTPUT_TEMPORARY_SUFFIX: &str = ".tmp";

/// A path as the watcher compares it: the folder canonical, the rest lexically normalised.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Location {
    /// Where events about the file are reported: `folder/name` with `folder` canonical.
    key: PathBuf,
    /// The nearest existing ancestor folder of the file, canonical: what to watch.
    folder: PathBuf,
}

/// Where `path` is compared and watched from. `None` only for a path with no file name (`/`,
/// `..`), which the loader never records.
fn locate(path: &Path) -> Option<Location> {
    let absolute = std::path::absolute(path).ok()?;
    let name = absolute.file_name()?.to_os_string();
    let parent = absolute.parent()?;
    if let Ok(folder) = parent.canonicalize() {
        return Some(Location {
            key: folder.join(name),
            folder,
        });
    }
    // The folder does not exist (yet). Its missing components cannot be symlinks, so resolving
    // `..` lexically there is exact; the existing part is canonicalised.
    let normalized = normalize_lexically(&absolute);
    let mut existing = normalized.parent()?;
    loop {
        if let Ok(folder) = existing.canonicalize() {
            let rest = normalized.strip_prefix(existing).ok()?;
            return Some(Location {
                key: folder.join(rest),
                folder,
            });
        }
        existing = existing.parent()?;
    }
}

/// Whether `a` and `b` name the same file, compared the way events are matched.
pub fn same_location(a: &Path, b: &Path) -> bool {
    match (locate(a), locate(b)) {
        (Some(a), Some(b)) => a.key == b.key,
        _ => false,
    }
}

/// `path` with `.` removed and each `..` cancelling the component before it.
fn normalize_lexically(path: &Path) -> PathBuf {
    let mut normalized = PathBuf::new();
    for component in path.components() {
        match component {
            Component::CurDir => {}
            Component::ParentDir => {
                normalized.pop();
            }
            other => normalized.push(other.as_os_str()),
        }
    }
    normalized
}

/// The files a watch follows and the folders it needs watched for them.
#[derive(Debug)]
pub struct WatchedFiles {
    /// Each followed file by the path events report it under, with the path as the loader
    /// named it (for messages).
    files: BTreeMap<PathBuf, PathBuf>,
    /// The folders to watch so that every followed file is seen.
    folders: BTreeSet<PathBuf>,
    /// The output image; events on it (and on its temporary files) are ours, never a change.
    output: Option<Location>,
}

impl WatchedFiles {
    /// No files followed yet; `output` is the image the watch writes.
    pub fn new(output: &Path) -> Self {
        WatchedFiles {
            files: BTreeMap::new(),
            folders: BTreeSet::new(),
            output: locate(output),
        }
    }

    /// Follows exactly `paths` from now on (the files a build read).
    pub fn follow<'p>(&mut self, paths: impl IntoIterator<Item = &'p Path>) {
        self.files.clear();
        self.folders.clear();
        for path in paths {
            let Some(location) = locate(path) else { continue };
            // A symlinked file is edited through its target, whose folder may be elsewhere.
            if let Ok(target) = path.canonicalize()
                && target != location.key
                && let Some(parent) = target.parent()
            {
                self.folders.insert(parent.to_path_buf());
                self.files.insert(target.clone(), path.to_path_buf());
            }
            self.folders.insert(location.folder);
            self.files.insert(location.key, path.to_path_buf());
        }
    }

    /// The followed files, as the loader named them, in a stable order and without repeats.
    pub fn files(&self) -> Vec<&Path> {
        let unique: BTreeSet<&Path> = self.files.values().map(PathBuf::as_path).collect();
        unique.into_iter().collect()
    }

    /// Followed files that do not exist at the moment.
    pub fn missing(&self) -> Vec<&Path> {
        let missing: BTreeSet<&Path> = self
            .files
            .iter()
            .filter(|(key, _)| !key.exists())
            .map(|(_, named)| named.as_path())
            .collect();
        missing.into_iter().collect()
    }

    /// The folders that must be watched.
    pub fn folders(&self) -> &BTreeSet<PathBuf> {
        &self.folders
    }

    /// What `event` may have changed, as the user would name it: followed files as the loader
    /// named them, or a folder on the way to one (`meshes/`, created or removed: the file itself
    /// may still not exist, so it is not named as changed).
    pub fn changed_by(&self, event: &notify::Event) -> BTreeSet<PathBuf> {
        if event.need_rescan() {
            // The OS dropped events: anything may have changed.
            return self.files.values().cloned().collect();
        }
        if !changes_contents(&event.kind) {
            return BTreeSet::new();
        }
        let mut changed = BTreeSet::new();
        for path in &event.paths {
            if self.is_our_output(path) {
                continue;
            }
            for (key, named) in &self.files {
                if key == path {
                    changed.insert(named.clone());
                } else if key.starts_with(path) {
                    // A folder on the way to the file (created, removed or renamed: the file
                    // appears or disappears with it).
                    let below = key.components().count() - path.components().count();
                    changed.insert(folder_named(named, below).unwrap_or_else(|| with_separator(path)));
                }
            }
        }
        changed
    }

    /// Whether `event` leaves a followed file complete: a write to it was closed, or a file was
    /// renamed into its place. Most saves end with one of these; what may follow (a metadata
    /// touch, the next file of a multi-file save) comes within milliseconds.
    pub fn completes_a_save(&self, event: &notify::Event) -> bool {
        let completed = match event.kind {
            EventKind::Access(AccessKind::Close(AccessMode::Write))
            | EventKind::Modify(ModifyKind::Name(RenameMode::To)) => event.paths.first(),
            // `[from, to]`: only the destination is complete (renaming a followed file *away*,
            // as vim does with its backup, is the start of a save, not its end).
            EventKind::Modify(ModifyKind::Name(RenameMode::Both)) => event.paths.get(1),
            _ => None,
        };
        completed.is_some_and(|path| !self.is_our_output(path) && self.files.contains_key(path))
    }

    fn is_our_output(&self, path: &Path) -> bool {
        let Some(output) = &self.output else { return false };
        if path == output.key {
            return true;
        }
        let is_temporary = path.file_name().and_then(OsStr::to_str).is_some_and(|name| {
            name.starts_with(OUTPUT_TEMPORARY_PREFIX) && name.ends_with(OUTPUT_TEMPORARY_SUFFIX)
        });
        is_temporary && output.key.parent() == path.parent()
    }
}

/// The folder `levels` above the file `named`, spelled as `named` spells it, with a trailing
/// separator to say it is a folder (`meshes/` for `meshes/low/../tri.obj` and 1); `None` when
/// `named` does not reach that high (a symlink's target, the scene's own folder).
fn folder_named(named: &Path, levels: usize) -> Option<PathBuf> {
    let mut folder = PathBuf::new();
    for component in named.components() {
        match component {
            Component::CurDir => {}
            Component::ParentDir if matches!(folder.components().next_back(), Some(Component::Normal(_))) => {
                folder.pop();
            }
            other => folder.push(other.as_os_str()),
        }
    }
    for _ in 0..levels {
        if !matches!(folder.components().next_back(), Some(Component::Normal(_))) {
            return None;
        }
        folder.pop();
    }
    let reaches_a_folder = matches!(folder.components().next_back(), Some(Component::Normal(_)));
    reaches_a_folder.then(|| with_separator(&folder))
}

/// `folder/`: a path shown as a folder.
fn with_separator(folder: &Path) -> PathBuf {
    folder.join("")
}

/// Whether an event of this kind can mean that a file's contents changed.
fn changes_contents(kind: &EventKind) -> bool {
    match kind {
        EventKind::Create(_) | EventKind::Modify(_) | EventKind::Remove(_) | EventKind::Any => true,
        EventKind::Access(AccessKind::Close(AccessMode::Write)) => true,
        // Opening and reading (the build itself does both), and notify's meta events.
        EventKind::Access(_) | EventKind::Other => false,
    }
}

/// The operating system's watches: one non-recursive watch per folder in use.
pub struct FolderWatches {
    watcher: RecommendedWatcher,
    /// Each watched folder with the identity it had when its watch was placed.
    watched: BTreeMap<PathBuf, FolderIdentity>,
}

/// Which folder a path named when it was watched: a folder deleted and recreated, or moved away
/// and replaced, is another folder at the same path, and the old watch does not see it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct FolderIdentity {
    device: u64,
    inode: u64,
}

impl FolderIdentity {
    fn of(folder: &Path) -> Option<Self> {
        let metadata = std::fs::metadata(folder).ok()?;
        if !metadata.is_dir() {
            return None;
        }
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            Some(FolderIdentity {
                device: metadata.dev(),
                inode: metadata.ino(),
            })
        }
        #[cfg(not(unix))]
        {
            // Without inode numbers, existence is all that can be checked.
            let _ = metadata;
            Some(FolderIdentity { device: 0, inode: 0 })
        }
    }
}

impl FolderWatches {
    /// Starts the OS watcher; `on_event` receives every raw event, on notify's thread.
    pub fn new(on_event: impl notify::EventHandler) -> notify::Result<Self> {
        Ok(FolderWatches {
            watcher: notify::recommended_watcher(on_event)?,
            watched: BTreeMap::new(),
        })
    }

    /// Watches exactly `folders` (re-placing watches on folders replaced since they were
    /// watched). Returns a message for each folder that could not be watched.
    pub fn sync(&mut self, folders: &BTreeSet<PathBuf>) -> Vec<String> {
        let stale: Vec<PathBuf> = self
            .watched
            .iter()
            .filter(|(folder, identity)| {
                !folders.contains(*folder) || FolderIdentity::of(folder) != Some(**identity)
            })
            .map(|(folder, _)| folder.clone())
            .collect();
        for folder in stale {
            // A folder that was deleted has already lost its watch: the error says so, harmlessly.
            let _ = self.watcher.unwatch(&folder);
            self.watched.remove(&folder);
        }
        let mut problems = Vec::new();
        for folder in folders {
            if self.watched.contains_key(folder) {
                continue;
            }
            if let Err(problem) = self.watch_nearest(folder) {
                problems.push(problem);
            }
        }
        problems
    }

    /// Watches `folder`, or if it vanished since it was located, its nearest ancestor that
    /// still exists (the file then shows up again like any missing file).
    fn watch_nearest(&mut self, folder: &Path) -> Result<(), String> {
        let mut candidate = Some(folder);
        while let Some(folder) = candidate {
            if self.watched.contains_key(folder) {
                return Ok(());
            }
            if let Some(identity) = FolderIdentity::of(folder) {
                match self.watcher.watch(folder, RecursiveMode::NonRecursive) {
                    Ok(()) => {
                        self.watched.insert(folder.to_path_buf(), identity);
                        return Ok(());
                    }
                    Err(error) if matches!(error.kind, notify::ErrorKind::PathNotFound) => {}
                    Err(error) => return Err(format!("cannot watch `{}`: {error}", folder.display())),
                }
            }
            candidate = folder.parent();
        }
        Err(format!(
            "cannot watch `{}`: no part of it exists",
            folder.display()
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use notify::event::{CreateKind, DataChange, RemoveKind};

    fn event(kind: EventKind, paths: &[&Path]) -> notify::Event {
        let mut event = notify::Event::new(kind);
        for path in paths {
            event = event.add_path(path.to_path_buf());
        }
        event
    }

    fn modified() -> EventKind {
        EventKind::Modify(ModifyKind::Data(DataChange::Any))
    }

    /// A temporary folder, canonical (as notify would report paths under it).
    fn folder() -> (tempfile::TempDir, PathBuf) {
        let temporary = tempfile::tempdir().unwrap();
        let canonical = temporary.path().canonicalize().unwrap();
        (temporary, canonical)
    }

    #[test]
    fn events_on_followed_files_count_and_others_do_not() {
        let (_temporary, dir) = folder();
        std::fs::write(dir.join("scene.ron"), "()").unwrap();
        let mut files = WatchedFiles::new(&dir.join("scene.png"));
        files.follow([dir.join("scene.ron").as_path(), dir.join("mats.ron").as_path()]);
        assert_eq!(files.folders().iter().collect::<Vec<_>>(), [&dir]);
        assert_eq!(files.missing(), [dir.join("mats.ron")]);

        let scene = dir.join("scene.ron");
        assert_eq!(
            files.changed_by(&event(modified(), &[&scene])),
            [scene.clone()].into()
        );
        let created = event(EventKind::Create(CreateKind::File), &[&dir.join("mats.ron")]);
        assert_eq!(files.changed_by(&created), [dir.join("mats.ron")].into());
        let unrelated = event(modified(), &[&dir.join("notes.txt")]);
        assert!(files.changed_by(&unrelated).is_empty());
    }

    #[test]
    fn reading_a_file_is_not_a_change_but_finishing_a_write_is() {
        let (_temporary, dir) = folder();
        let scene = dir.join("scene.ron");
        let mut files = WatchedFiles::new(&dir.join("scene.png"));
        files.follow([scene.as_path()]);
        let opened = event(EventKind::Access(AccessKind::Open(AccessMode::Any)), &[&scene]);
        let read = event(EventKind::Access(AccessKind::Close(AccessMode::Read)), &[&scene]);
        let written = event(EventKind::Access(AccessKind::Close(AccessMode::Write)), &[&scene]);
        assert!(files.changed_by(&opened).is_empty());
        assert!(files.changed_by(&read).is_empty());
        assert_eq!(files.changed_by(&written).len(), 1);
    }

    #[test]
    fn a_rename_over_a_followed_file_counts_by_either_path() {
        let (_temporary, dir) = folder();
        let scene = dir.join("scene.ron");
        let mut files = WatchedFiles::new(&dir.join("scene.png"));
        files.follow([scene.as_path()]);
        let swap = dir.join("scene.ron.swp");
        let both = event(
            EventKind::Modify(ModifyKind::Name(RenameMode::Both)),
            &[&swap, &scene],
        );
        assert_eq!(files.changed_by(&both), [scene.clone()].into());
        let away = event(EventKind::Modify(ModifyKind::Name(RenameMode::From)), &[&scene]);
        assert_eq!(files.changed_by(&away), [scene.clone()].into());
        let removed = event(EventKind::Remove(RemoveKind::File), &[&scene]);
        assert_eq!(files.changed_by(&removed), [scene].into());
    }

    #[test]
    fn closing_a_write_or_renaming_into_place_completes_a_save_and_nothing_else_does() {
        let (_temporary, dir) = folder();
        let scene = dir.join("scene.ron");
        let backup = dir.join("scene.ron~");
        let mut files = WatchedFiles::new(&dir.join("scene.png"));
        files.follow([scene.as_path()]);
        let closed = event(EventKind::Access(AccessKind::Close(AccessMode::Write)), &[&scene]);
        let renamed_in = event(EventKind::Modify(ModifyKind::Name(RenameMode::To)), &[&scene]);
        let swapped_in = event(
            EventKind::Modify(ModifyKind::Name(RenameMode::Both)),
            &[&backup, &scene],
        );
        assert!(files.completes_a_save(&closed));
        assert!(files.completes_a_save(&renamed_in));
        assert!(files.completes_a_save(&swapped_in));

        let renamed_away = event(
            EventKind::Modify(ModifyKind::Name(RenameMode::Both)),
            &[&scene, &backup],
        );
        let created = event(EventKind::Create(CreateKind::File), &[&scene]);
        let other_closed = event(
            EventKind::Access(AccessKind::Close(AccessMode::Write)),
            &[&backup],
        );
        assert!(!files.completes_a_save(&renamed_away));
        assert!(!files.completes_a_save(&event(modified(), &[&scene])));
        assert!(!files.completes_a_save(&created));
        assert!(!files.completes_a_save(&other_closed));
    }

    #[test]
    fn our_own_output_never_counts_even_when_a_scene_reads_it() {
        let (_temporary, dir) = folder();
        let output = dir.join("out.png");
        let mut files = WatchedFiles::new(&output);
        files.follow([dir.join("scene.ron").as_path(), output.as_path()]);
        let temporary = dir.join(".lampshade-Ab12Cd.tmp");
        let written = event(EventKind::Create(CreateKind::File), &[&temporary]);
        assert!(files.changed_by(&written).is_empty());
        let renamed = event(
            EventKind::Modify(ModifyKind::Name(RenameMode::Both)),
            &[&temporary, &output],
        );
        assert!(files.changed_by(&renamed).is_empty());
    }

    #[test]
    fn a_file_in_a_missing_folder_is_watched_from_the_nearest_existing_one() {
        let (_temporary, dir) = folder();
        let mut files = WatchedFiles::new(&dir.join("out.png"));
        let wanted = dir.join("meshes/low/../tri.obj");
        files.follow([wanted.as_path()]);
        assert_eq!(files.folders().iter().collect::<Vec<_>>(), [&dir]);
        // Creating `meshes/` is on the way to the file.
        // It is the folder that changed, named as the scene names it; the file is still missing.
        let created = event(EventKind::Create(CreateKind::Folder), &[&dir.join("meshes")]);
        assert_eq!(files.changed_by(&created), [dir.join("meshes/")].into());
        let elsewhere = event(EventKind::Create(CreateKind::Folder), &[&dir.join("textures")]);
        assert!(files.changed_by(&elsewhere).is_empty());

        // Once the folder exists, it is the one watched, and the file is matched inside it.
        std::fs::create_dir(dir.join("meshes")).unwrap();
        files.follow([wanted.as_path()]);
        assert_eq!(files.folders().iter().collect::<Vec<_>>(), [&dir.join("meshes")]);
        let written = event(modified(), &[&dir.join("meshes/tri.obj")]);
        assert_eq!(files.changed_by(&written), [wanted].into());
    }

    #[test]
    fn a_folder_on_the_way_to_a_file_is_named_as_the_scene_spells_it() {
        assert_eq!(
            folder_named(Path::new("meshes/tri.obj"), 1),
            Some("meshes/".into())
        );
        assert_eq!(folder_named(Path::new("a/b/../c/d.obj"), 2), Some("a/".into()));
        assert_eq!(folder_named(Path::new("./a/b/d.obj"), 1), Some("a/b/".into()));
        assert_eq!(folder_named(Path::new("../x/d.obj"), 1), Some("../x/".into()));
        // Above what the name spells: the caller falls back to the event's own path.
        assert_eq!(folder_named(Path::new("tri.obj"), 1), None);
        assert_eq!(folder_named(Path::new("../tri.obj"), 1), None);
        assert_eq!(folder_named(Path::new("/tri.obj"), 1), None);

        // The folder holding the scene itself removed: named by its path.
        let (_temporary, dir) = folder();
        let mut files = WatchedFiles::new(&dir.join("out.png"));
        files.follow([Path::new("scene.ron")]);
        let here = std::env::current_dir().unwrap().canonicalize().unwrap();
        let removed = event(EventKind::Remove(RemoveKind::Folder), &[&here]);
        assert_eq!(files.changed_by(&removed), [here.join("")].into());
    }

    #[test]
    fn relative_and_dotted_spellings_meet_the_canonical_event_path() {
        let (_temporary, dir) = folder();
        std::fs::create_dir(dir.join("sub")).unwrap();
        let mut files = WatchedFiles::new(&dir.join("out.png"));
        let dotted = dir.join("sub/./../sub/mats.ron");
        files.follow([dotted.as_path()]);
        assert_eq!(files.folders().iter().collect::<Vec<_>>(), [&dir.join("sub")]);
        let written = event(modified(), &[&dir.join("sub/mats.ron")]);
        assert_eq!(files.changed_by(&written), [dotted].into());
    }

    #[cfg(unix)]
    #[test]
    fn a_symlinked_file_is_followed_at_its_target_too() {
        let (_temporary, dir) = folder();
        std::fs::create_dir(dir.join("real")).unwrap();
        std::fs::write(dir.join("real/scene.ron"), "()").unwrap();
        std::os::unix::fs::symlink(dir.join("real/scene.ron"), dir.join("scene.ron")).unwrap();
        let mut files = WatchedFiles::new(&dir.join("out.png"));
        let link = dir.join("scene.ron");
        files.follow([link.as_path()]);
        assert!(files.folders().contains(&dir.join("real")));
        let edited = event(modified(), &[&dir.join("real/scene.ron")]);
        assert_eq!(files.changed_by(&edited), [link].into());
    }

    #[test]
    fn a_rescan_request_changes_everything() {
        let (_temporary, dir) = folder();
        let mut files = WatchedFiles::new(&dir.join("out.png"));
        files.follow([dir.join("a.ron").as_path(), dir.join("b.obj").as_path()]);
        let rescan = notify::Event::new(EventKind::Other).set_flag(notify::event::Flag::Rescan);
        assert_eq!(files.changed_by(&rescan).len(), 2);
    }
}
