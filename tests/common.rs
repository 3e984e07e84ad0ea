//! Helpers shared by the command-line tests.

use std::ffi::OsStr;
use std::path::Path;
use std::process::{Command, Output};

/// Runs the `sepg` binary with `args` and returns its output.
pub fn sepg(args: &[&str]) -> Output {
    sepg_os(args)
}

/// Runs the `sepg` binary with `args` (strings or paths) and returns its output.
fn sepg_os<S: AsRef<OsStr>>(args: &[S]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sepg"))
        .args(args)
        .output()
        .expect("the sepg binary runs")
}

/// Runs the `sepg` binary with `args`, asserting exit status 0; returns its output.
pub fn sepg_ok<S: AsRef<OsStr>>(args: &[S]) -> Output {
    let out = sepg_os(args);
    assert_eq!(
        out.status.code(),
        Some(0),
        "sepg {:?}: {}",
        args.iter().map(AsRef::as_ref).collect::<Vec<_>>(),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The arguments of the README's example run, shortened to `iterations` iterations and
/// quiet, into the run folder `out`:
///
/// ```text
/// sepg run --env lqg1d --algo sepg-zv --gradients sampled --v0 -0.1 --sigma0 1.0 \
///   --iterations N --batch 100 --horizon 20 --delta 0.2 --seed 1 --quiet --out DIR
/// ```
pub fn readme_run(out: &Path, iterations: u64) -> Vec<String> {
    let iterations = iterations.to_string();
    with_out(
        &[
            "run",
            "--env",
            "lqg1d",
            "--algo",
            "sepg-zv",
            "--gradients",
            "sampled",
            "--v0",
            "-0.1",
            "--sigma0",
            "1.0",
            "--iterations",
            &iterations,
            "--batch",
            "100",
            "--horizon",
            "20",
            "--delta",
            "0.2",
            "--seed",
            "1",
            "--quiet",
            "--out",
        ],
        out,
    )
}

/// The arguments `args` followed by the path `out` (the value of a final `--out`), as
/// strings.
pub fn with_out(args: &[&str], out: &Path) -> Vec<String> {
    args.iter()
        .map(|s| s.to_string())
        .chain([out.display().to_string()])
        .collect()
}

/// Asserts the contract for bad input: exit status 2, nothing on standard output, exactly
/// one non-empty line on standard error. Returns that line.
pub fn assert_usage_error(out: &Output) -> String {
    assert_eq!(
        out.status.code(),
        Some(2),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.stdout.is_empty(),
        "stdout must be empty, got {:?}",
        String::from_utf8_lossy(&out.stdout)
    );
    let err = String::from_utf8(out.stderr.clone()).expect("utf-8 stderr");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "exactly one line on stderr, got {err:?}");
    assert!(!lines[0].trim().is_empty());
    lines[0].to_string()
}

/// Parses standard output as one JSON object, asserting success.
pub fn json_ok(out: &Output) -> serde_json::Value {
    assert_eq!(
        out.status.code(),
        Some(0),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is one JSON value")
}

/// Relative closeness, `rel` in units of the larger magnitude, with an absolute floor of
/// `rel`·1e-300 (so that two zeros are close).
pub fn close(a: f64, b: f64, rel: f64) -> bool {
    sepg_testkit::close(a, b, rel, 1e-300)
}

/// The number under `key` of a JSON object, panicking with the object if it is missing.
pub fn get(v: &serde_json::Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("key {key} missing or not a number in {v}"))
}
