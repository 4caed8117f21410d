//! What `check` prints while it runs.
//!
//! On an interactive terminal (stderr is a terminal and `CI` is not set) a progress bar on
//! stderr counts finished scenes and names the last one; lines printed meanwhile appear above
//! it. Otherwise (CI logs, pipes) there is no bar and every scene gets a plain line. Either
//! way, lines come in suite order (the runner hands results over in that order), a failure or
//! error always gets a line, and diagnostics go to stderr in full.
//!
//! Lines, on stdout (`-q` keeps all but `ok`):
//! ```text
//! ok      scenes/minimal.ron
//! FAILED  scenes/matlab-shiny.ron: 1.234% of pixels (3,790 of 307,200) differ by more than 2 levels ...
//! ERROR   scenes/broken.ron: the scene could not be rendered (1 error)
//! BLESSED scenes/new.ron → scenes/refs/new.png: new reference
//! ```

use std::io::IsTerminal;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::check::runner::{RunObserver, SceneError, SceneResult, SceneStatus};
use crate::check::suite::SuiteScene;
use crate::diag::render_diagnostics;

/// Prints progress and per-scene lines.
pub struct Console {
    bar: Option<ProgressBar>,
    /// Print `ok` lines for passing scenes (plain mode, not `--quiet`).
    print_passes: bool,
    color: bool,
}

/// Whether to draw a progress bar: a person is watching stderr, and it is not a CI log that
/// merely looks like a terminal.
pub fn interactive() -> bool {
    std::io::stderr().is_terminal() && std::env::var_os("CI").is_none()
}

impl Console {
    pub fn new(scene_count: usize, quiet: bool) -> Self {
        let bar = interactive().then(|| {
            let style =
                ProgressStyle::with_template("{bar:30.cyan/blue} {pos}/{len} scenes  {elapsed}  {wide_msg}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("█▌ ");
            let bar = ProgressBar::with_draw_target(Some(scene_count as u64), ProgressDrawTarget::stderr())
                .with_style(style);
            bar.enable_steady_tick(Duration::from_millis(200));
            bar
        });
        Console {
            print_passes: bar.is_none() && !quiet,
            bar,
            color: crate::cli::use_color(),
        }
    }

    /// Prints a line on stdout, above the bar when there is one.
    pub fn line(&self, text: &str) {
        match &self.bar {
            Some(bar) => bar.suspend(|| outln!("{text}")),
            None => outln!("{text}"),
        }
    }

    /// Prints text (diagnostics) on stderr, above the bar when there is one.
    fn error_text(&self, text: &str) {
        match &self.bar {
            Some(bar) => bar.suspend(|| errout!("{text}")),
            None => errout!("{text}"),
        }
    }

    /// Removes the bar, before the summary is printed.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

impl RunObserver for Console {
    fn scene_finished(&mut self, scene: &SuiteScene, _result: &SceneResult) {
        if let Some(bar) = &self.bar {
            bar.set_message(scene.name.clone());
            bar.inc(1);
        }
    }

    fn scene_in_order(&mut self, scene: &SuiteScene, result: &SceneResult) {
        let path = scene.path.display();
        match &result.status {
            SceneStatus::Passed(_) if self.print_passes => self.line(&format!("ok      {path}")),
            SceneStatus::Passed(_) | SceneStatus::NotRun(_) => {}
            SceneStatus::Failed(failure) => {
                self.line(&format!("FAILED  {path}: {}", failure.describe(scene)))
            }
            SceneStatus::Blessed(reason) => self.line(&format!(
                "BLESSED {path} → {}: {reason}",
                scene.reference.display()
            )),
            SceneStatus::Errored(error) => {
                self.line(&format!("ERROR   {path}: {}", error.describe()));
                if let SceneError::Load(load) = error {
                    self.error_text(&render_diagnostics(&load.diagnostics, &load.sources, self.color));
                }
            }
        }
        if let Some(problem) = &result.picture_error {
            self.error_text(&format!("error: report pictures of {path}: {problem}\n"));
        }
    }
}
