//! lampshade's integration tests, one binary (it links the library once):
//! - `render`: the rasterizer's contract on scenes built in code;
//! - `check`: `lampshade check` on small suites (verdicts, exit codes, bless, shards, reports);
//! - `cli`: the command line on good and bad scene files (`tests/bad-scenes/`);
//! - `outputs`: where commands write (never over an input), formats, standard output, closed
//!   streams, Ctrl-C, and the command-line overrides;
//! - `hard_cases`: numerical hard cases on the scenes of `scenes/hard/` (watertightness,
//!   degenerate triangles, the eye plane, large coordinates and images, depth precision, broken
//!   normals, extreme lighting), against the exact reference where one exists;
//! - `golden`: every bundled scene against its reference image (`scenes/refs/`), through the
//!   library behind `lampshade check`;
//! - `watch`: `lampshade watch` as a process on a temporary folder (save styles, includes, meshes,
//!   errors and recovery, Ctrl-C, the preview server);
//! - `lsp`: `lampshade lsp` driven over standard input and output as an editor drives it;
//! - `turntable`: `render --turntable` (APNG frames against single renders, numbered frames,
//!   shards, refused arguments);
//! - `watch_browser`: the preview page in headless Chromium (skipped without Chromium);
//!   `browser` drives Chromium for them;
//! - `pick`: the pixel inspector, `render --pick` and `GET /api/pick`; `pick_browser`: its panel,
//!   source links and highlight in headless Chromium; `compare_browser`: the preview's compare
//!   views and the `check --report` viewer there;
//! - `view_browser`: the preview's camera, toggles and camera writeback in headless Chromium,
//!   and the drag benchmark (ignored);
//! - `process` runs the binary for them all.

mod browser;
mod check;
mod cli;
mod compare_browser;
mod golden;
mod hard_cases;
mod loading;
mod lsp;
mod outputs;
mod pick;
mod pick_browser;
mod process;
mod render;
mod robustness;
mod turntable;
mod view_browser;
mod watch;
mod watch_browser;

use std::path::{Path, PathBuf};

/// The repository's root folder.
pub fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Every `*.ron` scene file directly in `folder`, sorted: a suite's `lampshade-check.ron` is
/// not a scene.
pub fn ron_files(folder: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(folder)
        .unwrap_or_else(|e| panic!("cannot list {}: {e}", folder.display()))
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == "ron"))
        .filter(|path| !path.ends_with(lampshade::check::config::CONFIG_FILE_NAME))
        .collect();
    files.sort();
    files
}
