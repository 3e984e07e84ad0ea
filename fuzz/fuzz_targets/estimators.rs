//! Every public function of `sepg-estimators` on batches of arbitrary shape and content and
//! every estimator, baseline, fit, width and quantile: no panic, and every `Ok` value finite.
#![no_main]

#[allow(dead_code)]
#[path = "../../tests/robustness.rs"]
mod robustness;

use libfuzzer_sys::fuzz_target;
use robustness::{EstimatorsCase, Source, estimators_case};

fuzz_target!(|data: &[u8]| {
    estimators_case(&EstimatorsCase::decode(&mut Source::new(data)));
});
