//! lampshade: render hand-written RON scene files with a tiled, deterministic CPU rasterizer.
//!
//! The crate is a one-way pipeline; each stage is one module entered through one function:
//!
//! ```text
//! scene::load ──► render::render ──────────────────────────────────────► output::write_png
//!  (RON, includes,   geometry ──► bin ──► raster (per tile) ──► shade (per tile) ──► resolve
//!   meshes, checks)
//! ```
//!
//! After `scene::load` succeeds, rendering cannot fail: every user-input problem is reported
//! by the loader as a [`diag::Diagnostic`]. See `ARCHITECTURE.md` for the code map.
//!
//! Beside the pipeline, for accuracy: [`reference`] renders analytic shapes exactly (ray cast
//! and lit in `f64`), [`metrics`] measures an image against it, and [`report`] sweeps shading
//! modes and tessellations for the speed/error report.
#![deny(unsafe_code)]

// First, so that its printing macros are in scope in every module below.
#[macro_use]
pub mod console;
#[cfg(test)]
mod test_support;

pub mod bench;
pub mod check;
pub mod cli;
pub mod cpu_time;
pub mod diag;
pub mod inspect;
pub mod lighting;
pub mod lsp;
pub mod mesh;
pub mod metrics;
pub mod output;
pub mod pipeline;
pub mod progress;
pub mod reference;
pub mod render;
pub mod report;
pub mod scene;
pub mod texture;
pub mod turntable;
pub mod watch;
