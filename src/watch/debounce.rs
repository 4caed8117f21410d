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
//! [`Debounce::quiet`]. A flat 50 ms would be simpler, but it is half of the 100 ms a change may
//! take to show, and the render of a 130,000-triangle scene needs most of the rest.
//!
//! Events are stamped when notify delivers them, and the quiet period is measured between those
//! stamps, not from when the loop gets round to reading them. So a save made while a render was
//! running is usually already quiet when the render ends, and the next render starts at once,
//! covering every change made meanwhile in one batch (never a queue of renders to work through).
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

/// Waits for the next batch of changes to `files`. Returns `None` when asked to stop (the
/// changes still waiting, if any, are dropped: the user is leaving).
///
/// Watcher errors (e.g. the OS limit on watches) are reported through `on_error` and do not end
/// the watch.
pub fn wait_for_changes(
    signals: &Receiver<Signal>,
    files: &WatchedFiles,
    timing: Debounce,
    on_error: &mut dyn FnMut(notify::Error),
) -> Option<Changes> {
    let mut pending: Option<Changes> = None;
    // When the batch may be rendered if nothing else comes (last event + its quiet period).
    let mut settled_at = Instant::now();
    loop {
        let signal = match &pending {
            None => signals.recv().ok()?,
            Some(changes) => {
                let cut_off = changes.first_seen + timing.max_delay;
                if Instant::now() >= cut_off {
                    return pending;
                }
                // Everything already queued (e.g. during a render) belongs to this batch and
                // may extend the quiet period: read it before deciding.
                match signals.try_recv() {
                    Ok(signal) => signal,
                    Err(TryRecvError::Disconnected) => return None,
                    Err(TryRecvError::Empty) => {
                        let deadline = settled_at.min(cut_off);
                        let now = Instant::now();
                        if now >= deadline {
                            return pending;
                        }
                        match signals.recv_timeout(deadline - now) {
                            Ok(signal) => signal,
                            Err(RecvTimeoutError::Timeout) => return pending,
                            Err(RecvTimeoutError::Disconnected) => return None,
                        }
                    }
                }
            }
        };
        match signal {
            Signal::Stop => return None,
            Signal::FileSystem {
                event: Err(error), ..
            } => on_error(error),
            Signal::FileSystem { event: Ok(event), at } => {
                let changed = files.changed_by(&event);
                if changed.is_empty() {
                    continue;
                }
                let quiet = if files.completes_a_save(&event) {
                    timing.after_save
                } else {
                    timing.quiet
                };
                // Events arrive in order, so this is the latest event's settling time.
                settled_at = at + quiet;
                match &mut pending {
                    Some(changes) => changes.files.extend(changed),
                    None => {
                        pending = Some(Changes {
                            files: changed,
                            first_seen: at,
                        });
                    }
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
        let changes = wait_for_changes(&receiver, &files, TIMING, &mut no_errors).unwrap();
        assert!(started.elapsed() < TIMING.quiet, "already quiet: no extra wait");
        assert_eq!(changes.first_seen, long_ago);
        assert_eq!(
            changes.files,
            [dir.join("mats.ron"), dir.join("scene.ron")].into()
        );
    }

    #[test]
    fn a_recent_change_waits_for_the_quiet_period() {
        let (_temporary, dir, files, sender, receiver) = setup();
        let now = Instant::now();
        sender.send(modified(&dir.join("scene.ron"), now)).unwrap();
        let changes = wait_for_changes(&receiver, &files, TIMING, &mut no_errors).unwrap();
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
        let changes = wait_for_changes(&receiver, &files, timing, &mut no_errors).unwrap();
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
        let changes = wait_for_changes(&receiver, &files, TIMING, &mut no_errors).unwrap();
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
