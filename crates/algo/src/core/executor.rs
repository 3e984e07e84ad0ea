//! The [`Solver`] trait, the [`Executor`] that drives a solver and the [`Observer`]s that
//! receive its [`Record`]s (argmin's solver/executor/observer split): algorithms never print
//! or write files.
use crate::core::error::RunError;
use crate::core::record::Record;
use crate::core::state::State;

/// An iterative policy-optimisation algorithm operating on a [`State`].
pub trait Solver {
    /// Prepares the state before the first iteration (for example allocates Adam moments).
    /// Called once by [`Executor::run`] when `state.iteration == 0`; must be idempotent.
    ///
    /// # Errors
    /// [`RunError::Checkpoint`] when the state does not fit the solver.
    fn init(&mut self, state: &mut State) -> Result<(), RunError>;

    /// Runs iteration `state.iteration`, updates the state (parameters, budget, counters,
    /// `iteration + 1`) and returns what happened.
    ///
    /// # Errors
    /// A [`RunError`] when a bound, rollout or estimator fails or a quantity becomes
    /// non-finite; the state is then left unchanged.
    fn next_iter(&mut self, state: &mut State) -> Result<Record, RunError>;
}

/// Receives every [`Record`] of a run, in order (logging, progress bars, collection).
pub trait Observer {
    /// Called after each iteration with its record and the state after it.
    fn observe(&mut self, record: &Record, state: &State);
}

/// An [`Observer`] that keeps every record in memory.
///
/// # Examples
/// ```
/// use sepg_algo::core::executor::{Collect, Observer};
/// let c = Collect::default();
/// assert!(c.records.is_empty());
/// ```
#[derive(Debug, Default, Clone)]
pub struct Collect {
    /// The records received so far.
    pub records: Vec<Record>,
}

impl Observer for Collect {
    fn observe(&mut self, record: &Record, _state: &State) {
        self.records.push(record.clone());
    }
}

/// Runs a [`Solver`] for a number of iterations, feeding each [`Record`] to the observers.
pub struct Executor<'a, S: Solver> {
    solver: S,
    state: State,
    observers: Vec<&'a mut dyn Observer>,
}

impl<'a, S: Solver> Executor<'a, S> {
    /// An executor for `solver` starting (or resuming) from `state`.
    ///
    /// # Examples
    /// See [`crate::solver::PolicySolver`].
    pub fn new(solver: S, state: State) -> Self {
        Executor {
            solver,
            state,
            observers: Vec::new(),
        }
    }

    /// Adds an observer that receives every subsequent record.
    pub fn observe(mut self, observer: &'a mut dyn Observer) -> Self {
        self.observers.push(observer);
        self
    }

    /// Runs `iterations` more iterations (calling [`Solver::init`] first on a fresh state).
    ///
    /// # Errors
    /// The first [`RunError`] of the solver; the state is left after the last completed
    /// iteration and can be taken with [`Executor::state`] to resume.
    pub fn run(&mut self, iterations: u64) -> Result<(), RunError> {
        if self.state.iteration == 0 {
            self.solver.init(&mut self.state)?;
        }
        for _ in 0..iterations {
            let record = self.solver.next_iter(&mut self.state)?;
            for o in self.observers.iter_mut() {
                o.observe(&record, &self.state);
            }
        }
        Ok(())
    }

    /// The current state (the checkpoint to save for resuming).
    pub fn state(&self) -> &State {
        &self.state
    }

    /// Consumes the executor, returning the solver and the state.
    pub fn into_parts(self) -> (S, State) {
        (self.solver, self.state)
    }
}
