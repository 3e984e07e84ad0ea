//! `sepg sweep --shard slurm` and the job-array script `scripts/slurm/sweep.sbatch`: the
//! script's shard tasks, run with the variables Slurm sets for each task of an array, and
//! its merge step give the same run folders as an unsharded sweep.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common::assert_usage_error;

/// Every variable by which Slurm describes a job array.
const SLURM_VARS: [&str; 4] = [
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_COUNT",
    "SLURM_ARRAY_TASK_MIN",
    "SLURM_ARRAY_TASK_STEP",
];

const SWEEP: &str = r#"
presets = ["lqg", "lqg1d"]
seeds = 2
sigma0 = [0.5, 1.0]
[base]
iterations = 10
batch = 20
[[variant]]
name = "zv"
algo = "sepg-zv"
[[variant]]
name = "lb2"
algo = "sepg-lb2"
"#;

/// `sepg` with `args` and the given Slurm variables (and no others), in `dir`.
fn sepg_in(dir: &Path, args: &[&str], slurm: &[(&str, String)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_sepg"));
    cmd.args(args).current_dir(dir);
    for v in SLURM_VARS {
        cmd.env_remove(v);
    }
    cmd.envs(slurm.iter().map(|(k, v)| (*k, v.as_str())));
    cmd.output().expect("sepg runs")
}

/// The job-array script with `args`, as Slurm would start it for one task.
fn sbatch_body(dir: &Path, args: &[&str], slurm: &[(&str, String)]) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/slurm/sweep.sbatch");
    let mut cmd = Command::new("bash");
    cmd.arg(script).args(args).current_dir(dir);
    for v in SLURM_VARS {
        cmd.env_remove(v);
    }
    let out = cmd
        .envs(slurm.iter().map(|(k, v)| (*k, v.as_str())))
        .env("SEPG", env!("CARGO_BIN_EXE_sepg"))
        .env("SLURM_CPUS_PER_TASK", "2")
        .output()
        .expect("bash runs");
    assert_eq!(
        out.status.code(),
        Some(0),
        "{args:?} {slurm:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).expect("read")).expect("json")
}

/// A JSON file without its wall-clock fields (the only ones that differ between machines).
fn without_timings(p: &Path) -> serde_json::Value {
    let mut v = json(p);
    let obj = v.as_object_mut().expect("object");
    for k in [
        "wall_time_s",
        "iterations_per_s",
        "env_steps_per_s",
        "elapsed_s",
    ] {
        obj.remove(k);
    }
    v
}

/// Names of the files of a run folder, sorted.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut names: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("run folder")
        .map(|e| PathBuf::from(e.expect("entry").file_name()))
        .collect();
    names.sort();
    names
}

#[test]
fn the_slurm_job_array_script_gives_the_unsharded_sweep() {
    let tmp = tempfile::tempdir().expect("tempdir");
    std::fs::write(tmp.path().join("sweep.toml"), SWEEP).expect("write");
    let out = sepg_in(
        tmp.path(),
        &[
            "sweep",
            "--quiet",
            "--config",
            "sweep.toml",
            "--out",
            "whole",
        ],
        &[],
    );
    assert_eq!(out.status.code(), Some(0), "{out:?}");
    // An array --array=1-3: ids 1, 2, 3, as Slurm numbers them, then the dependent merge job.
    for id in 1..=3 {
        let slurm = [
            ("SLURM_ARRAY_TASK_ID", id.to_string()),
            ("SLURM_ARRAY_TASK_COUNT", "3".to_owned()),
            ("SLURM_ARRAY_TASK_MIN", "1".to_owned()),
            ("SLURM_ARRAY_TASK_STEP", "1".to_owned()),
        ];
        sbatch_body(tmp.path(), &["shard", "sweep.toml", "results"], &slurm);
        let shard = json(
            &tmp.path()
                .join(format!("results.shards/shard-{}/sweep.json", id - 1)),
        );
        assert_eq!(shard["shard"]["index"], id - 1);
        assert_eq!(shard["shard"]["count"], 3);
    }
    sbatch_body(tmp.path(), &["merge", "sweep.toml", "results"], &[]);

    let (whole, merged) = (tmp.path().join("whole"), tmp.path().join("results"));
    let (w, m) = (
        json(&whole.join("sweep.json")),
        json(&merged.join("sweep.json")),
    );
    for key in ["sweep_id", "spec", "runs", "shard"] {
        assert_eq!(m[key], w[key], "sweep.json differs in {key}");
    }
    assert_eq!(m["merged_from"], 3);
    let runs = w["runs"].as_array().expect("runs");
    // 2 presets × 2 variants × 2 σ⁰ × 2 seeds.
    assert_eq!(runs.len(), 16);
    for r in runs {
        let dir = r["dir"].as_str().expect("dir");
        let (a, b) = (whole.join(dir), merged.join(dir));
        assert_eq!(files(&a), files(&b), "{dir}");
        for f in ["config.toml", "log.csv"] {
            let bytes = std::fs::read(a.join(f)).expect("read");
            assert_eq!(bytes, std::fs::read(b.join(f)).expect("read"), "{dir}/{f}");
        }
        for f in ["summary.json", "checkpoint.json"] {
            assert_eq!(
                without_timings(&a.join(f)),
                without_timings(&b.join(f)),
                "{dir}/{f}"
            );
        }
    }
}

#[test]
fn shard_slurm_outside_a_job_array_is_a_usage_error() {
    let tmp = tempfile::tempdir().expect("tempdir");
    std::fs::write(tmp.path().join("sweep.toml"), SWEEP).expect("write");
    let args = [
        "sweep",
        "--config",
        "sweep.toml",
        "--out",
        "s",
        "--shard",
        "slurm",
    ];
    let line = assert_usage_error(&sepg_in(tmp.path(), &args, &[]));
    assert!(line.contains("SLURM_ARRAY_TASK_ID is not set"), "{line}");
    let line = assert_usage_error(&sepg_in(
        tmp.path(),
        &args,
        &[
            ("SLURM_ARRAY_TASK_ID", "3".to_owned()),
            ("SLURM_ARRAY_TASK_COUNT", "3".to_owned()),
        ],
    ));
    assert!(line.contains("--array=0-2"), "{line}");
    assert!(!tmp.path().join("s").exists());
    // Inside an array the task's shard is the one run.
    let out = sepg_in(
        tmp.path(),
        &args,
        &[
            ("SLURM_ARRAY_TASK_ID", "1".to_owned()),
            ("SLURM_ARRAY_TASK_COUNT", "3".to_owned()),
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{out:?}");
    let file = json(&tmp.path().join("s/sweep.json"));
    assert_eq!(file["shard"]["index"], 1);
    assert_eq!(file["shard"]["count"], 3);
}
