//! (being written)

/// Arguments of `lampshade watch`.
#[derive(Debug, clap::Args)]
pub struct WatchArgs {}

pub fn run(_args: &WatchArgs) -> i32 {
    eprintln!("error: `lampshade watch` is being written");
    crate::cli::EXIT_BAD_INPUT
}
