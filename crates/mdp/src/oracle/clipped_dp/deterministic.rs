//! The deterministic policy without transition noise, exactly: intervals of initial states
//! on which the trajectory is affine.

use super::*;

/// An interval of initial states on which `s_t = α s_0 + β` (exact deterministic method).
#[derive(Debug, Clone, Copy)]
pub(super) struct Piece {
    pub(super) lo: f64,
    pub(super) hi: f64,
    pub(super) alpha: Dual,
    pub(super) beta: Dual,
}

impl ClippedDpOracle {
    /// Deterministic policy without noise: exact propagation of initial-state intervals on
    /// which `s_t` is affine in `s_0`, with first derivatives in `v` (dual numbers); the
    /// quadratic rewards are integrated exactly (2-point Gauss–Legendre). The integrand is
    /// continuous in `s_0`, so the moving interval ends contribute no boundary terms.
    pub(super) fn eval_deterministic_exact(
        &self,
        v: f64,
        horizon: usize,
    ) -> Result<ExactEval, OracleError> {
        let (lo, hi) = (self.i_lo, self.i_hi);
        let width = hi - lo;
        let vd = Dual { x: v, d: 1.0 };
        let mut pieces = vec![Piece {
            lo,
            hi,
            alpha: Dual::c(1.0),
            beta: Dual::c(0.0),
        }];
        let mut j = Dual::c(0.0);
        let mut disc = 1.0;
        let action_kinks: Vec<f64> = if v == 0.0 {
            Vec::new()
        } else {
            vec![self.a_lo / v, self.a_hi / v]
        };
        for _ in 0..horizon {
            if crate::cancel::requested() {
                break;
            }
            let mut next = Vec::with_capacity(pieces.len());
            for pc in &pieces {
                for (l0, l1) in split(pc.lo, pc.hi, pc.alpha.x, pc.beta.x, &action_kinks) {
                    let weight = if width > 0.0 { (l1 - l0) / width } else { 1.0 };
                    let (ca, cb) = self.clipped_action(pc, vd, 0.5 * (l0 + l1));
                    for rwd in self.node_rewards(pc, (ca, cb), (l0, l1)) {
                        j = j.add(rwd.scale(0.5 * weight * disc));
                    }
                    self.next_pieces(pc, (ca, cb), (l0, l1), &mut next);
                }
            }
            if next.len() > MAX_PIECES {
                return Err(OracleError::ResolutionExceeded {
                    needed: next.len(),
                    max: MAX_PIECES,
                });
            }
            pieces = next;
            disc *= self.gamma;
        }
        finish(ExactEval {
            j: j.x,
            grad_v: vec![j.d],
            grad_w: Vec::new(),
            mixed_wv: Vec::new(),
            hessian: None,
            sigma: Vec::new(),
        })
    }

    /// The action `a_c = ca·s₀ + cb` on the piece `pc` of initial states (dual coefficients
    /// in `v`; `vd` = v with derivative 1), clipped or not as at the initial state `mid`: the
    /// piece is split at the action kinks, so one side holds on all of it.
    pub(super) fn clipped_action(&self, pc: &Piece, vd: Dual, mid: f64) -> (Dual, Dual) {
        let s_mid = pc.alpha.x * mid + pc.beta.x;
        let u = vd.x * s_mid;
        if u <= self.a_lo {
            (Dual::c(0.0), Dual::c(self.a_lo))
        } else if u >= self.a_hi {
            (Dual::c(0.0), Dual::c(self.a_hi))
        } else {
            (vd.mul(pc.alpha), vd.mul(pc.beta))
        }
    }

    /// The rewards `r(s(s₀), a(s₀))` at the 2-point Gauss–Legendre nodes `s₀` of `[l0, l1]`
    /// (exact for the quadratic reward), `s = α s₀ + β` on the piece `pc`, `a = ca s₀ + cb`.
    pub(super) fn node_rewards(
        &self,
        pc: &Piece,
        (ca, cb): (Dual, Dual),
        (l0, l1): (f64, f64),
    ) -> [Dual; 2] {
        let gl2 = [-(1.0f64 / 3.0).sqrt(), (1.0f64 / 3.0).sqrt()];
        let mid = 0.5 * (l0 + l1);
        gl2.map(|x| {
            let s0 = Dual::c(mid + 0.5 * (l1 - l0) * x);
            let s = pc.alpha.mul(s0).add(pc.beta);
            let a = ca.mul(s0).add(cb);
            s.mul(s).scale(-self.q).add(a.mul(a).scale(-self.r))
        })
    }

    /// The pieces of `[l0, l1]` after one step, `s' = clip(A s + B a_c)`: split where the
    /// unclipped next state crosses a state bound, clipped pieces constant.
    pub(super) fn next_pieces(
        &self,
        pc: &Piece,
        (ca, cb): (Dual, Dual),
        (l0, l1): (f64, f64),
        next: &mut Vec<Piece>,
    ) {
        let ya = pc.alpha.scale(self.a).add(ca.scale(self.b));
        let yb = pc.beta.scale(self.a).add(cb.scale(self.b));
        for (m0, m1) in split(l0, l1, ya.x, yb.x, &[self.s_lo, self.s_hi]) {
            let y_mid = ya.x * 0.5 * (m0 + m1) + yb.x;
            let (alpha, beta) = if y_mid <= self.s_lo {
                (Dual::c(0.0), Dual::c(self.s_lo))
            } else if y_mid >= self.s_hi {
                (Dual::c(0.0), Dual::c(self.s_hi))
            } else {
                (ya, yb)
            };
            next.push(Piece {
                lo: m0,
                hi: m1,
                alpha,
                beta,
            });
        }
    }
}

/// Sub-intervals of `[lo, hi]` separated by the points where `α x + β` crosses a level.
pub(super) fn split(lo: f64, hi: f64, alpha: f64, beta: f64, levels: &[f64]) -> Vec<(f64, f64)> {
    let mut cuts = vec![lo, hi];
    if alpha != 0.0 {
        for &k in levels {
            let x = (k - beta) / alpha;
            if x > lo && x < hi {
                cuts.push(x);
            }
        }
    }
    cuts.sort_by(f64::total_cmp);
    cuts.windows(2)
        .filter(|w| w[1] > w[0] || lo == hi)
        .map(|w| (w[0], w[1]))
        .collect()
}
