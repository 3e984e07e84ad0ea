//! The baseline-and-sample kernel shared by every likelihood-ratio estimator of this crate.
//!
//! Every estimator here has the form `x_{i,c} = Σ_t p(v_{i,t,c}; b_{t,c})`: per entry
//! (trajectory `i`, step `t`, component `c`) a few inputs `v` (cumulative score and reward, or
//! the products of `ĥ`), a baseline `b_{t,c} = Σ num(v) / Σ den(v)` summed over a set of
//! trajectories (all of them, or all but `i`), and a sample term `p`. A [`Formula`] gives
//! `num`, `den` and `p` for one entry; [`Sums::run`] runs the fit in flat passes:
//!
//! - no baseline: the sample terms, then the sums over time;
//! - plug-in: the totals of the terms, the sample terms, the sums over time;
//! - leave-one-out: one backward pass storing suffix sums over trajectories; one forward pass
//!   in which trajectory `i` gets the baseline of `prefix_i + suffix_{i+1}`, the exact sum over
//!   the other trajectories (no subtraction `total − own`, so no cancellation when one
//!   trajectory dominates the sums), and its sample terms, written over `suffix_{i+1}`; the
//!   sums over time.
//!
//! Terms are recomputed from the inputs in each pass instead of being stored. Every pass runs
//! over contiguous rows of the row-major [`sepg_mdp::Batch`] buffers, so that it vectorises
//! across time steps and components; the sums over time run in the order of `t` for each
//! trajectory, four trajectories at a time (independent dependency chains).

use crate::gradient::{Baseline, BaselineFit};

/// Row-major rows of a matrix: row `r` starts at `r · stride` (`stride = 0`: one shared row).
#[derive(Clone, Copy)]
pub(crate) struct Rows<'a> {
    data: &'a [f64],
    stride: usize,
}

impl<'a> Rows<'a> {
    pub(crate) fn new(data: &'a [f64], stride: usize) -> Self {
        Rows { data, stride }
    }

    #[inline(always)]
    pub(crate) fn row(&self, r: usize, len: usize) -> &'a [f64] {
        &self.data[r * self.stride..][..len]
    }
}

/// The element-wise formulas of one estimator with `K` inputs per entry.
pub(crate) trait Formula<const K: usize> {
    /// Baseline terms `(num, den)` of one entry.
    fn term(v: [f64; K]) -> (f64, f64);
    /// Sample term of one entry with the baseline `b`.
    fn sample(v: [f64; K], b: f64) -> f64;
    /// Sample term of one entry without baseline.
    fn plain(v: [f64; K]) -> f64;
}

/// Score-function estimators, inputs `[S, F]` (cumulative score, discounted reward or return):
/// optimal terms `(S² F, S²)` (`OPTIMAL`) or mean terms `(F, 1)`; sample `S (F − b)`.
pub(crate) struct Score<const OPTIMAL: bool>;

impl<const OPTIMAL: bool> Formula<2> for Score<OPTIMAL> {
    #[inline(always)]
    fn term([s, f]: [f64; 2]) -> (f64, f64) {
        if OPTIMAL {
            let s2 = s * s;
            (s2 * f, s2)
        } else {
            (f, 1.0)
        }
    }

    #[inline(always)]
    fn sample([s, f]: [f64; 2], b: f64) -> f64 {
        s * (f - b)
    }

    #[inline(always)]
    fn plain([s, f]: [f64; 2]) -> f64 {
        s * f
    }
}

/// `ĥ` with the baseline of Appendix B.2, inputs `[u, z]` (`u = G H F`, `z = G + H`): terms
/// `(u z, z²)`, sample `u − b z`.
pub(crate) struct HOptimal;

impl Formula<2> for HOptimal {
    #[inline(always)]
    fn term([u, z]: [f64; 2]) -> (f64, f64) {
        (u * z, z * z)
    }

    #[inline(always)]
    fn sample([u, z]: [f64; 2], b: f64) -> f64 {
        u - b * z
    }

    #[inline(always)]
    fn plain([u, _]: [f64; 2]) -> f64 {
        u
    }
}

/// `ĥ` with the per-step mean baseline, inputs `[u, z, F]` (`z = G H`): terms `(F, 1)`,
/// sample `u − b z`.
pub(crate) struct HMean;

impl Formula<3> for HMean {
    #[inline(always)]
    fn term([_, _, f]: [f64; 3]) -> (f64, f64) {
        (f, 1.0)
    }

    #[inline(always)]
    fn sample([u, z, _]: [f64; 3], b: f64) -> f64 {
        u - b * z
    }

    #[inline(always)]
    fn plain([u, _, _]: [f64; 3]) -> f64 {
        u
    }
}

/// How the samples are formed from the fitted baselines.
pub(crate) enum Output<'a> {
    /// `x_{r,c} = Σ_t p(v_{r,t,c}; b_{t,c})` into `rows × comps` samples.
    Sums(&'a mut [f64]),
    /// Keep the baselines themselves, for a sample of another order (PGT); read them with
    /// [`Sums::baselines`].
    Baselines,
}

/// Reusable buffers of the baseline fit.
#[derive(Debug, Clone, Default)]
pub(crate) struct Sums {
    /// Prefix sums (leave-one-out) or totals (plug-in) of the terms, then (plug-in) the
    /// baseline.
    pre_num: Vec<f64>,
    pre_den: Vec<f64>,
    /// `(rows + 1) × width`: suffix sums over trajectories (leave-one-out), row `r + 1`
    /// overwritten by the sample terms (or baselines) of trajectory `r`.
    suf_num: Vec<f64>,
    suf_den: Vec<f64>,
    /// Where [`Output::Baselines`] left the baselines: shared (stride 0) or per trajectory.
    shared_base: bool,
}

fn zeroed(v: &mut Vec<f64>, len: usize) {
    v.clear();
    v.resize(len, 0.0);
}

/// Makes `v` at least `len` long; it never shrinks, so that blocks of alternating sizes do
/// not refill it with zeros (every entry used is written before it is read).
fn grow(v: &mut Vec<f64>, len: usize) {
    if v.len() < len {
        v.resize(len, 0.0);
    }
}

/// The arguments of one call of [`Sums::run`], handed to the build that runs it.
struct Fit<'a, const K: usize> {
    inputs: [Rows<'a>; K],
    /// `(rows, width, comps)`.
    shape: (usize, usize, usize),
    choice: (Baseline, BaselineFit),
    output: Output<'a>,
}

impl Sums {
    /// Fits the baseline of `F` over `rows` trajectories of `width` entries with inputs
    /// `inputs`, and writes the samples (`comps` per trajectory, `width = steps · comps`) or
    /// keeps the baselines.
    ///
    /// On x86-64 processors with AVX2 the passes run in a copy of this function compiled for
    /// AVX2 (four lanes instead of two). Only the width of the vectors changes: every entry
    /// goes through the same IEEE operations in the same order (no fused multiply-add), so the
    /// results are the same bits on every processor.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn run<const K: usize, F: Formula<K>>(
        &mut self,
        inputs: [Rows<'_>; K],
        rows: usize,
        width: usize,
        comps: usize,
        baseline: Baseline,
        fit: BaselineFit,
        output: Output<'_>,
    ) {
        let job = Fit {
            inputs,
            shape: (rows, width, comps),
            choice: (baseline, fit),
            output,
        };
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor supports AVX2, the only feature `run_avx2` is built for.
            unsafe { self.run_avx2::<K, F>(job) };
            return;
        }
        self.run_any::<K, F>(job);
    }

    /// [`Sums::run`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn run_avx2<const K: usize, F: Formula<K>>(&mut self, job: Fit<'_, K>) {
        self.run_any::<K, F>(job);
    }

    /// The passes of [`Sums::run`], inlined into each build of it.
    #[inline(always)]
    fn run_any<const K: usize, F: Formula<K>>(&mut self, job: Fit<'_, K>) {
        let Fit {
            inputs,
            shape: (rows, width, comps),
            choice: (baseline, fit),
            output,
        } = job;
        let keep_base = matches!(output, Output::Baselines);
        // Row r + 1 of `suf_num` receives trajectory r's sample terms (or baselines).
        grow(&mut self.suf_num, (rows + 1) * width);
        self.shared_base = false;
        match (baseline, fit) {
            (Baseline::None, _) => self.no_baseline::<K, F>(inputs, rows, width, keep_base),
            (_, BaselineFit::PlugIn) => self.plug_in::<K, F>(inputs, rows, width, keep_base),
            (_, BaselineFit::LeaveOneOut) => {
                self.leave_one_out::<K, F>(inputs, rows, width, keep_base)
            }
        }
        if let Output::Sums(out) = output {
            self.write_sums(out, rows, width, comps);
        }
    }

    /// The samples (or, keeping baselines, the zero baseline) without a baseline.
    #[inline(always)]
    fn no_baseline<const K: usize, F: Formula<K>>(
        &mut self,
        inputs: [Rows<'_>; K],
        rows: usize,
        width: usize,
        keep_base: bool,
    ) {
        let w = width;
        let row = |r: usize| -> [&[f64]; K] { std::array::from_fn(|k| inputs[k].row(r, w)) };
        let used = (rows + 1) * w;
        if keep_base {
            self.suf_num[..w].fill(0.0);
            self.shared_base = true;
        } else {
            for (r, p) in self.suf_num[w..used].chunks_exact_mut(w).enumerate() {
                let v = row(r);
                for (e, p) in p.iter_mut().enumerate() {
                    *p = F::plain(std::array::from_fn(|k| v[k][e]));
                }
            }
        }
    }

    /// The plug-in fit: one baseline from every trajectory, then the samples (or the baseline).
    #[inline(always)]
    fn plug_in<const K: usize, F: Formula<K>>(
        &mut self,
        inputs: [Rows<'_>; K],
        rows: usize,
        width: usize,
        keep_base: bool,
    ) {
        let w = width;
        let row = |r: usize| -> [&[f64]; K] { std::array::from_fn(|k| inputs[k].row(r, w)) };
        let used = (rows + 1) * w;
        zeroed(&mut self.pre_num, w);
        zeroed(&mut self.pre_den, w);
        for r in 0..rows {
            let v = row(r);
            for (e, (pn, pd)) in self.pre_num.iter_mut().zip(&mut self.pre_den).enumerate() {
                let (n, d) = F::term(std::array::from_fn(|k| v[k][e]));
                *pn += n;
                *pd += d;
            }
        }
        for (b, d) in self.pre_num.iter_mut().zip(&self.pre_den) {
            *b = ratio(*b, *d);
        }
        if keep_base {
            self.suf_num[..w].copy_from_slice(&self.pre_num);
            self.shared_base = true;
        } else {
            for (r, p) in self.suf_num[w..used].chunks_exact_mut(w).enumerate() {
                let v = row(r);
                for (e, (p, b)) in p.iter_mut().zip(&self.pre_num).enumerate() {
                    *p = F::sample(std::array::from_fn(|k| v[k][e]), *b);
                }
            }
        }
    }

    /// The leave-one-out fit: suffix sums of the fit's terms, then one pass that keeps prefix
    /// sums, so that trajectory r's baseline uses every trajectory but r.
    #[inline(always)]
    fn leave_one_out<const K: usize, F: Formula<K>>(
        &mut self,
        inputs: [Rows<'_>; K],
        rows: usize,
        width: usize,
        keep_base: bool,
    ) {
        let w = width;
        let row = |r: usize| -> [&[f64]; K] { std::array::from_fn(|k| inputs[k].row(r, w)) };
        let used = (rows + 1) * w;
        grow(&mut self.suf_den, used);
        // Rows 0..rows are overwritten; row `rows` is the empty sum.
        self.suf_num[rows * w..used].fill(0.0);
        self.suf_den[rows * w..used].fill(0.0);
        for r in (0..rows).rev() {
            let v = row(r);
            let (sn, sn_next) = self.suf_num[r * w..(r + 2) * w].split_at_mut(w);
            let (sd, sd_next) = self.suf_den[r * w..(r + 2) * w].split_at_mut(w);
            let next = sn_next.iter().zip(sd_next.iter());
            for (e, ((sn, sd), (nn, nd))) in sn.iter_mut().zip(sd).zip(next).enumerate() {
                let (n, d) = F::term(std::array::from_fn(|k| v[k][e]));
                *sn = nn + n;
                *sd = nd + d;
            }
        }
        zeroed(&mut self.pre_num, w);
        zeroed(&mut self.pre_den, w);
        let others = self.suf_num[w..used]
            .chunks_exact_mut(w)
            .zip(self.suf_den[w..used].chunks_exact(w));
        for (r, (on, od)) in others.enumerate() {
            let v = row(r);
            let pre = self.pre_num.iter_mut().zip(self.pre_den.iter_mut());
            for (e, ((p, od), (pn, pd))) in on.iter_mut().zip(od).zip(pre).enumerate() {
                let ve = std::array::from_fn(|k| v[k][e]);
                let b = ratio(*pn + *p, *pd + od);
                let (n, d) = F::term(ve);
                *pn += n;
                *pd += d;
                *p = if keep_base { b } else { F::sample(ve, b) };
            }
        }
    }

    /// Sums each trajectory's sample terms over its steps into `out` (`comps` per trajectory).
    #[inline(always)]
    fn write_sums(&self, out: &mut [f64], rows: usize, width: usize, comps: usize) {
        let (w, used) = (width, (rows + 1) * width);
        let terms = &self.suf_num[w..used];
        if comps == 1 {
            row_sums(&mut out[..rows], w, 0.0, [Rows::new(terms, w)], |[p]| p);
        } else {
            for (x, p) in out[..rows * comps]
                .chunks_exact_mut(comps)
                .zip(terms.chunks_exact(w))
            {
                x.fill(0.0);
                for pt in p.chunks_exact(comps) {
                    for (xc, pc) in x.iter_mut().zip(pt) {
                        *xc += pc;
                    }
                }
            }
        }
    }
    /// The baselines left by [`Output::Baselines`]: trajectory `r` uses
    /// `buffer[r · stride..][..width]`.
    pub(crate) fn baselines(&self, width: usize) -> Rows<'_> {
        if self.shared_base {
            Rows::new(&self.suf_num[..width], 0)
        } else {
            Rows::new(&self.suf_num[width..], width)
        }
    }
}

/// Baseline ratio with the explicit convention `0/0 = 0` (Sec 2.3.2, docs/CONVENTIONS.md §3); written as a
/// select after the division so that it vectorises.
#[inline(always)]
fn ratio(num: f64, den: f64) -> f64 {
    let q = num / den;
    if den > 0.0 { q } else { 0.0 }
}

/// `out[r] = init + Σ_{t<len} term(a_{r,t}, b_{r,t}, …)`, summed in the order of `t` for every
/// row `r`, four rows at a time (independent dependency chains; the result does not depend on
/// the blocking).
#[inline(always)]
#[expect(
    clippy::needless_range_loop,
    reason = "`t` indexes the same column of several rows"
)]
pub(crate) fn row_sums<const A: usize>(
    out: &mut [f64],
    len: usize,
    init: f64,
    inputs: [Rows<'_>; A],
    term: impl Fn([f64; A]) -> f64,
) {
    const BLOCK: usize = 4;
    let mut blocks = out.chunks_exact_mut(BLOCK);
    let mut r = 0;
    for x in &mut blocks {
        let rows: [[&[f64]; BLOCK]; A] =
            std::array::from_fn(|a| std::array::from_fn(|q| inputs[a].row(r + q, len)));
        let mut acc = [init; BLOCK];
        for t in 0..len {
            for (q, acc) in acc.iter_mut().enumerate() {
                *acc += term(std::array::from_fn(|a| rows[a][q][t]));
            }
        }
        x.copy_from_slice(&acc);
        r += BLOCK;
    }
    for x in blocks.into_remainder() {
        let rows: [&[f64]; A] = std::array::from_fn(|a| inputs[a].row(r, len));
        let mut acc = init;
        for t in 0..len {
            acc += term(std::array::from_fn(|a| rows[a][t]));
        }
        *x = acc;
        r += 1;
    }
}

/// PGT order for one trajectory: `x_c = Σ_k (S_k − S_{k−1})_c Σ_{l≥k} (F_l − b_{l,c})`, with
/// cumulative scores `s` (`steps × comps`), rewards `f` and baselines `base`.
pub(crate) fn pgt_sample(s: &[f64], f: &[f64], base: &[f64], x: &mut [f64]) {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Every fit and output of [`Sums::run`] on `rows` trajectories of `width` entries (the
    /// inputs chosen by `pick`), run by `build`; the samples or baselines as bits.
    fn all_fits<const K: usize>(
        (rows, width, comps): (usize, usize, usize),
        pick: for<'a> fn([Rows<'a>; 3]) -> [Rows<'a>; K],
        build: impl Fn(&mut Sums, Fit<'_, K>),
    ) -> Vec<u64> {
        // Deterministic, irregular inputs of both signs, with exact zeros (0/0 baselines).
        let data: Vec<f64> = (0..3 * rows * width)
            .map(|i| {
                let x = ((i * 7919 + 13) % 1009) as f64 / 97.0 - 5.0;
                if i % 11 == 0 { 0.0 } else { x }
            })
            .collect();
        let (a, rest) = data.split_at(rows * width);
        let (b, c) = rest.split_at(rows * width);
        let inputs = pick([a, b, c].map(|d| Rows::new(d, width)));
        let mut bits = Vec::new();
        for baseline in [Baseline::None, Baseline::Optimal] {
            for fit in [BaselineFit::PlugIn, BaselineFit::LeaveOneOut] {
                let mut sums = Sums::default();
                let mut out = vec![0.0; rows * comps];
                for output in [Output::Sums(&mut out), Output::Baselines] {
                    let shape = (rows, width, comps);
                    let choice = (baseline, fit);
                    build(
                        &mut sums,
                        Fit {
                            inputs,
                            shape,
                            choice,
                            output,
                        },
                    );
                }
                bits.extend(out.iter().map(|x| x.to_bits()));
                let base = sums.baselines(width);
                for r in 0..rows {
                    bits.extend(base.row(r, width).iter().map(|x| x.to_bits()));
                }
            }
        }
        bits
    }

    fn two<'a>([a, b, _]: [Rows<'a>; 3]) -> [Rows<'a>; 2] {
        [a, b]
    }

    fn three<'a>(i: [Rows<'a>; 3]) -> [Rows<'a>; 3] {
        i
    }

    /// The AVX2 build of the fits computes the same bits as the portable one, for every
    /// formula, fit and output, with and without a remainder of rows and lanes.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_avx2_fits_compute_the_portable_bits() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2 on this processor: the portable build is the only one run");
            return;
        }
        for (rows, steps, comps) in [(1, 1, 1), (5, 7, 1), (9, 20, 1), (6, 3, 3), (13, 5, 2)] {
            let shape = (rows, steps * comps, comps);
            macro_rules! both {
                ($k:literal, $f:ty, $pick:expr) => {{
                    let portable = all_fits::<$k>(shape, $pick, |s, job| s.run_any::<$k, $f>(job));
                    // SAFETY: AVX2 was detected above.
                    let avx2 =
                        all_fits::<$k>(shape, $pick, |s, job| unsafe { s.run_avx2::<$k, $f>(job) });
                    assert_eq!(portable, avx2, "{} {shape:?}", stringify!($f));
                }};
            }
            both!(2, Score<true>, two);
            both!(2, Score<false>, two);
            both!(2, HOptimal, two);
            both!(3, HMean, three);
        }
    }
}
