//! The certificate of the update that is applied (docs/THEOREMS.md, "Statements over a whole
//! run").
//!
//! A safe step size is certified as a real number, but the run applies the rounded update
//! x₁ = fl(x₀ + Δ), whose realised change x₁ − x₀ differs from Δ by up to half an ulp of x₁:
//! relative to a step of 1e-6 that is 1e-10, far more than certification removes. Under the
//! certified accounting every step is therefore certified again at the change it realises,
//! against a bound that holds for every change of one coordinate, and moved toward x₀ until
//! it passes:
//!
//! ```text
//! mean coordinate k:  J(v + Δe_k, w) − J(v, w) ≥ Δ·ĝ − |Δ|·ε − c_ℝ(σ)·Δ²          (Thm 4.2)
//! log-σ coordinate h: J(v, w + Δe_h) − J(v, w) ≥ Δ·ĝ − |Δ|·ε − a·Δ²·max(1, e^{−Δ}) ∨ a_ℝΔ²
//!                                                  − G·KL2(Δ)        (rigorous Thm 4.3)
//! ```
//!
//! with ĝ the estimate of the coordinate's partial derivative and ε its confidence width (0
//! for exact gradients). On the confidence event |∂J − ĝ| ≤ ε both hold for every Δ at once;
//! c_ℝ is c of Theorem 4.2 with the box term made sound on ℝ (`sepg_bounds::rigorous::c`),
//! and the log-σ bound is the rigorous form of Theorem 4.3 (`sepg_bounds::rigorous::bound`,
//! sound for every σ and both signs of Δ). With the tight constants (docs/THEOREMS.md
//! "Tight constants") c_ℝ = c and the log-σ bound is Δ·ĝ − |Δ|·ε − d·Δ²: both are proven on
//! ℝ for every Δ. The first bound dominates Theorem 4.7's (with
//! Δ = α ĝ_k, αĝ_k² − α|ĝ_k|ε ≥ α(|ĝ_k| − ε)² and c α² ĝ_k² ≤ c α²(|ĝ_k| + ε)²), so it only
//! differs from the step's own certificate by the rounding of the update; the second differs
//! from the thesis form by the Θ(Δ³) terms Theorem 4.3 neglects (docs/ERRATA.md §10).
use sepg_bounds::BoundsError;
use sepg_bounds::constants::TaskConstants;
use sepg_bounds::direction::Direction;
use sepg_bounds::rigorous;
use sepg_certified::{self as certified, EnclosedBound, Interval, RigorousEnclosure};

/// A rigorous lower bound of J(x₀ + Δ) − J(x₀) for changes Δ of one coordinate (module
/// docs), valid for every Δ at once on the confidence event of the coordinate's estimate.
#[derive(Debug, Clone, Copy)]
pub enum CoordinateBound {
    /// A mean coordinate: Δ·ĝ − |Δ|·ε − c·Δ², c enclosed.
    Mean {
        /// ĝ.
        grad: f64,
        /// ε ≥ 0.
        eps: f64,
        /// Enclosure of c_ℝ(σ).
        c: Interval,
    },
    /// A log-standard-deviation coordinate: the rigorous w-bound at ĝ minus |Δ|·ε.
    LogSigma {
        /// The rigorous bound with slope ĝ, direction 1 (Δw = x).
        rigorous: RigorousEnclosure,
        /// ε ≥ 0.
        eps: f64,
    },
}

fn k_mu() -> Interval {
    let k = rigorous::k_mu();
    // `rigorous::k_mu` is 4e^{-1/2}/√(2π) computed in a few roundings; 1e-13 relative encloses
    // it with a wide margin (as for K_W in `certified::RigorousEnclosure`).
    Interval::new(k * (1.0 - 1e-13), k * (1.0 + 1e-13)).unwrap_or(Interval::ENTIRE)
}

/// An enclosure of c_ℝ(σ) (`sepg_bounds::rigorous::c`); for the tight family, whose c holds
/// on ℝ, an enclosure of that c.
///
/// # Formula
/// ```text
/// c_ℝ(σ) = R M_φ² / ((1 − γ)² σ²) · ( max(|A| / (√(2π) σ), K_MU) + γ / (2 (1 − γ)) )
/// ```
fn c_real_line(k: &TaskConstants, sigma: f64) -> Result<Interval, BoundsError> {
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(BoundsError::OutOfDomain {
            name: "sigma",
            value: sigma,
            domain: "(0, inf)",
        });
    }
    if let sepg_bounds::Family::Tight(_) = k.family() {
        return certified::c(k, sigma);
    }
    let om = Interval::point(1.0) - Interval::point(k.gamma());
    let s = Interval::point(sigma);
    let front =
        Interval::point(k.r_max()) * Interval::point(k.m_phi()).sqr() / (om.sqr() * s.sqr());
    let box_term = Interval::point(k.action_volume()) / (certified::sqrt_2pi() * s);
    let bracket = box_term.max(k_mu()) + Interval::point(k.gamma()) / (om + om);
    Ok(front * bracket)
}

impl CoordinateBound {
    /// The bound of a mean coordinate with estimate `grad` ± `eps` (the units of ∂J/∂v) at
    /// standard deviation `sigma` > 0 (the smallest σ of the policy, as in Theorem 4.2's c).
    ///
    /// # Errors
    /// [`BoundsError::OutOfDomain`] for σ not finite and positive.
    pub fn mean(k: &TaskConstants, sigma: f64, grad: f64, eps: f64) -> Result<Self, BoundsError> {
        Ok(CoordinateBound::Mean {
            grad,
            eps,
            c: c_real_line(k, sigma)?,
        })
    }

    /// The bound of a log-σ coordinate at σ > 0 with estimate `grad` ± `eps` (units of
    /// ∂J/∂w).
    ///
    /// # Errors
    /// The errors of [`RigorousEnclosure::new`] (σ not positive, non-finite inputs).
    pub fn log_sigma(
        k: &TaskConstants,
        sigma: f64,
        grad: f64,
        eps: f64,
    ) -> Result<Self, BoundsError> {
        Ok(CoordinateBound::LogSigma {
            rigorous: RigorousEnclosure::new(k, sigma, grad, 1.0)?,
            eps,
        })
    }

    /// An enclosure of the bound at the exact change `delta` (units of the coordinate).
    pub fn enclose(&self, delta: f64) -> Interval {
        if delta == 0.0 {
            return Interval::point(0.0);
        }
        let d = Interval::point(delta);
        match *self {
            CoordinateBound::Mean { grad, eps, c } => {
                d.scale(grad) - d.abs().scale(eps) - c * d.sqr()
            }
            CoordinateBound::LogSigma { rigorous, eps } => {
                rigorous.enclose(delta) - d.abs().scale(eps)
            }
        }
    }
}

/// Theorem T's bound of a change Δ of the mean parameters (module docs), valid for every Δ
/// whose non-zero entries are among those of the direction it was built for, on the
/// confidence event of every component.
#[derive(Debug, Clone, PartialEq)]
pub struct DirectionalBound {
    grad: Vec<f64>,
    eps: Vec<f64>,
    c2: Interval,
}

impl DirectionalBound {
    /// The bound for the direction `d` (its estimate ĝ ± ε and feature norm) at standard
    /// deviation `sigma` > 0, the smallest σ of the policy: c₂ = c_ℝ(σ)·κ_φ enclosed.
    ///
    /// # Errors
    /// An invalid direction, σ not finite and positive, a non-coordinate direction with the
    /// thesis's constants (`BoundsError::UnprovenDirection`).
    pub fn new(k: &TaskConstants, sigma: f64, d: &Direction) -> Result<Self, BoundsError> {
        d.validate()?;
        let kappa = certified::enclosure::feature_factor(k, d)?;
        Ok(DirectionalBound {
            grad: d.grad_hat.to_vec(),
            eps: d.eps.to_vec(),
            c2: c_real_line(k, sigma)? * kappa,
        })
    }

    /// An enclosure of the bound at the exact change `delta` (units of v; the length of the
    /// direction, extra entries ignored).
    pub fn enclose(&self, delta: &[f64]) -> Interval {
        let zero = Interval::point(0.0);
        let (mut linear, mut norm2) = (zero, zero);
        for ((&d, &g), &e) in delta.iter().zip(&self.grad).zip(&self.eps) {
            let d = Interval::point(d);
            linear = linear + d.scale(g) - d.abs().scale(e);
            norm2 = norm2 + d.sqr();
        }
        linear - self.c2 * norm2
    }
}

/// The update of several coordinates that is applied, and the certified lower end of its
/// bound.
#[derive(Debug, Clone, PartialEq)]
pub struct RealisedChange {
    /// The new values of the coordinates.
    pub values: Vec<f64>,
    /// The step t·f along the direction that was applied (f the shrink factor; 0 for no
    /// change).
    pub step: f64,
    /// The lower end of the enclosure of the bound at the realised change.
    pub guaranteed: f64,
    /// Whether the realised change meets the requirement (`guaranteed ≥ required`).
    pub meets: bool,
}

/// Applies x₀ → fl(x₀ + t·u) coordinate by coordinate and certifies the realised change
/// (exact by TwoSum in every coordinate) against `bound` for `required`; as [`realise`], a
/// change that falls short is shrunk (t·(1 − 2⁻ʲ) for j = 52, …, 1) until one passes, no
/// change being the last resort, and with `shrink` false the rounded update is kept and only
/// its guarantee evaluated.
pub fn realise_along(
    x0: &[f64],
    u: &[f64],
    t: f64,
    bound: &DirectionalBound,
    required: f64,
    shrink: bool,
) -> RealisedChange {
    let check = |factor: f64| -> Option<RealisedChange> {
        let step = t * factor;
        let values: Vec<f64> = x0.iter().zip(u).map(|(&x, &ui)| x + step * ui).collect();
        let delta = values
            .iter()
            .zip(x0)
            .map(|(&y, &x)| exact_difference(y, x))
            .collect::<Option<Vec<f64>>>()?;
        let lo = bound.enclose(&delta).lo();
        (lo.is_finite() && (!shrink || lo >= required)).then_some(RealisedChange {
            values,
            step,
            guaranteed: lo,
            meets: lo >= required,
        })
    };
    if t > 0.0 {
        if let Some(r) = check(1.0) {
            return r;
        }
        if shrink {
            for j in (1..=52).rev() {
                if let Some(r) = check(1.0 - (-(j as f64)).exp2()) {
                    return r;
                }
            }
        }
    }
    RealisedChange {
        values: x0.to_vec(),
        step: 0.0,
        guaranteed: 0.0,
        meets: required <= 0.0,
    }
}

/// The realised change y − x if it is exact in `f64` (the error term of TwoSum is 0), else
/// `None`.
fn exact_difference(y: f64, x: f64) -> Option<f64> {
    let (a, b) = (y, -x);
    let s = a + b;
    let bb = s - a;
    let err = (a - (s - bb)) + (b - bb);
    (err == 0.0 && s.is_finite()).then_some(s)
}

/// The update of one coordinate that is applied, and the certified lower end of its bound.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Realised {
    /// The new value of the coordinate.
    pub value: f64,
    /// The lower end of the enclosure of the bound at the realised change.
    pub guaranteed: f64,
    /// Whether the realised change meets the requirement (`guaranteed ≥ required`).
    pub meets: bool,
}

/// Applies x₀ → fl(x₀ + Δ) and certifies the realised change against `bound` for
/// `required`: if the bound's enclosure at the realised change falls short, the change is
/// shrunk (x₀ + Δ(1 − 2⁻ʲ) for j = 52, 51, …, 1) until one passes, and no change at all is
/// the last resort. With `shrink` false (a step that was not certified, e.g. an infeasible
/// requirement) the rounded update is kept and only its guarantee evaluated.
pub fn realise(
    x0: f64,
    delta: f64,
    bound: &CoordinateBound,
    required: f64,
    shrink: bool,
) -> Realised {
    let check = |x1: f64| -> Option<Realised> {
        let d = exact_difference(x1, x0)?;
        let lo = bound.enclose(d).lo();
        (lo.is_finite() && (!shrink || lo >= required)).then_some(Realised {
            value: x1,
            guaranteed: lo,
            meets: lo >= required,
        })
    };
    if let Some(r) = check(x0 + delta) {
        return r;
    }
    if shrink {
        for j in (1..=52).rev() {
            let factor = 1.0 - (-(j as f64)).exp2();
            if let Some(r) = check(x0 + delta * factor) {
                return r;
            }
        }
    }
    Realised {
        value: x0,
        guaranteed: 0.0,
        meets: required <= 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lqg1d() -> TaskConstants {
        TaskConstants::new(0.99, 28.8, 4.0, 8.0).expect("constants")
    }

    /// c_ℝ encloses the f64 value of `rigorous::c` below and above the box threshold.
    #[test]
    fn c_real_line_encloses_the_rigorous_c() {
        let k = lqg1d();
        for sigma in [0.05, 0.5, 1.0, 3.0, 3.3, 10.0] {
            let c = c_real_line(&k, sigma).expect("c");
            let f = rigorous::c(&k, sigma).expect("c");
            assert!(c.contains(f), "σ = {sigma}: {c:?} vs {f}");
            assert!(c.width() <= 1e-12 * f, "σ = {sigma}: width {}", c.width());
        }
        assert!(c_real_line(&k, 0.0).is_err());
    }

    /// The mean bound at Δ = αĝ is at least the Theorem 4.7 bound at α (dominance, module
    /// docs), computed independently in f64 with a relative slack of 1e-12.
    #[test]
    fn mean_bound_dominates_theorem_4_7() {
        let k = lqg1d();
        let (sigma, g, eps) = (0.7, -3.2, 0.9);
        let b = CoordinateBound::mean(&k, sigma, g, eps).expect("bound");
        let c = sepg_bounds::constants::c(&k, sigma).expect("c");
        for alpha in [1e-9, 1e-7, 3e-6, 1e-5] {
            let thm47 =
                alpha * (g.abs() - eps).powi(2) - alpha * alpha * c * (g.abs() + eps).powi(2);
            let ours = b.enclose(alpha * g).lo();
            assert!(
                ours >= thm47 - 1e-12 * thm47.abs(),
                "α = {alpha}: {ours} < {thm47}"
            );
        }
    }

    /// A rounded update whose realised change falls short is moved toward x₀ until the
    /// enclosure passes; the realised change is then exact and certified.
    #[test]
    fn a_failing_rounded_update_is_moved_until_it_passes() {
        let k = lqg1d();
        let (sigma, g) = (1.0, 2.5);
        let b = CoordinateBound::mean(&k, sigma, g, 0.0).expect("bound");
        let c = c_real_line(&k, sigma).expect("c").hi();
        // the largest change with B(Δ) ≥ 0 is Δ = g/c: aim exactly at the boundary from an
        // x₀ whose ulp is much larger than the rounding of Δ.
        let x0 = -0.1;
        let delta = g / c;
        let r = realise(x0, delta, &b, 0.0, true);
        assert!(r.meets && r.guaranteed >= 0.0);
        let d = exact_difference(r.value, x0).expect("exact");
        assert!(b.enclose(d).lo() >= 0.0);
        assert!(d > 0.0 && d <= delta * (1.0 + 1e-12));
        // with a requirement no change can meet, nothing moves
        let none = realise(x0, delta, &b, 1e9, true);
        assert_eq!((none.value, none.guaranteed, none.meets), (x0, 0.0, false));
    }

    /// A change of two coordinates aimed at the boundary of Theorem T's bound is shrunk until
    /// its realised change, exact in both coordinates, passes; c₂ = c·p for p = 2 features.
    #[test]
    fn a_failing_change_of_several_coordinates_is_shrunk_until_it_passes() {
        use sepg_bounds::direction::FeatureNorm;
        use sepg_bounds::penalties::{Family, Horizon, Rewards, Tight};
        let k = lqg1d()
            .with_family(Family::Tight(Tight::new(
                Horizon::Finite(20),
                Rewards::NonPositive,
            )))
            .expect("tight");
        let (g, eps, u) = ([3.0, -1.0], [0.5, 0.25], [0.3, -0.7]);
        let d = Direction {
            direction: &u,
            grad_hat: &g,
            eps: &eps,
            features: FeatureNorm::FromMax { features: 2 },
        };
        let b = DirectionalBound::new(&k, 1.0, &d).expect("bound");
        let c2 = 2.0 * sepg_bounds::constants::c(&k, 1.0).expect("c");
        // B(t) = t·a − c₂t²‖u‖² with a = u·g − Σ|u_i|ε_i: zero at t = a/(c₂‖u‖²)
        let a = 0.3 * 3.0 + 0.7 - (0.3 * 0.5 + 0.7 * 0.25);
        let t = a / (c2 * (0.09 + 0.49));
        let x0 = [-0.1, 0.37];
        let r = realise_along(&x0, &u, t, &b, 0.0, true);
        assert!(r.meets && r.guaranteed >= 0.0 && r.step > 0.0 && r.step <= t);
        let delta: Vec<f64> = r
            .values
            .iter()
            .zip(&x0)
            .map(|(&y, &x)| exact_difference(y, x).expect("exact"))
            .collect();
        assert!(b.enclose(&delta).lo() >= 0.0);
        assert!(r.step >= t * (1.0 - 1e-9));
        // a requirement no change meets leaves x₀ unchanged
        let none = realise_along(&x0, &u, t, &b, 1e9, true);
        assert_eq!(
            (none.values, none.step, none.meets),
            (x0.to_vec(), 0.0, false)
        );
    }

    /// The log-σ bound is below the thesis form for Δ < 0 (the neglected terms) and the
    /// realisation shrinks a thesis-form boundary step until the rigorous bound passes.
    #[test]
    fn log_sigma_steps_are_certified_against_the_rigorous_bound() {
        // γ = 0.5, R = M_φ = 1, |A| = 2, σ = 0.5: d ≈ 8.19, so the boundary step of the thesis
        // form is Δ = g/d ≈ −0.12, where the neglected Θ(Δ³) terms are visible.
        let k = TaskConstants::new(0.5, 1.0, 1.0, 2.0).expect("constants");
        let (sigma, g) = (0.5, -1.0);
        let b = CoordinateBound::log_sigma(&k, sigma, g, 0.0).expect("bound");
        let d = sepg_bounds::constants::d(&k, sigma).expect("d");
        let delta = g / d;
        let thesis = delta * g - d * delta * delta;
        assert!(thesis.abs() < 1e-15 && delta < -0.1);
        assert!(
            b.enclose(delta).hi() < -1e-4,
            "the rigorous bound must be below the thesis form"
        );
        let w0 = -0.69;
        let r = realise(w0, delta, &b, 0.0, true);
        assert!(r.meets && r.guaranteed >= 0.0);
        let moved = exact_difference(r.value, w0).expect("exact");
        assert!(
            moved < 0.0 && moved > delta,
            "shrunk toward w0: {moved} vs {delta}"
        );
        // the shrink is the largest of the 52 candidates that passes: the next larger fails
        assert!(b.enclose(moved).lo() >= 0.0);
    }
}
