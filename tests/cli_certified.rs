//! `--certified-steps` (key `certified-steps`) of `run`, `sweep` and `reproduce`: accepted,
//! recorded in `config.toml` and `summary.json`, and a run without certified steps differs
//! from the same run with them only by the certification: the steps (moved by a few ulps),
//! their guarantees (the lower ends of the enclosures) and the `certified_*` columns.
//!
//! Cost: four `lqg1d` runs of 12 iterations (N = 24), a sweep of two such runs, a
//! reproduction of 2 runs × 2 iterations; the rest fail at parsing.

use std::path::Path;

use crate::common::{assert_usage_error, sepg, sepg_ok, with_out};

/// The arguments of a short sampled SEPG-ZV run on `lqg1d` into `out`, then `extra`.
fn short_run(out: &Path, extra: &[&str]) -> Vec<String> {
    let mut args = with_out(
        &[
            "run",
            "--env",
            "lqg1d",
            "--algo",
            "sepg-zv",
            "--iterations",
            "12",
            "--batch",
            "24",
            "--seed",
            "5",
            // the proven widths take no step at N = 24: Student-t widths, so that steps are taken
            "--confidence",
            "student-t",
            // the thesis's constants: under the tight ones iteration 0's w-requirement of 0 is
            // found uncertifiable by the certified path (λ_w = 0, infeasible_w = 1) where the f64
            // path takes a zero step, so λ_w differs beyond the certification's columns
            "--constants",
            "thesis",
            "--quiet",
            "--out",
        ],
        out,
    );
    args.extend(extra.iter().map(|s| s.to_string()));
    args
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The `certified_steps` of a run folder's `summary.json`.
fn summary_flag(dir: &Path) -> serde_json::Value {
    let s: serde_json::Value =
        serde_json::from_str(&read(&dir.join("summary.json"))).expect("summary.json");
    s["certified_steps"].clone()
}

/// The rows of `log.csv` as (header, rows of fields).
fn log(dir: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = read(&dir.join("log.csv"));
    let mut lines = text.lines();
    let header = lines
        .next()
        .expect("header")
        .split(',')
        .map(str::to_owned)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect();
    (header, rows)
}

/// The columns that certification changes: the steps, their guarantees and the flags.
const CERTIFICATION_COLUMNS: [&str; 6] = [
    "alpha",
    "beta",
    "guaranteed_v",
    "guaranteed_w",
    "certified_v",
    "certified_w",
];

#[test]
fn certified_steps_can_be_turned_off_and_the_runs_record_it() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (on, off, default) = (
        tmp.path().join("on"),
        tmp.path().join("off"),
        tmp.path().join("default"),
    );
    sepg_ok(&short_run(&on, &["--certified-steps", "true"]));
    sepg_ok(&short_run(&off, &["--certified-steps", "false"]));
    sepg_ok(&short_run(&default, &[]));
    assert!(read(&on.join("config.toml")).contains("certified-steps = true"));
    assert!(read(&off.join("config.toml")).contains("certified-steps = false"));
    assert!(read(&default.join("config.toml")).contains("certified-steps = true"));
    assert_eq!(summary_flag(&on), serde_json::json!(true));
    assert_eq!(summary_flag(&off), serde_json::json!(false));
    // on is the default: the same run, byte for byte
    assert_eq!(read(&on.join("log.csv")), read(&default.join("log.csv")));

    let ((header, rows_on), (header_off, rows_off)) = (log(&on), log(&off));
    assert_eq!(header, header_off);
    let col = |name: &str| header.iter().position(|h| h == name).expect(name);
    // the flags: 1 or 0 for a step taken with certification, empty without it (or without
    // a step)
    for name in ["certified_v", "certified_w"] {
        let c = col(name);
        assert!(
            rows_on
                .iter()
                .all(|r| ["", "0", "1"].contains(&r[c].as_str()))
        );
        assert!(
            rows_on.iter().any(|r| r[c] == "1"),
            "{name}: no certified step"
        );
        assert!(rows_off.iter().all(|r| r[c].is_empty()), "{name} off");
    }
    // Iteration 0 starts from the same state with the same trajectories: every column but
    // the certification's is bit-identical, and each step is the same or differs by the
    // certification's move, a few ulps toward the vertex (at most 1e-13 relative).
    let certification: Vec<usize> = CERTIFICATION_COLUMNS.iter().map(|c| col(c)).collect();
    for (i, (a, b)) in rows_on[0].iter().zip(&rows_off[0]).enumerate() {
        if !certification.contains(&i) {
            assert_eq!(a, b, "column {} at iteration 0", header[i]);
        }
    }
    for name in ["alpha", "beta"] {
        let c = col(name);
        let (a, b): (f64, f64) = (
            rows_on[0][c].parse().expect("step"),
            rows_off[0][c].parse().expect("step"),
        );
        assert!(
            (a - b).abs() <= 1e-13 * b.abs(),
            "{name}: certified {a:e}, uncertified {b:e}"
        );
    }
}

#[test]
fn certified_steps_reach_sweeps_and_reproductions() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let file = tmp.path().join("sweep.toml");
    std::fs::write(
        &file,
        "presets = [\"lqg1d\"]\nseeds = [1]\nsigma0 = [1.0]\n[base]\niterations = 12\n\
         batch = 24\ncertified-steps = false\n[[variant]]\nname = \"zv\"\nalgo = \"sepg-zv\"\n\
         [[variant]]\nname = \"zv-certified\"\nalgo = \"sepg-zv\"\ncertified-steps = true\n",
    )
    .expect("write");
    let out = tmp.path().join("sweep");
    sepg_ok(&[
        "sweep",
        "--quiet",
        "--config",
        &file.display().to_string(),
        "--out",
        &out.display().to_string(),
    ]);
    let configs: Vec<String> = ["zv", "zv-certified"]
        .iter()
        .map(|v| read(&out.join(format!("runs/lqg1d/{v}/sigma-1.0/seed-1/config.toml"))))
        .collect();
    assert!(
        configs[0].contains("certified-steps = false"),
        "{}",
        configs[0]
    );
    assert!(
        configs[1].contains("certified-steps = true"),
        "{}",
        configs[1]
    );

    let rep = tmp.path().join("reproduce");
    sepg_ok(&[
        "reproduce",
        "fig-5.1",
        "--preset",
        "lqg1d",
        "--seeds",
        "1",
        "--iterations",
        "2",
        "--band",
        "none",
        "--quiet",
        "--certified-steps",
        "false",
        "--out",
        &rep.display().to_string(),
    ]);
    for variant in ["mi", "lb1"] {
        let dir = rep.join(format!("runs/lqg1d/{variant}/sigma-1.0/seed-0"));
        assert!(read(&dir.join("config.toml")).contains("certified-steps = false"));
        assert_eq!(summary_flag(&dir), serde_json::json!(false));
    }
}

#[test]
fn bad_certified_steps_values_are_one_line_errors() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("unused");
    let line = assert_usage_error(&sepg(
        &short_run(&out, &["--certified-steps", "maybe"])
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    ));
    assert!(line.contains("--certified-steps"), "{line}");
    let config = tmp.path().join("bad.toml");
    std::fs::write(&config, "certified-steps = \"no\"\n").expect("write");
    let line = assert_usage_error(&sepg(&[
        "run",
        "--config",
        &config.display().to_string(),
        "--out",
        &out.display().to_string(),
    ]));
    assert!(
        line.contains("bad.toml") && line.contains("boolean"),
        "{line}"
    );
    // the comparison algorithms take no safe steps to certify
    let line = assert_usage_error(&sepg(&[
        "run",
        "--algo",
        "adastep",
        "--certified-steps",
        "false",
        "--out",
        &out.display().to_string(),
    ]));
    assert!(
        line.contains("certified-steps") && line.contains("adastep"),
        "{line}"
    );
    assert!(!out.exists());
}
