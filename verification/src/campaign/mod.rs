//! The exact-arithmetic campaign for certified safe steps (`sepg_certified`).
//!
//! For every input configuration and every bound form (Theorems 4.2, 4.3, 4.5, 4.7–4.9 in
//! both high-probability forms, the rigorous w-bound along ∇_wJ and ∇_wL with the real-line
//! curvature K_W, the exploring w-update, and the guarantee of Pirotta et al.'s adaptive step,
//! Corollary 3.11), the largest safe step computed in
//! `f64` (uncertified) and the certified step are evaluated in multiple-precision interval
//! arithmetic (module `mp`), with the `f64` inputs and the step taken as exact dyadic rationals and
//! every irrational constant (π, √7, e^x, hence √(2π) and ψ) enclosed by series with rigorous
//! remainders. The bound formulas here are written from the thesis, independently of
//! `sepg-bounds`. A step *violates* its requirement C when the enclosure of B(step) lies
//! entirely below C; it is *proven* when the enclosure lies entirely at or above C; anything
//! else is *undecided* (reported, and counted as a failure of the campaign). Certified steps
//! are tallied by the path that certified them (the a-priori rounding-error bound or interval
//! arithmetic), so that both are shown to be sound. The adaptive step has no requirement: its
//! certified guarantee is the lower end of its enclosure, its uncertified one the `f64` value.
//!
//! Configurations are random (log-uniform constants, σ, gradients with both signs, subnormal
//! and huge gradients, requirements C = C_max·(1 − k·2⁻⁵²), C_max/2, 0, −C_max, −10·C_max)
//! or adversarial (a fixed grid of extreme values). Half of them (every other one in the grid)
//! take c and d from the tight constants of docs/THEOREMS.md "Tight constants" instead of the
//! thesis's, with a horizon in {1, …, 200} or ∞ and either reward sign: there c = ρRM²S_H/σ²,
//! d = 2ρRS_H with S_H summed exactly, the c on ℝ of an applied mean change is c itself and
//! the rigorous w-bound is Δw·∇_wJ − dΔw². Every chunk of 256 configurations has its
//! own Xoshiro256++ stream derived from (seed, chunk), so the tallies do not depend on the
//! number of threads.

mod mp;

use std::cell::OnceCell;

use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;
use sepg_bounds::constants::TaskConstants;
use sepg_bounds::high_probability::{self as hp, HighProbabilityBound, HpForm};
use sepg_bounds::outcome::StepOutcome;
use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
use sepg_bounds::{exploring, pirotta, rigorous, v_update, w_update};
use sepg_certified::{self as certified, Certified, CertifiedStep};

use sepg_algo::solver::realise::{CoordinateBound, realise};

use crate::check::splitmix64;
use mp::{Dyadic, Mp};

/// Configurations per random stream.
const CHUNK: u64 = 256;

/// Which configurations to draw.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CampaignConfig {
    /// Master seed of the random configurations.
    pub seed: u64,
    /// Number of random configurations (each is tried with every bound form).
    pub random: u64,
    /// Whether to add the fixed adversarial grid.
    pub adversarial: bool,
}

/// What the campaign found for one bound form.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct FormTally {
    /// The bound form (thesis theorem).
    pub form: &'static str,
    /// Configurations tried.
    pub cases: u64,
    /// Feasible requirements: uncertified largest steps evaluated exactly.
    pub uncertified_steps: u64,
    /// Uncertified steps whose bound is below C in exact arithmetic.
    pub uncertified_violations: u64,
    /// Certified steps evaluated exactly.
    pub certified_steps: u64,
    /// Certified steps whose bound is below C in exact arithmetic (must be 0).
    pub certified_violations: u64,
    /// Certified steps certified by the a-priori rounding-error bound (the fast path).
    pub by_error_bound: u64,
    /// Certified steps certified in interval arithmetic (the fallback, or the only path).
    pub by_interval: u64,
    /// Certified steps whose comparison with C the 256-bit enclosure could not decide.
    pub undecided: u64,
    /// Returned enclosures that do not contain the exact bound (must be 0).
    pub enclosure_failures: u64,
    /// Certified outcomes that do not carry the `f64` outcome of the same inputs bit for bit
    /// (the safe interval of a certified step, the vertex of an infeasible or uncertifiable
    /// requirement; must be 0).
    pub outcome_mismatches: u64,
    /// Feasible requirements that no `f64` step could certify.
    pub uncertifiable: u64,
    /// Certified steps that had to move from the computed step.
    pub moved: u64,
    /// Largest move, in ulps.
    pub max_ulps: u64,
    /// The configuration of the largest move.
    pub largest_move: Option<String>,
    /// The first failing configuration (lowest case index), if any.
    pub counterexample: Option<String>,
    /// Certified steps applied to a parameter value as SEPG applies them, x₁ = fl(x₀ + Δ),
    /// whose realised change x₁ − x₀ is exact in `f64` (the others are not counted).
    pub raw_updates: u64,
    /// Of those, the rounded updates whose coordinate bound (`sepg_algo::solver::realise`) at
    /// the realised change is below C in exact arithmetic: what certifying the step size alone
    /// leaves open.
    pub raw_violations: u64,
    /// Certified steps applied through `sepg_algo::solver::realise` that report meeting C.
    pub realised: u64,
    /// Of those, the ones whose realised change is not exact in `f64`, or whose coordinate
    /// bound at the realised change is below C or its logged guarantee (or undecided) in exact
    /// arithmetic (must be 0).
    pub realised_violations: u64,
    /// Applied updates that report not meeting C (no `f64` change passed: nothing moved).
    pub realised_unmet: u64,
    /// Certified steps whose task constants are of the tight family (docs/THEOREMS.md "Tight
    /// constants"), included in `certified_steps`.
    pub tight_certified_steps: u64,
}

impl FormTally {
    fn merge(&mut self, o: FormTally) {
        self.cases += o.cases;
        self.uncertified_steps += o.uncertified_steps;
        self.uncertified_violations += o.uncertified_violations;
        self.certified_steps += o.certified_steps;
        self.certified_violations += o.certified_violations;
        self.by_error_bound += o.by_error_bound;
        self.by_interval += o.by_interval;
        self.undecided += o.undecided;
        self.enclosure_failures += o.enclosure_failures;
        self.outcome_mismatches += o.outcome_mismatches;
        self.uncertifiable += o.uncertifiable;
        self.moved += o.moved;
        self.raw_updates += o.raw_updates;
        self.raw_violations += o.raw_violations;
        self.realised += o.realised;
        self.realised_violations += o.realised_violations;
        self.realised_unmet += o.realised_unmet;
        self.tight_certified_steps += o.tight_certified_steps;
        if o.max_ulps > self.max_ulps {
            self.max_ulps = o.max_ulps;
            self.largest_move = o.largest_move;
        }
        if self.counterexample.is_none() {
            self.counterexample = o.counterexample;
        }
    }

    /// The failures of every kind: certified violations, undecided comparisons, enclosures
    /// that miss the exact bound, outcome mismatches and realised updates that break their
    /// requirement or guarantee.
    pub fn failures(&self) -> u64 {
        self.certified_violations
            + self.undecided
            + self.enclosure_failures
            + self.outcome_mismatches
            + self.realised_violations
    }

    /// Whether every certified step was proven safe, every enclosure held and every certified
    /// outcome carried its `f64` outcome ([`Self::failures`] is 0).
    pub fn clean(&self) -> bool {
        self.failures() == 0
    }
}

/// The names of the forms, in report order.
pub const FORMS: [&str; 13] = [
    "Thm 4.2 v-step",
    "Thm 4.3 w along J",
    "Thm 4.5 w along L",
    "Thm 4.7 v (sign-aware)",
    "Thm 4.7 v (thesis form)",
    "Thm 4.8 w along J (sign-aware)",
    "Thm 4.9 w along L (sign-aware)",
    "Thm 4.9 w along L (thesis form)",
    "rigorous w along J",
    "rigorous w along L",
    "Thm 4.8 w along J (thesis form)",
    "exploring w along L^ (Theorem E)",
    "Cor 3.11 adaptive step (guarantee)",
];

/// The form whose certified guarantee is the lower end of its own enclosure (no requirement).
const ADAPTIVE: usize = 12;

/// One input configuration.
#[derive(Debug, Clone, PartialEq)]
struct Case {
    gamma: f64,
    r_max: f64,
    m_phi: f64,
    volume: f64,
    sigma: f64,
    grad_v: Vec<f64>,
    grad_w_j: f64,
    grad_w_l: f64,
    eps_v: f64,
    eps_j: f64,
    eps_l: f64,
    /// How C is chosen from the form's C_max.
    requirement: Requirement,
    /// The family of the penalty coefficients c and d.
    family: Family,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Requirement {
    /// C = C_max·(1 − k·2⁻⁵²).
    NearMax(u32),
    /// C = C_max · factor.
    Scaled(f64),
}

impl Requirement {
    fn of(self, c_max: f64) -> f64 {
        match self {
            Requirement::NearMax(k) => c_max * (1.0 - f64::from(k) * f64::EPSILON),
            Requirement::Scaled(f) => c_max * f,
        }
    }
}

fn log_uniform(rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64) -> f64 {
    10f64.powf(rng.random_range(lo..hi))
}

fn gradient(rng: &mut Xoshiro256PlusPlus) -> f64 {
    let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
    let u: f64 = rng.random();
    let magnitude = if u < 0.02 {
        f64::from_bits(rng.random_range(1..(1u64 << 52)))
    } else if u < 0.04 {
        log_uniform(rng, 100.0, 150.0)
    } else {
        log_uniform(rng, -12.0, 6.0)
    };
    sign * magnitude
}

fn requirement(rng: &mut Xoshiro256PlusPlus) -> Requirement {
    match rng.random_range(0..6) {
        0 | 1 => Requirement::NearMax(rng.random_range(0..=16)),
        2 => Requirement::Scaled(0.5),
        3 => Requirement::Scaled(0.0),
        4 => Requirement::Scaled(-1.0),
        _ => Requirement::Scaled(-10.0 * rng.random::<f64>()),
    }
}

fn random_case(rng: &mut Xoshiro256PlusPlus) -> Case {
    let u: f64 = rng.random();
    let gamma = if u < 0.05 {
        0.0
    } else if u < 0.3 {
        1.0 - log_uniform(rng, -6.0, 0.0)
    } else {
        rng.random_range(0.0..1.0)
    };
    let s: f64 = rng.random();
    let sigma = if s < 0.05 {
        log_uniform(rng, -10.0, -4.0)
    } else if s < 0.1 {
        log_uniform(rng, 2.0, 6.0)
    } else {
        log_uniform(rng, -4.0, 2.0)
    };
    let dim = rng.random_range(1..=3);
    let grad_v: Vec<f64> = (0..dim).map(|_| gradient(rng)).collect();
    let grad_w_j = gradient(rng);
    let grad_w_l = gradient(rng);
    let norm_v = grad_v.iter().fold(0.0_f64, |m, g| m.max(g.abs()));
    let eps_v = norm_v * rng.random_range(0.0..1.2);
    let eps_j = grad_w_j.abs() * rng.random_range(0.0..1.2);
    let eps_l = grad_w_l.abs() * rng.random_range(0.0..1.2);
    Case {
        gamma,
        r_max: log_uniform(rng, -3.0, 3.0),
        m_phi: log_uniform(rng, -3.0, 3.0),
        volume: log_uniform(rng, -3.0, 3.0),
        sigma,
        grad_v,
        grad_w_j,
        grad_w_l,
        eps_v,
        eps_j,
        eps_l,
        requirement: requirement(rng),
        family: family(rng),
    }
}

/// Half of the random configurations use the tight constants, with a horizon uniform in
/// {1, …, 200} (or ∞, one time in ten) and either reward sign.
fn family(rng: &mut Xoshiro256PlusPlus) -> Family {
    if rng.random::<bool>() {
        return Family::Thesis;
    }
    let horizon = if rng.random_range(0..10) == 0 {
        Horizon::Infinite
    } else {
        Horizon::Finite(rng.random_range(1..=200))
    };
    let rewards = if rng.random::<bool>() {
        Rewards::NonPositive
    } else {
        Rewards::TwoSided
    };
    Family::Tight(Tight::new(horizon, rewards))
}

/// The family of the adversarial grid's `index`-th configuration: every other one uses the
/// tight constants, cycling through H ∈ {1, 20, 200, ∞} and both reward signs.
fn adversarial_family(index: usize) -> Family {
    if index.is_multiple_of(2) {
        return Family::Thesis;
    }
    let horizons = [
        Horizon::Finite(1),
        Horizon::Finite(20),
        Horizon::Finite(200),
        Horizon::Infinite,
    ];
    let k = index / 2;
    let rewards = if (k / horizons.len()).is_multiple_of(2) {
        Rewards::NonPositive
    } else {
        Rewards::TwoSided
    };
    Family::Tight(Tight::new(horizons[k % horizons.len()], rewards))
}

/// The fixed adversarial grid: extreme σ, γ, huge and subnormal gradients with mixed signs,
/// and C within 32 ulps of C_max; every other configuration with the tight constants.
fn adversarial_cases() -> Vec<Case> {
    let mut out = Vec::new();
    let gammas = [0.0, 0.5, 0.99, 0.999_999];
    let sigmas = [1e-10, 1e-6, 0.1, 1.0, 1e4, 1e6];
    let grads: [(&[f64], f64, f64); 5] = [
        (&[0.7], 0.3, -2.0),
        (&[1e-300, -3.0, 2.5], -1e-3, 4.0),
        (&[5e-324], 1e-310, -5e-324),
        (&[-1e150, 1e149], 1e150, 1e-150),
        (&[-2.5e-7, 2.5e-7], -7e5, -7e5),
    ];
    let requirements = [0, 1, 2, 3, 4, 8, 16, 32]
        .map(Requirement::NearMax)
        .into_iter()
        .chain([0.5, 0.0, -1.0, -10.0].map(Requirement::Scaled));
    for requirement in requirements {
        for &gamma in &gammas {
            for &sigma in &sigmas {
                for &(gv, gj, gl) in &grads {
                    let norm_v = gv.iter().fold(0.0_f64, |m, g| m.max(g.abs()));
                    out.push(Case {
                        gamma,
                        r_max: 4.0,
                        m_phi: 2.0,
                        volume: 4.0,
                        sigma,
                        grad_v: gv.to_vec(),
                        grad_w_j: gj,
                        grad_w_l: gl,
                        eps_v: norm_v / 3.0,
                        eps_j: gj.abs() / 3.0,
                        eps_l: gl.abs() / 3.0,
                        requirement,
                        family: adversarial_family(out.len()),
                    });
                }
            }
        }
    }
    out
}

/// Exact task constants of a case, with c and d computed once.
struct Exact {
    gamma: Mp,
    one_minus: Mp,
    r: Mp,
    m: Mp,
    volume: Mp,
    sigma: Mp,
    /// ρ·S_H of the tight family (docs/THEOREMS.md "Tight constants"), `None` for the
    /// thesis's constants.
    tight: Option<Mp>,
    c: OnceCell<Option<Mp>>,
    d: OnceCell<Option<Mp>>,
}

impl Exact {
    fn new(c: &Case) -> Self {
        Self {
            gamma: Mp::f(c.gamma),
            one_minus: Mp::int(1).sub(&Mp::f(c.gamma)),
            r: Mp::f(c.r_max),
            m: Mp::f(c.m_phi),
            volume: Mp::f(c.volume),
            sigma: Mp::f(c.sigma),
            tight: match c.family {
                Family::Tight(t) => rho_s_h(c.gamma, t),
                _ => None,
            },
            c: OnceCell::new(),
            d: OnceCell::new(),
        }
    }

    fn c(&self) -> Option<Mp> {
        self.c.get_or_init(|| self.c_uncached()).clone()
    }

    fn d(&self) -> Option<Mp> {
        self.d.get_or_init(|| self.d_uncached()).clone()
    }

    /// c(σ) = R M²/((1−γ)²σ²) · (|A|/(√(2π)σ) + γ/(2(1−γ))), Theorem 4.2; for the tight
    /// family c(σ) = ρ R M² S_H/σ².
    fn c_uncached(&self) -> Option<Mp> {
        if let Some(rho_s) = &self.tight {
            return self.r.mul(&self.m.sqr()).mul(rho_s).div(&self.sigma.sqr());
        }
        let front = self
            .r
            .mul(&self.m.sqr())
            .div(&self.one_minus.sqr().mul(&self.sigma.sqr()))?;
        let box_term = self.volume.div(&mp::sqrt_2pi().mul(&self.sigma))?;
        let discount = self.gamma.div(&self.one_minus.ldexp(1))?;
        Some(front.mul(&box_term.add(&discount)))
    }

    /// c on ℝ: c with the box term replaced by max(|A|/(√(2π)σ), K_MU), K_MU = 4e^{−1/2}/√(2π)
    /// (docs/ERRATA.md §27), the curvature constant of the applied mean-coordinate change.
    /// The tight family's c holds on ℝ: it is its own c_ℝ.
    fn c_real_line(&self) -> Option<Mp> {
        if self.tight.is_some() {
            return self.c();
        }
        let front = self
            .r
            .mul(&self.m.sqr())
            .div(&self.one_minus.sqr().mul(&self.sigma.sqr()))?;
        let box_term = self.volume.div(&mp::sqrt_2pi().mul(&self.sigma))?;
        let k_mu = Mp::int(4).mul(&Mp::f(-0.5).exp()?).div(mp::sqrt_2pi())?;
        let discount = self.gamma.div(&self.one_minus.ldexp(1))?;
        Some(front.mul(&box_term.max(&k_mu).add(&discount)))
    }

    /// The bound of an applied change Δ of one coordinate (`sepg_algo::solver::realise`),
    /// written here from its statement: Δ·ĝ − |Δ|·ε − c_ℝΔ² for a mean coordinate, the
    /// rigorous w-bound at ĝ minus |Δ|·ε for a log-σ coordinate, at the exact Δ.
    fn coordinate(&self, mean: bool, grad: f64, eps: f64, delta: f64) -> Option<Mp> {
        let d = Mp::f(delta);
        let slack = Mp::f(delta.abs()).mul(&Mp::f(eps));
        if mean {
            Some(
                d.mul(&Mp::f(grad))
                    .sub(&slack)
                    .sub(&self.c_real_line()?.mul(&d.sqr())),
            )
        } else {
            Some(self.rigorous(grad, delta, 1.0)?.sub(&slack))
        }
    }

    /// d(σ) = R/(1−γ)² · (ψ|A|/(2σ) + γ/(1−γ)), Theorem 4.3; for the tight family
    /// d = 2ρ R S_H.
    fn d_uncached(&self) -> Option<Mp> {
        if let Some(rho_s) = &self.tight {
            return Some(self.r.mul(rho_s).ldexp(1));
        }
        let front = self.r.div(&self.one_minus.sqr())?;
        let box_term = mp::psi().mul(&self.volume).div(&self.sigma.ldexp(1))?;
        Some(front.mul(&box_term.add(&self.gamma.div(&self.one_minus)?)))
    }

    /// The rigorous w-bound f(Δw) = Δw ∇_wJ − a Δw² max(1, e^{−Δw}) − G·KL2(Δw) with
    /// a = Rψ|A|/(2(1−γ)²σ), G = γR/(2(1−γ)³), at the exact Δw = β·u. For the tight family,
    /// whose d bounds the curvature in w for every σ, it is Δw ∇_wJ − d Δw².
    fn rigorous(&self, grad_w_j: f64, beta: f64, u: f64) -> Option<Mp> {
        let dw = Dyadic::product(beta, u);
        if self.tight.is_some() {
            let dw = Mp::point(dw);
            return Some(dw.mul(&Mp::f(grad_w_j)).sub(&self.d()?.mul(&dw.sqr())));
        }
        let kl = mp::kl2(&dw.abs());
        let dw = Mp::point(dw);
        let a = self
            .r
            .mul(mp::psi())
            .mul(&self.volume)
            .div(&self.one_minus.sqr().mul(&self.sigma).ldexp(1))?;
        let g = self
            .gamma
            .mul(&self.r)
            .div(&self.one_minus.sqr().mul(&self.one_minus).ldexp(1))?;
        // max(1, e^{−Δw}) = 1 for Δw ≥ 0
        let curvature = if beta * u >= 0.0 {
            Mp::int(1)
        } else {
            Mp::int(1).max(&dw.neg().exp()?)
        };
        // The real-line curvature a_ℝ = R K_W/(2(1−γ)²) with K_W = ∫_ℝ |∂²π/∂w²| da
        // = 4(g(√(2−√3)) − g(√(2+√3))), g(z) = (z − z³) e^{−z²/2}/√(2π); the coefficient is
        // the larger of the two (docs/ERRATA.md §27).
        let a_line = self.r.mul(&k_w()?).div(&self.one_minus.sqr().ldexp(1))?;
        let coefficient = a.mul(&curvature).max(&a_line);
        Some(
            dw.mul(&Mp::f(grad_w_j))
                .sub(&coefficient.mul(&dw.sqr()))
                .sub(&g.mul(&kl)),
        )
    }
}

/// ρ·S_H of the tight constants, exactly: S_H = Σ_{t<H} (t + 1) γᵗ by Horner's rule on exact
/// rationals (H ≤ 200 here), S_∞ = 1/(1 − γ)²; ρ = 1/2 for non-positive rewards, 1 otherwise.
fn rho_s_h(gamma: f64, tight: Tight) -> Option<Mp> {
    let g = Mp::f(gamma);
    let s = match tight.horizon() {
        Horizon::Infinite => Mp::int(1).div(&Mp::int(1).sub(&g).sqr())?,
        Horizon::Finite(h) => {
            let mut acc = Mp::int(i64::try_from(h).ok()?);
            for t in (0..h - 1).rev() {
                acc = Mp::int(i64::try_from(t + 1).ok()?).add(&g.mul(&acc));
            }
            acc
        }
    };
    Some(match tight.rewards() {
        Rewards::NonPositive => s.ldexp(-1),
        Rewards::TwoSided => s,
    })
}

/// K_W = ∫_ℝ |z⁴ − 4z² + 1| φ(z) dz in closed form, enclosed.
fn k_w() -> Option<Mp> {
    let s3 = Mp::int(3).sqrt();
    let g = |z: Mp| -> Option<Mp> {
        let e = z.sqr().ldexp(-1).neg().exp()?;
        z.sub(&z.sqr().mul(&z)).mul(&e).div(mp::sqrt_2pi())
    };
    let z1 = Mp::int(2).sub(&s3).sqrt();
    let z2 = Mp::int(2).add(&s3).sqrt();
    Some(g(z1)?.sub(&g(z2)?).ldexp(2))
}

/// The parabola s·x·a − x²·b at the exact step x.
fn parabola(x: f64, linear: &Mp, quadratic: &Mp) -> Mp {
    let x = Mp::f(x);
    x.mul(linear).sub(&x.sqr().mul(quadratic))
}

/// A high-probability bound at x: the thesis form s·x·a⁻ − x²b everywhere, the sign-aware
/// form −|x|·a⁺ − x²b for steps against the favoured direction s.
fn high_probability(x: f64, s: f64, lower: &Mp, upper: &Mp, b: &Mp, sign_aware: bool) -> Mp {
    if sign_aware && s * x < 0.0 {
        // −|x| a⁺ = s·x·a⁺ when s·x < 0
        let a = if s > 0.0 { upper.clone() } else { upper.neg() };
        parabola(x, &a, b)
    } else {
        let a = if s > 0.0 { lower.clone() } else { lower.neg() };
        parabola(x, &a, b)
    }
}

/// (|ĝ| − ε, |ĝ| + ε) exactly.
fn corrected(g: f64, eps: f64) -> (Mp, Mp) {
    let n = Mp::f(g.abs());
    let e = Mp::f(eps);
    (n.sub(&e), n.add(&e))
}

fn inf_norm(g: &[f64]) -> f64 {
    g.iter().fold(0.0_f64, |m, x| m.max(x.abs()))
}

/// The `f64` outcomes of one form: (C, uncertified outcome, certified outcome).
type Outcomes = (f64, StepOutcome, Certified);

/// Runs form `form` on a case in `f64`; `None` when an input is rejected (overflow).
fn outcomes(form: usize, c: &Case, k: &TaskConstants) -> Option<Outcomes> {
    let result = match form {
        3..=7 | 10 => hp_outcomes(form, c, k)?,
        11 => exploring_outcomes(c, k)?,
        ADAPTIVE => adaptive_outcomes(c, k)?,
        _ => exact_gradient_outcomes(form, c, k)?,
    };
    result
        .1
        .c_max()
        .is_none_or(f64::is_finite)
        .then_some(result)
}

/// Forms 0–2, 8 and 9: the steps of Theorems 4.2, 4.3 (along ∇J and ∇L) and the rigorous
/// w-steps, on exact gradients.
fn exact_gradient_outcomes(form: usize, c: &Case, k: &TaskConstants) -> Option<Outcomes> {
    let (s, g, j, l) = (c.sigma, &c.grad_v[..], c.grad_w_j, c.grad_w_l);
    Some(match form {
        0 => {
            let req = c.requirement.of(v_update::c_max(k, s, g).ok()?);
            (
                req,
                v_update::safe_step(k, s, g, req).ok()?,
                certified::v_safe_step(k, s, g, req).ok()?,
            )
        }
        1 => {
            let req = c.requirement.of(w_update::c_max(k, s, j).ok()?);
            (
                req,
                w_update::safe_step_along_j(k, s, j, req).ok()?,
                certified::w_safe_step_along_j(k, s, j, req).ok()?,
            )
        }
        2 => {
            let req = c.requirement.of(w_update::c_max(k, s, j).ok()?);
            (
                req,
                w_update::safe_step_along_l(k, s, j, l, req).ok()?,
                certified::w_safe_step_along_l(k, s, j, l, req).ok()?,
            )
        }
        8 => {
            let c_max = rigorous::safe_step_along_j(k, s, j, 0.0).ok()?.c_max()?;
            let req = c.requirement.of(c_max);
            (
                req,
                rigorous::safe_step_along_j(k, s, j, req).ok()?,
                certified::rigorous_safe_step_along_j(k, s, j, req).ok()?,
            )
        }
        _ => {
            let c_max = rigorous::safe_step_along_l(k, s, j, l, 0.0).ok()?.c_max()?;
            let req = c.requirement.of(c_max);
            (
                req,
                rigorous::safe_step_along_l(k, s, j, l, req).ok()?,
                certified::rigorous_safe_step_along_l(k, s, j, l, req).ok()?,
            )
        }
    })
}

/// Forms 3–7 and 10: the high-probability steps of Theorems 4.7–4.9, sign-aware or as printed.
fn hp_outcomes(form: usize, c: &Case, k: &TaskConstants) -> Option<Outcomes> {
    let (s, g, j, l) = (c.sigma, &c.grad_v[..], c.grad_w_j, c.grad_w_l);
    let sa = HpForm::SignAware;
    let th = HpForm::Thesis;
    let hp_c_max = |b: Option<HighProbabilityBound>| b.map_or(0.0, |b| b.c_max());
    Some(match form {
        3 | 4 => {
            let form = if form == 3 { sa } else { th };
            let b = HighProbabilityBound::v_update(k, s, g, c.eps_v).ok()?;
            let req = c.requirement.of(hp_c_max(b));
            (
                req,
                hp::v_safe_step(k, s, g, c.eps_v, req, form).ok()?,
                certified::hp_v_safe_step(k, s, g, c.eps_v, req, form).ok()?,
            )
        }
        5 | 10 => {
            let form = if form == 5 { sa } else { th };
            let b = HighProbabilityBound::w_along_j(k, s, j, c.eps_j).ok()?;
            let req = c.requirement.of(hp_c_max(b));
            (
                req,
                hp::w_safe_step_along_j(k, s, j, c.eps_j, req, form).ok()?,
                certified::hp_w_safe_step_along_j(k, s, j, c.eps_j, req, form).ok()?,
            )
        }
        _ => {
            let form = if form == 6 { sa } else { th };
            let b = HighProbabilityBound::w_along_l(k, s, j, c.eps_j, l, c.eps_l).ok()?;
            let req = c.requirement.of(hp_c_max(b));
            (
                req,
                hp::w_safe_step_along_l(k, s, j, c.eps_j, l, c.eps_l, req, form).ok()?,
                certified::hp_w_safe_step_along_l(k, s, (j, c.eps_j), (l, c.eps_l), req, form)
                    .ok()?,
            )
        }
    })
}

/// Form 11: the exploring w-step.
fn exploring_outcomes(c: &Case, k: &TaskConstants) -> Option<Outcomes> {
    let (s, j, l) = (c.sigma, c.grad_w_j, c.grad_w_l);
    // the exploring C_max, or Theorem 4.3's when |∇̂_wJ| ≤ ε_J makes it 0, so that
    // negative requirements are drawn too
    let own = exploring::w_exploring_step(k, s, j, c.eps_j, l, 0.0)
        .ok()?
        .c_max()?;
    let c_max = if own > 0.0 {
        own
    } else {
        w_update::c_max(k, s, j).ok()?
    };
    let req = c.requirement.of(c_max);
    Some((
        req,
        exploring::w_exploring_step(k, s, j, c.eps_j, l, req).ok()?,
        certified::exploring_safe_step(k, s, j, c.eps_j, l, req).ok()?,
    ))
}

/// The adaptive step of Theorem 3.10 / Corollary 3.11.
fn adaptive_outcomes(c: &Case, k: &TaskConstants) -> Option<Outcomes> {
    let (s, g) = (c.sigma, &c.grad_v[..]);
    let (alpha, guarantee) = match pirotta::optimal_step(k, s, g).ok()? {
        pirotta::AdaptiveStep::Step { alpha, guarantee } => (alpha, guarantee),
        _ => return None,
    };
    let step = StepOutcome::Feasible(sepg_bounds::outcome::SafeInterval {
        c_max: guarantee,
        vertex: alpha,
        lambda: Some(0.0),
        lo: alpha,
        hi: alpha,
    });
    Some((guarantee, step, certified::adaptive_step(k, s, g).ok()?))
}

/// The exact bound of form `form` at the step x.
fn exact_bound(form: usize, c: &Case, ex: &Exact, x: f64) -> Option<Mp> {
    let (j, l) = (c.grad_w_j, c.grad_w_l);
    Some(match form {
        0 => {
            let n2 = Mp::f(inf_norm(&c.grad_v)).sqr();
            parabola(x, &n2, &ex.c()?.mul(&n2))
        }
        1 => {
            let g2 = Mp::f(j).sqr();
            parabola(x, &g2, &ex.d()?.mul(&g2))
        }
        2 => parabola(x, &Mp::f(l).mul(&Mp::f(j)), &ex.d()?.mul(&Mp::f(l).sqr())),
        3 | 4 => {
            let (lo, hi) = corrected(inf_norm(&c.grad_v), c.eps_v);
            let upper = hi.sqr();
            let b = ex.c()?.mul(&upper);
            high_probability(x, 1.0, &lo.sqr(), &upper, &b, form == 3)
        }
        5 | 10 => {
            let (lo, hi) = corrected(j, c.eps_j);
            let upper = hi.sqr();
            let b = ex.d()?.mul(&upper);
            high_probability(x, 1.0, &lo.sqr(), &upper, &b, form == 5)
        }
        6 | 7 => {
            let (j_lo, j_hi) = corrected(j, c.eps_j);
            let (l_lo, l_hi) = corrected(l, c.eps_l);
            let s = if (j > 0.0) == (l > 0.0) { 1.0 } else { -1.0 };
            let b = ex.d()?.mul(&l_hi.sqr());
            high_probability(x, s, &l_lo.mul(&j_lo), &l_hi.mul(&j_hi), &b, form == 6)
        }
        8 => ex.rigorous(j, x, j)?,
        9 => ex.rigorous(j, x, l)?,
        11 => {
            // B = Δw·∇̂_wJ − |Δw|·ε_J − d·Δw² at the exact Δw = β·∇̂_wL
            let dw = Dyadic::product(x, l);
            let abs = Mp::point(dw.abs());
            let dw = Mp::point(dw);
            dw.mul(&Mp::f(j))
                .sub(&abs.mul(&Mp::f(c.eps_j)))
                .sub(&ex.d()?.mul(&dw.sqr()))
        }
        _ => {
            // Theorem 3.10: α‖∇‖₂² − α²c‖∇‖₁²
            let l2 = c
                .grad_v
                .iter()
                .fold(Mp::int(0), |acc, &g| acc.add(&Mp::f(g).sqr()));
            let l1 = c
                .grad_v
                .iter()
                .fold(Mp::int(0), |acc, &g| acc.add(&Mp::f(g.abs())));
            parabola(x, &l2, &ex.c()?.mul(&l1.sqr()))
        }
    })
}

/// Parameter values the certified steps are applied to (one per case and form, by index):
/// from small to large against the steps, so that rounding x₀ + Δ moves the realised change.
const STARTS: [f64; 4] = [-0.1, -std::f64::consts::LN_2, 1.0, -123.456];

/// The coordinate change SEPG applies for a certified step of `form` on `c`: (the direction
/// component that multiplies the step, ĝ of the moved coordinate, its width ε, whether it is a
/// mean coordinate); `None` for the adaptive step, which moves every coordinate.
fn applied(form: usize, c: &Case) -> Option<(f64, f64, f64, bool)> {
    let (j, l) = (c.grad_w_j, c.grad_w_l);
    let g = c
        .grad_v
        .iter()
        .copied()
        .fold(0.0_f64, |m, x| if x.abs() > m.abs() { x } else { m });
    Some(match form {
        0 => (g, g, 0.0, true),
        3 | 4 => (g, g, c.eps_v, true),
        1 | 8 => (j, j, 0.0, false),
        5 | 10 => (j, j, c.eps_j, false),
        2 | 9 => (l, j, 0.0, false),
        6 | 7 | 11 => (l, j, c.eps_j, false),
        _ => return None,
    })
}

/// y − x when it is exact in `f64` (the error term of TwoSum is 0).
fn exact_change(y: f64, x: f64) -> Option<f64> {
    let s = y - x;
    let bb = s - y;
    let err = (y - (s - bb)) + (-x - bb);
    (err == 0.0 && s.is_finite()).then_some(s)
}

/// Applies the certified step `step` of `form` at x₀ = STARTS[(index + form) mod 4], rounded
/// as a run rounds it and through `sepg_algo::solver::realise`, and checks both in exact
/// arithmetic.
#[allow(clippy::too_many_arguments)]
fn tally_applied(
    t: &mut FormTally,
    form: usize,
    index: u64,
    c: &Case,
    k: &TaskConstants,
    step: f64,
    required: f64,
    ex: &Exact,
) {
    let Some((dir, grad, eps, mean)) = applied(form, c) else {
        return;
    };
    let bound = if mean {
        CoordinateBound::mean(k, c.sigma, grad, eps)
    } else {
        CoordinateBound::log_sigma(k, c.sigma, grad, eps)
    };
    let Ok(bound) = bound else {
        return;
    };
    let x0 = STARTS[((index + form as u64) % 4) as usize];
    let delta = step * dir;
    if !delta.is_finite() {
        return;
    }
    let cc = Mp::f(required);
    // a log-σ change beyond ±64 is far outside any safe step (e^{64} in the bound); its
    // exact evaluation would need numbers of e^{|Δ|} bits
    if let Some(d) = exact_change(x0 + delta, x0).filter(|d| mean || d.abs() <= 64.0)
        && let Some(b) = ex.coordinate(mean, grad, eps, d)
    {
        t.raw_updates += 1;
        t.raw_violations += u64::from(b.certainly_lt(&cc));
    }
    let r = realise(x0, delta, &bound, required, true);
    if !r.meets {
        t.realised_unmet += 1;
        return;
    }
    t.realised += 1;
    let ok = exact_change(r.value, x0)
        .and_then(|d| ex.coordinate(mean, grad, eps, d))
        .is_some_and(|b| b.certainly_ge(&cc) && b.certainly_ge(&Mp::f(r.guaranteed)));
    if !ok {
        t.realised_violations += 1;
        if t.counterexample.is_none() {
            t.counterexample = Some(format!(
                "realised update breaks C or its guarantee: case {index} {c:?}, x0 {x0:e}, step {step:e}, C {required:e}, x1 {:e}, guaranteed {:e}",
                r.value, r.guaranteed
            ));
        }
    }
}

/// Tallies one form on one case.
fn tally(t: &mut FormTally, form: usize, index: u64, c: &Case, ex: &Exact) {
    t.cases += 1;
    let Ok(k) = TaskConstants::new(c.gamma, c.r_max, c.m_phi, c.volume)
        .and_then(|k| k.with_family(c.family))
    else {
        return;
    };
    let Some((required, uncertified, certified)) = outcomes(form, c, &k) else {
        return;
    };
    if !carries(&uncertified, &certified) {
        t.outcome_mismatches += 1;
        if t.counterexample.is_none() {
            t.counterexample = Some(format!(
                "certified outcome does not carry the f64 outcome: case {index} {c:?}, \
                 f64 {uncertified:?}, certified {certified:?}"
            ));
        }
    }
    let cc = Mp::f(required);
    if let StepOutcome::Feasible(s) = uncertified
        && let Some(b) = exact_bound(form, c, ex, s.hi)
    {
        t.uncertified_steps += 1;
        if b.certainly_lt(&cc) {
            t.uncertified_violations += 1;
        }
    }
    let (Some(step), Some(enclosure)) = (certified.chosen_step(), certified.bound()) else {
        return;
    };
    let Some(b) = exact_bound(form, c, ex, step) else {
        return;
    };
    // the adaptive step certifies the lower end of its own enclosure (a vacuous −∞ when its
    // interval evaluation overflows: nothing to check)
    let cc = match (form == ADAPTIVE, enclosure.lo()) {
        (false, _) => cc,
        (true, lo) if lo.is_finite() => Mp::f(lo),
        (true, _) => return,
    };
    let mut failure = None;
    if !b.inside(enclosure.lo(), enclosure.hi()) {
        t.enclosure_failures += 1;
        failure = Some("enclosure misses the exact bound");
    }
    match certified {
        Certified::Step(st) => {
            let applied = Applied {
                form,
                index,
                c,
                k: &k,
                step,
                required,
            };
            failure = tally_step(t, &st, &applied, ex, &b, &cc).or(failure);
        }
        Certified::Uncertifiable { .. } => t.uncertifiable += 1,
        _ => {}
    }
    if let (Some(why), None) = (failure, &t.counterexample) {
        t.counterexample = Some(format!(
            "{why}: case {index} {c:?}, step {step:e}, C {required:e}, exact bound ≈ {:e},              enclosure [{:e}, {:e}]",
            b.approx(),
            enclosure.lo(),
            enclosure.hi()
        ));
    }
}

/// One certified step of the campaign, with the case it came from.
struct Applied<'a> {
    form: usize,
    index: u64,
    c: &'a Case,
    k: &'a TaskConstants,
    step: f64,
    required: f64,
}

/// Tallies a certified step: how it was certified, how far it moved, whether its exact bound
/// `b` meets the requirement `cc`, and the same step applied to a parameter value; returns the
/// failure to report, if any.
fn tally_step(
    t: &mut FormTally,
    st: &CertifiedStep,
    a: &Applied<'_>,
    ex: &Exact,
    b: &Mp,
    cc: &Mp,
) -> Option<&'static str> {
    let Applied {
        form,
        index,
        c,
        k,
        step,
        required,
    } = *a;
    tally_applied(t, form, index, c, k, step, required, ex);
    t.certified_steps += 1;
    t.tight_certified_steps += u64::from(matches!(c.family, Family::Tight(_)));
    if st.by_error_bound {
        t.by_error_bound += 1;
    } else {
        t.by_interval += 1;
    }
    if st.ulps_moved > 0 {
        t.moved += 1;
        if st.ulps_moved > t.max_ulps {
            t.max_ulps = st.ulps_moved;
            t.largest_move = Some(format!(
                "case {index} {c:?}: C {required:e}, f64 interval {:?}, certified {step:e}",
                st.interval
            ));
        }
    }
    if b.certainly_lt(cc) {
        t.certified_violations += 1;
        return Some("certified step violates C");
    } else if !b.certainly_ge(cc) {
        t.undecided += 1;
        return Some("undecided at 256 bits");
    }
    None
}

/// Whether `certified` carries the `f64` outcome `uncertified` of the same inputs bit for bit:
/// a certified step its safe interval, an uncertifiable requirement the interval's vertex, an
/// infeasible one its vertex, and the same zero-gradient and below-noise outcomes. The fast
/// path computes the interval apart from the `f64` step function (`feasible_*` in
/// `sepg-bounds`); this is where the two are compared.
fn carries(uncertified: &StepOutcome, certified: &Certified) -> bool {
    let same = |x: f64, y: f64| x.to_bits() == y.to_bits();
    match (uncertified, certified) {
        (StepOutcome::Feasible(s), Certified::Step(st)) => {
            let t = st.interval;
            same(s.c_max, t.c_max)
                && same(s.vertex, t.vertex)
                && same(s.lo, t.lo)
                && same(s.hi, t.hi)
                && match (s.lambda, t.lambda) {
                    (Some(x), Some(y)) => same(x, y),
                    (None, None) => true,
                    _ => false,
                }
        }
        (StepOutcome::Feasible(s), Certified::Uncertifiable { step, .. }) => same(s.vertex, *step),
        (StepOutcome::Infeasible { vertex, .. }, Certified::Infeasible { step, .. }) => {
            same(*vertex, *step)
        }
        (
            StepOutcome::ZeroGradient { requirement_met: a },
            Certified::ZeroGradient { requirement_met: b },
        ) => a == b,
        (StepOutcome::BelowNoise, Certified::BelowNoise) => true,
        _ => false,
    }
}

fn empty() -> Vec<FormTally> {
    FORMS
        .iter()
        .map(|&form| FormTally {
            form,
            ..FormTally::default()
        })
        .collect()
}

fn run_cases(cases: impl Iterator<Item = (u64, Case)>) -> Vec<FormTally> {
    let mut tallies = empty();
    for (index, case) in cases {
        let ex = Exact::new(&case);
        for (form, t) in tallies.iter_mut().enumerate() {
            tally(t, form, index, &case, &ex);
        }
    }
    tallies
}

/// Runs the campaign: every form on every configuration, in parallel over chunks of 256
/// random configurations with their own streams (results independent of thread count).
///
/// ```
/// use sepg_verification::campaign::{run, CampaignConfig};
/// let tallies = run(&CampaignConfig { seed: 1, random: 64, adversarial: false });
/// assert!(tallies.iter().all(|t| t.clean() && t.cases == 64));
/// ```
pub fn run(config: &CampaignConfig) -> Vec<FormTally> {
    let total = config.random;
    let mut parts = vec![run_random(config.seed, total, 0..total.div_ceil(CHUNK))];
    if config.adversarial {
        parts.push(run_adversarial(total));
    }
    merged(parts)
}

/// The random configurations of the chunks `chunks` (of 256) out of `total`, tallied in
/// parallel: [`run`] without the adversarial grid is `run_random(seed, total, 0..⌈total/256⌉)`,
/// and tallies of consecutive ranges [`merge`]d in order equal those of the whole range, so a
/// long campaign can report its progress.
pub fn run_random(seed: u64, total: u64, chunks: std::ops::Range<u64>) -> Vec<FormTally> {
    let parts: Vec<Vec<FormTally>> = chunks
        .into_par_iter()
        .map(|chunk| {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(splitmix64(seed ^ splitmix64(chunk)));
            let start = chunk * CHUNK;
            let end = (start + CHUNK).min(total);
            run_cases((start..end).map(|i| (i, random_case(&mut rng))))
        })
        .collect();
    merged(parts)
}

/// The tallies of `parts`, in order, added form by form.
fn merged(parts: impl IntoIterator<Item = Vec<FormTally>>) -> Vec<FormTally> {
    let mut out = empty();
    for part in parts {
        merge(&mut out, part);
    }
    out
}

/// Adds the tallies `part` (of later configurations) to `into`, form by form.
pub fn merge(into: &mut [FormTally], part: Vec<FormTally>) {
    for (t, p) in into.iter_mut().zip(part) {
        t.merge(p);
    }
}

/// The tallies of the fixed adversarial grid alone, numbered after `random` random
/// configurations ([`run`] adds them when `adversarial` is set).
pub fn run_adversarial(random: u64) -> Vec<FormTally> {
    let cases = adversarial_cases();
    let parts: Vec<Vec<FormTally>> = cases
        .par_chunks(64)
        .enumerate()
        .map(|(chunk, cs)| {
            let base = random + (chunk * 64) as u64;
            run_cases(
                cs.iter()
                    .enumerate()
                    .map(|(i, c)| (base + i as u64, c.clone())),
            )
        })
        .collect();
    merged(parts)
}

/// Number of configurations in the adversarial grid.
pub fn adversarial_len() -> u64 {
    adversarial_cases().len() as u64
}
