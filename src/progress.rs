//! The progress bar of long renders: tiles done, on a terminal only.
//!
//! A render that ends within [`PROGRESS_DELAY`] shows nothing (a bar that flashes for a frame is
//! noise); a longer one gets an indicatif bar on stderr, fed by the renderer's tile counter
//! ([`RenderProgress`]) from a thread of its own, so the renderer never waits for the terminal.
//! Never shown when stderr is not a terminal, with `CI` set, or with `--quiet`: logs and pipes
//! get the one summary line and nothing else.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::render::RenderProgress;

/// How long a render runs before its bar appears.
pub const PROGRESS_DELAY: Duration = Duration::from_millis(500);

/// How often the bar reads the tile counter.
const REFRESH: Duration = Duration::from_millis(50);

/// Whether progress bars may be drawn at all: stderr is a terminal and `CI` is not set.
pub fn progress_allowed() -> bool {
    std::io::stderr().is_terminal() && std::env::var_os("CI").is_none()
}

/// A bar that follows one render from a thread of its own until [`RenderBar::finish`].
pub struct RenderBar {
    done: Arc<AtomicBool>,
    shown: Arc<Mutex<Option<ProgressBar>>>,
    thread: Option<JoinHandle<()>>,
}

impl RenderBar {
    /// Follows `progress` for the render of `label`; draws nothing unless `enabled`.
    pub fn start(label: String, progress: Arc<RenderProgress>, enabled: bool) -> RenderBar {
        let done = Arc::new(AtomicBool::new(false));
        let shown: Arc<Mutex<Option<ProgressBar>>> = Arc::default();
        let thread = enabled.then(|| {
            let (done, shown) = (Arc::clone(&done), Arc::clone(&shown));
            std::thread::spawn(move || follow(&label, &progress, &done, &shown))
        });
        RenderBar { done, shown, thread }
    }

    /// Removes the bar (if it was shown) before anything else is printed.
    pub fn finish(mut self) {
        self.stop();
    }

    /// A handle that clears the bar from another thread (the Ctrl-C handler).
    pub fn clearer(&self) -> BarClearer {
        BarClearer(Arc::clone(&self.shown))
    }

    fn stop(&mut self) {
        self.done.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            // Woken at once: a render that ends must not wait out the refresh interval.
            thread.thread().unpark();
            let _ = thread.join();
        }
    }
}

impl Drop for RenderBar {
    fn drop(&mut self) {
        self.stop();
    }
}

/// Clears a [`RenderBar`]'s line from any thread.
#[derive(Clone)]
pub struct BarClearer(Arc<Mutex<Option<ProgressBar>>>);

impl BarClearer {
    pub fn clear(&self) {
        if let Some(bar) = self.0.lock().unwrap_or_else(|p| p.into_inner()).take() {
            bar.finish_and_clear();
        }
    }
}

fn follow(label: &str, progress: &RenderProgress, done: &AtomicBool, shown: &Mutex<Option<ProgressBar>>) {
    let started = Instant::now();
    while !done.load(Ordering::Relaxed) {
        std::thread::park_timeout(REFRESH);
        if done.load(Ordering::Relaxed) || started.elapsed() < PROGRESS_DELAY {
            continue;
        }
        let mut shown = shown.lock().unwrap_or_else(|p| p.into_inner());
        let bar = shown.get_or_insert_with(|| new_bar(label));
        let (tiles_done, tiles_total) = progress.tiles();
        if tiles_total == 0 {
            bar.set_message(format!("{label}: loading and preparing"));
        } else {
            bar.set_length(tiles_total as u64);
            bar.set_position(tiles_done as u64);
            bar.set_message(label.to_string());
        }
    }
    if let Some(bar) = shown.lock().unwrap_or_else(|p| p.into_inner()).take() {
        bar.finish_and_clear();
    }
}

fn new_bar(label: &str) -> ProgressBar {
    let style = ProgressStyle::with_template("{bar:30.cyan/blue} {pos}/{len} tiles  {elapsed}  {wide_msg}")
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("█▌ ");
    let bar = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr()).with_style(style);
    bar.set_message(label.to_string());
    bar.enable_steady_tick(Duration::from_millis(200));
    bar
}
