#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| petrinav_fuzz::harness::bt_xml(data));
