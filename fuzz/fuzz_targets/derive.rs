#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| dae_fuzz::derive(data));
