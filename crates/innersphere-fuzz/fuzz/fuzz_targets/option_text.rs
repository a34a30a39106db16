#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| innersphere_fuzz::option_text(data));
