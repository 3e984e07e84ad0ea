//! `sepg audit`: every check fails when its requirement is broken by an edit of the log and
//! holds on the unedited run; exact runs fail on one failure, sampled runs only when the
//! binomial test rejects; every malformed or incomplete folder exits with status 2.
//!
//! Cost: eight runs of 12–300 iterations on the clipped presets (well under a second each).

use std::fs;
use std::path::Path;

use crate::common::{assert_usage_error, readme_run, sepg, sepg_ok};

fn path(dir: &Path) -> &str {
    dir.to_str().expect("utf-8 path")
}

/// `sepg run ... --quiet --out dir`, asserting success.
fn run(dir: &Path, args: &[&str]) {
    let mut all = vec!["run", "--quiet", "--out", path(dir)];
    all.extend_from_slice(args);
    sepg_ok(&all);
}

/// A short exact run of `algo` on the `lqg` preset (clipped: audited with the DP oracle).
fn exact_run(dir: &Path, algo: &str) {
    run(
        dir,
        &[
            "--env",
            "lqg",
            "--algo",
            algo,
            "--gradients",
            "exact",
            "--sigma0",
            "0.5",
            "--iterations",
            "12",
        ],
    );
}

fn audit_json(dir: &Path) -> (Option<i32>, serde_json::Value) {
    let out = sepg(&["audit", "--json", path(dir)]);
    let report = serde_json::from_slice(&out.stdout).unwrap_or_else(|_| {
        panic!(
            "the report is JSON; stderr: {}",
            String::from_utf8_lossy(&out.stderr)
        )
    });
    (out.status.code(), report)
}

/// The summary of check `name` in a JSON report.
fn check<'a>(report: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    report["checks"]
        .as_array()
        .expect("checks")
        .iter()
        .find(|c| c["check"] == name)
        .unwrap_or_else(|| panic!("no check {name} in {report}"))
}

/// Replaces, in `log.csv`, the cell of column `column` on the row of `iteration` (every row
/// when `iteration` is `None`) by `value`.
fn set_cell(dir: &Path, column: &str, iteration: Option<u64>, value: &str) {
    let p = dir.join("log.csv");
    let text = fs::read_to_string(&p).expect("log.csv");
    let mut lines = text.lines();
    let header = lines.next().expect("header");
    let col = header
        .split(',')
        .position(|c| c == column)
        .unwrap_or_else(|| panic!("no column {column}"));
    let mut out = vec![header.to_owned()];
    for line in lines {
        let mut cells: Vec<String> = line.split(',').map(String::from).collect();
        if iteration.is_none_or(|t| cells[0] == t.to_string()) {
            cells[col] = value.to_owned();
        }
        out.push(cells.join(","));
    }
    fs::write(&p, out.join("\n") + "\n").expect("write log.csv");
}

/// The checks of a report whose verdict is `violated`, and the iterations of their failures.
fn violated(report: &serde_json::Value) -> (Vec<String>, Vec<u64>) {
    let names: Vec<String> = report["checks"]
        .as_array()
        .expect("checks")
        .iter()
        .filter(|c| c["verdict"] == "violated")
        .map(|c| c["check"].as_str().expect("name").to_owned())
        .collect();
    let mut its: Vec<u64> = report["failures"]
        .as_array()
        .expect("failures")
        .iter()
        .filter(|f| names.iter().any(|n| f["check"] == n.as_str()))
        .map(|f| f["iteration"].as_u64().expect("iteration"))
        .collect();
    its.dedup();
    (names, its)
}

/// Whether the printed `cell` shows `value` (a JSON number, or `-` for null) to its printed
/// precision: a mantissa m.ddd…e±k with D decimals is within half a unit of its last digit,
/// 0.5·10^(k − D) ≤ 0.5·10^(−D)·|value|.
fn shows(cell: &str, value: &serde_json::Value) -> bool {
    match value.as_f64() {
        None => cell == "-" && value.is_null(),
        Some(x) => {
            let printed: f64 = cell.parse().unwrap_or(f64::NAN);
            let decimals = cell
                .split('e')
                .next()
                .and_then(|m| m.split('.').nth(1))
                .map_or(0, str::len);
            let unit = 10f64.powi(-i32::try_from(decimals).expect("short"));
            (printed - x).abs() <= 0.5001 * unit * x.abs().max(printed.abs())
        }
    }
}

/// Asserts that every number and word of the printed report of `dir` is in its `--json`
/// report: the header, each check's line and each listed failure.
fn assert_table_is_in_the_json(dir: &Path) {
    let (_, report) = audit_json(dir);
    let out = sepg(&["audit", path(dir)]);
    let table = String::from_utf8(out.stdout).expect("utf-8");
    let mut lines = table.lines();
    assert_eq!(
        lines.next(),
        Some(format!("audit of {}", path(dir)).as_str())
    );
    let field = |line: Option<&str>, key: &str| {
        line.and_then(|l| l.split_once(':'))
            .map(|(k, v)| (k.to_owned(), v.trim().to_owned()))
            .filter(|(k, _)| k == key)
            .unwrap_or_else(|| panic!("no {key} line in {table}"))
            .1
    };
    assert_eq!(field(lines.next(), "algorithm"), report["algorithm"]);
    assert_eq!(field(lines.next(), "gradients"), report["gradients"]);
    assert_eq!(field(lines.next(), "J from"), report["source"]);
    let counts = format!(
        "{} of {} iterations done, {} rows, {} skipped (next parameters not logged)",
        report["iterations_done"], report["iterations_total"], report["rows"], report["skipped"]
    );
    assert_eq!(lines.next(), Some(counts.as_str()));
    assert!(lines.next().is_some_and(|l| l.starts_with("check")));
    let checks = report["checks"].as_array().expect("checks");
    for c in checks {
        let cells: Vec<&str> = lines
            .next()
            .expect("check line")
            .split_whitespace()
            .collect();
        assert_eq!(cells.len(), 9, "{cells:?}");
        assert_eq!(cells[0], c["check"]);
        let kind = c["kind"].as_str().expect("kind");
        assert!(kind.starts_with(cells[1]), "{kind} vs {}", cells[1]);
        assert_eq!(cells[2], c["checked"].to_string());
        assert_eq!(cells[3], c["failed"].to_string());
        assert!(shows(cells[4], &c["worst_shortfall"]), "{cells:?} {c}");
        assert_eq!(cells[5], c["worst_iteration"].to_string());
        assert!(shows(cells[6], &c["allowed_rate"]), "{cells:?} {c}");
        assert!(shows(cells[7], &c["p_value"]), "{cells:?} {c}");
        assert!(
            c["verdict"]
                .as_str()
                .expect("verdict")
                .eq_ignore_ascii_case(cells[8])
        );
    }
    let failures = report["failures"].as_array().expect("failures");
    let violated: Vec<&serde_json::Value> = failures
        .iter()
        .filter(|f| {
            checks
                .iter()
                .any(|c| c["check"] == f["check"] && c["verdict"] == "violated")
        })
        .collect();
    if !violated.is_empty() {
        assert!(
            lines
                .next()
                .is_some_and(|l| l.trim_start().starts_with("iteration"))
        );
        for f in violated.iter().take(20) {
            let cells: Vec<&str> = lines
                .next()
                .expect("failure line")
                .split_whitespace()
                .collect();
            assert_eq!(cells[0], f["iteration"].to_string());
            assert_eq!(cells[1], f["check"]);
            for (cell, key) in cells[2..].iter().zip(["required", "actual", "shortfall"]) {
                assert!(shows(cell, &f[key]), "{cells:?} {f}");
            }
        }
    }
}

#[test]
fn a_clean_exact_run_passes_and_an_injected_drop_is_reported_at_its_iteration() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("mi");
    exact_run(&dir, "sepg-mi");

    let (code, report) = audit_json(&dir);
    assert_eq!(code, Some(0), "{report}");
    assert_eq!(report["status"], "holds");
    assert_eq!(report["algorithm"], "sepg-mi");
    assert_eq!(report["rows"], 12);
    assert_eq!(report["skipped"], 0);
    // Every iteration checks its v-guarantee and monotonic improvement, listed although they
    // passed, with a negative worst shortfall (the smallest margin).
    for name in ["guarantee-v", "mi"] {
        let c = check(&report, name);
        assert_eq!(c["kind"], "exact");
        assert_eq!(c["checked"], 12, "{c}");
        assert_eq!(c["failed"], 0);
        assert_eq!(c["verdict"], "holds");
        assert!(c["worst_shortfall"].as_f64().expect("worst") <= 0.0, "{c}");
    }
    assert!(
        report["source"]
            .as_str()
            .expect("source")
            .contains("ClippedDpOracle")
    );
    assert_eq!(report["failures"], serde_json::json!([]));

    // θ⁶ moved to v = +0.5 (far from v* ≈ −0.615): J(θ⁶) < J(θ⁵), so the update of
    // iteration 5 broke monotonic improvement and its v-guarantee; iteration 6, which starts
    // from the worse policy, improves on it and must not be reported.
    set_cell(&dir, "v", Some(6), "0.5");
    let (code, report) = audit_json(&dir);
    assert_eq!(code, Some(1), "{report}");
    assert_eq!(report["status"], "violated");
    let (names, its) = violated(&report);
    assert!(
        names.contains(&"mi".to_owned()) && names.contains(&"guarantee-v".to_owned()),
        "{names:?}"
    );
    assert_eq!(its, vec![5], "{report}");
    for v in report["failures"].as_array().expect("failures") {
        let shortfall = v["shortfall"].as_f64().expect("shortfall");
        let gap = v["required"].as_f64().expect("required") - v["actual"].as_f64().expect("actual");
        assert!(
            shortfall > 1e-3 && (shortfall - gap).abs() <= 1e-12 * gap.abs(),
            "{v}"
        );
    }
    let mi = check(&report, "mi");
    assert_eq!(
        (mi["checked"].as_u64(), mi["failed"].as_u64()),
        (Some(12), Some(1))
    );
    assert_eq!(mi["worst_iteration"], 5);

    // The table lists every check, names the iteration, and the exit status says so; every
    // number it shows is in the JSON report.
    assert_table_is_in_the_json(&dir);
    let out = sepg(&["audit", path(&dir)]);
    assert_eq!(out.status.code(), Some(1));
    let table = String::from_utf8(out.stdout).expect("utf-8");
    assert!(
        table.contains("VIOLATED: 1 iteration(s) broke the safety requirement"),
        "{table}"
    );
    assert!(
        table.lines().any(|l| l.trim_start().starts_with("5  mi")),
        "{table}"
    );
    for name in ["guarantee-v", "mi"] {
        assert!(
            table.lines().any(|l| l.starts_with(name)),
            "{name}: {table}"
        );
    }
    let err = String::from_utf8(out.stderr).expect("utf-8");
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn each_exact_check_fails_when_its_own_requirement_is_broken() {
    let tmp = tempfile::tempdir().expect("tempdir");

    // guarantee-w: the update of iteration 3 must now guarantee an improvement of 1 in J,
    // which it does not achieve; nothing else changes.
    let zv = tmp.path().join("zv");
    exact_run(&zv, "sepg-zv");
    let (code, report) = audit_json(&zv);
    assert_eq!(code, Some(0), "{report}");
    set_cell(&zv, "guaranteed_w", Some(3), "1.0");
    let (code, report) = audit_json(&zv);
    assert_eq!(code, Some(1), "{report}");
    assert_eq!(violated(&report), (vec!["guarantee-w".to_owned()], vec![3]));

    // budget-exact: θ⁶ far from the optimum drops the exact J of the exploratory policy by
    // much more than B⁰ + the gains so far, at the update of iteration 5 (and, since J(θ⁶)
    // enters the budget, the later ones until the run recovers).
    let zv2 = tmp.path().join("zv2");
    exact_run(&zv2, "sepg-zv");
    set_cell(&zv2, "v", Some(6), "0.5");
    let (code, report) = audit_json(&zv2);
    assert_eq!(code, Some(1), "{report}");
    let (names, its) = violated(&report);
    assert!(names.contains(&"budget-exact".to_owned()), "{names:?}");
    assert_eq!(its.first(), Some(&5), "{report}");

    // lb-i: the same edit breaks J(θ⁶) ≥ J(θ⁰) for LB-I.
    let lb1 = tmp.path().join("lb1");
    exact_run(&lb1, "sepg-lb1");
    let (code, report) = audit_json(&lb1);
    assert_eq!(code, Some(0), "{report}");
    set_cell(&lb1, "v", Some(6), "0.5");
    let (code, report) = audit_json(&lb1);
    assert_eq!(code, Some(1), "{report}");
    let (names, its) = violated(&report);
    assert!(names.contains(&"lb-i".to_owned()), "{names:?}");
    assert_eq!(its, vec![5], "{report}");
    assert_eq!(check(&report, "lb-i")["failed"], 1);

    // budget (the algorithm's bookkeeping): a negative recorded budget is a note, not a
    // violation, and the exact checks still hold.
    let zv3 = tmp.path().join("zv3");
    exact_run(&zv3, "sepg-zv");
    set_cell(&zv3, "budget", Some(4), "-1.0");
    let (code, report) = audit_json(&zv3);
    assert_eq!(code, Some(0), "{report}");
    let b = check(&report, "budget");
    assert_eq!(b["kind"], "bookkeeping");
    assert_eq!(b["verdict"], "note");
    assert_eq!(
        (b["failed"].as_u64(), b["worst_iteration"].as_u64()),
        (Some(1), Some(4))
    );
    let out = sepg(&["audit", path(&zv3)]);
    let table = String::from_utf8(out.stdout).expect("utf-8");
    assert!(table.contains("note: budget failed at 1 of 12"), "{table}");
}

#[test]
fn a_sampled_run_is_judged_by_the_binomial_test() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("zv");
    // The README's example, shortened to 300 iterations.
    sepg_ok(&readme_run(&dir, 300));
    let (code, report) = audit_json(&dir);
    assert_eq!(code, Some(0), "{report}");
    assert_eq!(report["status"], "holds");
    for name in ["guarantee-v", "budget-exact"] {
        let c = check(&report, name);
        assert_eq!(c["kind"], "high-probability", "{c}");
        assert_eq!(c["verdict"], "holds", "{c}");
    }
    assert_eq!(check(&report, "guarantee-v")["allowed_rate"], 0.2);
    let both = check(&report, "budget-exact")["allowed_rate"]
        .as_f64()
        .expect("rate");
    assert!((both - 0.36).abs() < 1e-15, "1 − 0.8² = 0.36, got {both}");
    assert_eq!(check(&report, "budget")["kind"], "bookkeeping");

    // One failing step among hundreds is what δ = 0.2 allows: reported, not a violation.
    let row: u64 = 150;
    set_cell(&dir, "guaranteed_v", Some(row), "1.0");
    let (code, report) = audit_json(&dir);
    assert_eq!(code, Some(0), "{report}");
    let c = check(&report, "guarantee-v");
    assert_eq!(c["failed"], 1, "{c}");
    assert_eq!(c["worst_iteration"], row);
    // P(X ≥ 1) = 1 − 0.8ⁿ for X ~ Binomial(n, 0.2).
    let n = c["checked"].as_u64().expect("n");
    let p = c["p_value"].as_f64().expect("p");
    let expected = 1.0 - 0.8f64.powi(i32::try_from(n).expect("small"));
    assert!((p - expected).abs() <= 1e-12, "{p} vs {expected}");
    assert_table_is_in_the_json(&dir);

    // Every v-step claiming an improvement of 1 that it never delivers: the failure rate 1 is
    // far above δ = 0.2 (p-value 0.2ⁿ), so the test rejects and the run is violated.
    set_cell(&dir, "guaranteed_v", None, "1.0");
    let (code, report) = audit_json(&dir);
    assert_eq!(code, Some(1), "{report}");
    let c = check(&report, "guarantee-v");
    assert_eq!(c["failed"], c["checked"], "{c}");
    assert_eq!(c["verdict"], "violated");
    assert!(c["p_value"].as_f64().expect("p") < 1e-100, "{c}");
}

/// Asserts that auditing `dir` exits with status 2 and one line on standard error that
/// contains `what`.
fn assert_malformed(dir: &Path, what: &str) {
    let line = assert_usage_error(&sepg(&["audit", path(dir)]));
    assert!(line.contains(what), "expected {what:?} in {line:?}");
}

#[test]
fn every_malformed_or_incomplete_folder_exits_with_status_2() {
    let tmp = tempfile::tempdir().expect("tempdir");
    assert_malformed(&tmp.path().join("absent"), "is not a folder");
    assert_malformed(tmp.path(), "is not a run folder");

    let dir = tmp.path().join("mi");
    exact_run(&dir, "sepg-mi");
    let log = dir.join("log.csv");
    let text = fs::read_to_string(&log).expect("log.csv");
    let edit = |from: &str, to: &str| {
        assert!(text.contains(from), "{from:?}");
        fs::write(&log, text.replacen(from, to, 1)).expect("write");
    };
    let restore = || fs::write(&log, &text).expect("restore");

    let cases: [(&str, Option<u64>, &str, &str); 8] = [
        ("v", Some(4), "NaN", "is not a finite number"),
        ("j_explore", Some(4), "inf", "is not a finite number"),
        ("steps", Some(4), "many", "is not a non-negative integer"),
        ("infeasible", Some(4), "-1", "is not a non-negative integer"),
        ("budget", Some(4), "x", "is not a number"),
        ("j_target", Some(4), "", "is empty"),
        ("guaranteed_v", Some(4), "NaN", "is not a finite number"),
        ("w_target", Some(4), "+inf", "is not a finite number"),
    ];
    for (column, row, value, what) in cases {
        set_cell(&dir, column, row, value);
        assert_malformed(&dir, what);
        restore();
    }

    // A row too many cells, a deleted row, a duplicated row, a missing last row, a header
    // that is not the run's.
    edit("\n3,", "\n3,0,");
    assert_malformed(&dir, "cells");
    let lines: Vec<&str> = text.lines().collect();
    let without = |k: usize| {
        let mut l = lines.clone();
        l.remove(k);
        l.join("\n") + "\n"
    };
    fs::write(&log, without(5)).expect("write");
    assert_malformed(&dir, "expected 4: rows are missing");
    let mut dup = lines.clone();
    dup.insert(5, lines[5]);
    fs::write(&log, dup.join("\n") + "\n").expect("write");
    assert_malformed(&dir, "rows are missing or out of order");
    fs::write(&log, without(lines.len() - 1)).expect("write");
    assert_malformed(&dir, "ends before the row of iteration 11");
    fs::write(&log, "iteration,v\n").expect("write");
    assert_malformed(&dir, "header");
    restore();

    // summary.json missing, malformed, or for another number of iterations.
    let summary = dir.join("summary.json");
    let s = fs::read_to_string(&summary).expect("summary");
    fs::remove_file(&summary).expect("remove");
    assert_malformed(&dir, "without summary.json");
    fs::write(&summary, "{").expect("write");
    assert_malformed(&dir, "summary.json is malformed");
    fs::write(
        &summary,
        s.replace("\"iterations\": 12", "\"iterations\": 11"),
    )
    .expect("write");
    assert_malformed(&dir, "reports 11 iterations");
    fs::write(&summary, &s).expect("restore");
    assert_eq!(sepg(&["audit", path(&dir)]).status.code(), Some(0));
}

/// Turns the finished 12-iteration run in `dir` into the folder of a run interrupted after 8
/// iterations: the first 8 rows (and a torn 9th) in `log.partial.csv`, and a checkpoint
/// saying so (θ⁸ from row 8). Returns the checkpoint.
fn interrupt_after_8(dir: &Path) -> serde_json::Value {
    let text = fs::read_to_string(dir.join("log.csv")).expect("log.csv");
    let lines: Vec<&str> = text.lines().collect();
    let prefix = lines[..9].join("\n") + "\n";
    let row8: Vec<&str> = lines[9].split(',').collect();
    let ck_text = fs::read_to_string(dir.join("checkpoint.json")).expect("checkpoint");
    let mut ck: serde_json::Value = serde_json::from_str(&ck_text).expect("json");
    ck["log_bytes"] = prefix.len().into();
    ck["state"]["iteration"] = 8.into();
    ck["state"]["v"] = serde_json::json!([row8[1].parse::<f64>().expect("v")]);
    ck["state"]["w"] = serde_json::json!([row8[2].parse::<f64>().expect("w")]);
    fs::write(dir.join("checkpoint.json"), ck.to_string()).expect("write");
    fs::write(dir.join("log.partial.csv"), prefix + lines[9] + "\n").expect("write");
    fs::remove_file(dir.join("log.csv")).expect("remove");
    fs::remove_file(dir.join("summary.json")).expect("remove");
    ck
}

#[test]
fn an_interrupted_run_is_audited_up_to_its_checkpoint_and_reported_incomplete() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("mi");
    exact_run(&dir, "sepg-mi");
    interrupt_after_8(&dir);

    let out = sepg(&["audit", "--json", path(&dir)]);
    assert_eq!(out.status.code(), Some(2));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(report["status"], "incomplete");
    assert_eq!(
        (report["iterations_done"].as_u64(), report["rows"].as_u64()),
        (Some(8), Some(8))
    );
    assert_eq!(check(&report, "mi")["checked"], 8);
    let err = String::from_utf8(out.stderr).expect("utf-8");
    assert!(err.contains("sepg run --resume"), "{err}");
    assert_eq!(err.lines().count(), 1);
}

#[test]
fn summaries_and_checkpoints_that_do_not_fit_the_run_exit_with_status_2() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("mi");
    exact_run(&dir, "sepg-mi");

    // summary.json whose final parameters have two mean components for a 1-D policy.
    let summary = dir.join("summary.json");
    let text = fs::read_to_string(&summary).expect("summary");
    let mut s: serde_json::Value = serde_json::from_str(&text).expect("json");
    let v = s["final"]["v"][0].clone();
    s["final"]["v"] = serde_json::json!([v, v]);
    fs::write(&summary, s.to_string()).expect("write");
    assert_malformed(&dir, "the final parameters do not fit the run");
    fs::write(&summary, &text).expect("restore");

    // The interrupted folder, broken four ways.
    let ck = interrupt_after_8(&dir);
    let checkpoint = dir.join("checkpoint.json");
    let partial = dir.join("log.partial.csv");
    let restore = || fs::write(&checkpoint, ck.to_string()).expect("restore");

    let mut long = ck.clone();
    long["log_bytes"] = (fs::metadata(&partial).expect("partial").len() + 1).into();
    fs::write(&checkpoint, long.to_string()).expect("write");
    assert_malformed(&dir, "shorter than its checkpoint says");

    let mut wide = ck.clone();
    wide["state"]["w"] = serde_json::json!([0.0, 0.0]);
    fs::write(&checkpoint, wide.to_string()).expect("write");
    assert_malformed(&dir, "does not fit the run's configuration");

    let mut late = ck.clone();
    late["state"]["iteration"] = 13.into();
    fs::write(&checkpoint, late.to_string()).expect("write");
    assert_malformed(&dir, "does not fit the run's configuration");

    fs::remove_file(&checkpoint).expect("remove");
    assert_malformed(&dir, "without a valid checkpoint.json");
    restore();
    assert_eq!(sepg(&["audit", path(&dir)]).status.code(), Some(2));

    fs::remove_file(&partial).expect("remove");
    assert_malformed(&dir, "no log.csv and no readable log.partial.csv");
}

#[test]
fn help_documents_the_exit_statuses() {
    let out = sepg(&["audit", "--help"]);
    assert_eq!(out.status.code(), Some(0));
    let help = String::from_utf8(out.stdout).expect("utf-8");
    for line in [
        "0  every exact",
        "1  a check is violated",
        "2  malformed or incomplete",
    ] {
        assert!(help.contains(line), "{line:?} in {help}");
    }
}
