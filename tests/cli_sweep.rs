//! `sepg sweep` and `sepg merge`: shards merged equal the unsharded sweep byte for byte,
//! logs do not depend on the thread count, and bad sweeps or shard sets are rejected.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{assert_usage_error, sepg};

const SWEEP: &str = r#"
presets = ["lqg", "lqg1d"]
seeds = [3, 4]
sigma0 = [0.5, 1.0]
[base]
iterations = 12
batch = 24
[[variant]]
name = "zv"
algo = "sepg-zv"
[[variant]]
name = "adam"
algo = "gpomdp-adam"
lr = 1e-3
"#;

fn sweep_file(dir: &Path, text: &str) -> PathBuf {
    let p = dir.join("sweep.toml");
    std::fs::write(&p, text).expect("write");
    p
}

fn sweep_into(cfg: &Path, out: &Path, extra: &[&str], threads: &str) {
    let out = Command::new(env!("CARGO_BIN_EXE_sepg"))
        .args(["sweep", "--quiet", "--config"])
        .arg(cfg)
        .arg("--out")
        .arg(out)
        .args(extra)
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .expect("sweep");
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).expect("read")).expect("json")
}

/// `log.csv` of every run, by run folder.
fn logs(sweep: &Path) -> Vec<(String, Vec<u8>)> {
    json(&sweep.join("sweep.json"))["runs"]
        .as_array()
        .expect("runs")
        .iter()
        .map(|r| {
            let dir = r["dir"].as_str().expect("dir").to_owned();
            let log = std::fs::read(sweep.join(&dir).join("log.csv")).expect("log");
            (dir, log)
        })
        .collect()
}

#[test]
fn merged_shards_equal_the_unsharded_sweep_whatever_the_thread_count() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let cfg = sweep_file(tmp.path(), SWEEP);
    let one = tmp.path().join("one");
    let two = tmp.path().join("two");
    sweep_into(&cfg, &one, &[], "1");
    sweep_into(&cfg, &two, &[], "2");
    let reference = logs(&one);
    // 2 presets × 2 variants × 2 σ⁰ × 2 seeds, each log with a header and 12 rows.
    assert_eq!(reference.len(), 16);
    assert!(
        reference
            .iter()
            .all(|(_, l)| l.iter().filter(|&&b| b == b'\n').count() == 13)
    );
    assert_eq!(logs(&two), reference, "logs differ between 1 and 2 threads");
    let shards: Vec<PathBuf> = (0..3)
        .map(|i| tmp.path().join(format!("shard-{i}")))
        .collect();
    for (i, s) in shards.iter().enumerate() {
        sweep_into(&cfg, s, &["--shard", &format!("{i}/3")], "2");
        let file = json(&s.join("sweep.json"));
        assert_eq!(file["shard"]["count"], 3);
        // A shard holds exactly the runs whose index mod 3 is its index.
        for r in file["runs"].as_array().expect("runs") {
            let index = r["index"].as_u64().expect("index") as usize;
            assert_eq!(
                s.join(r["dir"].as_str().expect("dir")).exists(),
                index % 3 == i
            );
        }
    }
    let merged = tmp.path().join("merged");
    let mut args = vec![
        "merge".to_owned(),
        "--quiet".into(),
        "--out".into(),
        merged.display().to_string(),
    ];
    args.extend(shards.iter().rev().map(|s| s.display().to_string()));
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = sepg(&refs);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(logs(&merged), reference);
    let (m, u) = (
        json(&merged.join("sweep.json")),
        json(&one.join("sweep.json")),
    );
    assert_eq!(m["sweep_id"], u["sweep_id"]);
    assert_eq!(m["runs"], u["runs"]);
    assert_eq!(m["shard"], u["shard"]);
    assert_eq!(m["merged_from"], 3);
    // The merged summary.csv is the unsharded one, byte for byte, and each shard's lists its
    // own runs only.
    let table = std::fs::read_to_string(one.join("summary.csv")).expect("summary.csv");
    assert_eq!(
        std::fs::read_to_string(merged.join("summary.csv")).expect("summary.csv"),
        table
    );
    let shard_rows: usize = shards
        .iter()
        .map(|s| {
            std::fs::read_to_string(s.join("summary.csv"))
                .expect("summary.csv")
                .lines()
                .count()
                - 1
        })
        .sum();
    assert_eq!(shard_rows, 16);
    assert!(
        table.lines().skip(1).all(|l| l.ends_with(",not-audited")),
        "{table}"
    );
    // `sepg audit` on the sweep folder fills in the audit column.
    let out = sepg(&["audit", one.to_str().expect("utf-8")]);
    let table = std::fs::read_to_string(one.join("summary.csv")).expect("summary.csv");
    summary_csv_matches_the_runs(&one, &table);
    let groups = std::fs::read_to_string(one.join("audit-groups.csv")).expect("groups");
    let expected = if groups.contains(",rejected") { 1 } else { 0 };
    assert_eq!(out.status.code(), Some(expected), "{table}");

    // Merging an incomplete set of shards, or one shard twice, is refused.
    let out_bad = tmp.path().join("bad");
    let (s0, s1) = (
        shards[0].to_str().expect("utf-8"),
        shards[1].to_str().expect("utf-8"),
    );
    let o = out_bad.to_str().expect("utf-8");
    let line = assert_usage_error(&sepg(&["merge", "--out", o, s0, s1]));
    assert!(
        line.contains("missing shard") && line.contains("2/3"),
        "{line}"
    );
    assert_usage_error(&sepg(&["merge", "--out", o, s0, s0, s1]));
    // A shard of another sweep is refused.
    let other_cfg = tmp.path().join("other");
    std::fs::create_dir(&other_cfg).expect("mkdir");
    let other_cfg = sweep_file(
        &other_cfg,
        &SWEEP.replace("seeds = [3, 4]", "seeds = [3, 5]"),
    );
    let other = tmp.path().join("other-shard");
    sweep_into(&other_cfg, &other, &["--shard", "2/3"], "2");
    let line = assert_usage_error(&sepg(&[
        "merge",
        "--out",
        o,
        s0,
        s1,
        other.to_str().expect("utf-8"),
    ]));
    assert!(line.contains("same sweep"), "{line}");
    assert!(!out_bad.exists());
}

#[test]
fn bad_sweeps_are_rejected_before_anything_is_written() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("out");
    let o = out.to_str().expect("utf-8");
    let cases = [
        (
            "axis",
            SWEEP.replace("lr = 1e-3", "lr = 1e-3\nseed = 3"),
            "sweep axes",
        ),
        (
            "unknown",
            SWEEP.replace("[base]", "bogus = 1\n[base]"),
            "bogus",
        ),
        (
            "duplicate",
            SWEEP.replace("name = \"adam\"", "name = \"zv\""),
            "twice",
        ),
        (
            "sigma",
            SWEEP.replace("sigma0 = [0.5, 1.0]", "sigma0 = [0.5, -1.0]"),
            "sigma0",
        ),
        ("batch", SWEEP.replace("batch = 24", "batch = 1"), "batch"),
    ];
    for (name, text, needle) in cases {
        let dir = tmp.path().join(name);
        std::fs::create_dir(&dir).expect("mkdir");
        let cfg = sweep_file(&dir, &text);
        let line = assert_usage_error(&sepg(&[
            "sweep",
            "--config",
            cfg.to_str().expect("utf-8"),
            "--out",
            o,
        ]));
        assert!(line.contains(needle), "{name}: {line}");
        assert!(!out.exists(), "{name}");
    }
    let cfg = sweep_file(tmp.path(), SWEEP);
    let c = cfg.to_str().expect("utf-8");
    for shard in ["3/3", "1", "a/2", "0/0"] {
        assert_usage_error(&sepg(&[
            "sweep", "--config", c, "--out", o, "--shard", shard,
        ]));
    }
    assert_usage_error(&sepg(&[
        "sweep",
        "--config",
        "/nonexistent.toml",
        "--out",
        o,
    ]));
    assert!(!out.exists());
}

#[test]
fn an_interrupted_sweep_resumes_to_the_same_logs() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let cfg = sweep_file(tmp.path(), SWEEP);
    let reference = tmp.path().join("reference");
    sweep_into(&cfg, &reference, &[], "2");
    let dir = tmp.path().join("resumed");
    sweep_into(&cfg, &dir, &[], "2");
    // Simulate runs killed at different points: one never started, one mid-run.
    let runs = json(&dir.join("sweep.json"))["runs"]
        .as_array()
        .expect("runs")
        .clone();
    let gone = dir.join(runs[0]["dir"].as_str().expect("dir"));
    std::fs::remove_dir_all(&gone).expect("remove");
    let cut = dir.join(runs[5]["dir"].as_str().expect("dir"));
    std::fs::remove_file(cut.join("summary.json")).expect("remove");
    std::fs::rename(cut.join("log.csv"), cut.join("log.partial.csv")).expect("rename");
    // Garbage after the checkpointed length is discarded on resume.
    let mut partial = std::fs::read(cut.join("log.partial.csv")).expect("read");
    partial.extend_from_slice(b"12,torn row");
    std::fs::write(cut.join("log.partial.csv"), partial).expect("write");
    let out = sepg(&["sweep", "--quiet", "--resume", dir.to_str().expect("utf-8")]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(logs(&dir), logs(&reference));
    // Resuming the completed sweep runs nothing, and says so rather than report a speed.
    let d = dir.to_str().expect("utf-8");
    let again = sepg(&["sweep", "--resume", d]);
    assert_eq!(again.status.code(), Some(0));
    let line = String::from_utf8(again.stdout).expect("utf-8");
    assert_eq!(
        line.trim(),
        format!("{d}: no run left to run ({} complete)", runs.len())
    );
}

#[test]
fn a_terminated_sweep_names_the_sweep_resume_command() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let cfg = sweep_file(
        tmp.path(),
        r#"
presets = ["lqg1d"]
seeds = [1, 2]
sigma0 = [1.0]
[base]
iterations = 1000000
batch = 24
[[variant]]
name = "zv"
algo = "sepg-zv"
"#,
    );
    let dir = tmp.path().join("sweep");
    let child = Command::new(env!("CARGO_BIN_EXE_sepg"))
        .args(["sweep", "--quiet", "--config"])
        .arg(&cfg)
        .arg("--out")
        .arg(&dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    // sweep.json is written after the signal handler is installed.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    while !dir.join("sweep.json").exists() && std::time::Instant::now() < deadline {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
    let status = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(status.success());
    let out = child.wait_with_output().expect("wait");
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8(out.stderr).expect("utf-8");
    assert_eq!(err.lines().count(), 1, "{err}");
    let expected = format!("sepg sweep --resume {}", dir.display());
    assert!(err.contains(&expected), "{err}");
    assert!(err.contains("0 of 2 runs complete"), "{err}");
    assert!(!err.contains("sepg run --resume"), "{err}");
}

/// Checks each row of a sweep's `summary.csv` against the run it describes: settings from
/// `sweep.json`, outcome from the run's `summary.json`, verdict from `sepg audit`.
fn summary_csv_matches_the_runs(sweep: &Path, table: &str) {
    let mut lines = table.lines();
    assert_eq!(
        lines.next(),
        Some("preset,variant,algorithm,sigma0,seed,v,sigma,j,abs_v_error,infeasible,audit")
    );
    let runs = json(&sweep.join("sweep.json"))["runs"]
        .as_array()
        .expect("runs")
        .clone();
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), runs.len());
    for (row, run) in rows.iter().zip(&runs) {
        let cells: Vec<&str> = row.split(',').collect();
        assert_eq!(cells.len(), 11, "{row}");
        let dir = sweep.join(run["dir"].as_str().expect("dir"));
        let summary = json(&dir.join("summary.json"));
        let number = |s: &str| s.parse::<f64>().expect("number");
        assert_eq!(cells[0], run["preset"].as_str().expect("preset"));
        assert_eq!(cells[1], run["variant"].as_str().expect("variant"));
        let algo = if cells[1] == "zv" {
            "sepg-zv"
        } else {
            "gpomdp-adam"
        };
        assert_eq!(cells[2], algo);
        assert_eq!(number(cells[3]), run["sigma0"].as_f64().expect("sigma0"));
        assert_eq!(cells[4], run["seed"].to_string());
        assert_eq!(
            number(cells[5]),
            summary["final"]["v"][0].as_f64().expect("v")
        );
        assert_eq!(
            number(cells[6]),
            summary["final"]["sigma"][0].as_f64().expect("sigma")
        );
        assert_eq!(
            number(cells[7]),
            summary["last_j_explore"].as_f64().expect("j")
        );
        assert_eq!(
            number(cells[8]),
            summary["abs_v_error"].as_f64().expect("error")
        );
        assert_eq!(cells[9], summary["infeasible_iterations"].to_string());
        let audit = sepg(&["audit", "--json", dir.to_str().expect("utf-8")]);
        let report: serde_json::Value = serde_json::from_slice(&audit.stdout).expect("json");
        assert_eq!(
            cells[10],
            report["verdict"].as_str().expect("verdict"),
            "{row}"
        );
    }
}

/// `sepg sweep --constants` replaces the family of every run, the file's key included; without
/// it a run takes the file's key, else tight.
#[test]
fn the_constants_flag_sets_every_run_of_the_sweep() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let cfg = sweep_file(
        tmp.path(),
        r#"
presets = ["lqg1d"]
seeds = 1
sigma0 = [1.0]
[base]
iterations = 2
batch = 12
[[variant]]
name = "zv"
algo = "sepg-zv"
[[variant]]
name = "mi-thesis"
algo = "sepg-mi"
constants = "thesis"
"#,
    );
    let family = |sweep: &Path, variant: &str| {
        let run = sweep.join(format!("runs/lqg1d/{variant}/sigma-1.0/seed-0"));
        json(&run.join("summary.json"))["constants"]["family"]
            .as_str()
            .expect("family")
            .to_owned()
    };
    let plain = tmp.path().join("plain");
    sweep_into(&cfg, &plain, &[], "1");
    assert_eq!(family(&plain, "zv"), "tight");
    assert_eq!(family(&plain, "mi-thesis"), "thesis");
    let thesis = tmp.path().join("thesis");
    sweep_into(&cfg, &thesis, &["--constants", "thesis"], "1");
    assert_eq!(family(&thesis, "zv"), "thesis");
    let tight = tmp.path().join("tight");
    sweep_into(&cfg, &tight, &["--constants", "tight"], "1");
    assert_eq!(family(&tight, "mi-thesis"), "tight");
    let line = assert_usage_error(&sepg(&[
        "sweep",
        "--resume",
        tight.to_str().expect("utf-8"),
        "--constants",
        "thesis",
    ]));
    assert!(line.contains("--resume"), "{line}");
}

/// Safe Adam in a sweep file: the variant's keys reach its run (recorded in summary.json), and
/// `sepg sweep --constants thesis` over it is refused with one line and exit status 2.
#[test]
fn a_sweep_variant_takes_the_adam_v_direction() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let cfg = sweep_file(
        tmp.path(),
        r#"
presets = ["lqg1d"]
seeds = 1
sigma0 = [1.0]
[base]
iterations = 3
batch = 12
[[variant]]
name = "mi-adam"
algo = "sepg-mi"
v-direction = "adam"
adam-lr = 0.05
adam-beta1 = 0.5
"#,
    );
    let out = tmp.path().join("sweep");
    sweep_into(&cfg, &out, &[], "1");
    let run = out.join("runs/lqg1d/mi-adam/sigma-1.0/seed-0");
    let adam = &json(&run.join("summary.json"))["options"]["v_direction"]["adam"];
    assert_eq!(adam["lr"], 0.05);
    assert_eq!(adam["beta1"], 0.5);
    assert_eq!(adam["beta2"], 0.999);
    let thesis = tmp.path().join("thesis");
    let line = assert_usage_error(&sepg(&[
        "sweep",
        "--quiet",
        "--config",
        cfg.to_str().expect("utf-8"),
        "--out",
        thesis.to_str().expect("utf-8"),
        "--constants",
        "thesis",
    ]));
    assert!(line.contains("v-direction"), "{line}");
}
