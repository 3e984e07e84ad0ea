//! `sepg run` checks the declared constants against the rewards it samples
//! (docs/RELIABILITY.md, "Declared constants checked against the data"): an `--r-max` below the
//! true reward bound stops the run at the first reward beyond it (or, with
//! `--on-contradiction continue`, marks it "no guarantee"), and `sepg audit` never calls such
//! a run safe.

use std::path::Path;

use sepg_mdp::rng::{SeedKey, standard_normal, uniform};

use crate::common::{sepg, sepg_ok};

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).expect("file")).expect("json")
}

/// The LQG1d run of the README (seed 1, σ⁰ = 1, N = 100, H = 20) from v⁰ = `v0` with `extra`.
fn lqg1d(out: &Path, v0: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "run",
        "--env",
        "lqg1d",
        "--algo",
        "sepg-zv",
        "--v0",
        v0,
        "--sigma0",
        "1.0",
        "--iterations",
        "3",
        "--batch",
        "100",
        "--horizon",
        "20",
        "--seed",
        "1",
        "--quiet",
    ];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--out", out.to_str().expect("utf-8 path")]);
    sepg(&args)
}

/// The rewards of trajectory `i` of the v-block of iteration 0 (seed 1, v = −0.1, σ = 1,
/// H = 20) of lqg1d, computed from its definition (docs/CONVENTIONS.md §1): s₀ ~ U[−4, 4],
/// a_t = v s_t + σ z_t, r_t = −0.9 (s_t² + clip(a_t)²), s_{t+1} = clip(s_t + clip(a_t)), every
/// clip to [−4, 4], with the trajectory's own streams of the seed key (1, 0, v-block).
fn lqg1d_rewards(i: u64) -> Vec<f64> {
    let mut rngs = SeedKey::new(1, 0, 0).rngs(i);
    let mut s = uniform(&mut rngs.env, -4.0, 4.0);
    (0..20)
        .map(|_| {
            let a = -0.1 * s + standard_normal(&mut rngs.policy);
            let ac = a.clamp(-4.0, 4.0);
            let r = -(s * (0.9 * s) + ac * (0.9 * ac));
            s = (s + ac).clamp(-4.0, 4.0);
            r
        })
        .collect()
}

fn audit_line(dir: &Path) -> String {
    let out = sepg(&["audit", dir.to_str().expect("utf-8 path")]);
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn an_r_max_below_the_true_bound_stops_at_the_first_reward_beyond_it() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("stopped");
    let out = lqg1d(&dir, "-0.1", &["--r-max", "5"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("constants contradicted") && stderr.contains("exceeds r-max = 5"));

    let summary = json(&dir.join("summary.json"));
    assert_eq!(summary["status"], "stopped");
    assert_eq!(summary["iterations"], 0);
    assert_eq!(summary["statement"]["kind"], "none");
    let reason = summary["statement"]["reasons"][0].as_str().expect("reason");
    assert!(
        reason.starts_with("constants contradicted: no guarantee"),
        "{reason}"
    );
    let check = &summary["constants_check"];
    let first = &check["first"];
    assert_eq!(
        (check["r_max"].as_u64(), first["what"].as_str()),
        (Some(1), Some("r-max"))
    );
    assert_eq!(
        (first["iteration"].as_u64(), first["block"].as_str()),
        (Some(0), Some("v"))
    );
    // The first offending reward is the first |r| > 5 in trajectory order, and its value is the
    // reward of the LQG formula there (within the two roundings of γᵗ r / γᵗ).
    let (i, t) = (
        first["trajectory"].as_u64().expect("i"),
        first["step"].as_u64().expect("t"),
    );
    for j in 0..i {
        assert!(
            lqg1d_rewards(j).iter().all(|r| r.abs() <= 5.0),
            "trajectory {j}"
        );
    }
    let rewards = lqg1d_rewards(i);
    assert!(rewards[..t as usize].iter().all(|r| r.abs() <= 5.0));
    let (value, expected) = (first["value"].as_f64().expect("value"), rewards[t as usize]);
    assert!(expected.abs() > 5.0);
    assert!(
        (value - expected).abs() <= 4.0 * f64::EPSILON * expected.abs(),
        "{value} vs {expected}"
    );

    // The folder is consistent: the checkpoint holds the state before iteration 0 with the
    // offence counted, resuming refuses, and the audit states no guarantee.
    let ck = json(&dir.join("checkpoint.json"));
    assert_eq!(ck["state"]["iteration"], 0);
    assert_eq!(ck["state"]["constants_check"]["first"], *first);
    let resumed = sepg(&["run", "--resume", dir.to_str().expect("utf-8"), "--quiet"]);
    assert_eq!(resumed.status.code(), Some(1));
    let audit = audit_line(&dir);
    assert!(
        audit
            .contains("no-guarantee: the run states nothing about exact J: constants contradicted"),
        "{audit}"
    );
    assert!(!audit.contains("holds"), "{audit}");
}

#[test]
fn continue_runs_on_without_a_guarantee_and_the_audit_says_so() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("continued");
    let out = lqg1d(
        &dir,
        "-0.1",
        &["--r-max", "5", "--on-contradiction", "continue"],
    );
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let config = std::fs::read_to_string(dir.join("config.toml")).expect("config");
    assert!(
        config.contains("on-contradiction = \"continue\""),
        "{config}"
    );
    let summary = json(&dir.join("summary.json"));
    assert_eq!(
        (summary["status"].as_str(), summary["iterations"].as_u64()),
        (Some("complete"), Some(3))
    );
    assert_eq!(summary["statement"]["kind"], "none");
    let check = &summary["constants_check"];
    let (bad, seen) = (
        check["r_max"].as_u64().expect("count"),
        check["rewards_checked"].as_u64().expect("seen"),
    );
    assert!(bad > 0 && bad < seen, "{check}");
    // the same first offence as the run that stopped
    let stopped = tmp.path().join("stopped");
    lqg1d(&stopped, "-0.1", &["--r-max", "5"]);
    assert_eq!(
        check["first"],
        json(&stopped.join("summary.json"))["constants_check"]["first"]
    );
    let audit = audit_line(&dir);
    assert!(
        audit.contains("no-guarantee") && !audit.contains("holds"),
        "{audit}"
    );
    // An unfinished folder (no summary yet) is judged by its checkpoint's check, not by the
    // statement its configuration would give.
    std::fs::remove_file(dir.join("summary.json")).expect("remove");
    std::fs::rename(dir.join("log.csv"), dir.join("log.partial.csv")).expect("rename");
    let audit = audit_line(&dir);
    assert!(
        audit
            .contains("no-guarantee: the run states nothing about exact J: constants contradicted"),
        "{audit}"
    );
}

#[test]
fn the_presets_own_constants_are_never_contradicted_even_at_the_box_corners() {
    // v = 1 drives the state to the corner ±4 of the box and the clipped action to ±4, where
    // the reward is −28.8 = −R_max: no false alarm at the bound.
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("corners");
    let out = lqg1d(&dir, "1.0", &[]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let check = json(&dir.join("summary.json"))["constants_check"].clone();
    assert!(check["rewards_checked"].as_u64().expect("seen") > 0);
    assert_eq!(
        (check["r_max"].as_u64(), check["first"].is_null()),
        (Some(0), true),
        "{check}"
    );
}

#[test]
fn mountain_car_contradicts_its_r_max_only_with_actions_beyond_31_6() {
    // Its reward 100·[goal] − 0.1 a² uses the raw action: |r| > 100 exactly when
    // 0.1 a² > 100 (a reward at the goal is at most 100). With σ = 40 most actions are that
    // large; the first offending value must then be −0.1 a² < −100.
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("mc");
    let out = sepg(&[
        "run",
        "--env",
        "mountain-car",
        "--algo",
        "sepg-zv",
        "--sigma0",
        "40",
        "--iterations",
        "1",
        "--batch",
        "30",
        "--horizon",
        "20",
        "--seed",
        "2",
        "--quiet",
        "--out",
        dir.to_str().expect("utf-8"),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let first = json(&dir.join("summary.json"))["constants_check"]["first"].clone();
    assert_eq!(first["what"], "r-max");
    assert!(first["value"].as_f64().expect("value") < -100.0, "{first}");
    // σ = 1 (|a| > 31.6 has probability below 1e-200): the default run is never stopped.
    let ok = tmp.path().join("mc-ok");
    sepg_ok(&[
        "run",
        "--env",
        "mountain-car",
        "--algo",
        "sepg-zv",
        "--iterations",
        "2",
        "--batch",
        "30",
        "--horizon",
        "50",
        "--seed",
        "2",
        "--quiet",
        "--out",
        ok.to_str().expect("utf-8"),
    ]);
    let check = json(&ok.join("summary.json"))["constants_check"].clone();
    assert_eq!(
        (check["r_max"].as_u64(), check["first"].is_null()),
        (Some(0), true),
        "{check}"
    );
}
