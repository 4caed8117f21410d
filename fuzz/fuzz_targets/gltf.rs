//! Fuzz target `gltf`: see `fuzz/harness.rs` for what it feeds the library and checks.
#![no_main]

#[path = "../harness.rs"]
mod harness;

libfuzzer_sys::fuzz_target!(
    init: {
        // libfuzzer-sys aborts on every panic, even one the loaders contain with
        // `catch_unwind` by design (a panic inside the gltf or tobj crates becomes a
        // "malformed file" error). Keep the default hook: a contained panic is printed and
        // the run goes on; one that escapes still aborts, through libfuzzer-sys's wrapper.
        let _ = std::panic::take_hook();
    },
    |data: &[u8]| harness::gltf(data)
);
