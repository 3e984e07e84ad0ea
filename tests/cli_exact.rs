//! `sepg exact` and `sepg replay`: values against formulas derived here independently, and the
//! bad-input contract.

use crate::common::{assert_usage_error, close, get, json_ok, sepg};

/// Unclipped scalar LQG, infinite horizon, policy a ~ N(v s, σ²), s' = s + a, reward
/// −(q s² + r a²), s₀ ~ U[−b, b]: the value is −P s² − K with
/// P = (q + r v²)/(1 − γ(1 + v)²) and K = (r + γP)σ²/(1 − γ), so
/// J = −(b²/3)·P − K.
fn j_unclipped(q: f64, r: f64, b: f64, gamma: f64, v: f64, sigma: f64) -> f64 {
    let p = (q + r * v * v) / (1.0 - gamma * (1.0 + v) * (1.0 + v));
    let k = (r + gamma * p) * sigma * sigma / (1.0 - gamma);
    -(b * b / 3.0) * p - k
}

#[test]
fn optimal_values_of_both_presets() {
    let v_star = (1.0 - (1.0f64 + 4.0 * 0.99 * 0.99).sqrt()) / (2.0 * 0.99);
    assert!(close(v_star, -0.615_251_245_663_011, 1e-14));
    let vs = v_star.to_string();
    for (preset, expected) in [("lqg", -1.076_834), ("lqg1d", -7.753_206)] {
        let out = json_ok(&sepg(&[
            "exact", "--env", preset, "--v", &vs, "--sigma", "0", "--json",
        ]));
        assert!((get(&out, "j") - expected).abs() < 5e-7, "{preset}: {out}");
        assert!(get(&out, "grad_v").abs() < 1e-9, "v* is stationary: {out}");
        assert!(
            out.get("grad_w").is_none(),
            "no w-gradient for the deterministic policy"
        );
    }
}

#[test]
fn stochastic_closed_form_matches_value_and_finite_differences() {
    let (v, sigma) = (-0.4, 0.7);
    let out = json_ok(&sepg(&[
        "exact", "--env", "lqg", "--v", "-0.4", "--sigma", "0.7", "--json",
    ]));
    let j = |v: f64, s: f64| j_unclipped(0.5, 0.5, 2.0, 0.99, v, s);
    assert!(close(get(&out, "j"), j(v, sigma), 1e-10));
    let h = 1e-5;
    let dv = (j(v + h, sigma) - j(v - h, sigma)) / (2.0 * h);
    let ds = (j(v, sigma + h) - j(v, sigma - h)) / (2.0 * h);
    assert!(close(get(&out, "grad_v"), dv, 1e-7));
    assert!(close(get(&out, "grad_sigma"), ds, 1e-7));
    // ∂J/∂w = σ ∂J/∂σ.
    assert!(close(get(&out, "grad_w"), sigma * ds, 1e-7));
}

#[test]
fn clipped_model_by_dynamic_programming() {
    let clipped = json_ok(&sepg(&[
        "exact",
        "--env",
        "lqg",
        "--v",
        "-0.5",
        "--sigma",
        "0.3",
        "--clipped",
        "--horizon",
        "20",
        "--json",
    ]));
    assert_eq!(clipped["oracle"], "clipped-dp");
    // Clipping can only lose return relative to nothing: the clipped J is finite and below 0,
    // and with a = −0.5 s the closed loop contracts, so it stays close to the unclipped value.
    let unclipped = json_ok(&sepg(&[
        "exact",
        "--env",
        "lqg",
        "--v",
        "-0.5",
        "--sigma",
        "0.3",
        "--horizon",
        "20",
        "--json",
    ]));
    let (jc, ju) = (get(&clipped, "j"), get(&unclipped, "j"));
    assert!(
        jc < 0.0 && (jc - ju).abs() < 0.05 * ju.abs(),
        "{jc} vs {ju}"
    );
    assert!(get(&clipped, "mixed_wv").is_finite());
}

#[test]
fn replay_follows_the_gym_rules() {
    let out = json_ok(&sepg(&[
        "replay",
        "--env",
        "mountain-car",
        "--state",
        "0.44,0.02",
        "--actions",
        "0.5,1,1",
        "--json",
    ]));
    // One step by hand: vel' = vel + 0.0015·clip(a) − 0.0025·cos(3·pos); pos' = pos + vel'.
    let vel = 0.02 + 0.0015 * 0.5 - 0.0025 * (3.0f64 * 0.44).cos();
    let pos = 0.44 + vel;
    assert!(pos >= 0.45 && vel >= 0.0, "the first step reaches the goal");
    assert_eq!(out["terminated_at"].as_u64(), Some(0));
    assert_eq!(out["positions"][1].as_f64(), Some(pos));
    assert_eq!(out["velocities"][1].as_f64(), Some(vel));
    assert_eq!(out["rewards"].as_array().map(Vec::len), Some(1));
    assert!(close(
        out["rewards"][0].as_f64().unwrap_or(f64::NAN),
        100.0 - 0.1 * 0.25,
        1e-15
    ));

    // The left wall stops the car, and the reward uses the raw action.
    let out = json_ok(&sepg(&[
        "replay",
        "--env",
        "mountain-car",
        "--state",
        "-1.2,-0.01",
        "--actions",
        "-3",
        "--json",
    ]));
    assert_eq!(out["positions"][1].as_f64(), Some(-1.2));
    assert_eq!(out["velocities"][1].as_f64(), Some(0.0));
    assert!(close(
        out["rewards"][0].as_f64().unwrap_or(f64::NAN),
        -0.9,
        1e-15
    ));
    assert!(out["terminated_at"].is_null());
}

#[test]
fn bad_input_is_one_line_and_exit_2() {
    let cases: [&[&str]; 9] = [
        &["exact", "--env", "pendulum", "--v", "-0.5", "--sigma", "1"],
        &["exact", "--env", "lqg", "--v", "-0.5", "--sigma", "-1"],
        &[
            "exact",
            "--env",
            "lqg",
            "--v",
            "-0.5",
            "--sigma",
            "1",
            "--horizon",
            "0",
        ],
        &[
            "exact",
            "--env",
            "lqg",
            "--v",
            "-0.5",
            "--sigma",
            "1",
            "--clipped",
            "--horizon",
            "inf",
        ],
        &["exact", "--env", "lqg", "--v", "0.5", "--sigma", "1"],
        &["replay", "--env", "lqg", "--state", "0,0", "--actions", "1"],
        &[
            "replay",
            "--env",
            "mountain-car",
            "--state",
            "0",
            "--actions",
            "1",
        ],
        &[
            "replay",
            "--env",
            "mountain-car",
            "--state",
            "-0.5,0",
            "--actions",
            "1,,x",
        ],
        &[
            "replay",
            "--env",
            "mountain-car",
            "--state",
            "3,0",
            "--actions",
            "1",
        ],
    ];
    for args in cases {
        let line = assert_usage_error(&sepg(args));
        assert!(line.starts_with("sepg: error:"), "{args:?}: {line}");
    }
}

/// `sepg estimate` on the clipped `lqg` preset against the clipped-LQG dynamic programme
/// (`sepg exact --clipped`): each 95% half-width h gives a standard error h/1.96; every
/// component must lie within 4.5 standard errors of the exact value (two-sided false-alarm
/// rate 6.8e-6 per component, 2.1e-5 for the three together by Bonferroni).
#[test]
fn estimate_agrees_with_the_exact_clipped_oracle() {
    let exact = json_ok(&sepg(&[
        "exact",
        "--env",
        "lqg",
        "--v",
        "-0.4",
        "--sigma",
        "0.6",
        "--clipped",
        "--horizon",
        "20",
        "--json",
    ]));
    let est = json_ok(&sepg(&[
        "estimate",
        "--env",
        "lqg",
        "--v",
        "-0.4",
        "--sigma",
        "0.6",
        "--horizon",
        "20",
        "--n",
        "20000",
        "--seed",
        "7",
        "--json",
    ]));
    for (key, exact_key) in [("j", "j"), ("grad_v", "grad_v"), ("grad_w", "grad_w")] {
        let mean = est[key]["mean"].as_f64().expect("mean");
        let lo = est[key]["ci95"][0].as_f64().expect("ci low");
        let hi = est[key]["ci95"][1].as_f64().expect("ci high");
        let se = (hi - lo) / 2.0 / 1.959_963_984_540_054;
        let truth = get(&exact, exact_key);
        assert!(
            (mean - truth).abs() <= 4.5 * se,
            "{key}: {mean} ± {se} vs exact {truth}"
        );
    }
    assert!(get(&est, "steps_per_sec") > 0.0);
    assert_eq!(est["steps"].as_u64(), Some(400_000));
}

#[test]
fn estimate_is_reproducible_and_rejects_bad_input() {
    let args = [
        "estimate",
        "--env",
        "mountain-car",
        "--v",
        "0,0.5,0",
        "--sigma",
        "1",
        "--horizon",
        "50",
        "--n",
        "10",
        "--seed",
        "3",
        "--json",
    ];
    let (a, b) = (json_ok(&sepg(&args)), json_ok(&sepg(&args)));
    assert_eq!(a["j"], b["j"]);
    assert_eq!(a["grad_v"], b["grad_v"]);
    assert_eq!(a["grad_v"]["mean"].as_array().map(Vec::len), Some(3));

    let cases: [&[&str]; 6] = [
        &[
            "estimate",
            "--env",
            "cartpole",
            "--v",
            "0",
            "--sigma",
            "1",
            "--horizon",
            "5",
            "--n",
            "4",
            "--seed",
            "1",
        ],
        &[
            "estimate",
            "--env",
            "lqg",
            "--v",
            "0",
            "--sigma",
            "-1",
            "--horizon",
            "5",
            "--n",
            "4",
            "--seed",
            "1",
        ],
        &[
            "estimate",
            "--env",
            "lqg",
            "--v",
            "0",
            "--sigma",
            "1",
            "--horizon",
            "0",
            "--n",
            "4",
            "--seed",
            "1",
        ],
        &[
            "estimate",
            "--env",
            "lqg",
            "--v",
            "0",
            "--sigma",
            "1",
            "--horizon",
            "5",
            "--n",
            "1",
            "--seed",
            "1",
        ],
        &[
            "estimate",
            "--env",
            "lqg",
            "--v",
            "0,1",
            "--sigma",
            "1",
            "--horizon",
            "5",
            "--n",
            "4",
            "--seed",
            "1",
        ],
        &[
            "estimate",
            "--env",
            "lqg",
            "--v",
            "zero",
            "--sigma",
            "1",
            "--horizon",
            "5",
            "--n",
            "4",
            "--seed",
            "1",
        ],
    ];
    for args in cases {
        let line = assert_usage_error(&sepg(args));
        assert!(line.starts_with("sepg: error:"), "{args:?}: {line}");
    }
}

/// Output files are written atomically with the permissions of an ordinary file (0644 less
/// the umask), not the 0600 of a private temporary file.
#[cfg(unix)]
#[test]
fn report_files_have_ordinary_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().expect("temporary folder");
    let report = dir.path().join("report.md");
    let out = sepg(&[
        "verify",
        "--quick",
        "--quiet",
        "--check",
        "thm-3.3",
        "--out",
        report.to_str().expect("utf-8 path"),
    ]);
    assert_eq!(out.status.code(), Some(0));
    let reference = dir.path().join("reference");
    std::fs::write(&reference, b"x").expect("write");
    let mode = |p: &std::path::Path| std::fs::metadata(p).expect("metadata").permissions().mode();
    assert_eq!(mode(&report) & 0o777, mode(&reference) & 0o644);
    let text = std::fs::read_to_string(&report).expect("report");
    assert!(text.contains("thm-3.3-performance-difference"));
}

/// `sepg estimate` streams its trajectories in work items merged in a fixed order: the
/// estimates are the same bits with one and with three rayon threads, for N not a multiple of
/// the work item (1024) and across two rounds of 64 work items.
#[test]
fn estimate_is_identical_for_any_thread_count() {
    let run = |threads: &str| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_sepg"))
            .args([
                "estimate",
                "--env",
                "lqg1d",
                "--v",
                "-0.3",
                "--sigma",
                "0.5",
                "--horizon",
                "5",
                "--n",
                "70001",
                "--seed",
                "4",
                "--json",
            ])
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .expect("the sepg binary runs");
        let mut v = json_ok(&out);
        v.as_object_mut().expect("object").remove("steps_per_sec");
        v
    };
    assert_eq!(run("1"), run("3"));
}
