#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| innersphere_fuzz::landmarks(data));
