//! `sepg bounds`: values against formulas re-derived here from the thesis, and the bad-input
//! contract.

use std::f64::consts::PI;

use crate::common::{assert_usage_error, close, get, json_ok, sepg};

const BASE: [&str; 10] = [
    "bounds",
    "--gamma",
    "0.99",
    "--r-max",
    "4",
    "--m-phi",
    "2",
    "--action-volume",
    "4",
    "--sigma",
];

fn run_json(extra: &[&str]) -> serde_json::Value {
    let mut args: Vec<&str> = BASE.to_vec();
    args.push("0.5");
    args.extend_from_slice(extra);
    args.push("--json");
    json_ok(&sepg(&args))
}

/// c and d of Theorems 4.2 and 4.3 written out again from the printed formulas.
fn c_and_d(gamma: f64, r: f64, m_phi: f64, vol: f64, sigma: f64) -> (f64, f64) {
    let psi = 4.0 * (7f64.sqrt() - 2.0) * (7f64.sqrt() / 2.0 - 2.0).exp() / (2.0 * PI).sqrt();
    let c = r * m_phi * m_phi / ((1.0 - gamma).powi(2) * sigma * sigma)
        * (vol / ((2.0 * PI).sqrt() * sigma) + gamma / (2.0 * (1.0 - gamma)));
    let d = r / (1.0 - gamma).powi(2) * (psi * vol / (2.0 * sigma) + gamma / (1.0 - gamma));
    (c, d)
}

#[test]
fn constants_only_match_the_printed_formulas() {
    let v = run_json(&[]);
    let (c, d) = c_and_d(0.99, 4.0, 2.0, 4.0, 0.5);
    assert!(close(get(&v, "psi"), 0.523_557_020_3, 1e-9));
    assert!(close(get(&v, "c"), c, 1e-12));
    assert!(close(get(&v, "d"), d, 1e-12));
    assert!(close(get(&v, "alpha_star"), 1.0 / (2.0 * c), 1e-12));
    assert!(close(get(&v, "beta_star"), 1.0 / (2.0 * d), 1e-12));
    assert!(v.get("c_max_v").is_none(), "no gradient given, no C_max");
}

#[test]
fn gradients_give_every_step_quantity() {
    let v = run_json(&[
        "--grad-v",
        "0.8,-1.5",
        "--grad-w",
        "0.05",
        "--grad-w-l",
        "-0.3",
        "--required",
        "-1e-9",
    ]);
    let (c, d) = c_and_d(0.99, 4.0, 2.0, 4.0, 0.5);
    let required = -1e-9;
    // Theorem 4.2: C_max^v = ‖∇‖∞²/(4c), λ_v = √(1 − C/C_max), ᾱ = (1 + λ)/(2c).
    let c_max_v = 1.5f64.powi(2) / (4.0 * c);
    let lambda_v = (1.0 - required / c_max_v).sqrt();
    assert!(close(get(&v, "c_max_v"), c_max_v, 1e-12));
    assert!(close(get(&v, "lambda_v"), lambda_v, 1e-12));
    assert!(close(
        get(&v, "alpha_bar"),
        (1.0 + lambda_v) / (2.0 * c),
        1e-12
    ));
    assert_eq!(v["greedy_index"].as_u64(), Some(1));
    // Corollary 4.4: L = ‖∇_v J‖₂²/(4mc) with m = 2.
    assert!(close(
        get(&v, "surrogate"),
        (0.64 + 2.25) / (8.0 * c),
        1e-12
    ));
    // Theorems 4.3 and 4.5.
    let (gj, gl) = (0.05, -0.3);
    let c_max_w = gj * gj / (4.0 * d);
    let lambda_w = (1.0 - required / c_max_w).sqrt();
    let beta_tilde = gj / (2.0 * d * gl);
    assert!(close(get(&v, "c_max_w"), c_max_w, 1e-12));
    assert!(close(get(&v, "lambda_w"), lambda_w, 1e-12));
    assert!(close(get(&v, "beta_tilde"), beta_tilde, 1e-12));
    assert!(close(
        get(&v, "beta_bar"),
        beta_tilde + lambda_w * beta_tilde.abs(),
        1e-12
    ));
}

#[test]
fn infeasible_requirement_is_reported_not_nan() {
    let v = run_json(&["--grad-v", "1e-3", "--required", "1.0"]);
    assert_eq!(v["feasible_v"].as_bool(), Some(false));
    assert!(v.get("lambda_v").is_none());
    // The λ = 0 step of maximal guaranteed improvement is reported instead.
    let (c, _) = c_and_d(0.99, 4.0, 2.0, 4.0, 0.5);
    assert!(close(get(&v, "alpha_bar"), 1.0 / (2.0 * c), 1e-12));
}

#[test]
fn plain_output_is_a_table() {
    let mut args: Vec<&str> = BASE.to_vec();
    args.extend_from_slice(&["0.5", "--grad-v", "0.8"]);
    let out = sepg(&args);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8(out.stdout).expect("utf-8");
    for key in [
        "psi",
        "alpha_star",
        "beta_star",
        "c_max_v",
        "lambda_v",
        "alpha_bar",
    ] {
        assert!(
            text.lines().any(|l| l.starts_with(key)),
            "row {key} missing in\n{text}"
        );
    }
}

#[test]
fn bad_input_is_one_line_and_exit_2() {
    let cases: [&[&str]; 7] = [
        &[
            "bounds",
            "--gamma",
            "1.5",
            "--r-max",
            "4",
            "--m-phi",
            "2",
            "--action-volume",
            "4",
            "--sigma",
            "0.5",
        ],
        &[
            "bounds",
            "--gamma",
            "0.99",
            "--r-max",
            "4",
            "--m-phi",
            "2",
            "--action-volume",
            "4",
            "--sigma",
            "-1",
        ],
        &[
            "bounds",
            "--gamma",
            "0.99",
            "--r-max",
            "0",
            "--m-phi",
            "2",
            "--action-volume",
            "4",
            "--sigma",
            "1",
        ],
        &[
            "bounds",
            "--gamma",
            "0.99",
            "--r-max",
            "4",
            "--m-phi",
            "2",
            "--action-volume",
            "4",
            "--sigma",
            "1",
            "--grad-v",
            "1,x",
        ],
        &[
            "bounds",
            "--gamma",
            "0.99",
            "--r-max",
            "4",
            "--m-phi",
            "2",
            "--action-volume",
            "4",
            "--sigma",
            "1",
            "--grad-w-l",
            "1",
        ],
        &[
            "bounds",
            "--gamma",
            "nan",
            "--r-max",
            "4",
            "--m-phi",
            "2",
            "--action-volume",
            "4",
            "--sigma",
            "1",
        ],
        &["bounds", "--gamma", "0.99", "--bogus"],
    ];
    for args in cases {
        let line = assert_usage_error(&sepg(args));
        assert!(line.starts_with("sepg: error:"), "{line}");
    }
    let line = assert_usage_error(&sepg(cases[0]));
    assert!(
        line.contains("gamma"),
        "the message names the parameter: {line}"
    );
}

#[test]
fn certified_prints_enclosures_around_the_f64_values() {
    let v = run_json(&[
        "--grad-v",
        "0.8,-1.5",
        "--grad-w",
        "0.05",
        "--grad-w-l",
        "-0.3",
        "--required",
        "-1e-9",
        "--certified",
    ]);
    let cert = &v["certified"];
    let enclosure = |name: &str| {
        let e = &cert["enclosures"][name];
        let (lo, hi) = (e[0].as_f64().expect("lo"), e[1].as_f64().expect("hi"));
        assert!(lo <= hi, "{name}: [{lo}, {hi}]");
        (lo, hi)
    };
    // the f64 values lie in (or within rounding of) their enclosures, which are ulps wide
    let (c, d) = c_and_d(0.99, 4.0, 2.0, 4.0, 0.5);
    for (name, value) in [
        ("c", c),
        ("d", d),
        ("c_max_v", get(&v, "c_max_v")),
        ("alpha_hi", get(&v, "alpha_bar")),
    ] {
        let (lo, hi) = enclosure(name);
        assert!(close(lo, value, 1e-14) && close(hi, value, 1e-14), "{name}");
    }
    let (lo, hi) = enclosure("psi");
    assert!(lo < 0.523_557_020_321_373_7 && 0.523_557_020_321_373_7 <= hi);
    // the certified largest step guarantees C: its bound's lower end is at least C
    let step = &cert["steps"]["alpha_bar"];
    assert_eq!(step["outcome"], "certified");
    assert!(step["bound"][0].as_f64().expect("bound") >= -1e-9);
    assert!(step["step"].as_f64().expect("step") <= get(&v, "alpha_bar"));
    // without the flag there is no certified section
    assert!(run_json(&[]).get("certified").is_none());
}

/// S_H = Σ_{t<H} (t + 1)γᵗ in closed form, (1 − (H + 1)γ^H + Hγ^{H+1}) / (1 − γ)².
fn s_h_closed(gamma: f64, h: i32) -> f64 {
    (1.0 - f64::from(h + 1) * gamma.powi(h) + f64::from(h) * gamma.powi(h + 1))
        / (1.0 - gamma).powi(2)
}

fn tight_json(sigma: &str, extra: &[&str]) -> serde_json::Value {
    let mut args: Vec<&str> = BASE.to_vec();
    args.extend_from_slice(&[sigma, "--constants", "tight"]);
    args.extend_from_slice(extra);
    args.push("--json");
    json_ok(&sepg(&args))
}

/// The tight constants (docs/THEOREMS.md, "Tight constants"): c = ρRM_φ²S_H/σ² and
/// d = 2ρRS_H, two-sided (ρ = 1) unless the rewards are stated non-positive (ρ = 1/2), with
/// S_H from its closed form; the report names the family, S_H and ρ.
#[test]
fn tight_constants_match_the_closed_form_at_every_sigma() {
    let (r, m) = (4.0, 2.0);
    let s_h = s_h_closed(0.99, 20);
    for sigma in ["0.05", "0.5", "1", "3.7"] {
        let s: f64 = sigma.parse().expect("number");
        let two = tight_json(sigma, &["--horizon", "20"]);
        assert_eq!(two["constants"], "tight");
        assert_eq!(two["rewards"], "two-sided");
        assert_eq!(two["horizon"], "20");
        assert!(close(get(&two, "s_h"), s_h, 1e-13));
        assert_eq!(get(&two, "rho"), 1.0);
        assert!(close(get(&two, "c"), r * m * m * s_h / (s * s), 1e-13));
        assert!(close(get(&two, "d"), 2.0 * r * s_h, 1e-13));
        assert!(close(
            get(&two, "alpha_star"),
            s * s / (2.0 * r * m * m * s_h),
            1e-12
        ));
        let half = tight_json(sigma, &["--horizon", "20", "--rewards", "non-positive"]);
        assert_eq!(half["rewards"], "non-positive");
        assert_eq!(get(&half, "rho"), 0.5);
        assert!(close(
            get(&half, "c"),
            0.5 * r * m * m * s_h / (s * s),
            1e-13
        ));
        assert!(close(get(&half, "d"), r * s_h, 1e-13));
    }
    // H = ∞: S_∞ = 1/(1 − γ)².
    let inf = tight_json("0.5", &["--horizon", "inf"]);
    assert_eq!(inf["horizon"], "inf");
    let s_inf = 1.0 / (0.01f64 * 0.01);
    assert!(close(get(&inf, "s_h"), s_inf, 1e-12));
    assert!(close(get(&inf, "d"), 2.0 * r * s_inf, 1e-12));
    // H = 1: S_1 = 1, whatever γ.
    let one = tight_json("0.5", &["--horizon", "1"]);
    assert!(close(get(&one, "c"), r * m * m / 0.25, 1e-15));
    // The thesis's family stays the default, and its report says so.
    let thesis = run_json(&[]);
    assert_eq!(thesis["constants"], "thesis");
    assert!(thesis.get("s_h").is_none());
}

/// `--certified` with the tight constants encloses the closed-form c and d, and certifies
/// the safe step of the tight penalty.
#[test]
fn certified_tight_constants_enclose_the_closed_form() {
    let v = tight_json(
        "0.5",
        &[
            "--horizon",
            "20",
            "--rewards",
            "non-positive",
            "--grad-v",
            "0.3",
            "--certified",
        ],
    );
    let s_h = s_h_closed(0.99, 20);
    let (c, d) = (0.5 * 4.0 * 4.0 * s_h / 0.25, 4.0 * s_h);
    let enc = &v["certified"]["enclosures"];
    let ends = |name: &str| {
        [
            enc[name][0].as_f64().expect("lo"),
            enc[name][1].as_f64().expect("hi"),
        ]
    };
    // The closed form is evaluated in f64 here: within 1e-13 relative of the enclosure.
    for (name, value) in [("c", c), ("d", d)] {
        let [lo, hi] = ends(name);
        assert!(lo <= hi && lo <= value * (1.0 + 1e-13) && value <= hi * (1.0 + 1e-13));
        assert!(hi - lo <= 1e-12 * value, "{name}: [{lo}, {hi}]");
    }
    let step = &v["certified"]["steps"]["alpha_bar"];
    assert_eq!(step["outcome"], "certified");
    // ᾱ = (1 + λ)/(2c) with λ = 1 at C = 0: 1/c.
    assert!(close(step["step"].as_f64().expect("step"), 1.0 / c, 1e-12));
}

#[test]
fn bad_constants_arguments_are_one_line_exit_2() {
    let with = |extra: &[&str]| {
        let mut args: Vec<&str> = BASE.to_vec();
        args.push("0.5");
        args.extend_from_slice(extra);
        assert_usage_error(&sepg(&args))
    };
    assert!(with(&["--constants", "foo"]).contains("--constants"));
    assert!(with(&["--constants", "tight", "--horizon", "0"]).contains("horizon"));
    assert!(with(&["--constants", "tight", "--horizon", "-3"]).contains("horizon"));
    assert!(with(&["--constants", "tight"]).contains("--horizon"));
    assert!(with(&["--rewards", "non-positive"]).contains("--rewards"));
    assert!(
        with(&["--constants", "tight", "--horizon", "20", "--rewards", "up"]).contains("--rewards")
    );
    assert!(with(&["--horizon", "inf", "--delta", "0.1", "--eps", "0.1"]).contains("finite"));
}
