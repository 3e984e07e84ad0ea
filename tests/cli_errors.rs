//! Command-line errors keep the parser's detail in one line, negative numbers reach the
//! validation of their flag, and `estimate --sigma 0` estimates the deterministic J.
//!
//! Cost: one estimate of 4,000 trajectories of 20 steps; the rest fail at parsing.

use crate::common::{assert_usage_error, get, json_ok, sepg, with_out};

#[test]
fn a_missing_flag_is_named() {
    let line = assert_usage_error(&sepg(&["bounds"]));
    for flag in [
        "--gamma",
        "--r-max",
        "--m-phi",
        "--action-volume",
        "--sigma",
    ] {
        assert!(line.contains(flag), "{flag} in {line}");
    }
    let line = assert_usage_error(&sepg(&["bounds", "--gamma", "0.9", "--r-max", "1"]));
    assert!(
        line.contains("--m-phi") && !line.contains("--gamma"),
        "{line}"
    );
}

#[test]
fn an_invalid_choice_lists_the_valid_values() {
    let line = assert_usage_error(&sepg(&["run", "--algo", "ppo", "--out", "unused"]));
    assert!(line.contains("'ppo'"), "{line}");
    for algo in ["sepg-mi", "sepg-zv", "gpomdp-adam", "adastep"] {
        assert!(line.contains(algo), "{algo} in {line}");
    }
    // A flag without its value names the flag and the values it takes.
    let line = assert_usage_error(&sepg(&["run", "--env"]));
    assert!(
        line.contains("--env") && line.contains("mountain-car"),
        "{line}"
    );
    // An unknown flag keeps clap's suggestion.
    let line = assert_usage_error(&sepg(&["run", "--forc"]));
    assert!(
        line.contains("--forc") && line.contains("--force"),
        "{line}"
    );
}

#[test]
fn a_negative_seed_is_refused_with_the_reason() {
    for args in [
        &["run", "--seed", "-1", "--out", "unused"][..],
        &["verify", "--quick", "--seed", "-1"],
        &[
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
            "10",
            "--seed",
            "-1",
        ],
    ] {
        let line = assert_usage_error(&sepg(args));
        assert!(
            line.contains("'-1'") && line.contains("non-negative") && line.contains("negative"),
            "{args:?}: {line}"
        );
        assert!(!line.contains("unexpected argument"), "{line}");
    }
    let line = assert_usage_error(&sepg(&["run", "--seed", "1.5", "--out", "unused"]));
    assert!(line.contains("not an integer"), "{line}");
}

#[test]
fn negative_numbers_reach_the_validation_of_their_flag() {
    // σ⁰ < 0 is parsed, then refused by the run's validation, naming σ⁰.
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("fig");
    let line = assert_usage_error(&sepg(&[
        "reproduce",
        "fig-5.1",
        "--fig-sigma0",
        "-1",
        "--iterations",
        "1",
        "--seeds",
        "1",
        "--quiet",
        "--out",
        out.to_str().expect("utf-8"),
    ]));
    assert!(line.contains("sigma0") && line.contains("-1"), "{line}");
    // A negative count is an invalid value of that flag, not an unknown argument.
    for (flag, cmd) in [
        ("--batch", "run"),
        ("--iterations", "run"),
        ("--seeds", "reproduce"),
    ] {
        let args: Vec<&str> = if cmd == "run" {
            vec!["run", flag, "-5", "--out", "unused"]
        } else {
            vec!["reproduce", "table-5.1", flag, "-5"]
        };
        let line = assert_usage_error(&sepg(&args));
        assert!(line.contains("'-5'") && line.contains(flag), "{line}");
    }
}

#[test]
fn estimate_with_sigma_zero_estimates_the_deterministic_j() {
    let exact = json_ok(&sepg(&[
        "exact",
        "--env",
        "lqg1d",
        "--v",
        "-0.3",
        "--sigma",
        "0",
        "--horizon",
        "20",
        "--json",
    ]));
    let j_exact = get(&exact, "j");
    let est = json_ok(&sepg(&[
        "estimate",
        "--env",
        "lqg1d",
        "--v",
        "-0.3",
        "--sigma",
        "0",
        "--horizon",
        "20",
        "--n",
        "4000",
        "--seed",
        "3",
        "--json",
    ]));
    assert!(
        est.get("grad_v").is_none() && est.get("grad_w").is_none(),
        "{est}"
    );
    let mean = get(&est["j"], "mean");
    let ci = est["j"]["ci95"].as_array().expect("ci95");
    let (lo, hi) = (ci[0].as_f64().expect("lo"), ci[1].as_f64().expect("hi"));
    assert!(lo < mean && mean < hi, "{est}");
    // The half-width is t(0.975, 3999)·SE ≈ 1.96·SE; the exact J lies within 4 SE of the mean
    // except with probability 6e-5 (normal approximation of the mean of 4,000 returns).
    let se = (hi - lo) / 2.0 / 1.9606;
    assert!(
        (mean - j_exact).abs() <= 4.0 * se,
        "mean {mean}, exact {j_exact}, se {se}"
    );
}

/// `sepg run` with `extra` options (a one-iteration lqg1d run by default) into `out`.
fn run_into(out: &std::path::Path, extra: &[&str]) -> std::process::Output {
    let out = out.display().to_string();
    let mut args = vec!["run", "--env", "lqg1d", "--iterations", "1", "--quiet"];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--out", &out]);
    sepg(&args)
}

#[test]
fn a_batch_that_cannot_fit_in_memory_is_refused_before_any_folder() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("run");
    let line = assert_usage_error(&run_into(&out, &["--batch", "100000000000"]));
    // 10¹¹ trajectories · (20 steps · (1 + 1 + 1) numbers + 1 length) · 8 bytes
    // = 4.88e13 bytes = 45,449 GiB (rounded up).
    assert!(
        line.contains("45449 GiB") && line.contains("8 GiB"),
        "{line}"
    );
    assert!(!out.exists(), "no folder for a refused run");
    // The same size in a sweep file is refused before its folder too.
    let file = tmp.path().join("sweep.toml");
    std::fs::write(
        &file,
        "presets = [\"lqg1d\"]\nseeds = 1\nsigma0 = [1.0]\n[base]\niterations = 1\nbatch = 100000000000\n\
         [[variant]]\nname = \"zv\"\nalgo = \"sepg-zv\"\n",
    )
    .expect("write");
    let sweep = tmp.path().join("sweep");
    let line = assert_usage_error(&sepg(&[
        "sweep",
        "--config",
        &file.display().to_string(),
        "--out",
        &sweep.display().to_string(),
        "--quiet",
    ]));
    assert!(line.contains("GiB"), "{line}");
    assert!(!sweep.exists());
    // 10¹¹ seeds of one preset, variant and σ⁰: 10¹¹ runs, above the limit of 10⁶.
    std::fs::write(
        &file,
        "presets = [\"lqg1d\"]\nseeds = 100000000000\nsigma0 = [1.0]\n[base]\niterations = 1\n\
         batch = 12\n[[variant]]\nname = \"zv\"\nalgo = \"sepg-zv\"\n",
    )
    .expect("write");
    let line = assert_usage_error(&sepg(&[
        "sweep",
        "--config",
        &file.display().to_string(),
        "--out",
        &sweep.display().to_string(),
        "--quiet",
    ]));
    assert!(
        line.contains("100000000000 runs") && line.contains("1000000"),
        "{line}"
    );
    assert!(!sweep.exists());
}

#[test]
fn horizons_and_iterations_beyond_the_limits_are_refused() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("run");
    let line = assert_usage_error(&run_into(&out, &["--horizon", "4294967296"]));
    assert!(line.contains("100000"), "{line}");
    let out2 = tmp.path().join("run2");
    let line = assert_usage_error(&sepg(&[
        "run",
        "--env",
        "lqg1d",
        "--iterations",
        "1000000001",
        "--quiet",
        "--out",
        &out2.display().to_string(),
    ]));
    assert!(line.contains("1000000000"), "{line}");
    assert!(!out.exists() && !out2.exists());
    let line = assert_usage_error(&sepg(&[
        "exact",
        "--env",
        "lqg1d",
        "--clipped",
        "--horizon",
        "100000000",
        "--v",
        "-0.3",
        "--sigma",
        "0.5",
    ]));
    assert!(line.contains("100000"), "{line}");
    let line = assert_usage_error(&sepg(&[
        "bounds",
        "--gamma",
        "0.9",
        "--r-max",
        "1",
        "--m-phi",
        "1",
        "--action-volume",
        "1",
        "--sigma",
        "1",
        "--delta",
        "0.1",
        "--eps",
        "0.1",
        "--horizon",
        "4294967295",
    ]));
    assert!(line.contains("100000"), "{line}");
}

#[test]
fn an_initial_policy_the_first_iteration_would_refuse_is_refused_up_front() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("run");
    // ln(1e300) = 690.8 > 354, the largest |w| a policy represents.
    let line = assert_usage_error(&run_into(&out, &["--sigma0", "1e300"]));
    assert!(line.contains("sigma0"), "{line}");
    assert!(!out.exists(), "no partial folder");
}

#[test]
fn an_initial_mean_the_environment_or_oracle_cannot_take_is_refused_without_a_folder() {
    let tmp = tempfile::tempdir().expect("tempdir");
    // Mountain Car: a mean of 1e300 makes the score (a − μ)/σ² · φ overflow at the first step;
    // the clipped DP would need more elements than it allows for |v| = 1e300 on lqg1d.
    let cases: [&[&str]; 2] = [
        &["--env", "mountain-car", "--v0", "1e300,0,0"],
        &["--env", "lqg1d", "--gradients", "exact", "--v0", "1e300"],
    ];
    for (i, case) in cases.iter().enumerate() {
        let out = tmp.path().join(format!("run{i}"));
        let out_s = out.display().to_string();
        let mut args = vec!["run", "--iterations", "2", "--quiet"];
        args.extend_from_slice(case);
        args.extend_from_slice(&["--out", &out_s]);
        let line = assert_usage_error(&sepg(&args));
        assert!(line.contains("initial policy"), "{line}");
        assert!(!out.exists(), "no partial folder for {case:?}");
    }
}

#[test]
fn an_unwritable_out_is_bad_input() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let file = tmp.path().join("a-file");
    std::fs::write(&file, "x").expect("write");
    let line = assert_usage_error(&run_into(&file.join("run"), &[]));
    assert!(line.contains("is not a folder"), "{line}");
    #[cfg(target_os = "linux")]
    {
        let line = assert_usage_error(&run_into(std::path::Path::new("/proc/sepg-run"), &[]));
        assert!(line.contains("not writable"), "{line}");
    }
}

#[test]
fn the_batch_message_states_the_true_requirement() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("run");
    // MI runs 2 blocks of SEPG, each cross-fitting ∇_w L on two halves: 4 per block, N ≥ 8.
    for n in ["4", "7"] {
        let line = assert_usage_error(&run_into(&out, &["--algo", "sepg-mi", "--batch", n]));
        assert!(
            line.contains("at least 4 trajectories each") && line.contains("N >= 8"),
            "{line}"
        );
    }
    let ok = run_into(&out, &["--algo", "sepg-mi", "--batch", "8"]);
    assert_eq!(
        ok.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
}

#[test]
fn a_list_of_the_wrong_length_names_the_one_value_needed() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let line = assert_usage_error(&run_into(&tmp.path().join("run"), &["--v0", "-0.1,0.2"]));
    assert!(
        line.ends_with("v0 has 2 values, the environment needs 1"),
        "{line}"
    );
}

#[test]
fn merge_refuses_a_shard_with_a_bad_log() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let file = tmp.path().join("sweep.toml");
    std::fs::write(
        &file,
        "presets = [\"lqg1d\"]\nseeds = 2\nsigma0 = [1.0]\n[base]\niterations = 6\nbatch = 12\n\
         [[variant]]\nname = \"zv\"\nalgo = \"sepg-zv\"\n",
    )
    .expect("write");
    let shards: Vec<std::path::PathBuf> = (0..2)
        .map(|i| tmp.path().join(format!("shard-{i}")))
        .collect();
    for (i, s) in shards.iter().enumerate() {
        let out = sepg(&[
            "sweep",
            "--config",
            &file.display().to_string(),
            "--shard",
            &format!("{i}/2"),
            "--out",
            &s.display().to_string(),
            "--quiet",
        ]);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let log = walk_logs(&shards[1]).pop().expect("a log in shard 1");
    let text = std::fs::read_to_string(&log).expect("log");
    let merge = |name: &str| {
        let out = tmp.path().join(name);
        let args = [
            "merge".to_owned(),
            "--quiet".into(),
            "--out".into(),
            out.display().to_string(),
            shards[0].display().to_string(),
            shards[1].display().to_string(),
        ];
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        (sepg(&refs), out)
    };
    // Cut inside the row of iteration 3 (line 5): that line is named.
    let starts: Vec<usize> = text.match_indices('\n').map(|(i, _)| i + 1).collect();
    std::fs::write(&log, &text[..starts[3] + 7]).expect("cut");
    let (out, dir) = merge("cut");
    let line = assert_usage_error(&out);
    assert!(
        line.contains(&log.display().to_string()) && line.contains("log line 5"),
        "{line}"
    );
    assert!(!dir.exists());
    // A NaN in the row of iteration 1 (line 3).
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut cells: Vec<&str> = lines[2].split(',').collect();
    cells[3] = "NaN";
    lines[2] = cells.join(",");
    std::fs::write(&log, lines.join("\n") + "\n").expect("write");
    let line = assert_usage_error(&merge("nan").0);
    assert!(
        line.contains("log line 3") && line.contains("NaN"),
        "{line}"
    );
    // The intact log merges.
    std::fs::write(&log, &text).expect("restore");
    assert_eq!(merge("whole").0.status.code(), Some(0));
}

/// Every `log.csv` under `dir`.
fn walk_logs(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut found = Vec::new();
    for e in std::fs::read_dir(dir).expect("read_dir").flatten() {
        let p = e.path();
        if p.is_dir() {
            found.extend(walk_logs(&p));
        } else if p.file_name().is_some_and(|n| n == "log.csv") {
            found.push(p);
        }
    }
    found
}

/// Ctrl-C in the middle of a long iteration (an exact-gradient run on the clipped `lqg1d` at
/// the largest horizon, whose dynamic programme takes seconds per iteration) stops the run
/// inside that iteration: it exits with one line naming `--resume` and the checkpoint of
/// iteration 1, not after finishing the iteration; resumed, it gives the uninterrupted log.
#[cfg(unix)]
#[test]
fn ctrl_c_stops_inside_a_long_iteration_and_the_run_resumes_identically() {
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};

    let tmp = tempfile::tempdir().expect("tempdir");
    let args = |dir: &std::path::Path| {
        with_out(
            &[
                "run",
                "--env",
                "lqg1d",
                "--gradients",
                "exact",
                "--horizon",
                "100000",
                "--iterations",
                "2",
                "--quiet",
                "--out",
            ],
            dir,
        )
    };
    let dir = tmp.path().join("interrupted");
    let mut child = Command::new(env!("CARGO_BIN_EXE_sepg"))
        .args(args(&dir))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    // The handler is in place once the configuration is written (it is installed before the
    // folder is created, which follows iteration 0, run in memory); iteration 1 then runs for
    // seconds.
    let start = Instant::now();
    while !dir.join("config.toml").exists() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the run never started"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(Duration::from_millis(300));
    let sent = Instant::now();
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(kill.success());
    // A liveness bound, not a speed measurement: generous for a loaded machine.
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break s;
        }
        if sent.elapsed() > Duration::from_secs(10) {
            let _ = child.kill();
            panic!("the run ignored Ctrl-C for 10 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().expect("stderr"), &mut err)
        .expect("stderr");
    assert_eq!(status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err:?}");
    assert!(
        err.contains("interrupted after iteration 1 of 2") && err.contains("--resume"),
        "{err}"
    );
    assert!(!dir.join("summary.json").exists());
    let resumed = sepg(&["run", "--resume", &dir.display().to_string(), "--quiet"]);
    assert_eq!(
        resumed.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&resumed.stderr)
    );
    let reference = tmp.path().join("reference");
    let refs: Vec<String> = args(&reference);
    let refs: Vec<&str> = refs.iter().map(String::as_str).collect();
    assert_eq!(sepg(&refs).status.code(), Some(0));
    assert_eq!(
        std::fs::read(dir.join("log.csv")).expect("log"),
        std::fs::read(reference.join("log.csv")).expect("reference log")
    );
}
