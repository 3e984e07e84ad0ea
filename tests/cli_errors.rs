//! Command-line errors keep the parser's detail in one line, negative numbers reach the
//! validation of their flag, and `estimate --sigma 0` estimates the deterministic J.
//!
//! Cost: one estimate of 4,000 trajectories of 20 steps; the rest fail at parsing.

use crate::common::{assert_usage_error, get, json_ok, sepg};

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
