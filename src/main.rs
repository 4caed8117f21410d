//! The `lampshade` binary: the command line of the library, and the last line of defence.
//!
//! A panic anywhere is a bug in lampshade, never the user's fault: it is caught here and reported
//! as an internal error with exit code 101, after the panic message itself.

use std::panic;

use lampshade::cli::{self, EXIT_INTERNAL_ERROR};
use lampshade::errln;

/// A frame allocates some hundred megabytes in many large blocks (per-chunk raster triangles,
/// vertex arrays, the frame buffer) and frees them at its end. glibc's allocator maps and unmaps
/// such blocks each frame, and the page faults and zeroing cost 15–20 % of a frame on dense
/// meshes; mimalloc keeps and reuses them (S2 flat 65 → 51 ms, docs/performance.md).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    let default_hook = panic::take_hook();
    panic::set_hook(Box::new(move |info| {
        default_hook(info);
        errln!(
            "error: internal error in lampshade {} (a bug, not a problem with your files).\n\
             Please report it with the scene that triggered it and the message above.",
            env!("CARGO_PKG_VERSION")
        );
    }));
    let code = panic::catch_unwind(|| cli::run(std::env::args_os())).unwrap_or(EXIT_INTERNAL_ERROR);
    std::process::exit(code);
}
