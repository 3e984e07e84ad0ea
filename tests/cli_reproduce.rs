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
        Some("preset,sigma0,variant,seeds,iterations,mean,sd,ucb95,thesis")
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
    assert!(text.contains("mean and 95% t-interval across seeds") && bands(&text) == 6);

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
}
