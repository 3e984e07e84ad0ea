//! `sepg audit`: a clean exact run passes; a log edited so that J drops at one iteration is
//! reported at exactly that iteration; bad input is a usage error.

use std::fs;
use std::path::Path;

use crate::common::{assert_usage_error, sepg};

/// A short exact SEPG-MI run on the `lqg` preset (clipped: audited with the DP oracle).
fn mi_run(dir: &Path) {
    let out = sepg(&[
        "run",
        "--env",
        "lqg",
        "--algo",
        "sepg-mi",
        "--gradients",
        "exact",
        "--sigma0",
        "0.5",
        "--iterations",
        "12",
        "--quiet",
        "--out",
        dir.to_str().expect("utf-8 path"),
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn audit_json(dir: &Path) -> (Option<i32>, serde_json::Value) {
    let out = sepg(&["audit", "--json", dir.to_str().expect("utf-8 path")]);
    let report = serde_json::from_slice(&out.stdout).expect("the report is JSON");
    (out.status.code(), report)
}

/// Replaces the `v` cell (column 1) of the row of `iteration` in `log.csv`.
fn set_v(dir: &Path, iteration: u64, v: f64) {
    let path = dir.join("log.csv");
    let text = fs::read_to_string(&path).expect("log.csv");
    let edited: Vec<String> = text
        .lines()
        .map(|line| {
            let mut cells: Vec<String> = line.split(',').map(String::from).collect();
            if cells[0] == iteration.to_string() {
                cells[1] = format!("{v:?}");
            }
            cells.join(",")
        })
        .collect();
    fs::write(&path, edited.join("\n") + "\n").expect("write log.csv");
}

#[test]
fn a_clean_exact_run_passes_and_an_injected_drop_is_reported_at_its_iteration() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("mi");
    mi_run(&dir);

    let (code, report) = audit_json(&dir);
    assert_eq!(code, Some(0), "{report}");
    assert_eq!(report["iterations"], 12);
    assert_eq!(report["skipped"], 0);
    // Every iteration checks its v-guarantee and monotonic improvement.
    assert!(report["checks"].as_u64().expect("count") >= 24, "{report}");
    assert!(
        report["source"]
            .as_str()
            .expect("source")
            .contains("ClippedDpOracle")
    );
    assert_eq!(report["violations"], serde_json::json!([]));

    // θ⁶ moved to v = +0.5 (far from v* ≈ −0.615): J(θ⁶) < J(θ⁵), so the update of
    // iteration 5 broke monotonic improvement and its v-guarantee; iteration 6, which starts
    // from the worse policy, improves on it and must not be reported.
    set_v(&dir, 6, 0.5);
    let (code, report) = audit_json(&dir);
    assert_eq!(code, Some(1), "{report}");
    let violations = report["violations"].as_array().expect("violations");
    assert!(!violations.is_empty());
    for v in violations {
        assert_eq!(v["iteration"], 5, "{report}");
        let shortfall = v["shortfall"].as_f64().expect("shortfall");
        let gap = v["required"].as_f64().expect("required") - v["actual"].as_f64().expect("actual");
        assert!(
            shortfall > 1e-3 && (shortfall - gap).abs() <= 1e-12 * gap.abs(),
            "{v}"
        );
    }
    let checks: Vec<&str> = violations
        .iter()
        .map(|v| v["check"].as_str().expect("check"))
        .collect();
    assert!(
        checks.contains(&"mi") && checks.contains(&"guarantee-v"),
        "{checks:?}"
    );

    // The table names the iteration and the exit status says that some iteration broke it.
    let out = sepg(&["audit", dir.to_str().expect("utf-8 path")]);
    assert_eq!(out.status.code(), Some(1));
    let table = String::from_utf8(out.stdout).expect("utf-8");
    assert!(
        table.contains("1 iteration(s) broke the safety requirement"),
        "{table}"
    );
    assert!(
        table.lines().any(|l| l.trim_start().starts_with("5  mi")),
        "{table}"
    );
    let err = String::from_utf8(out.stderr).expect("utf-8");
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn bad_input_is_a_usage_error() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let missing = tmp.path().join("absent");
    assert_usage_error(&sepg(&["audit", missing.to_str().expect("utf-8 path")]));

    let dir = tmp.path().join("mi");
    mi_run(&dir);
    let log = dir.join("log.csv");
    let text = fs::read_to_string(&log).expect("log.csv");
    // A row with a cell too many, then a cell that is not a number.
    fs::write(&log, text.replacen("\n1,", "\n1,0,", 1)).expect("write");
    assert_usage_error(&sepg(&["audit", dir.to_str().expect("utf-8 path")]));
    fs::write(&log, text.replacen("\n1,", "\n1,x", 1)).expect("write");
    assert_usage_error(&sepg(&["audit", dir.to_str().expect("utf-8 path")]));
    fs::write(&log, "iteration,v\n").expect("write");
    assert_usage_error(&sepg(&["audit", dir.to_str().expect("utf-8 path")]));
}
