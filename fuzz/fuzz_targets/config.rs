//! The run configuration of `sepg run --config FILE.toml`, from arbitrary text through the
//! same code as the command: `toml` → `RunSpec` → overlay → `RunSpec::resolve` (defaults,
//! validation, `SepgConfig::check`). Invariants: no panic; a resolved configuration holds only
//! finite numbers, and writing it back as `config.toml` and resolving it again gives the same
//! configuration (what `sepg run --resume` relies on).
#![no_main]

use libfuzzer_sys::fuzz_target;
use sepg_runs::spec::{RunSpec, Values};

fn finite_values(v: &Option<Values>) -> bool {
    match v {
        None => true,
        Some(Values::One(x)) => x.is_finite(),
        Some(Values::Many(xs)) => xs.iter().all(|x| x.is_finite()),
    }
}

fn all_finite(spec: &RunSpec) -> bool {
    let scalars = [
        spec.delta,
        spec.nu,
        spec.budget0,
        spec.alpha,
        spec.beta,
        spec.lr,
        spec.lr_w,
    ];
    scalars.iter().flatten().all(|x| x.is_finite())
        && finite_values(&spec.v0)
        && finite_values(&spec.sigma0)
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(file) = toml::from_str::<RunSpec>(text) else {
        return;
    };
    let merged = RunSpec {
        sepg_version: None,
        ..file.overlay(&RunSpec::default())
    };
    let Ok(resolved) = merged.resolve() else {
        return;
    };
    assert!(
        all_finite(&resolved.spec),
        "non-finite resolved configuration {:?}",
        resolved.spec
    );
    let written = resolved
        .toml()
        .expect("a resolved configuration serialises");
    let again: RunSpec = toml::from_str(&written).expect("config.toml parses back");
    let twice = again.resolve().expect("config.toml resolves again");
    assert_eq!(
        resolved.spec, twice.spec,
        "config.toml does not round-trip:\n{written}"
    );
    assert_eq!(
        resolved.checked, twice.checked,
        "config.toml does not round-trip:\n{written}"
    );
});
