//! `sepg reproduce` and `sepg plot`: the table is the 95% upper confidence bound recomputed
//! here from the runs' summaries, next to the published values; figures are PNG and SVG.

use std::path::Path;

use crate::common::{assert_usage_error, sepg};

fn ok(args: &[&str]) -> String {
    let out = sepg(args);
    assert_eq!(
        out.status.code(),
        Some(0),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8")
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).expect("read")).expect("json")
}

#[test]
fn table_5_1_is_the_t_bound_of_the_runs_next_to_the_thesis() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("t");
    let d = dir.to_str().expect("utf-8");
    let stdout = ok(&[
        "reproduce",
        "table-5.1",
        "--preset",
        "lqg1d",
        "--seeds",
        "2",
        "--iterations",
        "15",
        "--quiet",
        "--out",
        d,
    ]);
    assert!(stdout.contains("| σ⁰ | adam-1e-4 |"), "{stdout}");
    assert_eq!(
        std::fs::read_to_string(dir.join("table-5.1.md")).expect("md"),
        stdout
    );
    let csv = std::fs::read_to_string(dir.join("table-5.1.csv")).expect("csv");
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("preset,sigma0,variant,seeds,iterations,mean,sd,ucb95,thesis,tolerance,reproduces")
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 4 * 11);
    let sweep = json(&dir.join("sweep.json"));
    let runs = sweep["runs"].as_array().expect("runs");
    // t(0.975, 1) = tan(0.475π) = 12.706204736174705.
    let t = (0.475 * std::f64::consts::PI).tan();
    for row in &rows {
        let (sigma0, variant) = (row[1].parse::<f64>().expect("sigma0"), row[2]);
        let errors: Vec<f64> = runs
            .iter()
            .filter(|r| r["variant"] == variant && r["sigma0"].as_f64() == Some(sigma0))
            .map(|r| {
                let s = json(
                    &dir.join(r["dir"].as_str().expect("dir"))
                        .join("summary.json"),
                );
                let v = s["final"]["v"][0].as_f64().expect("v");
                (v - s["v_star"][0].as_f64().expect("v*")).abs()
            })
            .collect();
        assert_eq!(errors.len(), 2);
        let mean = (errors[0] + errors[1]) / 2.0;
        let sd = (errors[0] - errors[1]).abs() / 2f64.sqrt();
        let ucb = mean + t * sd / 2f64.sqrt();
        let got = row[7].parse::<f64>().expect("ucb");
        assert!(
            (got - ucb).abs() <= 1e-12 * ucb.abs().max(1.0),
            "{row:?}: {got} vs {ucb}"
        );
        check_tolerance(row, &errors, ucb, t);
    }
    // The published values, copied from the thesis's Table 5.1.
    let published = |sigma0: &str, variant: &str| {
        rows.iter()
            .find(|r| r[1] == sigma0 && r[2] == variant)
            .map(|r| r[8].to_owned())
            .expect("row")
    };
    assert_eq!(published("0.1", "adam-1e-4"), "0.126");
    assert_eq!(published("0.5", "lb1"), "0.29");
    assert_eq!(published("1.0", "zv"), "0.028");
    assert_eq!(published("0.2", "const-1e-5"), "0.018");
}

/// Checks the tolerance and verdict of a two-seed row of table-5.1.csv against docs/
/// REPRODUCTION.md: tolerance = 0.5·10^(−digits of P) + 1.96·√2·SD₂, SD₂ the standard
/// deviation of U over bootstrap resamples of the two seeds. With errors a, b the resample
/// is {a, a} or {b, b} with probability 1/4 each (s = 0, U = a or b) and {a, b} with
/// probability 1/2 (U = c = (a + b)/2 + t(0.975, 1)·|a − b|/2), so SD₂ has a closed form;
/// the table estimates it from 2,000 resamples, whose standard error √(μ₄ − σ⁴)/(2σ√2000) is
/// allowed 5 times (a false alarm below 6e-7 a cell, 3e-5 for the 44 cells).
fn check_tolerance(row: &[&str], errors: &[f64], ucb: f64, t: f64) {
    let (a, b) = (errors[0], errors[1]);
    let c = (a + b) / 2.0 + t * (a - b).abs() / 2.0;
    let dist = [(a, 0.25), (b, 0.25), (c, 0.5)];
    let mu: f64 = dist.iter().map(|(u, p)| u * p).sum();
    let var: f64 = dist.iter().map(|(u, p)| p * (u - mu).powi(2)).sum();
    let mu4: f64 = dist.iter().map(|(u, p)| p * (u - mu).powi(4)).sum();
    let se = if var > 0.0 {
        (mu4 - var * var).max(0.0).sqrt() / (2.0 * var.sqrt() * 2000f64.sqrt())
    } else {
        0.0
    };
    let published = row[8];
    let digits = published.split_once('.').map_or(0, |(_, f)| f.len());
    let rounding = 0.5 * 10f64.powi(-(digits as i32));
    let widen = 1.96 * 2f64.sqrt();
    let exact = rounding + widen * var.sqrt();
    let slack = widen * 5.0 * se + 1e-12;
    let tol = row[9].parse::<f64>().expect("tolerance");
    assert!(
        (tol - exact).abs() <= slack,
        "{row:?}: {tol} vs {exact} ± {slack}"
    );
    let p = published.parse::<f64>().expect("published");
    let gap = (ucb - p).abs();
    if (gap - exact).abs() > slack {
        let verdict = if gap <= exact { "yes" } else { "no" };
        assert_eq!(
            row[10], verdict,
            "{row:?}: |U − P| = {gap}, tolerance {exact}"
        );
    }
}

#[test]
fn table_5_1_with_one_seed_warns_and_shows_no_bound() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("t1");
    let d = dir.to_str().expect("utf-8");
    let out = sepg(&[
        "reproduce",
        "table-5.1",
        "--preset",
        "lqg1d",
        "--seeds",
        "1",
        "--iterations",
        "3",
        "--quiet",
        "--out",
        d,
    ]);
    assert_eq!(out.status.code(), Some(0));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("warning") && err.contains("cannot be computed from one seed"),
        "{err}"
    );
    let md = String::from_utf8(out.stdout).expect("utf-8");
    let cells = md
        .lines()
        .filter(|l| l.starts_with("| 0.") || l.starts_with("| 1."));
    for line in cells {
        assert_eq!(line.matches("n/a").count(), 11, "{line}");
    }
    let csv = std::fs::read_to_string(dir.join("table-5.1.csv")).expect("csv");
    for row in csv.lines().skip(1) {
        let cells: Vec<&str> = row.split(',').collect();
        // One seed: a mean, but no sd, no bound, no tolerance and no verdict.
        assert_eq!(cells[3], "1", "{row}");
        assert!(cells[5].parse::<f64>().is_ok(), "{row}");
        assert_eq!(
            (cells[6], cells[7], cells[9], cells[10]),
            ("", "", "", ""),
            "{row}"
        );
    }
}

/// A finished 30-iteration `lqg1d` SEPG-LB-II run with the thesis's estimated budget in `dir`.
fn run_30(dir: &Path) {
    ok(&[
        "run",
        "--env",
        "lqg1d",
        "--algo",
        "sepg-lb2",
        "--accounting",
        "estimated",
        "--batch",
        "50",
        "--sigma0",
        "0.5",
        "--iterations",
        "30",
        "--seed",
        "4",
        "--quiet",
        "--out",
        dir.to_str().expect("utf-8"),
    ]);
}

/// The numbers drawn as text in `svg` (tick labels among them).
fn numbers(svg: &str) -> Vec<f64> {
    svg.split("</text>")
        .filter_map(|chunk| chunk.rsplit('>').next())
        .filter_map(|t| t.trim().parse::<f64>().ok())
        .collect()
}

#[test]
fn plot_refuses_torn_and_nan_logs_and_marks_unfinished_runs() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("r");
    run_30(&dir);
    let d = dir.to_str().expect("utf-8");
    let log = std::fs::read_to_string(dir.join("log.csv")).expect("log");
    let svg_path = tmp.path().join("p.svg");
    let svg_out = svg_path.to_str().expect("utf-8");

    // The whole run: its title says what ran, the budget panel that it is estimated, and
    // the last x tick is at or beyond the last iteration (29) and the last step count.
    ok(&["plot", d, "--out", svg_out]);
    let svg = std::fs::read_to_string(&svg_path).expect("svg");
    assert!(
        svg.contains("lqg1d, SEPG-LB-II, σ⁰ = 0.5, N = 50, seed 4"),
        "title"
    );
    assert!(svg.contains("estimated"), "budget panel");
    assert!(!svg.contains(d), "the folder is not the title");
    assert!(numbers(&svg).iter().any(|&x| x >= 29.0));
    let steps: f64 = log
        .lines()
        .last()
        .and_then(|l| l.split(',').rev().nth(2))
        .and_then(|c| c.parse().ok())
        .expect("steps of the last row");
    ok(&["plot", d, "--x-axis", "steps", "--out", svg_out]);
    let svg = std::fs::read_to_string(&svg_path).expect("svg");
    assert!(svg.contains("environment steps"));
    assert!(numbers(&svg).iter().any(|&x| x >= steps), "{steps}");

    // Cut to 1,500 bytes: refused, naming the file and its first torn line.
    let torn = &log[..1500];
    let rows = torn.matches('\n').count();
    std::fs::write(dir.join("log.csv"), torn).expect("write");
    let line = assert_usage_error(&sepg(&["plot", d, "--quiet"]));
    assert!(line.contains("log.csv"), "{line}");
    if torn.ends_with('\n') {
        assert!(line.contains(&format!("iteration {}", rows - 1)), "{line}");
    } else {
        assert!(line.contains(&format!("log line {}", rows + 1)), "{line}");
    }
    // A NaN cell on line 7 (iteration 5): refused, naming the line.
    let mut lines: Vec<String> = log.lines().map(String::from).collect();
    let mut cells: Vec<&str> = lines[6].split(',').collect();
    cells[4] = "NaN";
    lines[6] = cells.join(",");
    std::fs::write(dir.join("log.csv"), lines.join("\n") + "\n").expect("write");
    let line = assert_usage_error(&sepg(&["plot", d, "--quiet"]));
    assert!(
        line.contains("log.csv") && line.contains("log line 7"),
        "{line}"
    );

    // Interrupted after 8 of 30 iterations: plotted, marked and warned about.
    std::fs::write(dir.join("log.csv"), &log).expect("restore");
    let all: Vec<&str> = log.lines().collect();
    let prefix = all[..9].join("\n") + "\n";
    let row8: Vec<&str> = all[9].split(',').collect();
    let ck_text = std::fs::read_to_string(dir.join("checkpoint.json")).expect("checkpoint");
    let mut ck: serde_json::Value = serde_json::from_str(&ck_text).expect("json");
    ck["log_bytes"] = prefix.len().into();
    ck["state"]["iteration"] = 8.into();
    ck["state"]["v"] = serde_json::json!([row8[1].parse::<f64>().expect("v")]);
    ck["state"]["w"] = serde_json::json!([row8[2].parse::<f64>().expect("w")]);
    std::fs::write(dir.join("checkpoint.json"), ck.to_string()).expect("write");
    std::fs::write(dir.join("log.partial.csv"), prefix + all[9] + "\n").expect("write");
    std::fs::remove_file(dir.join("log.csv")).expect("remove");
    std::fs::remove_file(dir.join("summary.json")).expect("remove");
    let out = sepg(&["plot", d, "--out", svg_out]);
    assert_eq!(out.status.code(), Some(0));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("incomplete: 8 of 30 iterations"), "{err}");
    let svg = std::fs::read_to_string(&svg_path).expect("svg");
    assert!(svg.contains("incomplete: 8 of 30 iterations"), "mark");
}

#[test]
fn figures_and_plots_are_png_and_svg() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("f");
    let d = dir.to_str().expect("utf-8");
    let stdout = ok(&[
        "reproduce",
        "fig-5.1",
        "--preset",
        "lqg",
        "--seeds",
        "2",
        "--iterations",
        "10",
        "--out",
        d,
    ]);
    assert!(
        stdout.contains("fig-5.1-lqg.png") && stdout.contains("fig-5.1-lqg.svg"),
        "{stdout}"
    );
    let png = std::fs::read(dir.join("fig-5.1-lqg.png")).expect("png");
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let svg = std::fs::read_to_string(dir.join("fig-5.1-lqg.svg")).expect("svg");
    assert!(svg.contains("<svg") && svg.contains("fig-5.1") && svg.contains("SEPG-LB-I"));
    // A sweep folder and a run folder both plot; two seeds draw a band with a warning,
    // which `--band none` silences.
    let two = sepg(&["plot", d, "--quiet"]);
    assert!(two.status.success());
    let warned = String::from_utf8_lossy(&two.stderr);
    assert!(
        warned.contains("warning") && warned.contains("2 seed"),
        "{warned}"
    );
    let none = sepg(&["plot", d, "--quiet", "--band", "none"]);
    assert!(none.status.success() && none.stderr.is_empty());
    assert!(dir.join("plot.png").is_file() && dir.join("plot.svg").is_file());
    // The budget panel carries its B = 0 line (in the legend as a reference line).
    let sweep_svg = std::fs::read_to_string(dir.join("plot.svg")).expect("svg");
    assert!(sweep_svg.contains("B = 0") && sweep_svg.contains("budget"));
    // Under the default setting every budget is certified, and the panel says so.
    assert!(sweep_svg.contains("budget Bᵗ (certified: sums of certified improvements)"));
    let run = dir.join("runs/lqg/mi/sigma-1.0/seed-0");
    let file = tmp.path().join("one.svg");
    ok(&[
        "plot",
        run.to_str().expect("utf-8"),
        "--out",
        file.to_str().expect("utf-8"),
    ]);
    let run_svg = std::fs::read_to_string(&file).expect("svg");
    assert!(run_svg.contains("budget") && run_svg.contains("B = 0"));
}

/// `sepg reproduce fig-5.1` on `lqg1d` with two seeds of 5 iterations into `d`, with
/// `extra` flags.
fn reproduce_two_seeds(d: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "reproduce",
        "fig-5.1",
        "--preset",
        "lqg1d",
        "--seeds",
        "2",
        "--iterations",
        "5",
        "--quiet",
        "--out",
        d,
    ];
    args.extend_from_slice(extra);
    sepg(&args)
}

#[test]
fn reproduce_draws_the_band_asked_for_and_warns_below_three_seeds() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("f");
    let d = dir.to_str().expect("utf-8");
    let svg = || std::fs::read_to_string(dir.join("fig-5.1-lqg1d.svg")).expect("svg");
    // Bands are filled polygons; the legend and the curves are paths and polylines.
    let bands = |svg: &str| svg.matches("<polygon").count();

    let se = reproduce_two_seeds(d, &["--band", "se"]);
    assert!(
        se.status.success(),
        "{}",
        String::from_utf8_lossy(&se.stderr)
    );
    assert!(se.stdout.is_empty());
    let warned = String::from_utf8_lossy(&se.stderr);
    assert!(
        warned.starts_with("warning: ")
            && warned.contains("2 seed(s)")
            && warned.contains("--band none"),
        "{warned}"
    );
    let text = svg();
    assert!(text.contains("mean ± one standard error across seeds"));
    // Three panels (J, σ, v), two variants each.
    assert_eq!(bands(&text), 6);

    let none = reproduce_two_seeds(d, &["--band", "none", "--force"]);
    assert!(none.status.success() && none.stderr.is_empty());
    let text = svg();
    assert!(text.contains("mean across seeds") && bands(&text) == 0);

    let ci = reproduce_two_seeds(d, &["--force"]);
    assert!(String::from_utf8_lossy(&ci.stderr).contains("warning: "));
    let text = svg();
    assert!(text.contains("mean and 95% interval across seeds") && bands(&text) == 6);

    let other = tmp.path().join("t");
    let line = assert_usage_error(&sepg(&[
        "reproduce",
        "table-5.1",
        "--band",
        "se",
        "--out",
        other.to_str().expect("utf-8"),
    ]));
    assert!(line.contains("--band"), "{line}");
    assert!(!other.exists());
}

#[test]
fn bad_reproduce_and_plot_input_is_rejected() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("x");
    let o = out.to_str().expect("utf-8");
    assert_usage_error(&sepg(&["reproduce", "table-9.9", "--out", o]));
    assert_usage_error(&sepg(&[
        "reproduce",
        "fig-5.4",
        "--preset",
        "lqg",
        "--out",
        o,
    ]));
    assert_usage_error(&sepg(&["reproduce", "fig-5.1", "--seeds", "0", "--out", o]));
    assert_usage_error(&sepg(&[
        "reproduce",
        "fig-5.1",
        "--delta",
        "1.5",
        "--out",
        o,
    ]));
    assert!(!out.exists());
    assert_usage_error(&sepg(&["plot", tmp.path().to_str().expect("utf-8")]));
    assert_usage_error(&sepg(&["plot", o, "--out", "figure.pdf"]));
    // Font size and resolution out of range, and figure options on the table, are refused
    // before anything runs.
    for args in [
        ["reproduce", "fig-5.1", "--dpi", "10"],
        ["reproduce", "fig-5.1", "--font-size", "0"],
        ["reproduce", "table-5.1", "--dpi", "200"],
        ["reproduce", "table-5.1", "--x-axis", "steps"],
    ] {
        let mut args = args.to_vec();
        args.extend(["--out", o]);
        assert_usage_error(&sepg(&args));
    }
    assert!(!out.exists());
    let run = tmp.path().join("run");
    run_30(&run);
    let r = run.to_str().expect("utf-8");
    assert_usage_error(&sepg(&["plot", r, "--dpi", "5000"]));
    assert_usage_error(&sepg(&["plot", r, "--font-size", "NaN"]));
}
