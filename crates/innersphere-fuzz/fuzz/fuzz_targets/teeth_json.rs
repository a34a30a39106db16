#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| innersphere_fuzz::teeth_json(data));
