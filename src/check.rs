//! (being written)

/// Arguments of `lampshade check`.
#[derive(Debug, clap::Args)]
pub struct CheckArgs {}

pub fn run(_args: &CheckArgs) -> i32 {
    eprintln!("error: `lampshade check` is being written");
    crate::cli::EXIT_BAD_INPUT
}
