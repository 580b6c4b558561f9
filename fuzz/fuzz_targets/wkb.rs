//! Any bytes given as a region's WKB (see fuzz/checks/wkb.rs).
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../checks/wkb.rs"]
mod checks;

fuzz_target!(|bytes: &[u8]| checks::check(bytes));
