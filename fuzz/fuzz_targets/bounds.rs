//! Every public function of `sepg-bounds` on arbitrary f64 (NaN, ±∞, subnormals, ±0, huge)
//! and vectors of arbitrary lengths: no panic, and every `Ok` value finite.
#![no_main]

#[allow(dead_code)]
#[path = "../../tests/robustness.rs"]
mod robustness;

use libfuzzer_sys::fuzz_target;
use robustness::{BoundsCase, Source, bounds_case};

fuzz_target!(|data: &[u8]| {
    bounds_case(&BoundsCase::decode(&mut Source::new(data)));
});
