//! One run: executes an algorithm of `sepg-algo` into a run folder, checkpointing as it goes,
//! and resumes it bit for bit.
//!
//! Rows are appended in chunks of `checkpoint_every` iterations; after each chunk the log is
//! flushed to disk and the checkpoint is replaced atomically. When every iteration is done,
//! `log.partial.csv` is renamed to `log.csv` and then `summary.json` is written. A run killed
//! at any point therefore leaves one of three folders, each of which every reader recognises:
//! - no `log.csv`: a checkpoint whose state matches the first `log_bytes` bytes of
//!   `log.partial.csv` (resuming truncates the log there and continues);
//! - `log.csv` but no `summary.json`: every row is written and the checkpoint holds the final
//!   state (the run is still incomplete; resuming writes only the summary);
//! - `summary.json`: the run is complete.
//!
//! Because every batch of trajectories is seeded by (seed, iteration, block), the resumed run
//! produces the same rows, bit for bit, as an uninterrupted one.
//!
//! A run stops early, after checkpointing, when its stop flag is raised (the command line
//! raises it on Ctrl-C): after the current iteration, or inside it when the process-wide
//! cancellation request of `sepg_mdp::cancel` is raised too (the iteration's rollouts or
//! dynamic programme then fail at once, its work is discarded and the checkpoint is that of
//! the last completed iteration). It reports its progress to a [`RunObserver`].

use std::fs::{self, File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use sepg_algo::core::check::{ConstantsCheck, Offence};
use sepg_algo::core::error::RunError;
use sepg_algo::core::executor::Solver;
use sepg_algo::core::record::Record;
use sepg_algo::core::state::State;

use crate::error::{Error, Result};
use crate::folder::{
    CHECKPOINT_FILE, CONFIG_FILE, Checkpoint, FinalParams, LOG_FILE, PARTIAL_LOG_FILE,
    SUMMARY_FILE, Summary, Tally, UsedConstants, io_fail, is_complete, load_resolved, log_header,
    log_row, read_summary, to_json_line, write_atomic,
};
use crate::spec::{Resolved, VERSION};

/// Receives the progress of a run (iterations) or of a sweep (runs). Every method does
/// nothing by default; implementations must be shareable across the threads of a sweep.
pub trait RunObserver: Sync {
    /// Called once before the work starts: `done` of `total` units are already done.
    fn begin(&self, _done: u64, _total: u64) {}
    /// Called after each unit of work: `done` units are done so far.
    fn advance(&self, _done: u64) {}
    /// Called once when the work ends, whether it completed or not.
    fn end(&self) {}
    /// Called each time a file of the run folder has been given its new contents on disk:
    /// `file` is the name of the file written (one of [`crate::folder::RUN_FILES`]). The run
    /// writes its folder in steps (the partial log, then the checkpoint, then the
    /// configuration when it starts; rows appended to the partial log, then the checkpoint
    /// replaced, at each checkpoint; the partial log renamed to the log, then the summary, when
    /// it ends), and a process killed between two calls leaves the folder as it was at the
    /// last one.
    fn wrote(&self, _file: &str) {}
}

/// The observer that ignores every report.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl RunObserver for Silent {}

/// How a run is driven: checkpoint period, stop flag and progress observer.
#[derive(Clone, Copy)]
pub struct RunOptions<'a> {
    /// Iterations between checkpoints (at least 1).
    pub checkpoint_every: u64,
    /// When raised, the run stops after its current iteration, checkpoints and returns
    /// [`Error::Interrupted`].
    pub stop: &'a AtomicBool,
    /// Receives the number of iterations done.
    pub observer: &'a dyn RunObserver,
}

/// Starts a new run of `resolved` in `dir` (created if needed; the caller has checked it is
/// empty, see [`crate::folder::check_out_dir`]) and runs it to completion.
///
/// # Errors
/// [`Error::Failed`] for I/O errors or a failing iteration; [`Error::Interrupted`] when the
/// stop flag was raised (after checkpointing).
pub fn start(dir: &Path, resolved: &Resolved, opts: RunOptions<'_>) -> Result<Summary> {
    let first = preflight(resolved).map_err(|e| {
        if stopping(&opts) {
            Error::failed(format!(
                "{}: interrupted before the run started; nothing was written",
                dir.display()
            ))
        } else {
            e
        }
    })?;
    fs::create_dir_all(dir).map_err(|e| io_fail("create", dir, e))?;
    let mut log = log_header(resolved.dims.0, resolved.dims.1);
    let mut ck = Checkpoint {
        log_bytes: 0,
        elapsed_s: 0.0,
        tally: Tally::default(),
        state: resolved.checked.initial_state(),
    };
    let mut done = 0;
    if let Some(first) = first {
        // iteration 0 ran in memory: its row and the state after it are the folder's start
        if first.record.iteration.is_multiple_of(resolved.log_every())
            || first.state.iteration == resolved.iterations()
        {
            log.push_str(&log_row(&first.record));
        }
        ck.tally.add(&first.record);
        ck.elapsed_s = first.elapsed_s;
        done = first.state.iteration;
        ck.state = first.state;
    }
    ck.log_bytes = log.len() as u64;
    write_atomic(&dir.join(PARTIAL_LOG_FILE), log.as_bytes())?;
    opts.observer.wrote(PARTIAL_LOG_FILE);
    write_atomic(&dir.join(CHECKPOINT_FILE), to_json_line(&ck)?.as_bytes())?;
    opts.observer.wrote(CHECKPOINT_FILE);
    // The configuration goes last: a folder with a config.toml always has a checkpoint.
    write_atomic(&dir.join(CONFIG_FILE), resolved.toml()?.as_bytes())?;
    opts.observer.wrote(CONFIG_FILE);
    let total = resolved.iterations();
    if done > 0 {
        // the iteration done in memory counts as any other: reported, and a stop raised
        // meanwhile ends the run after it
        opts.observer.begin(0, total);
        opts.observer.advance(done);
        if opts.stop.load(Ordering::SeqCst) && done < total {
            opts.observer.end();
            return Err(Error::Interrupted {
                iteration: done,
                total,
                dir: dir.to_path_buf(),
            });
        }
    }
    drive(dir, resolved, ck, opts)
}

/// Resumes the run in `dir` from its checkpoint and runs it to completion; a complete run is
/// returned as is.
///
/// # Errors
/// [`Error::Invalid`] when `dir` is not a resumable run folder; otherwise as [`start`].
pub fn resume(dir: &Path, opts: RunOptions<'_>) -> Result<Summary> {
    let resolved = load_resolved(dir)?;
    if is_complete(dir) {
        let summary = read_summary(dir)?;
        if let Some(reason) = summary
            .constants_check
            .as_ref()
            .and_then(ConstantsCheck::reason)
            .filter(|_| summary.status == "stopped")
        {
            return Err(Error::failed(format!(
                "{}: the run stopped and cannot be resumed: {reason}",
                dir.display()
            )));
        }
        return Ok(summary);
    }
    let ck_path = dir.join(CHECKPOINT_FILE);
    let text = fs::read_to_string(&ck_path)
        .map_err(|e| Error::invalid_from(format!("cannot read {}", ck_path.display()), e))?;
    let ck: Checkpoint = serde_json::from_str(&text).map_err(|e| {
        Error::invalid_from(
            format!("{} is not a valid checkpoint", ck_path.display()),
            e,
        )
    })?;
    let partial = dir.join(PARTIAL_LOG_FILE);
    let finished = dir.join(LOG_FILE);
    if !partial.exists() && finished.is_file() && ck.state.iteration == resolved.iterations() {
        // Killed between the final rename and the summary: only the summary is missing.
        return finish(dir, &resolved, &ck, opts.observer);
    }
    truncate_log(&partial, ck.log_bytes)?;
    opts.observer.wrote(PARTIAL_LOG_FILE);
    drive(dir, &resolved, ck, opts)
}

/// Cuts the partial log back to the `log_bytes` its checkpoint vouches for.
fn truncate_log(partial: &Path, log_bytes: u64) -> Result<()> {
    let file = OpenOptions::new()
        .write(true)
        .open(partial)
        .map_err(|e| Error::invalid_from(format!("cannot open {}", partial.display()), e))?;
    let len = file
        .metadata()
        .map_err(|e| io_fail("read", partial, e))?
        .len();
    if len < log_bytes {
        return Err(Error::invalid(format!(
            "{} is shorter ({len} bytes) than its checkpoint says ({log_bytes} bytes)",
            partial.display(),
        )));
    }
    file.set_len(log_bytes)
        .map_err(|e| io_fail("truncate", partial, e))?;
    file.sync_all().map_err(|e| io_fail("sync", partial, e))
}

/// The log being appended to and the checkpoint of the rows already on disk.
struct Writer {
    dir: PathBuf,
    partial: PathBuf,
    log: File,
    ck: Checkpoint,
    chunk: String,
    segment: Instant,
}

impl Writer {
    fn open(dir: &Path, ck: Checkpoint) -> Result<Writer> {
        let partial = dir.join(PARTIAL_LOG_FILE);
        let log = OpenOptions::new()
            .append(true)
            .open(&partial)
            .map_err(|e| io_fail("open", &partial, e))?;
        Ok(Writer {
            dir: dir.to_path_buf(),
            partial,
            log,
            ck,
            chunk: String::new(),
            segment: Instant::now(),
        })
    }

    /// Appends the buffered rows to the log, syncs it, and replaces the checkpoint by one for
    /// `tally` and `state`, telling `observer` after each of the two writes.
    fn checkpoint(
        &mut self,
        tally: &Tally,
        state: &State,
        observer: &dyn RunObserver,
    ) -> Result<()> {
        self.log
            .write_all(self.chunk.as_bytes())
            .and_then(|()| self.log.sync_data())
            .map_err(|e| io_fail("write", &self.partial, e))?;
        observer.wrote(PARTIAL_LOG_FILE);
        self.ck = Checkpoint {
            log_bytes: self.ck.log_bytes + self.chunk.len() as u64,
            elapsed_s: self.ck.elapsed_s + self.segment.elapsed().as_secs_f64(),
            tally: tally.clone(),
            state: state.clone(),
        };
        self.segment = Instant::now();
        self.chunk.clear();
        write_atomic(
            &self.dir.join(CHECKPOINT_FILE),
            to_json_line(&self.ck)?.as_bytes(),
        )?;
        observer.wrote(CHECKPOINT_FILE);
        Ok(())
    }
}

/// Whether the run was asked to stop: its stop flag, or the process-wide cancellation request
/// of `sepg-mdp` (which makes a rollout or dynamic programme in progress fail with a
/// `Cancelled` error, so that a long iteration stops within one chunk of its work).
fn stopping(opts: &RunOptions<'_>) -> bool {
    opts.stop.load(Ordering::SeqCst) || sepg_mdp::cancel::requested()
}

/// The first iteration of a run, computed before its folder exists.
struct First {
    record: Record,
    state: State,
    elapsed_s: f64,
}

/// Runs the first iteration in memory, before anything is written: a configuration whose
/// initial policy the environment or the oracle cannot take (a mean so large that the scores
/// overflow, a clipped DP that would need more elements than it allows, …) is bad input,
/// refused without leaving a folder. The iteration is kept: the folder starts with its row and
/// the state after it, as a run resumed from that checkpoint would, so the results are the same
/// bit for bit and nothing is computed twice. `None` when there is nothing to run, or when the
/// first batch contradicts the declared constants (the run itself then records that, as it
/// does at any iteration).
fn preflight(resolved: &Resolved) -> Result<Option<First>> {
    let refuse = |e: &dyn std::fmt::Display| {
        Error::invalid(format!("the run cannot start from its initial policy: {e}"))
    };
    let mut solver = resolved.solver()?;
    if resolved.iterations() == 0 {
        return Ok(None);
    }
    let clock = Instant::now();
    let mut state = resolved.checked.initial_state();
    let record = solver
        .init(&mut state)
        .and_then(|()| solver.next_iter(&mut state));
    match record {
        Ok(record) => Ok(Some(First {
            record,
            state,
            elapsed_s: clock.elapsed().as_secs_f64(),
        })),
        Err(RunError::ConstantsContradicted(_)) => Ok(None),
        Err(e) => Err(refuse(&e)),
    }
}

/// Iterates from the checkpoint `ck` to the end of the run, then finishes the folder.
fn drive(dir: &Path, resolved: &Resolved, ck: Checkpoint, opts: RunOptions<'_>) -> Result<Summary> {
    let total = resolved.iterations();
    let every = resolved.log_every();
    let mut writer = Writer::open(dir, ck)?;
    let mut solver = resolved.solver()?;
    let mut state = writer.ck.state.clone();
    if state.iteration == 0
        && let Err(e) = solver.init(&mut state)
    {
        if stopping(&opts) {
            return Err(Error::Interrupted {
                iteration: 0,
                total,
                dir: dir.to_path_buf(),
            });
        }
        return Err(Error::failed(e.to_string()));
    }
    opts.observer.begin(state.iteration, total);
    let mut tally = writer.ck.tally.clone();
    let period = opts.checkpoint_every.max(1);
    while state.iteration < total {
        let before = state.clone();
        let record = match solver.next_iter(&mut state) {
            Ok(r) => r,
            Err(RunError::ConstantsContradicted(offence)) => {
                opts.observer.end();
                return stop_contradicted(dir, resolved, writer, &tally, before, *offence, opts);
            }
            Err(e) => {
                opts.observer.end();
                // Keep every row computed so far: checkpoint the state the failing iteration
                // started from, with the rows up to it.
                writer.checkpoint(&tally, &before, opts.observer)?;
                if stopping(&opts) {
                    // Cancelled in the middle of the iteration: its work is discarded.
                    return Err(Error::Interrupted {
                        iteration: before.iteration,
                        total,
                        dir: dir.to_path_buf(),
                    });
                }
                return Err(Error::failed(format!(
                    "{}: iteration {} failed ({e}); the {} row(s) before it are kept in {PARTIAL_LOG_FILE}",
                    dir.display(),
                    before.iteration,
                    before.iteration
                )).with_source(e));
            }
        };
        tally.add(&record);
        if record.iteration.is_multiple_of(every) || state.iteration == total {
            writer.chunk.push_str(&log_row(&record));
        }
        opts.observer.advance(state.iteration);
        let stop = opts.stop.load(Ordering::SeqCst);
        if state.iteration.is_multiple_of(period) || state.iteration == total || stop {
            writer.checkpoint(&tally, &state, opts.observer)?;
            if stop && state.iteration < total {
                opts.observer.end();
                return Err(Error::Interrupted {
                    iteration: state.iteration,
                    total,
                    dir: dir.to_path_buf(),
                });
            }
        }
    }
    opts.observer.end();
    close(dir, resolved, writer, opts.observer)
}

/// Ends a run whose iteration `before.iteration` saw `offence`, a value contradicting the
/// declared constants (option `on-contradiction = stop`): the rows so far and the state before
/// that iteration, with the offence counted, are checkpointed; the log is closed and
/// `summary.json` written with status `stopped`, a statement of kind `none` and the
/// `constants_check` block. Returns the one-line error.
fn stop_contradicted(
    dir: &Path,
    resolved: &Resolved,
    mut writer: Writer,
    tally: &Tally,
    mut before: State,
    offence: Offence,
    opts: RunOptions<'_>,
) -> Result<Summary> {
    let message = RunError::ConstantsContradicted(Box::new(offence.clone())).to_string();
    before.constants_check.record(offence);
    writer.checkpoint(tally, &before, opts.observer)?;
    close(dir, resolved, writer, opts.observer)?;
    Err(Error::failed(format!(
        "{}: run stopped: {message}",
        dir.display()
    )))
}

/// Closes the log of `writer` (log.partial.csv becomes log.csv) and finishes the folder with
/// [`finish`]: the end of a complete run and of one stopped by a contradiction.
fn close(
    dir: &Path,
    resolved: &Resolved,
    writer: Writer,
    observer: &dyn RunObserver,
) -> Result<Summary> {
    let Writer {
        partial, log, ck, ..
    } = writer;
    drop(log);
    fs::rename(&partial, dir.join(LOG_FILE)).map_err(|e| io_fail("rename", &partial, e))?;
    observer.wrote(LOG_FILE);
    finish(dir, resolved, &ck, observer)
}

/// Writes `summary.json` from the final checkpoint `ck`, completing the run.
fn finish(
    dir: &Path,
    resolved: &Resolved,
    ck: &Checkpoint,
    observer: &dyn RunObserver,
) -> Result<Summary> {
    let s = &ck.state;
    let v_star = resolved.v_star();
    let abs_v_error = v_star.as_ref().map(|vs| {
        s.v.iter()
            .zip(vs)
            .fold(0.0_f64, |m, (v, vs)| m.max((v - vs).abs()))
    });
    let wall = ck.elapsed_s;
    let rate = |x: f64| if wall > 0.0 { x / wall } else { 0.0 };
    let contradicted = s.constants_check.contradicted();
    let summary = Summary {
        status: if contradicted && s.iteration < resolved.iterations() {
            "stopped".into()
        } else {
            "complete".into()
        },
        name: resolved.spec.name.clone().unwrap_or_default(),
        sepg_version: VERSION.into(),
        iterations: s.iteration,
        final_params: FinalParams {
            v: s.v.clone(),
            w: s.w.clone(),
            sigma: s.sigma(),
            budget: s.budget,
        },
        v_star,
        abs_v_error,
        last_j_explore: ck.tally.last_j_explore,
        last_j_target: ck.tally.last_j_target,
        infeasible_iterations: ck.tally.infeasible,
        below_noise_v_iterations: ck.tally.below_noise_v,
        below_noise_w_iterations: ck.tally.below_noise_w,
        trajectories: s.trajectories,
        steps: s.steps,
        wall_time_s: wall,
        iterations_per_s: rate(s.iteration as f64),
        env_steps_per_s: rate(s.steps as f64),
        options: resolved.checked.config().options,
        constants: UsedConstants::of(resolved),
        scores: resolved.spec.scores,
        certified_steps: resolved.spec.certified_steps,
        statement: Some(
            resolved
                .checked
                .statement()
                .checked_against(&s.constants_check),
        ),
        self_check: Some(ck.tally.self_check),
        constants_check: matches!(
            resolved.checked.config().gradient,
            sepg_algo::core::config::GradientMode::Sampled { .. }
        )
        .then(|| s.constants_check.clone()),
    };
    write_atomic(&dir.join(SUMMARY_FILE), to_json_line(&summary)?.as_bytes())?;
    observer.wrote(SUMMARY_FILE);
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::RunSpec;

    /// Raises the stop flag once `at` iterations are done, as Ctrl-C would.
    struct StopAt<'a> {
        at: u64,
        stop: &'a AtomicBool,
    }

    impl RunObserver for StopAt<'_> {
        fn advance(&self, done: u64) {
            if done == self.at {
                self.stop.store(true, Ordering::SeqCst);
            }
        }
    }

    /// Counts the folder writes and aborts the process (no destructor or unwinding runs, as
    /// under SIGKILL) right after the `after`-th one.
    struct AbortAfter {
        after: usize,
        count: std::sync::atomic::AtomicUsize,
    }

    impl RunObserver for AbortAfter {
        fn wrote(&self, _file: &str) {
            if self.count.fetch_add(1, Ordering::SeqCst) + 1 == self.after {
                std::process::abort();
            }
        }
    }

    /// Records the name of every file written, in order.
    #[derive(Default)]
    struct Writes(std::sync::Mutex<Vec<String>>);

    impl RunObserver for Writes {
        fn wrote(&self, file: &str) {
            self.0.lock().expect("lock").push(file.to_owned());
        }
    }

    /// Set in the child process of [`a_run_killed_after_any_write_resumes_to_the_uninterrupted_run`]:
    /// the write after which it aborts, and its run folder.
    const ABORT_AFTER: &str = "SEPG_RUNS_TEST_ABORT_AFTER_WRITE";
    const ABORT_DIR: &str = "SEPG_RUNS_TEST_ABORT_DIR";

    fn nine_iterations() -> Resolved {
        RunSpec {
            iterations: Some(9),
            batch: Some(10),
            algo: Some(crate::spec::AlgoName::SepgLb2),
            ..RunSpec::default()
        }
        .resolve()
        .expect("valid")
    }

    /// Asserts that the folder `dir` of a run killed at any instant is one of the three the
    /// module documentation lists, given the log of the same run uninterrupted. Returns whether
    /// `dir` is a run folder yet (it has a configuration).
    fn assert_consistent(dir: &Path, reference_log: &str, total: u64) -> bool {
        if !dir.join(CONFIG_FILE).exists() {
            return false;
        }
        let ck: Checkpoint = serde_json::from_str(
            &fs::read_to_string(dir.join(CHECKPOINT_FILE)).expect("checkpoint"),
        )
        .expect("valid checkpoint");
        let valid = usize::try_from(ck.log_bytes).expect("log_bytes");
        if dir.join(LOG_FILE).exists() {
            // All rows written: the final checkpoint vouches for the whole log.
            assert!(!dir.join(PARTIAL_LOG_FILE).exists());
            assert_eq!(ck.state.iteration, total);
            assert_eq!(
                fs::read_to_string(dir.join(LOG_FILE)).expect("log"),
                reference_log
            );
            assert_eq!(valid, reference_log.len());
        } else {
            assert!(!is_complete(dir), "summary.json without log.csv");
            let partial = fs::read_to_string(dir.join(PARTIAL_LOG_FILE)).expect("partial log");
            assert!(partial.len() >= valid);
            // The checkpointed prefix is the uninterrupted log's, cut after the row of the
            // checkpoint's last iteration (one row per iteration here).
            assert_eq!(partial[..valid], reference_log[..valid]);
            let rows = reference_log[..valid].lines().count();
            assert_eq!(
                rows as u64,
                ck.state.iteration + 1,
                "header and one row each"
            );
        }
        true
    }

    /// Kills a run right after each of its folder writes in turn (a child process that aborts,
    /// which like SIGKILL runs no destructor), checks the folder it leaves, resumes it, and
    /// compares with the uninterrupted run: a deterministic cover of every point a SIGKILL can
    /// land between two writes.
    #[cfg(unix)]
    #[test]
    fn a_run_killed_after_any_write_resumes_to_the_uninterrupted_run() {
        use std::os::unix::process::ExitStatusExt;

        let never = AtomicBool::new(false);
        let opts = |observer| RunOptions {
            checkpoint_every: 4,
            stop: &never,
            observer,
        };
        if let (Ok(after), Ok(dir)) = (std::env::var(ABORT_AFTER), std::env::var(ABORT_DIR)) {
            let observer = AbortAfter {
                after: after.parse().expect("write index"),
                count: Default::default(),
            };
            start(Path::new(&dir), &nine_iterations(), opts(&observer)).expect("run");
            return;
        }
        let resolved = nine_iterations();
        let tmp = tempfile::tempdir().expect("tempdir");
        let whole = tmp.path().join("whole");
        let writes = Writes::default();
        let reference = start(&whole, &resolved, opts(&writes)).expect("complete run");
        let writes = writes.0.lock().expect("lock").clone();
        let (p, c) = (PARTIAL_LOG_FILE, CHECKPOINT_FILE);
        // Start; checkpoints after iterations 4, 8 and 9 (rows, then checkpoint); end.
        let expected = [p, c, CONFIG_FILE, p, c, p, c, p, c, LOG_FILE, SUMMARY_FILE];
        assert_eq!(writes, expected);
        let reference_log = fs::read_to_string(whole.join(LOG_FILE)).expect("log");
        for after in 1..=writes.len() {
            let dir = tmp.path().join(format!("killed-after-{after}"));
            let status = std::process::Command::new(std::env::current_exe().expect("test binary"))
                .args([
                    "run::tests::a_run_killed_after_any_write_resumes_to_the_uninterrupted_run",
                    "--exact",
                    "--test-threads=1",
                ])
                .env(ABORT_AFTER, after.to_string())
                .env(ABORT_DIR, &dir)
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::null())
                .status()
                .expect("child");
            assert_eq!(
                status.signal(),
                Some(6),
                "the child aborts after write {after}"
            );
            if !assert_consistent(&dir, &reference_log, 9) {
                // Killed before the configuration was written: not a run folder yet.
                assert!(after < 3, "no configuration after write {after}");
                assert!(matches!(
                    resume(&dir, opts(&Silent)),
                    Err(Error::Invalid(_))
                ));
                continue;
            }
            let summary = resume(&dir, opts(&Silent)).expect("resumed run");
            assert_eq!(
                fs::read_to_string(dir.join(LOG_FILE)).expect("log"),
                reference_log
            );
            assert_eq!(summary.final_params.v, reference.final_params.v);
            assert_eq!(summary.final_params.w, reference.final_params.w);
            assert_eq!(summary.final_params.budget, reference.final_params.budget);
            assert!(!dir.join(PARTIAL_LOG_FILE).exists());
        }
    }

    #[test]
    fn a_stopped_run_resumes_to_the_log_of_an_uninterrupted_one() {
        let resolved = RunSpec {
            iterations: Some(9),
            batch: Some(10),
            algo: Some(crate::spec::AlgoName::SepgLb2),
            ..RunSpec::default()
        }
        .resolve()
        .expect("valid");
        let tmp = tempfile::tempdir().expect("tempdir");
        let (whole, parts) = (tmp.path().join("whole"), tmp.path().join("parts"));
        let never = AtomicBool::new(false);
        let plain = RunOptions {
            checkpoint_every: 4,
            stop: &never,
            observer: &Silent,
        };
        start(&whole, &resolved, plain).expect("complete run");

        let stop = AtomicBool::new(false);
        let observer = StopAt { at: 3, stop: &stop };
        let stopping = RunOptions {
            observer: &observer,
            stop: &stop,
            ..plain
        };
        // Stopped between two checkpoints (every 4): the run checkpoints at iteration 3.
        match start(&parts, &resolved, stopping) {
            Err(Error::Interrupted {
                iteration: 3,
                total: 9,
                dir,
            }) => assert_eq!(dir, parts),
            other => panic!("expected an interruption at 3 of 9, got {other:?}"),
        }
        assert!(!is_complete(&parts));
        let ck: Checkpoint = serde_json::from_str(
            &fs::read_to_string(parts.join(CHECKPOINT_FILE)).expect("checkpoint"),
        )
        .expect("json");
        assert_eq!(ck.state.iteration, 3);
        let summary = resume(&parts, plain).expect("resumed run");
        assert_eq!(summary.iterations, 9);
        let log = |d: &Path| fs::read(d.join(LOG_FILE)).expect("log");
        assert_eq!(log(&parts), log(&whole));
    }
}
