//! The environment abstraction, the LQG environments of docs/CONVENTIONS.md §1 (`lqg`, `lqg1d`, `lqg-nd`) and
//! the preset registry.
//!
//! An [`Environment`] has continuous vector states and actions, writes every result into
//! caller-provided buffers (no allocation per step), computes its own policy features `φ(s)`,
//! and publishes the constants the bounds of Chapters 3–4 need ([`EnvConstants`]).

use std::fmt;
use std::str::FromStr;

use crate::features::FeatureError;
use crate::lqg_model::{LqgModel, ModelError};
use crate::mountain_car::MountainCar;
use crate::rng::{TrajRng, standard_normal, uniform};

/// Errors of environment construction and lookup.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EnvError {
    /// The LQG model is invalid.
    #[error("invalid LQG model: {0}")]
    Model(#[from] ModelError),
    /// The feature map is invalid or does not read the environment's state.
    #[error("invalid feature map: {0}")]
    Feature(#[from] FeatureError),
    /// The feature map reads `found` state components but the state has `expected`.
    #[error("feature map reads {found} state components, the state has {expected}")]
    FeatureInputDim {
        /// State dimension.
        expected: usize,
        /// Input dimension of the feature map.
        found: usize,
    },
    /// No preset has this name.
    #[error("unknown environment preset {0:?} (known: lqg, lqg1d, mountain-car)")]
    UnknownPreset(String),
    /// No LQG preset has this name.
    #[error("unknown LQG preset '{0}' (expected lqg or lqg1d)")]
    UnknownLqgPreset(String),
    /// The horizon is zero.
    #[error("the horizon must be at least 1")]
    ZeroHorizon,
    /// The discount factor is outside `[0, 1)`.
    #[error("discount factor gamma = {0} is outside [0, 1)")]
    InvalidGamma(f64),
}

/// The constants of an environment used by the bounds (docs/CONVENTIONS.md §1): `R_max`, `M_φ`, `|A|`, `γ`
/// and the episode horizon `H`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnvConstants {
    /// `R_max`: the largest |reward| (Theorem 4.3).
    pub r_max: f64,
    /// `M_φ`: the largest |feature| (eq. 4.7).
    pub m_phi: f64,
    /// `|A|`: the volume of the action box (Theorem 4.3, eq. 4.16).
    pub action_volume: f64,
    /// Discount factor `γ ∈ [0, 1)`.
    pub gamma: f64,
    /// Default episode horizon `H` (20 for the LQG presets, docs/CONVENTIONS.md §6; 999 for Mountain Car).
    pub horizon: usize,
}

/// A Markov decision process with continuous vector states and actions and linear-policy
/// features.
///
/// Implementations write into the caller's buffers and never allocate per step. The buffers
/// passed by the rollout engine always have the advertised lengths.
///
/// ```
/// use sepg_mdp::env::{Environment, LqgEnv};
/// let env = LqgEnv::thesis();
/// let mut rng = sepg_mdp::rng::rng_from_seed(0);
/// let mut s = [0.0];
/// env.reset(&mut rng, &mut s);
/// let mut next = [0.0];
/// let (r, done) = env.step(&[1.0], &[0.5], &mut rng, &mut next);
/// assert_eq!((r, done, next[0]), (-0.625, false, 1.5));
/// ```
pub trait Environment: Sync {
    /// State dimension `n`.
    fn state_dim(&self) -> usize;
    /// Action dimension `l`.
    fn action_dim(&self) -> usize;
    /// Number of policy features `p`.
    fn feature_dim(&self) -> usize;
    /// The constants used by the bounds.
    fn constants(&self) -> EnvConstants;
    /// The discount factor `γ` of [`Environment::constants`], without computing the other
    /// constants (`r_max` can take a search over the box corners).
    fn gamma(&self) -> f64 {
        self.constants().gamma
    }
    /// A step limit after which an episode is truncated (not terminated), if any.
    fn time_limit(&self) -> Option<usize> {
        None
    }
    /// Draws an initial state `s_0` into `state` (length `n`) from the environment stream.
    fn reset(&self, rng: &mut TrajRng, state: &mut [f64]);
    /// One transition from `state` under the raw action `action` (length `l`): writes `s'`
    /// into `next` and returns `(reward, terminated)`.
    fn step(
        &self,
        state: &[f64],
        action: &[f64],
        rng: &mut TrajRng,
        next: &mut [f64],
    ) -> (f64, bool);
    /// The policy features `φ(s)` into `phi` (length `p`).
    fn features(&self, state: &[f64], phi: &mut [f64]);
    /// Component `j` of the action that [`Environment::step`] applies for the raw action
    /// component `a`: `a` clipped to the action box `[a_low_j, a_high_j]`, or `a` itself for an
    /// environment without an action box (the default). Used by the scores on clipped actions
    /// ([`crate::rollout::ScoreAction::Clipped`]).
    ///
    /// ```
    /// use sepg_mdp::env::{Environment, LqgEnv};
    /// assert_eq!(LqgEnv::lqg1d().clip_action(0, 7.5), 4.0);
    /// ```
    fn clip_action(&self, j: usize, a: f64) -> f64 {
        let _ = j;
        a
    }
    /// The scalar LQG behind this environment, if it is one: rollouts then run a fused
    /// specialised kernel with identical results.
    fn as_scalar_lqg(&self) -> Option<&LqgEnv> {
        None
    }
    /// The Mountain Car behind this environment, if it is one: with state + bias features,
    /// rollouts then run a fused specialised kernel with identical results.
    fn as_mountain_car(&self) -> Option<&MountainCar> {
        None
    }
}

/// Scalar coefficients of a one-dimensional LQG, cached for the fused rollout kernel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ScalarLqg {
    pub a: f64,
    pub b: f64,
    pub q: f64,
    pub r: f64,
    pub noise_std: f64,
    pub state_low: f64,
    pub state_high: f64,
    pub action_low: f64,
    pub action_high: f64,
    pub init_low: f64,
    pub init_high: f64,
    pub gamma: f64,
    pub clipping: bool,
}

/// The LQG environment of an [`LqgModel`] with features `φ(s) = s` (Sec 5.1: `a ~ N(v s, σ²)`;
/// docs/CONVENTIONS.md §1 `lqg`, `lqg1d`, `lqg-nd`).
///
/// # Formula
/// ```text
/// a_c = clip(a),   r = −(sᵀQs + a_cᵀ R a_c),   s' = clip(A s + B a_c + η),   φ(s) = s
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct LqgEnv {
    model: LqgModel,
    horizon: usize,
    n: usize,
    l: usize,
    a: Vec<f64>,
    b: Vec<f64>,
    q: Vec<f64>,
    r: Vec<f64>,
    scalar: Option<ScalarLqg>,
}

/// The horizon of the LQG environments unless set otherwise, `H = 20` (Sec 5.1;
/// docs/CONVENTIONS.md §6), in steps.
pub const LQG_HORIZON: usize = 20;

impl LqgEnv {
    /// The environment of a validated model, with the default horizon [`LQG_HORIZON`] = 20
    /// (docs/CONVENTIONS.md §6).
    ///
    /// ```
    /// use sepg_mdp::env::{Environment, LqgEnv};
    /// use sepg_mdp::lqg_model::LqgModel;
    /// let env = LqgEnv::new(LqgModel::lqg1d()).unwrap();
    /// assert_eq!(env.constants().horizon, 20);
    /// ```
    pub fn new(model: LqgModel) -> Result<Self, EnvError> {
        model.validate()?;
        let n = model.state_dim();
        let l = model.action_dim();
        let row_major = |m: &nalgebra::DMatrix<f64>| m.transpose().as_slice().to_vec();
        let scalar = model.is_scalar().then(|| ScalarLqg {
            a: model.a[(0, 0)],
            b: model.b[(0, 0)],
            q: model.q[(0, 0)],
            r: model.r[(0, 0)],
            noise_std: model.noise_std[0],
            state_low: model.state_low[0],
            state_high: model.state_high[0],
            action_low: model.action_low[0],
            action_high: model.action_high[0],
            init_low: model.init_low[0],
            init_high: model.init_high[0],
            gamma: model.gamma,
            clipping: model.clipping,
        });
        Ok(LqgEnv {
            a: row_major(&model.a),
            b: row_major(&model.b),
            q: row_major(&model.q),
            r: row_major(&model.r),
            model,
            horizon: LQG_HORIZON,
            n,
            l,
            scalar,
        })
    }

    /// docs/CONVENTIONS.md §1 preset `lqg` (thesis Sec 5.1 as written).
    ///
    /// ```
    /// use sepg_mdp::env::{Environment, LqgEnv};
    /// assert_eq!(LqgEnv::thesis().constants().r_max, 4.0);
    /// ```
    pub fn thesis() -> Self {
        LqgEnv::from_valid(LqgModel::thesis())
    }

    /// docs/CONVENTIONS.md §1 preset `lqg1d` (the 1-D LQG the thesis's numbers came from).
    ///
    /// ```
    /// use sepg_mdp::env::{Environment, LqgEnv};
    /// assert_eq!(LqgEnv::lqg1d().constants().action_volume, 8.0);
    /// ```
    pub fn lqg1d() -> Self {
        LqgEnv::from_valid(LqgModel::lqg1d())
    }

    fn from_valid(model: LqgModel) -> Self {
        match LqgEnv::new(model) {
            Ok(env) => env,
            Err(e) => unreachable!("preset models are valid: {e}"),
        }
    }

    /// The same environment with default horizon `horizon ≥ 1`.
    ///
    /// ```
    /// use sepg_mdp::env::{Environment, LqgEnv};
    /// assert_eq!(LqgEnv::thesis().with_horizon(50).unwrap().constants().horizon, 50);
    /// ```
    pub fn with_horizon(mut self, horizon: usize) -> Result<Self, EnvError> {
        if horizon == 0 {
            return Err(EnvError::ZeroHorizon);
        }
        self.horizon = horizon;
        Ok(self)
    }

    /// The underlying model.
    ///
    /// ```
    /// assert_eq!(sepg_mdp::env::LqgEnv::thesis().model().gamma, 0.99);
    /// ```
    pub fn model(&self) -> &LqgModel {
        &self.model
    }

    pub(crate) fn scalar(&self) -> Option<&ScalarLqg> {
        self.scalar.as_ref()
    }
}

impl Environment for LqgEnv {
    fn state_dim(&self) -> usize {
        self.n
    }

    fn action_dim(&self) -> usize {
        self.l
    }

    fn feature_dim(&self) -> usize {
        self.n
    }

    fn gamma(&self) -> f64 {
        self.model.gamma
    }

    fn constants(&self) -> EnvConstants {
        EnvConstants {
            r_max: self.model.r_max(),
            m_phi: self.model.m_phi(),
            action_volume: self.model.action_volume(),
            gamma: self.model.gamma,
            horizon: self.horizon,
        }
    }

    fn reset(&self, rng: &mut TrajRng, state: &mut [f64]) {
        for (i, s) in state.iter_mut().enumerate() {
            *s = uniform(rng, self.model.init_low[i], self.model.init_high[i]);
        }
    }

    /// Order (docs/CONVENTIONS.md §1): `a_c = clip(a)`; `r = −(sᵀQs + a_cᵀRa_c)` on the pre-step state;
    /// `s' = clip(A s + B a_c + η)`, η drawn component by component from the environment
    /// stream (only where `noise_std > 0`). Dot products are summed from the first term on,
    /// matching the fused scalar kernel bit for bit.
    fn step(
        &self,
        state: &[f64],
        action: &[f64],
        rng: &mut TrajRng,
        next: &mut [f64],
    ) -> (f64, bool) {
        let (n, l) = (self.n, self.l);
        let m = &self.model;
        let ac = |j: usize| {
            if m.clipping {
                action[j].clamp(m.action_low[j], m.action_high[j])
            } else {
                action[j]
            }
        };
        let cost = quad_form(&self.q, n, |i| state[i]) + quad_form(&self.r, l, ac);
        for (i, out) in next.iter_mut().enumerate() {
            let arow = &self.a[i * n..(i + 1) * n];
            let brow = &self.b[i * l..(i + 1) * l];
            let mut x = arow[0] * state[0];
            for (aij, sj) in arow[1..].iter().zip(&state[1..]) {
                x += aij * sj;
            }
            for (j, bij) in brow.iter().enumerate() {
                x += bij * ac(j);
            }
            let sd = m.noise_std[i];
            if sd > 0.0 {
                x += sd * standard_normal(rng);
            }
            *out = if m.clipping {
                x.clamp(m.state_low[i], m.state_high[i])
            } else {
                x
            };
        }
        (-cost, false)
    }

    fn features(&self, state: &[f64], phi: &mut [f64]) {
        phi.copy_from_slice(state);
    }

    /// `a` clipped to `[action_low_j, action_high_j]` when the model clips, else `a`.
    fn clip_action(&self, j: usize, a: f64) -> f64 {
        let m = &self.model;
        if m.clipping {
            a.clamp(m.action_low[j], m.action_high[j])
        } else {
            a
        }
    }

    fn as_scalar_lqg(&self) -> Option<&LqgEnv> {
        self.scalar.is_some().then_some(self)
    }
}

/// `xᵀMx` for a row-major `d × d` matrix `M` and `x_i = x(i)`, each row product summed from
/// its first term, then the rows summed from the first one (`Σ_i x_i (Σ_j M_ij x_j)`).
#[inline(always)]
fn quad_form(m: &[f64], d: usize, x: impl Fn(usize) -> f64) -> f64 {
    let row = |i: usize| {
        let r = &m[i * d..(i + 1) * d];
        let mut acc = r[0] * x(0);
        for (j, mij) in r.iter().enumerate().skip(1) {
            acc += mij * x(j);
        }
        x(i) * acc
    };
    let mut total = row(0);
    for i in 1..d {
        total += row(i);
    }
    total
}

/// The named environment presets of docs/CONVENTIONS.md §1 (`lqg-nd` is built from a model with
/// [`LqgEnv::new`]), accepted by `--env`; serde and the command line (feature `clap`) use the
/// registry names of [`Preset::name`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Preset {
    /// Thesis Sec 5.1 as written (S, A = [−2, 2], r = −0.5(s² + a²)).
    Lqg,
    /// The 1-D LQG behind the thesis's numbers (S, A = [−4, 4], r = −0.9(s² + a²)).
    Lqg1d,
    /// Gymnasium's MountainCarContinuous-v0.
    MountainCar,
}

impl Preset {
    /// Every preset, in registry order.
    pub const ALL: [Preset; 3] = [Preset::Lqg, Preset::Lqg1d, Preset::MountainCar];

    /// The registry name (`"lqg"`, `"lqg1d"`, `"mountain-car"`).
    ///
    /// ```
    /// assert_eq!(sepg_mdp::env::Preset::MountainCar.name(), "mountain-car");
    /// ```
    pub fn name(&self) -> &'static str {
        match self {
            Preset::Lqg => "lqg",
            Preset::Lqg1d => "lqg1d",
            Preset::MountainCar => "mountain-car",
        }
    }

    /// Looks a preset up by registry name.
    ///
    /// ```
    /// use sepg_mdp::env::{EnvError, Preset};
    /// assert_eq!(Preset::from_name("lqg1d"), Ok(Preset::Lqg1d));
    /// assert!(matches!(Preset::from_name("cartpole"), Err(EnvError::UnknownPreset(_))));
    /// ```
    pub fn from_name(name: &str) -> Result<Self, EnvError> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name() == name)
            .ok_or_else(|| EnvError::UnknownPreset(name.to_owned()))
    }

    /// The LQG preset of this name, `None` for Mountain Car.
    pub fn lqg(self) -> Option<LqgPreset> {
        LqgPreset::ALL.into_iter().find(|p| p.preset() == self)
    }

    /// Builds the preset environment.
    ///
    /// ```
    /// use sepg_mdp::env::{Environment, Preset};
    /// assert_eq!(Preset::Lqg1d.build().constants().m_phi, 4.0);
    /// ```
    pub fn build(&self) -> AnyEnv {
        match self.lqg() {
            Some(lqg) => AnyEnv::Lqg(Box::new(lqg.build())),
            None => AnyEnv::MountainCar(MountainCar::state_bias()),
        }
    }
}

impl fmt::Display for Preset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Preset {
    type Err = EnvError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Preset::from_name(s)
    }
}

/// The scalar LQG presets, the subset of [`Preset`] that has an LQG model (`lqg`, `lqg1d`),
/// accepted by `--preset` and by `sepg exact --env`; their names are those of [`Preset`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum LqgPreset {
    /// Thesis Sec 5.1 as written.
    Lqg,
    /// The 1-D LQG behind the thesis's numbers.
    Lqg1d,
}

impl LqgPreset {
    /// Both LQG presets, in registry order.
    pub const ALL: [LqgPreset; 2] = [LqgPreset::Lqg, LqgPreset::Lqg1d];

    /// The preset of the registry.
    pub fn preset(self) -> Preset {
        match self {
            LqgPreset::Lqg => Preset::Lqg,
            LqgPreset::Lqg1d => Preset::Lqg1d,
        }
    }

    /// The registry name (`"lqg"`, `"lqg1d"`).
    pub fn name(self) -> &'static str {
        self.preset().name()
    }

    /// The preset's LQG model: S, A = [−2, 2] and reward −0.5(s² + a²) for `lqg`,
    /// S, A = [−4, 4] and reward −0.9(s² + a²) for `lqg1d` (docs/CONVENTIONS.md §1).
    pub fn model(self) -> LqgModel {
        match self {
            LqgPreset::Lqg => LqgModel::thesis(),
            LqgPreset::Lqg1d => LqgModel::lqg1d(),
        }
    }

    /// The preset's environment.
    pub fn build(self) -> LqgEnv {
        match self {
            LqgPreset::Lqg => LqgEnv::thesis(),
            LqgPreset::Lqg1d => LqgEnv::lqg1d(),
        }
    }
}

impl fmt::Display for LqgPreset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for LqgPreset {
    type Err = EnvError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        LqgPreset::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| EnvError::UnknownLqgPreset(s.to_owned()))
    }
}

/// Any of the crate's environments, dispatching statically per variant (the fused scalar LQG
/// kernel stays available through [`Environment::as_scalar_lqg`]).
#[derive(Debug, Clone, PartialEq)]
pub enum AnyEnv {
    /// An LQG environment (`lqg`, `lqg1d`, `lqg-nd`).
    Lqg(Box<LqgEnv>),
    /// Mountain Car.
    MountainCar(MountainCar),
}

macro_rules! dispatch {
    ($self:ident, $e:ident => $body:expr) => {
        match $self {
            AnyEnv::Lqg($e) => $body,
            AnyEnv::MountainCar($e) => $body,
        }
    };
}

impl Environment for AnyEnv {
    fn state_dim(&self) -> usize {
        dispatch!(self, e => e.state_dim())
    }

    fn action_dim(&self) -> usize {
        dispatch!(self, e => e.action_dim())
    }

    fn feature_dim(&self) -> usize {
        dispatch!(self, e => e.feature_dim())
    }

    fn constants(&self) -> EnvConstants {
        dispatch!(self, e => e.constants())
    }

    fn gamma(&self) -> f64 {
        dispatch!(self, e => e.gamma())
    }

    fn time_limit(&self) -> Option<usize> {
        dispatch!(self, e => e.time_limit())
    }

    fn reset(&self, rng: &mut TrajRng, state: &mut [f64]) {
        dispatch!(self, e => e.reset(rng, state))
    }

    fn step(
        &self,
        state: &[f64],
        action: &[f64],
        rng: &mut TrajRng,
        next: &mut [f64],
    ) -> (f64, bool) {
        dispatch!(self, e => e.step(state, action, rng, next))
    }

    fn features(&self, state: &[f64], phi: &mut [f64]) {
        dispatch!(self, e => e.features(state, phi))
    }

    fn clip_action(&self, j: usize, a: f64) -> f64 {
        dispatch!(self, e => e.clip_action(j, a))
    }

    fn as_scalar_lqg(&self) -> Option<&LqgEnv> {
        dispatch!(self, e => e.as_scalar_lqg())
    }

    fn as_mountain_car(&self) -> Option<&MountainCar> {
        dispatch!(self, e => e.as_mountain_car())
    }
}

#[cfg(test)]
mod preset_tests {
    use super::*;

    /// Every preset's name parses back to it, serde writes and reads the same name, and the
    /// LQG presets are the presets with an LQG model, under the same names.
    #[test]
    fn preset_names_round_trip_and_the_lqg_presets_are_a_subset() {
        for p in Preset::ALL {
            assert_eq!(p.to_string().parse::<Preset>(), Ok(p));
            let json = serde_json::to_string(&p).expect("json");
            assert_eq!(json, format!("\"{p}\""));
            assert_eq!(serde_json::from_str::<Preset>(&json).expect("parse"), p);
            assert_eq!(
                p.lqg().is_some(),
                matches!(p.build(), AnyEnv::Lqg(_)),
                "{p}"
            );
        }
        for q in LqgPreset::ALL {
            assert_eq!(q.to_string().parse::<LqgPreset>(), Ok(q));
            assert_eq!(q.preset().lqg(), Some(q));
            assert_eq!(q.name(), q.preset().name());
            assert_eq!(AnyEnv::Lqg(Box::new(q.build())), q.preset().build());
            assert_eq!(q.build().model(), &q.model());
        }
        assert_eq!(
            "mountain-car"
                .parse::<LqgPreset>()
                .expect_err("not LQG")
                .to_string(),
            "unknown LQG preset 'mountain-car' (expected lqg or lqg1d)"
        );
    }
}
