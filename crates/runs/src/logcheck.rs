//! Validation of the log of a run folder: the checks `sepg audit` makes before it reads a
//! log, shared with `sepg merge` and `sepg plot` so that no command accepts a log another
//! one refuses.
//!
//! A log is valid when it has the header of the run's dimensions, every row has the header's
//! width, every cell is a finite number (empty where a value does not apply, `-inf` for a
//! deterministic target's log standard deviation), counters are non-negative integers, and
//! the rows are exactly those of the iterations the run completed that its `log-every`
//! logs, in order. A finished run has `log.csv` and a `summary.json` reporting the
//! configured number of iterations; an interrupted one has `log.partial.csv`, read up to the
//! length its `checkpoint.json` records. [`validate_log`] reports what it found;
//! [`LogCheck::require_valid`] and [`LogCheck::require_complete`] turn that into the one-line
//! error the commands print.

use sepg_algo::core::check::ConstantsCheck;
use std::fs;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::folder::{
    CHECKPOINT_FILE, Checkpoint, LOG_FILE, PARTIAL_LOG_FILE, SUMMARY_FILE, Summary, load_resolved,
    log_header,
};

/// The first line of a log that is not valid.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BadLine {
    /// Line number in the file, from 1 (the header); one past the last line when rows are
    /// missing at the end.
    pub line: usize,
    /// What is wrong with it, for a user (names the line).
    pub reason: String,
}

/// What [`validate_log`] found in a run folder's log.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LogCheck {
    /// The log file read (`log.csv`, or `log.partial.csv` of an interrupted run).
    pub log: PathBuf,
    /// Iterations of the whole run (its configuration).
    pub iterations_expected: u64,
    /// Iterations the run completed: the configured total for a finished run (from
    /// `summary.json`), the checkpointed count for an interrupted one.
    pub iterations_done: u64,
    /// Rows the log must hold for the completed iterations (`log-every` k logs every k-th
    /// iteration and the last).
    pub rows_expected: u64,
    /// Valid rows read before the first bad line (all of them for a valid log).
    pub rows_valid: u64,
    /// Iteration of the last valid row.
    pub last_iteration: Option<u64>,
    /// Whether the run finished (`log.csv` with a matching `summary.json`).
    pub complete: bool,
    /// The first line that is not valid, if any.
    pub first_bad: Option<BadLine>,
}

impl LogCheck {
    /// Whether every line of the log is valid (the run may still be unfinished).
    pub fn is_valid(&self) -> bool {
        self.first_bad.is_none()
    }

    /// `Ok` for a valid log.
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the log file and its first bad line.
    pub fn require_valid(&self) -> Result<()> {
        match &self.first_bad {
            None => Ok(()),
            Some(b) => Err(Error::invalid(format!(
                "{}: {}",
                self.log.display(),
                b.reason
            ))),
        }
    }

    /// `Ok` for a valid log of a finished run.
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the log file and its first bad line, or stating that the
    /// run is unfinished.
    pub fn require_complete(&self) -> Result<()> {
        self.require_valid()?;
        if self.complete {
            return Ok(());
        }
        Err(Error::invalid(format!(
            "{}: the run is unfinished ({} of {} iterations)",
            self.log.display(),
            self.iterations_done,
            self.iterations_expected
        )))
    }
}

/// Validates the log of the run folder `path` (or of the folder holding `path`, when it is a
/// file such as `log.csv`) as `sepg audit` does, and reports what it found. A log with a bad
/// line is not an error here: the first bad line is in [`LogCheck::first_bad`].
///
/// # Errors
/// [`Error::Invalid`] when the folder has no valid configuration, no readable log, a
/// `log.csv` without a `summary.json` that matches the configuration, or a `log.partial.csv`
/// without a checkpoint that fits it.
pub fn validate_log(path: &Path) -> Result<LogCheck> {
    let dir = if path.is_file() {
        match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        }
    } else {
        path
    };
    if !dir.is_dir() {
        return Err(Error::invalid(format!("{} is not a folder", dir.display())));
    }
    let resolved = load_resolved(dir)?;
    let total = resolved.iterations();
    let every = resolved.log_every();
    let (bytes, progress) = log_bytes(dir, total, resolved.dims)?;
    let (rows, first_bad) = scan_log(&bytes, resolved.dims, (progress.done, every, total));
    let log = dir.join(if progress.complete {
        LOG_FILE
    } else {
        PARTIAL_LOG_FILE
    });
    Ok(LogCheck {
        log,
        iterations_expected: total,
        iterations_done: progress.done,
        rows_expected: (0..progress.done)
            .filter(|&t| logged(t, every, total))
            .count() as u64,
        rows_valid: rows.len() as u64,
        last_iteration: rows.last().map(|r| r.iteration),
        complete: progress.complete,
        first_bad,
    })
}

/// One parsed row of `log.csv`.
#[derive(Debug, Clone)]
pub(crate) struct Row {
    pub(crate) iteration: u64,
    pub(crate) v: Vec<f64>,
    pub(crate) w: Vec<f64>,
    pub(crate) w_target: Vec<f64>,
    pub(crate) budget: f64,
    pub(crate) alpha: f64,
    pub(crate) beta: f64,
    pub(crate) guaranteed_v: Option<f64>,
    pub(crate) guaranteed_w: Option<f64>,
}

pub(crate) fn bad(dir: &Path, what: impl std::fmt::Display) -> Error {
    Error::invalid(format!("{}: {what}", dir.display()))
}

/// Columns holding counters (non-negative integers).
const INTEGER_COLUMNS: [&str; 8] = [
    "iteration",
    "infeasible",
    "infeasible_v",
    "infeasible_w",
    "below_noise_v",
    "below_noise_w",
    "trajectories",
    "steps",
];

/// Columns that are empty when they do not apply to the algorithm or the iteration.
const OPTIONAL_COLUMNS: [&str; 9] = [
    "certified_v",
    "certified_w",
    "j_after_v",
    "required",
    "required_w",
    "lambda_v",
    "lambda_w",
    "guaranteed_v",
    "guaranteed_w",
];

/// How the cells of a column are validated.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Cell {
    /// A non-negative integer.
    Integer,
    /// A finite number, or empty.
    Optional,
    /// A finite number, or `-inf` (the deterministic target's log standard deviation).
    WTarget,
    /// A finite number.
    Number,
}

fn cell_kind(name: &str) -> Cell {
    if INTEGER_COLUMNS.contains(&name) {
        Cell::Integer
    } else if OPTIONAL_COLUMNS.contains(&name) {
        Cell::Optional
    } else if name == "w_target" || name.starts_with("w_target_") {
        Cell::WTarget
    } else {
        Cell::Number
    }
}

/// The configuration, the completed iterations and the parameters after the last one.
pub(crate) struct Progress {
    /// Iterations completed (= the configured total for a finished run).
    pub(crate) done: u64,
    /// Whether the run finished (`log.csv` and a matching `summary.json`).
    pub(crate) complete: bool,
    /// θ after `done` iterations.
    pub(crate) last: Params,
    /// The summary of a finished run.
    pub(crate) summary: Option<Summary>,
    /// The declared constants checked against the run's data (summary or checkpoint).
    pub(crate) constants_check: ConstantsCheck,
}

/// Parameters θᵗ = (vᵗ, wᵗ).
pub(crate) struct Params {
    pub(crate) v: Vec<f64>,
    pub(crate) w: Vec<f64>,
}

fn read_checkpoint(dir: &Path) -> Result<Option<Checkpoint>> {
    let path = dir.join(CHECKPOINT_FILE);
    if !path.is_file() {
        return Ok(None);
    }
    let text = fs::read_to_string(&path)
        .map_err(|e| bad(dir, format!("cannot read {CHECKPOINT_FILE}: {e}")).with_source(e))?;
    serde_json::from_str(&text)
        .map(Some)
        .map_err(|e| bad(dir, format!("{CHECKPOINT_FILE} is malformed: {e}")).with_source(e))
}

/// The bytes of the log and the run's progress: `log.csv` with its `summary.json`, or the
/// checkpointed prefix of `log.partial.csv`.
pub(crate) fn log_bytes(
    dir: &Path,
    total: u64,
    dims: (usize, usize),
) -> Result<(Vec<u8>, Progress)> {
    let done = dir.join(LOG_FILE);
    if done.is_file() {
        finished_log(dir, &done, total, dims)
    } else {
        partial_log(dir, total, dims)
    }
}

/// Whether every element of `xs` is finite.
fn finite(xs: &[f64]) -> bool {
    xs.iter().all(|x| x.is_finite())
}

/// The bytes of the finished log `done` and the progress its `summary.json` records.
fn finished_log(
    dir: &Path,
    done: &Path,
    total: u64,
    dims: (usize, usize),
) -> Result<(Vec<u8>, Progress)> {
    let bytes = fs::read(done)
        .map_err(|e| bad(dir, format!("cannot read {LOG_FILE}: {e}")).with_source(e))?;
    let path = dir.join(SUMMARY_FILE);
    if !path.is_file() {
        return Err(bad(
            dir,
            format!(
                "{LOG_FILE} without {SUMMARY_FILE}: the run did not finish writing its folder \
                 (sepg run --resume {} completes it)",
                dir.display()
            ),
        ));
    }
    let text = fs::read_to_string(&path)
        .map_err(|e| bad(dir, format!("cannot read {SUMMARY_FILE}: {e}")).with_source(e))?;
    let s: Summary = serde_json::from_str(&text)
        .map_err(|e| bad(dir, format!("{SUMMARY_FILE} is malformed: {e}")).with_source(e))?;
    // a run stopped by a contradiction of its constants ends before its total
    let stopped = s.status == "stopped"
        && s.constants_check
            .as_ref()
            .is_some_and(ConstantsCheck::contradicted);
    if s.iterations != total && !(stopped && s.iterations < total) {
        return Err(bad(
            dir,
            format!(
                "{SUMMARY_FILE} reports {} iterations, the configuration {total}",
                s.iterations
            ),
        ));
    }
    let (v, w) = (s.final_params.v.clone(), s.final_params.w.clone());
    if v.len() != dims.0 || w.len() != dims.1 || !finite(&v) || !finite(&w) {
        return Err(bad(
            dir,
            format!("{SUMMARY_FILE}: the final parameters do not fit the run"),
        ));
    }
    let progress = Progress {
        done: s.iterations,
        complete: true,
        last: Params { v, w },
        constants_check: s.constants_check.clone().unwrap_or_default(),
        summary: Some(s),
    };
    Ok((bytes, progress))
}

/// The checkpointed prefix of `log.partial.csv` and the progress its checkpoint records.
fn partial_log(dir: &Path, total: u64, dims: (usize, usize)) -> Result<(Vec<u8>, Progress)> {
    let mut bytes = fs::read(dir.join(PARTIAL_LOG_FILE)).map_err(|e| {
        bad(
            dir,
            format!("no {LOG_FILE} and no readable {PARTIAL_LOG_FILE}: {e}"),
        )
        .with_source(e)
    })?;
    let ck = read_checkpoint(dir)?.ok_or_else(|| {
        bad(
            dir,
            format!("{PARTIAL_LOG_FILE} without a valid {CHECKPOINT_FILE}"),
        )
    })?;
    let valid = usize::try_from(ck.log_bytes).unwrap_or(usize::MAX);
    if valid > bytes.len() {
        return Err(bad(
            dir,
            format!("{PARTIAL_LOG_FILE} is shorter than its checkpoint says"),
        ));
    }
    bytes.truncate(valid);
    let s = ck.state;
    if s.iteration > total
        || s.v.len() != dims.0
        || s.w.len() != dims.1
        || !finite(&s.v)
        || !finite(&s.w)
    {
        return Err(bad(
            dir,
            format!("{CHECKPOINT_FILE} does not fit the run's configuration"),
        ));
    }
    let progress = Progress {
        done: s.iteration,
        complete: false,
        last: Params { v: s.v, w: s.w },
        summary: None,
        constants_check: s.constants_check,
    };
    Ok((bytes, progress))
}

/// Positions of the columns the audit reads, in a header of this run's dimensions.
struct Columns<'h> {
    names: Vec<&'h str>,
    kinds: Vec<Cell>,
    v: Vec<usize>,
    w: Vec<usize>,
    w_target: Vec<usize>,
    /// budget, alpha, beta, guaranteed_v, guaranteed_w.
    scalars: [usize; 5],
}

impl<'h> Columns<'h> {
    fn new(header: &'h str, dims: (usize, usize)) -> Result<Columns<'h>, String> {
        let names: Vec<&str> = header.split(',').collect();
        let col = |name: &str| names.iter().position(|c| *c == name);
        let cols = |name: &str, dim: usize| -> Vec<usize> {
            if dim == 1 {
                col(name).into_iter().collect()
            } else {
                (0..dim)
                    .filter_map(|i| col(&format!("{name}_{i}")))
                    .collect()
            }
        };
        let named = |name: &str| col(name).ok_or_else(|| format!("the log has no column {name}"));
        let scalars = ["budget", "alpha", "beta", "guaranteed_v", "guaranteed_w"].map(named);
        let [a, b, c, d, e] = scalars;
        Ok(Columns {
            v: cols("v", dims.0),
            w: cols("w", dims.1),
            w_target: cols("w_target", dims.1),
            scalars: [a?, b?, c?, d?, e?],
            kinds: names.iter().map(|n| cell_kind(n)).collect(),
            names,
        })
    }

    /// Parses line `line_no` of the log (1 is the header): every cell is validated by the
    /// kind of its column.
    fn row(&self, line_no: usize, line: &str) -> Result<Row, String> {
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != self.names.len() {
            return Err(format!(
                "log line {line_no} has {} cells, the header {}",
                cells.len(),
                self.names.len()
            ));
        }
        let mut values = Vec::with_capacity(cells.len());
        for ((c, name), kind) in cells.iter().zip(&self.names).zip(&self.kinds) {
            let at = || format!("log line {line_no}, column {name}");
            let value = match kind {
                Cell::Integer => Some(
                    c.parse::<u64>()
                        .map_err(|_| format!("{}: {c:?} is not a non-negative integer", at()))?
                        as f64,
                ),
                _ if c.is_empty() => {
                    if *kind != Cell::Optional {
                        return Err(format!("{} is empty", at()));
                    }
                    None
                }
                _ => {
                    let x = c
                        .parse::<f64>()
                        .map_err(|_| format!("{}: {c:?} is not a number", at()))?;
                    let allowed =
                        x.is_finite() || (*kind == Cell::WTarget && x == f64::NEG_INFINITY);
                    if !allowed {
                        return Err(format!("{}: {c} is not a finite number", at()));
                    }
                    Some(x)
                }
            };
            values.push(value);
        }
        let iteration: u64 = cells[0].parse().unwrap_or_default();
        let req = |i: usize| values[i].unwrap_or_default();
        let many = |idx: &[usize]| idx.iter().map(|&i| req(i)).collect::<Vec<_>>();
        let [ib, ia, ibt, igv, igw] = self.scalars;
        Ok(Row {
            iteration,
            v: many(&self.v),
            w: many(&self.w),
            w_target: many(&self.w_target),
            budget: req(ib),
            alpha: req(ia),
            beta: req(ibt),
            guaranteed_v: values[igv],
            guaranteed_w: values[igw],
        })
    }
}

/// Whether the run logs the row of iteration `t` (`log-every` k: every k-th and the last).
fn logged(t: u64, every: u64, total: u64) -> bool {
    t.is_multiple_of(every) || t + 1 == total
}

/// Reads the log strictly: the header of this run's dimensions, rows of the same width and
/// validated cells, and exactly the rows of the first `done` iterations that `log-every`
/// logs, in order. Returns the valid rows before the first bad line, and that line.
fn scan_log(
    bytes: &[u8],
    dims: (usize, usize),
    (done, every, total): (u64, u64, u64),
) -> (Vec<Row>, Option<BadLine>) {
    let mut rows: Vec<Row> = Vec::new();
    let text = match std::str::from_utf8(bytes) {
        Ok(t) => t,
        Err(e) => {
            let line = 1 + bytes[..e.valid_up_to()]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            let reason = format!("log line {line} is not UTF-8");
            return (rows, Some(BadLine { line, reason }));
        }
    };
    let mut lines = text.split_terminator('\n');
    let header = log_header(dims.0, dims.1);
    if lines.next() != Some(header.trim_end()) {
        let reason = "the log header does not match the run's configuration".to_owned();
        return (rows, Some(BadLine { line: 1, reason }));
    }
    let columns = match Columns::new(header.trim_end(), dims) {
        Ok(c) => c,
        Err(reason) => return (rows, Some(BadLine { line: 1, reason })),
    };
    let mut expected = (0..done).filter(|&t| logged(t, every, total));
    let mut line_no = 1;
    for line in lines {
        line_no += 1;
        let row = match columns.row(line_no, line) {
            Ok(r) => r,
            Err(reason) => {
                return (
                    rows,
                    Some(BadLine {
                        line: line_no,
                        reason,
                    }),
                );
            }
        };
        let reason = match expected.next() {
            Some(t) if t == row.iteration => {
                rows.push(row);
                continue;
            }
            Some(t) => format!(
                "log line {line_no} is iteration {}, expected {t}: rows are missing or out of order",
                row.iteration
            ),
            None => format!(
                "log line {line_no} (iteration {}) is beyond the {done} iterations the run completed",
                row.iteration
            ),
        };
        return (
            rows,
            Some(BadLine {
                line: line_no,
                reason,
            }),
        );
    }
    if let Some(t) = expected.next() {
        let reason = format!("the log ends before the row of iteration {t} (rows are missing)");
        let line = line_no + 1;
        return (rows, Some(BadLine { line, reason }));
    }
    (rows, None)
}

/// [`scan_log`] as the audit needs it: the rows of a valid log.
///
/// # Errors
/// [`Error::Invalid`] naming the folder `dir` and the first bad line.
pub(crate) fn parse_log(
    dir: &Path,
    bytes: &[u8],
    dims: (usize, usize),
    progress: (u64, u64, u64),
) -> Result<Vec<Row>> {
    match scan_log(bytes, dims, progress) {
        (rows, None) => Ok(rows),
        (_, Some(b)) => Err(bad(dir, b.reason)),
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::AtomicBool;

    use super::*;
    use crate::run::{RunOptions, Silent, start};
    use crate::spec::RunSpec;

    /// The columns validated as counters or as optional are columns of log.csv: a name
    /// misspelled here would leave its column validated as a plain number.
    #[test]
    fn the_validated_column_kinds_name_columns_of_the_log() {
        for name in INTEGER_COLUMNS.iter().chain(&OPTIONAL_COLUMNS) {
            assert!(
                crate::folder::LOG_COLUMNS.contains(name),
                "{name} is not a column of log.csv"
            );
        }
    }

    /// A finished run of `iterations` iterations in a new folder `run` under `tmp`.
    fn finished(tmp: &Path, iterations: u64) -> PathBuf {
        let resolved = RunSpec {
            iterations: Some(iterations),
            batch: Some(12),
            ..RunSpec::default()
        }
        .resolve()
        .expect("valid");
        let dir = tmp.join("run");
        let never = AtomicBool::new(false);
        let opts = RunOptions {
            checkpoint_every: 2,
            stop: &never,
            observer: &Silent,
        };
        start(&dir, &resolved, opts).expect("run");
        dir
    }

    #[test]
    fn a_finished_log_is_valid_and_complete() {
        let tmp = tempfile::tempdir().expect("tempdir");
        let dir = finished(tmp.path(), 5);
        let check = validate_log(&dir.join(LOG_FILE)).expect("check");
        assert_eq!(check.first_bad, None);
        assert!(check.complete);
        assert_eq!((check.iterations_expected, check.iterations_done), (5, 5));
        assert_eq!((check.rows_expected, check.rows_valid), (5, 5));
        assert_eq!(check.last_iteration, Some(4));
        check.require_complete().expect("complete");
    }

    #[test]
    fn a_truncated_log_names_its_first_bad_line() {
        let tmp = tempfile::tempdir().expect("tempdir");
        let dir = finished(tmp.path(), 5);
        let log = dir.join(LOG_FILE);
        let text = fs::read_to_string(&log).expect("log");
        // Cut in the middle of the fourth line (the row of iteration 2).
        let starts: Vec<usize> = text.match_indices('\n').map(|(i, _)| i + 1).collect();
        fs::write(&log, &text[..starts[2] + 5]).expect("cut");
        let check = validate_log(&dir).expect("check");
        let bad = check.first_bad.clone().expect("bad line");
        assert_eq!(bad.line, 4);
        assert!(bad.reason.starts_with("log line 4 has "), "{}", bad.reason);
        assert_eq!((check.rows_valid, check.last_iteration), (2, Some(1)));
        let e = check.require_valid().expect_err("refused").to_string();
        assert!(e.contains("log.csv") && e.contains("log line 4"), "{e}");
        // Cut at the end of a line: the missing rows are named.
        fs::write(&log, &text[..starts[3]]).expect("cut");
        let bad = validate_log(&dir).expect("check").first_bad.expect("bad");
        assert_eq!(bad.line, 5);
        assert!(bad.reason.contains("iteration 3"), "{}", bad.reason);
    }

    #[test]
    fn a_nan_cell_is_refused_with_its_column() {
        let tmp = tempfile::tempdir().expect("tempdir");
        let dir = finished(tmp.path(), 3);
        let log = dir.join(LOG_FILE);
        let text = fs::read_to_string(&log).expect("log");
        let mut lines: Vec<String> = text.lines().map(String::from).collect();
        let mut cells: Vec<&str> = lines[2].split(',').collect();
        cells[1] = "NaN";
        lines[2] = cells.join(",");
        fs::write(&log, lines.join("\n") + "\n").expect("write");
        let bad = validate_log(&dir).expect("check").first_bad.expect("bad");
        assert_eq!(bad.line, 3);
        assert!(bad.reason.contains("column v: NaN"), "{}", bad.reason);
    }

    #[test]
    fn an_unfinished_run_is_valid_but_not_complete() {
        let tmp = tempfile::tempdir().expect("tempdir");
        let dir = finished(tmp.path(), 4);
        // The state a run leaves between its final rename and its summary.
        fs::remove_file(dir.join(SUMMARY_FILE)).expect("remove");
        assert!(validate_log(&dir).is_err());
        let tmp = tempfile::tempdir().expect("tempdir");
        let resolved = RunSpec {
            iterations: Some(6),
            batch: Some(12),
            ..RunSpec::default()
        }
        .resolve()
        .expect("valid");
        let dir = tmp.path().join("run");
        let stop = AtomicBool::new(true);
        let opts = RunOptions {
            checkpoint_every: 2,
            stop: &stop,
            observer: &Silent,
        };
        assert!(start(&dir, &resolved, opts).is_err());
        let check = validate_log(&dir).expect("check");
        assert!(check.is_valid() && !check.complete);
        assert_eq!((check.iterations_done, check.rows_valid), (1, 1));
        let e = check
            .require_complete()
            .expect_err("unfinished")
            .to_string();
        assert!(e.contains("unfinished (1 of 6 iterations)"), "{e}");
    }
}
