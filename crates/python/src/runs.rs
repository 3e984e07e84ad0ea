//! Run folders, sweeps, merges and audits of built-in environments through `sepg_runs`, the
//! library behind `sepg run`, `sepg sweep`, `sepg merge` and `sepg audit`: the same folders,
//! byte for byte. The options of a run are a dict with the keys of the command line
//! (`sepg.run` builds it from keyword arguments), a sweep is JSON text with the keys of a
//! sweep file, and summaries and reports are returned as dicts. The GIL is released while runs execute, and
//! Ctrl-C stops a run at its next iteration after checkpointing (the folder can be resumed).
use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyModule};
use sepg_runs::Error;
use sepg_runs::folder::{self, Log};
use sepg_runs::run::{self, RunObserver, RunOptions};
use sepg_runs::setup;
use sepg_runs::spec::RunSpec;
use sepg_runs::sweep::{self, Shard, SweepOptions, SweepSpec};

use crate::pyjson::{from_py, serialize_to_py};
use crate::{failed, invalid};

/// Raises the stop flag of a run when Python has a pending signal (Ctrl-C), keeping the
/// exception to re-raise it once the run has checkpointed. Signals are looked at every
/// [`SIGNAL_PERIOD`] at most, so that the run does not take the GIL at every iteration.
struct SignalWatch {
    stop: AtomicBool,
    error: Mutex<Option<PyErr>>,
    last: Mutex<Instant>,
}

/// The longest time between two looks at Python's pending signals.
const SIGNAL_PERIOD: Duration = Duration::from_millis(100);

impl SignalWatch {
    fn new() -> Self {
        SignalWatch {
            stop: AtomicBool::new(false),
            error: Mutex::new(None),
            last: Mutex::new(Instant::now()),
        }
    }

    /// The Python error for `e`: the pending signal's exception when the run stopped for
    /// it, else [`invalid`] for bad input and [`failed`] otherwise.
    fn error(&self, e: Error) -> PyErr {
        if let Some(err) = self.error.lock().ok().and_then(|mut s| s.take()) {
            return err;
        }
        run_error(e)
    }
}

/// [`invalid`] for an error of bad input, [`failed`] otherwise.
fn run_error(e: Error) -> PyErr {
    if e.is_invalid_input() {
        invalid(e)
    } else {
        failed(e)
    }
}

impl RunObserver for SignalWatch {
    fn advance(&self, _done: u64) {
        match self.last.lock() {
            Ok(mut last) if last.elapsed() >= SIGNAL_PERIOD => *last = Instant::now(),
            _ => return,
        }
        Python::attach(|py| {
            if let Err(e) = py.check_signals() {
                if let Ok(mut slot) = self.error.lock() {
                    slot.get_or_insert(e);
                }
                self.stop.store(true, Ordering::SeqCst);
            }
        });
    }
}

fn checkpoint_period(k: u64) -> PyResult<u64> {
    if k == 0 {
        Err(invalid("checkpoint_every must be at least 1"))
    } else {
        Ok(k)
    }
}

/// Starts a run of a built-in environment into the folder `out` (absent or empty unless
/// `force`) and runs it to completion; returns `summary.json` as a dict. `options` is a
/// dict with the keys of `sepg run` (`env`, `algo`, `iterations`, `batch`, `seed`, ...),
/// overriding those of the TOML file `config` when given.
#[pyfunction]
#[pyo3(signature = (out, options, config = None, force = false, checkpoint_every = 500))]
fn run_folder<'py>(
    py: Python<'py>,
    out: PathBuf,
    options: &Bound<'py, PyDict>,
    config: Option<PathBuf>,
    force: bool,
    checkpoint_every: u64,
) -> PyResult<Bound<'py, PyAny>> {
    let top: RunSpec = serde_json::from_value(from_py(options, "options")?)
        .map_err(|e| invalid(format!("{e}")))?;
    let new = setup::set_up(config.as_deref(), &top, Some(&out), force).map_err(invalid)?;
    let watch = SignalWatch::new();
    let every = checkpoint_period(checkpoint_every)?;
    let summary = py.detach(|| {
        new.start(RunOptions {
            checkpoint_every: every,
            stop: &watch.stop,
            observer: &watch,
        })
    });
    serialize_to_py(py, &summary.map_err(|e| watch.error(e))?)
}

/// Resumes the run in `dir` from its checkpoint (a complete run is returned as is); returns
/// `summary.json` as a dict.
#[pyfunction]
#[pyo3(signature = (dir, checkpoint_every = 500))]
fn resume_folder(
    py: Python<'_>,
    dir: PathBuf,
    checkpoint_every: u64,
) -> PyResult<Bound<'_, PyAny>> {
    let watch = SignalWatch::new();
    let every = checkpoint_period(checkpoint_every)?;
    let summary = py.detach(|| {
        run::resume(
            &dir,
            RunOptions {
                checkpoint_every: every,
                stop: &watch.stop,
                observer: &watch,
            },
        )
    });
    serialize_to_py(py, &summary.map_err(|e| watch.error(e))?)
}

/// The contents of a run folder: `(config, columns, rows, summary)` with the configuration
/// and the summary as dicts (`None` for an incomplete run's summary), the log's column
/// names, and its rows with empty cells (not applicable) as `None`. An incomplete run gives
/// the rows its checkpoint vouches for.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn read_folder(
    py: Python<'_>,
    dir: PathBuf,
) -> PyResult<(
    Bound<'_, PyAny>,
    Vec<String>,
    Vec<Vec<Option<f64>>>,
    Option<Bound<'_, PyAny>>,
)> {
    let resolved = folder::load_resolved(&dir).map_err(invalid)?;
    let log = Log::read_run(&dir).map_err(invalid)?;
    let rows = log
        .rows
        .iter()
        .map(|r| r.iter().map(|x| (!x.is_nan()).then_some(*x)).collect())
        .collect();
    let summary = if folder::is_complete(&dir) {
        Some(serialize_to_py(
            py,
            &folder::read_summary(&dir).map_err(failed)?,
        )?)
    } else {
        None
    };
    Ok((
        serialize_to_py(py, &resolved.spec)?,
        log.columns,
        rows,
        summary,
    ))
}

fn parse_sweep(spec: &str) -> PyResult<SweepSpec> {
    serde_json::from_str(spec).map_err(|e| invalid(format!("invalid sweep: {e}")))
}

fn parse_shard(shard: Option<&str>) -> PyResult<Shard> {
    match shard {
        Some(s) => sweep::parse_shard(s).map_err(invalid),
        None => Ok(Shard { index: 0, count: 1 }),
    }
}

/// Runs the sweep `spec` (JSON with the keys of a sweep file: `presets`, `seeds`, `sigma0`,
/// `base`, `variant`) into `out`, the runs in parallel on this machine, optionally only
/// shard `"I/N"`; returns `sweep.json` as a dict.
#[pyfunction]
#[pyo3(signature = (out, spec, shard = None, force = false, checkpoint_every = 2000))]
fn sweep_folder<'py>(
    py: Python<'py>,
    out: PathBuf,
    spec: &str,
    shard: Option<&str>,
    force: bool,
    checkpoint_every: u64,
) -> PyResult<Bound<'py, PyAny>> {
    let (file, resolved) =
        sweep::expand(&parse_sweep(spec)?, parse_shard(shard)?).map_err(invalid)?;
    let watch = SignalWatch::new();
    let every = checkpoint_period(checkpoint_every)?;
    py.detach(|| {
        sweep::start(
            &out,
            &file,
            &resolved,
            force,
            SweepOptions {
                checkpoint_every: every,
                stop: &watch.stop,
                observer: &watch,
            },
        )
    })
    .map_err(|e| watch.error(e))?;
    serialize_to_py(py, &file)
}

/// Creates the sweep folder `out` with its `sweep.json` without running anything, so that
/// the runs can be mapped over a cluster engine with [`sweep_run`] and closed with
/// [`sweep_finish`]; returns the indices of the shard's runs.
#[pyfunction]
#[pyo3(signature = (out, spec, shard = None, force = false))]
fn sweep_prepare(
    out: PathBuf,
    spec: &str,
    shard: Option<&str>,
    force: bool,
) -> PyResult<Vec<usize>> {
    let (file, _) = sweep::expand(&parse_sweep(spec)?, parse_shard(shard)?).map_err(invalid)?;
    sweep::prepare(&out, &file, force).map_err(run_error)?;
    Ok(file.shard_runs().map(|r| r.index).collect())
}

/// Runs (or resumes, or leaves as is when complete) run `index` of the sweep folder `out`,
/// re-expanding its `sweep.json`: one deterministic unit of a sweep, as `sepg sweep` runs
/// it. Returns the run folder.
#[pyfunction]
#[pyo3(signature = (out, index, checkpoint_every = 2000))]
fn sweep_run(
    py: Python<'_>,
    out: PathBuf,
    index: usize,
    checkpoint_every: u64,
) -> PyResult<PathBuf> {
    let watch = SignalWatch::new();
    let opts = RunOptions {
        checkpoint_every: checkpoint_period(checkpoint_every)?,
        stop: &watch.stop,
        observer: &watch,
    };
    py.detach(|| sweep::run_one(&out, index, opts))
        .map_err(|e| watch.error(e))
}

/// Closes the sweep folder `out` once every run of its shard is complete: writes
/// `summary.csv` as `sepg sweep` does at its end; returns `sweep.json` as a dict.
#[pyfunction]
fn sweep_finish(py: Python<'_>, out: PathBuf) -> PyResult<Bound<'_, PyAny>> {
    let file = sweep::finish(&out).map_err(run_error)?;
    serialize_to_py(py, &file)
}

/// Merges the complete shard folders `shards` of one sweep into `out`; returns the merged
/// `sweep.json` as a dict.
#[pyfunction]
#[pyo3(signature = (shards, out, force = false))]
fn merge_folders(
    py: Python<'_>,
    shards: Vec<PathBuf>,
    out: PathBuf,
    force: bool,
) -> PyResult<Bound<'_, PyAny>> {
    let file = sepg_runs::merge::merge(&shards, &out, force).map_err(run_error)?;
    serialize_to_py(py, &file)
}

/// Re-checks the log of the run folder `dir` against exactly what its statement promises
/// (with the exact oracle where one exists) and returns the report of `sepg audit` as a dict;
/// `tolerance` is relative to max(1, |J|), `alpha` the family-wise level of the tests.
#[pyfunction]
#[pyo3(signature = (dir, tolerance = sepg_runs::audit::DEFAULT_TOLERANCE, alpha = sepg_runs::audit::DEFAULT_ALPHA))]
fn audit_folder(
    py: Python<'_>,
    dir: PathBuf,
    tolerance: f64,
    alpha: f64,
) -> PyResult<Bound<'_, PyAny>> {
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(invalid(format!(
            "tolerance = {tolerance} must be finite and non-negative"
        )));
    }
    let report = sepg_runs::audit::audit(&dir, tolerance, alpha).map_err(run_error)?;
    serialize_to_py(py, &report)
}

/// The sweep file (TOML) at `path` as JSON text, for [`sweep_folder`] and [`sweep_prepare`].
#[pyfunction]
fn read_sweep_file(path: PathBuf) -> PyResult<String> {
    serde_json::to_string(&sweep::read_spec(&path).map_err(invalid)?).map_err(failed)
}

/// Runs the numerical checks of the thesis's statements (`sepg-verification`, as
/// `sepg verify`): all, or those whose identifier contains `check`; `quick` runs the CI
/// subset. Returns the report as a dict (each check's outcome and whether it is the
/// recorded one). Built with the `verify` feature only.
#[cfg(feature = "verify")]
#[pyfunction]
#[pyo3(signature = (quick = true, check = None, seed = 0))]
fn verify<'py>(
    py: Python<'py>,
    quick: bool,
    check: Option<&str>,
    seed: u64,
) -> PyResult<Bound<'py, PyAny>> {
    let checks = sepg_verification::registry();
    if let Some(f) = check
        && !checks.iter().any(|c| c.meta.id.contains(f))
    {
        return Err(invalid(format!("no check matches {f:?}")));
    }
    let config = sepg_verification::RunConfig { seed, quick };
    let report = py.detach(|| sepg_verification::run_checks(&checks, &config, check, |_| {}));
    serialize_to_py(py, &report)
}

/// Without the `verify` feature (the default wheel, which does not ship the verification
/// harness): says how to get the checks.
#[cfg(not(feature = "verify"))]
#[pyfunction]
#[pyo3(signature = (quick = true, check = None, seed = 0))]
fn verify<'py>(
    py: Python<'py>,
    quick: bool,
    check: Option<&str>,
    seed: u64,
) -> PyResult<Bound<'py, PyAny>> {
    let _ = (py, quick, check, seed);
    Err(failed(
        "this build of sepg has no verification harness: run `sepg verify`, or build the \
         package with `maturin develop --release --features verify`",
    ))
}

/// Adds the functions of this module to `m`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run_folder, m)?)?;
    m.add_function(wrap_pyfunction!(resume_folder, m)?)?;
    m.add_function(wrap_pyfunction!(read_folder, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_folder, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_prepare, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_run, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_finish, m)?)?;
    m.add_function(wrap_pyfunction!(merge_folders, m)?)?;
    m.add_function(wrap_pyfunction!(audit_folder, m)?)?;
    m.add_function(wrap_pyfunction!(read_sweep_file, m)?)?;
    m.add_function(wrap_pyfunction!(verify, m)?)?;
    Ok(())
}
