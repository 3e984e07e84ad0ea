//! The baseline-and-sample kernel shared by every likelihood-ratio estimator of this crate.
//!
//! Every estimator here has the form `x_{i,c} = Σ_t sample(i, t, c; b_{t,c})` with a baseline
//! `b_{t,c} = Σ num / Σ den` summed over a set of trajectories (all of them, or all but `i`).
//! A [`Terms`] implementation gives, per trajectory, its baseline terms and its sample; the
//! [`Sums`] workspace runs the fit:
//!
//! - plug-in: one pass accumulating the totals, then one pass of samples;
//! - leave-one-out: one backward pass storing suffix sums over trajectories, then one forward
//!   pass in which trajectory `i` uses `prefix_i + suffix_{i+1}`, the exact sum over the other
//!   trajectories (no subtraction `total − own`, so no cancellation when one trajectory
//!   dominates the sums).
//!
//! All loops run over contiguous slices of the row-major [`sepg_mdp::Batch`] buffers, one
//! trajectory at a time, so that they vectorise across time steps and components.

use crate::gradient::{Baseline, BaselineFit};

/// The per-trajectory data of one estimator (`rows` trajectories, `width = steps · comps`
/// baseline entries and `comps` sample components per trajectory).
pub(crate) trait Terms {
    /// Number of baseline entries per trajectory (`steps · comps`).
    fn width(&self) -> usize;
    /// Number of sample components per trajectory.
    fn comps(&self) -> usize;
    /// Adds the baseline terms `(num, den)` of trajectory `r` to `num` and `den`.
    fn add_terms(&self, r: usize, num: &mut [f64], den: &mut [f64]);
    /// Writes the sample of trajectory `r` with the baseline `base` (length `width`) into `x`.
    fn sample(&self, r: usize, base: &[f64], x: &mut [f64]);
    /// Writes the sample of trajectory `r` without baseline into `x`.
    fn sample_plain(&self, r: usize, x: &mut [f64]);
}

/// Reusable buffers of the baseline fit.
#[derive(Debug, Clone, Default)]
pub(crate) struct Sums {
    /// Baseline of the current trajectory.
    base: Vec<f64>,
    /// Prefix sums (leave-one-out) or totals (plug-in) of the baseline terms.
    pre_num: Vec<f64>,
    pre_den: Vec<f64>,
    /// Suffix sums over trajectories, `(rows + 1) × width` (leave-one-out).
    suf_num: Vec<f64>,
    suf_den: Vec<f64>,
}

fn zeroed(v: &mut Vec<f64>, len: usize) {
    v.clear();
    v.resize(len, 0.0);
}

impl Sums {
    /// Writes the `rows × comps` samples of `terms` into `out` with the given baseline.
    pub(crate) fn run<T: Terms>(
        &mut self,
        terms: &T,
        rows: usize,
        baseline: Baseline,
        fit: BaselineFit,
        out: &mut [f64],
    ) {
        let comps = terms.comps();
        let w = terms.width();
        let out = &mut out[..rows * comps];
        if baseline == Baseline::None {
            for (r, x) in out.chunks_exact_mut(comps).enumerate() {
                terms.sample_plain(r, x);
            }
            return;
        }
        zeroed(&mut self.base, w);
        zeroed(&mut self.pre_num, w);
        zeroed(&mut self.pre_den, w);
        match fit {
            BaselineFit::PlugIn => {
                for r in 0..rows {
                    terms.add_terms(r, &mut self.pre_num, &mut self.pre_den);
                }
                for ((b, n), d) in self.base.iter_mut().zip(&self.pre_num).zip(&self.pre_den) {
                    *b = ratio(*n, *d);
                }
                for (r, x) in out.chunks_exact_mut(comps).enumerate() {
                    terms.sample(r, &self.base, x);
                }
            }
            BaselineFit::LeaveOneOut => {
                zeroed(&mut self.suf_num, (rows + 1) * w);
                zeroed(&mut self.suf_den, (rows + 1) * w);
                for r in (0..rows).rev() {
                    let (num, num_next) = self.suf_num[r * w..(r + 2) * w].split_at_mut(w);
                    let (den, den_next) = self.suf_den[r * w..(r + 2) * w].split_at_mut(w);
                    num.copy_from_slice(num_next);
                    den.copy_from_slice(den_next);
                    terms.add_terms(r, num, den);
                }
                for (r, x) in out.chunks_exact_mut(comps).enumerate() {
                    let on = &self.suf_num[(r + 1) * w..(r + 2) * w];
                    let od = &self.suf_den[(r + 1) * w..(r + 2) * w];
                    for ((((b, pn), pd), on), od) in self
                        .base
                        .iter_mut()
                        .zip(&self.pre_num)
                        .zip(&self.pre_den)
                        .zip(on)
                        .zip(od)
                    {
                        *b = ratio(pn + on, pd + od);
                    }
                    terms.add_terms(r, &mut self.pre_num, &mut self.pre_den);
                    terms.sample(r, &self.base, x);
                }
            }
        }
    }
}

/// Baseline ratio with the explicit convention `0/0 = 0` (Sec 2.3.2, SPEC §3); written as a
/// select after the division so that it vectorises.
#[inline(always)]
pub(crate) fn ratio(num: f64, den: f64) -> f64 {
    let q = num / den;
    if den > 0.0 { q } else { 0.0 }
}

/// Score-function terms: G(PO)MDP and PGT (per step) or REINFORCE (one "step", the last
/// cumulative score and the return).
///
/// Trajectory `r` has cumulative scores `s[r · s_stride ..][.. steps · comps]` and rewards
/// `f[r · f_stride ..][.. steps]`.
pub(crate) struct ScoreTerms<'a> {
    pub s: &'a [f64],
    pub s_stride: usize,
    pub f: &'a [f64],
    pub f_stride: usize,
    pub steps: usize,
    pub comps: usize,
    /// Optimal `(S² F, S²)` terms, else mean `(F, 1)` terms.
    pub optimal: bool,
    /// PGT (reward-to-go) order of the sample.
    pub pgt: bool,
}

impl ScoreTerms<'_> {
    #[inline(always)]
    fn rows(&self, r: usize) -> (&[f64], &[f64]) {
        let s = &self.s[r * self.s_stride..][..self.steps * self.comps];
        let f = &self.f[r * self.f_stride..][..self.steps];
        (s, f)
    }
}

impl Terms for ScoreTerms<'_> {
    fn width(&self) -> usize {
        self.steps * self.comps
    }

    fn comps(&self) -> usize {
        self.comps
    }

    #[inline]
    fn add_terms(&self, r: usize, num: &mut [f64], den: &mut [f64]) {
        let (s, f) = self.rows(r);
        let (num, den) = (&mut num[..s.len()], &mut den[..s.len()]);
        if self.comps == 1 {
            for (((n, d), sc), ft) in num.iter_mut().zip(den.iter_mut()).zip(s).zip(f) {
                add_score_term(self.optimal, *sc, *ft, n, d);
            }
        } else {
            let c = self.comps;
            for (((nt, dt), st), ft) in num
                .chunks_exact_mut(c)
                .zip(den.chunks_exact_mut(c))
                .zip(s.chunks_exact(c))
                .zip(f)
            {
                for ((n, d), sc) in nt.iter_mut().zip(dt.iter_mut()).zip(st) {
                    add_score_term(self.optimal, *sc, *ft, n, d);
                }
            }
        }
    }

    #[inline]
    fn sample(&self, r: usize, base: &[f64], x: &mut [f64]) {
        let (s, f) = self.rows(r);
        if self.pgt {
            pgt_sample(s, f, base, x);
        } else if self.comps == 1 {
            let mut acc = 0.0;
            for ((sc, bc), ft) in s.iter().zip(base).zip(f) {
                acc += sc * (ft - bc);
            }
            x[0] = acc;
        } else {
            x.fill(0.0);
            let c = self.comps;
            for ((st, bt), ft) in s.chunks_exact(c).zip(base.chunks_exact(c)).zip(f) {
                for ((xc, sc), bc) in x.iter_mut().zip(st).zip(bt) {
                    *xc += sc * (ft - bc);
                }
            }
        }
    }

    #[inline]
    fn sample_plain(&self, r: usize, x: &mut [f64]) {
        let (s, f) = self.rows(r);
        if self.pgt {
            pgt_plain(s, f, x);
        } else if self.comps == 1 {
            let mut acc = 0.0;
            for (sc, ft) in s.iter().zip(f) {
                acc += sc * ft;
            }
            x[0] = acc;
        } else {
            x.fill(0.0);
            for (st, ft) in s.chunks_exact(self.comps).zip(f) {
                for (xc, sc) in x.iter_mut().zip(st) {
                    *xc += sc * ft;
                }
            }
        }
    }
}

/// Adds `(S² F, S²)` (optimal) or `(F, 1)` (mean) to `(n, d)`.
#[inline(always)]
fn add_score_term(optimal: bool, s: f64, f: f64, n: &mut f64, d: &mut f64) {
    if optimal {
        let s2 = s * s;
        *n += s2 * f;
        *d += s2;
    } else {
        *n += f;
        *d += 1.0;
    }
}

/// PGT order for one trajectory: `x_c = Σ_k (S_k − S_{k−1})_c Σ_{l≥k} (F_l − b_{l,c})`.
fn pgt_sample(s: &[f64], f: &[f64], base: &[f64], x: &mut [f64]) {
    let comps = x.len();
    for (c, xc) in x.iter_mut().enumerate() {
        let mut acc = 0.0;
        let mut to_go = 0.0;
        for t in (0..f.len()).rev() {
            to_go += f[t] - base[t * comps + c];
            let prev = if t == 0 { 0.0 } else { s[(t - 1) * comps + c] };
            acc += (s[t * comps + c] - prev) * to_go;
        }
        *xc = acc;
    }
}

/// [`pgt_sample`] without baseline.
fn pgt_plain(s: &[f64], f: &[f64], x: &mut [f64]) {
    let comps = x.len();
    for (c, xc) in x.iter_mut().enumerate() {
        let mut acc = 0.0;
        let mut to_go = 0.0;
        for t in (0..f.len()).rev() {
            to_go += f[t];
            let prev = if t == 0 { 0.0 } else { s[(t - 1) * comps + c] };
            acc += (s[t * comps + c] - prev) * to_go;
        }
        *xc = acc;
    }
}

/// The terms of `ĥ` (Theorem B.1) from per-entry products `u = G H F` and control variates
/// `z` (`G + H` for the optimal baseline of Appendix B.2, `G H` for the mean baseline),
/// precomputed for the trajectories of the range, layout `[(r · steps + t) · comps + c]`.
pub(crate) struct HTerms<'a> {
    pub u: &'a [f64],
    pub z: &'a [f64],
    /// Rewards `F` of the trajectories of the range, `[r · steps + t]`.
    pub f: &'a [f64],
    pub steps: usize,
    pub comps: usize,
    /// Optimal `(u z, z²)` terms, else mean `(F, 1)` terms.
    pub optimal: bool,
}

impl Terms for HTerms<'_> {
    fn width(&self) -> usize {
        self.steps * self.comps
    }

    fn comps(&self) -> usize {
        self.comps
    }

    #[inline]
    fn add_terms(&self, r: usize, num: &mut [f64], den: &mut [f64]) {
        let w = self.width();
        let (num, den) = (&mut num[..w], &mut den[..w]);
        if self.optimal {
            let u = &self.u[r * w..][..w];
            let z = &self.z[r * w..][..w];
            for (((n, d), u), z) in num.iter_mut().zip(den.iter_mut()).zip(u).zip(z) {
                *n += u * z;
                *d += z * z;
            }
        } else {
            let f = &self.f[r * self.steps..][..self.steps];
            for ((nt, dt), ft) in num
                .chunks_exact_mut(self.comps)
                .zip(den.chunks_exact_mut(self.comps))
                .zip(f)
            {
                for (n, d) in nt.iter_mut().zip(dt.iter_mut()) {
                    *n += ft;
                    *d += 1.0;
                }
            }
        }
    }

    #[inline]
    fn sample(&self, r: usize, base: &[f64], x: &mut [f64]) {
        let w = self.width();
        let u = &self.u[r * w..][..w];
        let z = &self.z[r * w..][..w];
        if self.comps == 1 {
            let mut acc = 0.0;
            for ((u, z), b) in u.iter().zip(z).zip(base) {
                acc += u - b * z;
            }
            x[0] = acc;
        } else {
            x.fill(0.0);
            let c = self.comps;
            for ((ut, zt), bt) in u.chunks_exact(c).zip(z.chunks_exact(c)).zip(base.chunks_exact(c))
            {
                for (((xc, u), z), b) in x.iter_mut().zip(ut).zip(zt).zip(bt) {
                    *xc += u - b * z;
                }
            }
        }
    }

    #[inline]
    fn sample_plain(&self, r: usize, x: &mut [f64]) {
        let w = self.width();
        let u = &self.u[r * w..][..w];
        if self.comps == 1 {
            let mut acc = 0.0;
            for u in u {
                acc += u;
            }
            x[0] = acc;
        } else {
            x.fill(0.0);
            for ut in u.chunks_exact(self.comps) {
                for (xc, u) in x.iter_mut().zip(ut) {
                    *xc += u;
                }
            }
        }
    }
}
