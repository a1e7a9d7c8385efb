//! Fuzzes scene loading (TOML, OBJ, MTL, PNG texture) against its contract:
//! `bounce_oracles::scene_fuzz::check_load` documents the input layout and what is checked.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("bounce-fuzz-{}", std::process::id()));
    bounce_oracles::scene_fuzz::check_load(data, &dir);
});
