//! Running the `lampshade` binary from the tests: plain output (no colour, no progress bars, as
//! on CI) and no standard input, so a command never waits for a terminal.

use std::path::Path;
use std::process::{Command, Output, Stdio};

/// `lampshade ARGS` run in `dir`, to completion.
pub fn lampshade(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lampshade"))
        .args(args)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .env("CI", "true")
        .stdin(Stdio::null())
        .output()
        .expect("the lampshade binary runs")
}

/// Standard output as text.
pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// Standard error as text.
pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// Both streams, labelled, for an assertion's message.
pub fn everything(output: &Output) -> String {
    format!("--- stdout\n{}--- stderr\n{}", stdout(output), stderr(output))
}
