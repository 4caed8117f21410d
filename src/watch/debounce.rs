//! Turning a stream of file-system events into "render now, because these files changed".
//!
//! One save is rarely one event: an in-place write is a modify and a close, a safe write is a
//! create, several modifies and one or two renames, a delete-and-recreate is a remove then a
//! create, and some editors write in several chunks. Rendering on the first event would read a
//! half-written file and flash an error. So changes are collected until the followed files have
//! been quiet for a while (the debounce), then handed over as one batch.
//!
//! How long "a while" is depends on the last event. After one that leaves a file complete (a
//! write closed, a file renamed into place: how nearly every save ends) only
//! [`Debounce::after_save`] is waited, enough for the rest of a multi-file save or a metadata
//! touch; after any other event (a file truncated, half written, removed) the full
//! [`Debounce::quiet`]. A metadata-only event (vim's `setxattr` after its write, a `chmod`)
//! changes no contents: it never shortens the wait, and after a complete save it waits no longer
//! than the save did. A flat 50 ms would be simpler, but it is half of the 100 ms a change may
//! take to show, and the render of a 130,000-triangle scene needs most of the rest.
//!
//! Events are stamped when notify delivers them, and the quiet period is measured between those
//! stamps, not from when the loop gets round to reading them. So a save made while a render was
//! running is usually already quiet when the render ends, and the next render starts at once,
//! covering every change made meanwhile in one batch (never a queue of renders to work through):
//! everything already queued is read before deciding, even when the first of it is older than the
//! maximum delay.
//! [`Debounce::max_delay`] caps the wait for a file that is written continuously.
//!
//! Rejected: `notify-debouncer-full`. It holds each event for a fixed timeout from *that* event
//! and releases expired events on a timer tick, so the events of one save can be released in two
//! ticks (two renders, the first of a half-written file) unless a quiet-period step like this one
//! is added on top, which then adds its own delay to the debouncer's; and its rename stitching
//! and file-id tracking bring nothing when every path of every event is matched by name.

use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, RecvTimeoutError, TryRecvError};
use std::time::{Duration, Instant};

use notify::event::{EventKind, ModifyKind};

use super::files::WatchedFiles;

/// What the watch loop is told, on one channel, so that it can wait for either.
#[derive(Debug)]
pub enum Signal {
    /// A raw file-system event (or watcher error), stamped when it arrived.
    FileSystem {
        event: notify::Result<notify::Event>,
        at: Instant,
    },
    /// Ctrl-C or a termination request: stop after the current render.
    Stop,
    /// The preview page or an editor left a request in the view inbox (`watch::view`).
    View,
}

/// Why the watch loop wakes up.
#[derive(Debug, PartialEq, Eq)]
pub enum Wake {
    Changes(Changes),
    /// A request waits in the view inbox, and no change to the files is pending.
    View,
}

/// How long to wait before a batch of changes is rendered.
#[derive(Debug, Clone, Copy)]
pub struct Debounce {
    /// Render once the followed files have had no event for this long...
    pub quiet: Duration,
    /// ... or this long, when the last event left a file complete.
    pub after_save: Duration,
    /// ... or once this long has passed since the first change, whatever is still arriving.
    pub max_delay: Duration,
}

/// Changes to render.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Changes {
    /// The followed files that changed, as the loader named them.
    pub files: BTreeSet<PathBuf>,
    /// When the first of them was seen: the start of the change-to-image latency.
    pub first_seen: Instant,
}

/// How an event leaves the file it concerns, which decides how long to wait after it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Settling {
    /// Complete: a write was closed, or a file renamed into place.
    Complete,
    /// Only its metadata changed (permissions, extended attributes, times): the contents are as
    /// the last event left them.
    MetadataOnly,
    /// Possibly half written: truncated, written, created, removed.
    Partial,
}

impl Settling {
    /// How `event` leaves the followed files it concerns.
    fn of(event: &notify::Event, files: &WatchedFiles) -> Self {
        if files.completes_a_save(event) {
            Settling::Complete
        } else if matches!(event.kind, EventKind::Modify(ModifyKind::Metadata(_))) {
            Settling::MetadataOnly
        } else {
            Settling::Partial
        }
    }
}

/// The batch being collected, and when it may be rendered: the debounce's decisions, apart from
/// the channel and the clock (so they can be tested with made-up times).
#[derive(Debug)]
struct Batch {
    changes: Changes,
    /// When the batch may be rendered if nothing else comes (last event + its quiet period).
    settled_at: Instant,
}

impl Batch {
    fn start(changed: BTreeSet<PathBuf>, settling: Settling, at: Instant, timing: Debounce) -> Self {
        let mut batch = Batch {
            changes: Changes {
                files: changed,
                first_seen: at,
            },
            settled_at: at,
        };
        batch.settle(settling, at, timing);
        batch
    }

    fn add(&mut self, changed: BTreeSet<PathBuf>, settling: Settling, at: Instant, timing: Debounce) {
        self.changes.files.extend(changed);
        self.settle(settling, at, timing);
    }

    /// Events arrive in order, so `at` is the latest event's time.
    fn settle(&mut self, settling: Settling, at: Instant, timing: Debounce) {
        self.settled_at = match settling {
            Settling::Complete => at + timing.after_save,
            Settling::Partial => at + timing.quiet,
            // The touch-up that follows a save (vim's `setxattr`, a `chmod`): it changes no
            // contents, so it never shortens the wait for a file still being written, and after a
            // complete one it waits only as long as the save itself would have.
            Settling::MetadataOnly => self.settled_at.max(at + timing.after_save),
        };
    }

    /// The latest the batch is held: a file written without pause still gets rendered.
    fn cut_off(&self, timing: Debounce) -> Instant {
        self.changes.first_seen + timing.max_delay
    }

    /// When the batch is to be rendered if no other event comes.
    fn ready_at(&self, timing: Debounce) -> Instant {
        self.settled_at.min(self.cut_off(timing))
    }
}

/// Waits for the next batch of changes to `files`, or for a request in the view inbox when no
/// change is pending (a pending change's build serves the inbox after it). Returns `None` when
/// asked to stop (the changes still waiting, if any, are dropped: the user is leaving).
///
/// Every event already queued when it is called (saves made during the last render) joins the
/// batch before anything is decided, however old: deciding on the first of them, already past
/// the maximum delay, would render once per queued event.
///
/// Watcher errors (e.g. the OS limit on watches) are reported through `on_error` and do not end
/// the watch.
pub fn wait_for_changes(
    signals: &Receiver<Signal>,
    files: &WatchedFiles,
    timing: Debounce,
    on_error: &mut dyn FnMut(notify::Error),
) -> Option<Wake> {
    // Events stamped before this were queued while the loop was busy (rendering).
    let reading_since = Instant::now();
    let mut pending: Option<Batch> = None;
    loop {
        let signal = match &pending {
            None => signals.recv().ok()?,
            Some(batch) => match signals.try_recv() {
                Ok(signal) => signal,
                Err(TryRecvError::Disconnected) => return None,
                Err(TryRecvError::Empty) => {
                    let deadline = batch.ready_at(timing);
                    let now = Instant::now();
                    if now >= deadline {
                        return pending.map(|batch| Wake::Changes(batch.changes));
                    }
                    match signals.recv_timeout(deadline - now) {
                        Ok(signal) => signal,
                        Err(RecvTimeoutError::Timeout) => {
                            return pending.map(|batch| Wake::Changes(batch.changes));
                        }
                        Err(RecvTimeoutError::Disconnected) => return None,
                    }
                }
            },
        };
        match signal {
            Signal::Stop => return None,
            Signal::View if pending.is_none() => return Some(Wake::View),
            Signal::View => {}
            Signal::FileSystem {
                event: Err(error), ..
            } => on_error(error),
            Signal::FileSystem { event: Ok(event), at } => {
                let changed = files.changed_by(&event);
                if changed.is_empty() {
                    continue;
                }
                let settling = Settling::of(&event, files);
                match &mut pending {
                    Some(batch) => batch.add(changed, settling, at, timing),
                    None => pending = Some(Batch::start(changed, settling, at, timing)),
                }
                // A file written without pause would keep the queue from ever being empty: past
                // the maximum delay, an event that arrived while waiting (not one queued during
                // the render) ends the batch, itself included.
                if let Some(batch) = &pending
                    && at >= reading_since
                    && Instant::now() >= batch.cut_off(timing)
                {
                    return pending.map(|batch| Wake::Changes(batch.changes));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use notify::event::{AccessKind, AccessMode, DataChange, EventKind, ModifyKind};
    use std::path::Path;
    use std::sync::mpsc::{Sender, channel};

    const TIMING: Debounce = Debounce {
        quiet: Duration::from_millis(50),
        after_save: Duration::from_millis(10),
        max_delay: Duration::from_millis(400),
    };

    fn modified(path: &Path, at: Instant) -> Signal {
        let event = notify::Event::new(EventKind::Modify(ModifyKind::Data(DataChange::Any)))
            .add_path(path.to_path_buf());
        Signal::FileSystem { event: Ok(event), at }
    }

    fn setup() -> (
        tempfile::TempDir,
        PathBuf,
        WatchedFiles,
        Sender<Signal>,
        Receiver<Signal>,
    ) {
        let temporary = tempfile::tempdir().unwrap();
        let dir = temporary.path().canonicalize().unwrap();
        let mut files = WatchedFiles::new(&dir.join("out.png"));
        files.follow([dir.join("scene.ron").as_path(), dir.join("mats.ron").as_path()]);
        let (sender, receiver) = channel();
        (temporary, dir, files, sender, receiver)
    }

    fn changes_of(wake: Option<Wake>) -> Changes {
        match wake {
            Some(Wake::Changes(changes)) => changes,
            other => panic!("expected changes, got {other:?}"),
        }
    }

    #[test]
    fn a_view_request_wakes_the_loop_unless_changes_are_pending() {
        let (_temporary, dir, files, sender, receiver) = setup();
        sender.send(Signal::View).unwrap();
        assert_eq!(
            wait_for_changes(&receiver, &files, TIMING, &mut no_errors),
            Some(Wake::View)
        );
        let now = Instant::now();
        sender.send(modified(&dir.join("scene.ron"), now)).unwrap();
        sender.send(Signal::View).unwrap();
        let changes = changes_of(wait_for_changes(&receiver, &files, TIMING, &mut no_errors));
        assert_eq!(changes.files, [dir.join("scene.ron")].into());
    }

    fn no_errors(error: notify::Error) {
        panic!("unexpected watcher error: {error}");
    }

    #[test]
    fn a_burst_already_quiet_is_one_batch_with_every_file() {
        let (_temporary, dir, files, sender, receiver) = setup();
        // As if these arrived during a render that has just ended: long enough ago to be quiet.
        let long_ago = Instant::now() - Duration::from_millis(200);
        sender.send(modified(&dir.join("scene.ron"), long_ago)).unwrap();
        sender.send(modified(&dir.join("notes.txt"), long_ago)).unwrap();
        sender
            .send(modified(
                &dir.join("mats.ron"),
                long_ago + Duration::from_millis(5),
            ))
            .unwrap();
        let started = Instant::now();
        let changes = changes_of(wait_for_changes(&receiver, &files, TIMING, &mut no_errors));
        assert!(started.elapsed() < TIMING.quiet, "already quiet: no extra wait");
        assert_eq!(changes.first_seen, long_ago);
        assert_eq!(
            changes.files,
            [dir.join("mats.ron"), dir.join("scene.ron")].into()
        );
    }

    #[test]
    fn saves_queued_during_a_render_longer_than_the_maximum_delay_are_one_batch() {
        let (_temporary, dir, files, sender, receiver) = setup();
        // Four saves to two files during a render of 1.5 × the maximum delay, all queued when
        // the render ends: the first is already past the maximum delay.
        let render_started = Instant::now() - TIMING.max_delay * 3 / 2;
        for (index, name) in ["scene.ron", "mats.ron", "scene.ron", "mats.ron"]
            .iter()
            .enumerate()
        {
            let at = render_started + TIMING.max_delay * (index as u32 + 1) / 4;
            sender.send(modified(&dir.join(name), at)).unwrap();
            let closed = notify::Event::new(EventKind::Access(AccessKind::Close(AccessMode::Write)))
                .add_path(dir.join(name));
            sender
                .send(Signal::FileSystem {
                    event: Ok(closed),
                    at,
                })
                .unwrap();
        }
        let changes = changes_of(wait_for_changes(&receiver, &files, TIMING, &mut no_errors));
        assert_eq!(
            changes.files,
            [dir.join("mats.ron"), dir.join("scene.ron")].into()
        );
        assert_eq!(changes.first_seen, render_started + TIMING.max_delay / 4);
        // Nothing of those saves is left for a second render.
        assert!(matches!(receiver.try_recv(), Err(TryRecvError::Empty)));
    }

    /// A batch started by `first` at `t0`, then `rest` as (settling, milliseconds after `t0`);
    /// returns when it would be rendered, in milliseconds after `t0`.
    fn ready_after(first: Settling, rest: &[(Settling, u64)]) -> Duration {
        let t0 = Instant::now();
        let scene: BTreeSet<PathBuf> = [PathBuf::from("scene.ron")].into();
        let mut batch = Batch::start(scene.clone(), first, t0, TIMING);
        for &(settling, after) in rest {
            batch.add(scene.clone(), settling, t0 + Duration::from_millis(after), TIMING);
        }
        batch.ready_at(TIMING) - t0
    }

    #[test]
    fn a_metadata_touch_after_a_closed_write_waits_only_as_long_as_a_save() {
        use Settling::*;
        let ms = Duration::from_millis;
        // vim: write, close, then `setxattr` (or a `chmod`) a moment later.
        assert_eq!(
            ready_after(Partial, &[(Complete, 1), (MetadataOnly, 2)]),
            ms(2) + TIMING.after_save
        );
        // A metadata event alone (`chmod`): nothing is half written either.
        assert_eq!(ready_after(MetadataOnly, &[]), TIMING.after_save);
        // The touch came within the short wait already running: it does not matter.
        assert_eq!(
            ready_after(Partial, &[(Complete, 1), (MetadataOnly, 1)]),
            ms(1) + TIMING.after_save
        );
    }

    #[test]
    fn a_metadata_touch_never_shortens_the_wait_for_a_file_being_written() {
        use Settling::*;
        let ms = Duration::from_millis;
        assert_eq!(ready_after(Partial, &[(MetadataOnly, 1)]), TIMING.quiet);
        // A write after the touch starts the full quiet period again.
        assert_eq!(
            ready_after(Partial, &[(MetadataOnly, 1), (Partial, 2)]),
            ms(2) + TIMING.quiet
        );
        // Nothing passes the maximum delay.
        let busy: Vec<(Settling, u64)> = (1..=TIMING.max_delay.as_millis() as u64 / 10)
            .map(|i| (Partial, i * 10))
            .collect();
        assert_eq!(ready_after(Partial, &busy), TIMING.max_delay);
    }

    #[test]
    fn a_recent_change_waits_for_the_quiet_period() {
        let (_temporary, dir, files, sender, receiver) = setup();
        let now = Instant::now();
        sender.send(modified(&dir.join("scene.ron"), now)).unwrap();
        let changes = changes_of(wait_for_changes(&receiver, &files, TIMING, &mut no_errors));
        assert!(now.elapsed() >= TIMING.quiet);
        assert_eq!(changes.files.len(), 1);
    }

    #[test]
    fn a_closed_write_settles_without_the_full_quiet_period() {
        let (_temporary, dir, files, sender, receiver) = setup();
        let scene = dir.join("scene.ron");
        // A quiet period far longer than the test may take: only the short wait can end it.
        let timing = Debounce {
            quiet: Duration::from_secs(600),
            after_save: Duration::from_millis(1),
            max_delay: Duration::from_secs(1200),
        };
        let now = Instant::now();
        sender.send(modified(&scene, now)).unwrap();
        let closed = notify::Event::new(EventKind::Access(AccessKind::Close(AccessMode::Write)))
            .add_path(scene.clone());
        sender
            .send(Signal::FileSystem {
                event: Ok(closed),
                at: now,
            })
            .unwrap();
        let changes = changes_of(wait_for_changes(&receiver, &files, timing, &mut no_errors));
        assert!(now.elapsed() < Duration::from_secs(60));
        assert_eq!(changes.files, [scene].into());
    }

    #[test]
    fn events_that_keep_coming_are_cut_off_at_the_maximum_delay() {
        let (_temporary, dir, files, sender, receiver) = setup();
        let scene = dir.join("scene.ron");
        let writing = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(true));
        let started = Instant::now();
        let writer = {
            let writing = writing.clone();
            // A file written every 5 ms for (at most) 5 s: never quiet.
            std::thread::spawn(move || {
                for _ in 0..1000 {
                    if !writing.load(std::sync::atomic::Ordering::Relaxed) {
                        break;
                    }
                    if sender.send(modified(&scene, Instant::now())).is_err() {
                        break;
                    }
                    std::thread::sleep(Duration::from_millis(5));
                }
            })
        };
        let changes = changes_of(wait_for_changes(&receiver, &files, TIMING, &mut no_errors));
        let waited = started.elapsed();
        writing.store(false, std::sync::atomic::Ordering::Relaxed);
        writer.join().unwrap();
        assert!(waited >= TIMING.max_delay, "returned after {waited:?}");
        assert!(waited < Duration::from_secs(5), "never cut off: {waited:?}");
        assert_eq!(changes.files, [dir.join("scene.ron")].into());
    }

    #[test]
    fn stop_wins_over_pending_changes_and_irrelevant_events_do_not_start_a_batch() {
        let (_temporary, dir, files, sender, receiver) = setup();
        sender
            .send(modified(&dir.join("out.png"), Instant::now()))
            .unwrap();
        sender.send(Signal::Stop).unwrap();
        assert_eq!(wait_for_changes(&receiver, &files, TIMING, &mut no_errors), None);

        sender
            .send(modified(&dir.join("scene.ron"), Instant::now()))
            .unwrap();
        sender.send(Signal::Stop).unwrap();
        assert_eq!(wait_for_changes(&receiver, &files, TIMING, &mut no_errors), None);
    }

    #[test]
    fn watcher_errors_are_reported_and_the_wait_goes_on() {
        let (_temporary, dir, files, sender, receiver) = setup();
        sender
            .send(Signal::FileSystem {
                event: Err(notify::Error::generic("too many watches")),
                at: Instant::now(),
            })
            .unwrap();
        sender
            .send(modified(&dir.join("scene.ron"), Instant::now() - TIMING.quiet))
            .unwrap();
        let mut errors = Vec::new();
        let changes = wait_for_changes(&receiver, &files, TIMING, &mut |e| errors.push(e.to_string()));
        assert!(changes.is_some());
        assert_eq!(errors, ["too many watches"]);
    }
}
