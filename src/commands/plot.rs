//! `sepg plot`: performance, σ, v and budget panels of a run folder, or of every
//! (preset, variant, σ⁰) group of a sweep folder with 95% bands across seeds.

use std::path::{Path, PathBuf};

use clap::Args;

use crate::cli::CliError;
use crate::commands::figure::{self, Figure, Panel, Series, mean_band};
use crate::commands::runfmt::{self, Log};
use crate::commands::sweep::{SWEEP_FILE, SweepFile};

/// Arguments of `sepg plot`.
#[derive(Debug, Args)]
pub struct PlotArgs {
    /// A run folder (from `sepg run`) or a sweep folder (from `sepg sweep` or `reproduce`).
    #[arg(value_name = "DIR")]
    dir: PathBuf,
    /// Output file, .png or .svg [default: DIR/plot.png and DIR/plot.svg].
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Print nothing.
    #[arg(long)]
    quiet: bool,
}

/// The (column, panel title, axis label) of the four panels.
const PANELS: [(&str, &str, &str); 4] = [
    (
        "j_explore",
        "performance J(θᵗ) of the exploratory policy",
        "J",
    ),
    ("sigma", "standard deviation σᵗ", "σ"),
    ("v", "mean parameter vᵗ (first component)", "v"),
    ("budget", "budget Bᵗ", "B"),
];

fn one_run(dir: &Path) -> Result<Figure, CliError> {
    let log = Log::read_run(dir)?;
    let x = log.column("iteration").ok_or_else(|| {
        CliError::usage(format!("{}: log has no iteration column", dir.display()))
    })?;
    let name = runfmt::RunSpec::from_file(&dir.join(runfmt::CONFIG_FILE))?
        .name
        .unwrap_or_default();
    let panels = PANELS
        .iter()
        .map(|&(col, title, y)| {
            let mut series: Vec<Series> = log
                .column(col)
                .map(|mean| Series {
                    label: name.clone(),
                    x: x.clone(),
                    mean,
                    band: None,
                })
                .into_iter()
                .collect();
            if col == "j_explore"
                && let Some(mean) = log.column("j_target")
            {
                series.push(Series {
                    label: format!("{name} target"),
                    x: x.clone(),
                    mean,
                    band: None,
                });
            }
            Panel {
                title: title.into(),
                x_label: "iteration".into(),
                y_label: y.into(),
                series,
                hlines: Vec::new(),
            }
        })
        .collect();
    let complete = if runfmt::is_complete(dir) {
        ""
    } else {
        " (incomplete run)"
    };
    Ok(Figure {
        title: format!("{}{complete}", dir.display()),
        panels,
        columns: 2,
    })
}

fn sweep(dir: &Path, file: &SweepFile) -> Result<Figure, CliError> {
    let mut groups: Vec<(String, Vec<Log>)> = Vec::new();
    for r in file.shard_runs() {
        let run_dir = dir.join(&r.dir);
        if !run_dir.join(runfmt::CONFIG_FILE).is_file() {
            continue;
        }
        let label = format!("{}/{}/σ⁰={}", r.preset.name(), r.variant, r.sigma0);
        let log = Log::read_run(&run_dir)?;
        match groups.iter_mut().find(|(l, _)| *l == label) {
            Some((_, logs)) => logs.push(log),
            None => groups.push((label, vec![log])),
        }
    }
    if groups.is_empty() {
        return Err(CliError::usage(format!(
            "{} has no started run yet",
            dir.display()
        )));
    }
    let panels = PANELS
        .iter()
        .map(|&(col, title, y)| {
            let series = groups
                .iter()
                .filter_map(|(label, logs)| {
                    let curves: Vec<Vec<f64>> = logs.iter().filter_map(|l| l.column(col)).collect();
                    let x = logs
                        .iter()
                        .filter_map(|l| l.column("iteration"))
                        .min_by_key(Vec::len)?;
                    let (mean, band) = mean_band(&curves);
                    Some(Series {
                        label: label.clone(),
                        x: x[..mean.len()].to_vec(),
                        mean,
                        band,
                    })
                })
                .collect();
            Panel {
                title: title.into(),
                x_label: "iteration".into(),
                y_label: y.into(),
                series,
                hlines: Vec::new(),
            }
        })
        .collect();
    Ok(Figure {
        title: format!("{} (mean and 95% band across seeds)", dir.display()),
        panels,
        columns: 2,
    })
}

/// Runs `sepg plot`.
///
/// # Errors
/// Usage error (exit 2) for a folder that is neither a run nor a sweep, or an output file
/// that is not .png or .svg; failure (exit 1) when drawing or writing fails.
pub fn run(args: &PlotArgs) -> Result<(), CliError> {
    if let Some(out) = &args.out
        && !matches!(
            out.extension().and_then(|e| e.to_str()),
            Some("png" | "svg")
        )
    {
        return Err(CliError::usage(format!(
            "{}: figures are written as .png or .svg",
            out.display()
        )));
    }
    let fig = if args.dir.join(SWEEP_FILE).is_file() {
        sweep(&args.dir, &SweepFile::read(&args.dir)?)?
    } else if args.dir.join(runfmt::CONFIG_FILE).is_file() {
        one_run(&args.dir)?
    } else {
        return Err(CliError::usage(format!(
            "{} is neither a run folder nor a sweep folder",
            args.dir.display()
        )));
    };
    let written = match &args.out {
        Some(out) => {
            figure::save(&fig, out)?;
            vec![out.clone()]
        }
        None => figure::save_both(&fig, &args.dir, "plot")?.to_vec(),
    };
    if !args.quiet {
        for p in written {
            println!("{}", p.display());
        }
    }
    Ok(())
}
