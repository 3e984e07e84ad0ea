//! Sparse operators of one backward step and the recursion that applies them.

use super::*;

/// A run of consecutive columns of one operator row.
#[derive(Debug, Clone, Copy)]
pub(super) struct Seg {
    /// First column.
    pub(super) start: usize,
    /// Number of columns.
    pub(super) len: usize,
    /// Offset of the run's weights in [`SpanOp::vals`].
    pub(super) off: usize,
}

/// A row-sparse operator whose entries carry the weights of the powers `z^0 … z^{kmax−1}`.
///
/// Each row is a list of runs of consecutive columns ([`Seg`]); the weights of power `k` of a
/// run are contiguous, at `vals[off + k·len ..][..len]`, so that applying the operator is a
/// sequence of dense dot products.
#[derive(Debug, Clone)]
pub(super) struct SpanOp {
    pub(super) kmax: usize,
    pub(super) row_ptr: Vec<usize>,
    pub(super) segs: Vec<Seg>,
    pub(super) vals: Vec<f64>,
}

impl SpanOp {
    pub(super) fn new(kmax: usize) -> Self {
        SpanOp {
            kmax,
            row_ptr: vec![0],
            segs: Vec::new(),
            vals: Vec::new(),
        }
    }

    pub(super) fn rows(&self) -> usize {
        self.row_ptr.len() - 1
    }

    /// The runs of row `i`.
    pub(super) fn row(&self, i: usize) -> &[Seg] {
        &self.segs[self.row_ptr[i]..self.row_ptr[i + 1]]
    }

    /// The weights of power `k` of a run.
    pub(super) fn weights(&self, seg: &Seg, k: usize) -> &[f64] {
        &self.vals[seg.off + k * seg.len..][..seg.len]
    }

    /// `Σ_c w_k[i, c] x[c]` for `k < out.len()` over row `i`.
    pub(super) fn row_dots(&self, i: usize, x: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        for seg in self.row(i) {
            let xs = &x[seg.start..][..seg.len];
            for (k, o) in out.iter_mut().enumerate() {
                *o += dot(self.weights(seg, k), xs);
            }
        }
    }

    /// `y = W_0 x` (the `k = 0` weights).
    pub(super) fn apply_k0(&self, x: &[f64], y: &mut [f64]) {
        for (i, yi) in y.iter_mut().enumerate() {
            *yi = self
                .row(i)
                .iter()
                .map(|seg| dot(self.weights(seg, 0), &x[seg.start..][..seg.len]))
                .sum();
        }
    }
}

/// Dense row accumulator for building a [`SpanOp`].
pub(super) struct RowAcc {
    pub(super) acc: Vec<[f64; 5]>,
    pub(super) touched: Vec<usize>,
    pub(super) mark: Vec<bool>,
}

/// Columns of zeros tolerated inside a run before a new run starts.
pub(super) const RUN_GAP: usize = 4;

impl RowAcc {
    pub(super) fn new(n: usize) -> Self {
        RowAcc {
            acc: vec![[0.0; 5]; n],
            touched: Vec::new(),
            mark: vec![false; n],
        }
    }

    pub(super) fn add(&mut self, col: usize, k: usize, x: f64) {
        if !self.mark[col] {
            self.mark[col] = true;
            self.touched.push(col);
        }
        self.acc[col][k] += x;
    }

    /// Moves the row into `op` (runs of touched columns) and resets the accumulator.
    pub(super) fn flush(&mut self, op: &mut SpanOp) {
        self.touched.sort_unstable();
        let mut i = 0;
        while i < self.touched.len() {
            let mut j = i + 1;
            while j < self.touched.len() && self.touched[j] <= self.touched[j - 1] + RUN_GAP {
                j += 1;
            }
            let (first, last) = (self.touched[i], self.touched[j - 1]);
            let seg = Seg {
                start: first,
                len: last + 1 - first,
                off: op.vals.len(),
            };
            for k in 0..op.kmax {
                op.vals.extend(self.acc[first..=last].iter().map(|a| a[k]));
            }
            op.segs.push(seg);
            i = j;
        }
        for &c in &self.touched {
            self.acc[c] = [0.0; 5];
            self.mark[c] = false;
        }
        self.touched.clear();
        op.row_ptr.push(op.segs.len());
    }
}

/// The backward recursion of the stochastic policy (module documentation) on the `V` grid.
pub(super) struct Recursion<'a> {
    pub(super) op: &'a SpanOp,
    pub(super) noise: Option<&'a SpanOp>,
    pub(super) rew: &'a [[f64; 5]],
    pub(super) nodes: &'a [f64],
    pub(super) sigma: f64,
    pub(super) gamma: f64,
    pub(super) horizon: usize,
}

impl Recursion<'_> {
    /// Runs `horizon` steps and returns the channels `[V, ∂_v V, ∂_w V, ∂²_wv V, ∂²_vv V,
    /// ∂²_ww V]` at the nodes (empty when not propagated). `KX`, `KV`, `KW`: powers of `z`
    /// integrated against `V`, `∂_v V`, `∂_w V`; `K2`: second-order channels propagated
    /// (`∂²_wv`, then `∂²_vv`, `∂²_ww`).
    pub(super) fn run<const KX: usize, const KV: usize, const KW: usize, const K2: usize>(
        &self,
    ) -> [Vec<f64>; 6] {
        let n = self.nodes.len();
        let sized = |on: bool| vec![0.0; if on { n } else { 0 }];
        let mut cur: [Vec<f64>; 6] = [
            sized(true),
            sized(KV > 0),
            sized(KW > 0),
            sized(K2 > 0),
            sized(K2 > 1),
            sized(K2 > 2),
        ];
        let mut next = cur.clone();
        let mut smooth: [Vec<f64>; 6] = match self.noise {
            Some(nop) => {
                std::array::from_fn(|c| vec![0.0; if cur[c].is_empty() { 0 } else { nop.rows() }])
            }
            None => Default::default(),
        };
        let (g, sigma) = (self.gamma, self.sigma);
        for _ in 0..self.horizon {
            if crate::cancel::requested() {
                break;
            }
            if let Some(nop) = self.noise {
                for (out, x) in smooth.iter_mut().zip(&cur) {
                    if !x.is_empty() {
                        nop.apply_k0(x, out);
                    }
                }
            }
            let src = if self.noise.is_some() { &smooth } else { &cur };
            let x2: [&[f64]; K2] = std::array::from_fn(|j| src[3 + j].as_slice());
            for (i, (rw, &s)) in self.rew.iter().zip(self.nodes).enumerate() {
                let (mut sx, mut sv, mut sw, mut s2) = ([0.0; KX], [0.0; KV], [0.0; KW], [0.0; K2]);
                for seg in self.op.row(i) {
                    seg_sums(
                        self.op, seg, &src[0], &src[1], &src[2], &x2, &mut sx, &mut sv, &mut sw,
                        &mut s2,
                    );
                }
                let eg: [f64; KX] = std::array::from_fn(|k| rw[k] + g * sx[k]);
                next[0][i] = eg[0];
                let so = s / sigma;
                if KV > 0 {
                    next[1][i] = so * eg[1] + g * sv[0];
                }
                if KW > 0 {
                    next[2][i] = eg[2] - eg[0] + g * sw[0];
                }
                if K2 > 0 {
                    next[3][i] =
                        so * (eg[3] - 3.0 * eg[1]) + g * (so * sw[1] + sv[2] - sv[0] + s2[0]);
                }
                if K2 > 2 {
                    next[4][i] = so * so * (eg[2] - eg[0]) + g * (2.0 * so * sv[1] + s2[1]);
                    next[5][i] =
                        (eg[4] - 4.0 * eg[2] + eg[0]) + g * (2.0 * (sw[2] - sw[0]) + s2[2]);
                }
            }
            std::mem::swap(&mut cur, &mut next);
        }
        cur
    }
}

/// Adds one run's contributions `Σ_c w_k[c] x[c]` to `sx[k]` (`k < KX`), likewise `sv` for
/// `∂_v V`, `sw` for `∂_w V`, and `Σ_c w_0[c] x2_j[c]` to `s2[j]`; two interleaved partial
/// sums per quantity (a fixed order: deterministic).
#[allow(clippy::too_many_arguments)]
#[inline]
pub(super) fn seg_sums<const KX: usize, const KV: usize, const KW: usize, const K2: usize>(
    op: &SpanOp,
    seg: &Seg,
    x: &[f64],
    xv: &[f64],
    xw: &[f64],
    x2: &[&[f64]; K2],
    sx: &mut [f64; KX],
    sv: &mut [f64; KV],
    sw: &mut [f64; KW],
    s2: &mut [f64; K2],
) {
    let len = seg.len;
    let w: [&[f64]; KX] = std::array::from_fn(|k| op.weights(seg, k));
    let cols = seg.start..seg.start + len;
    let x = &x[cols.clone()];
    let xv = if KV > 0 { &xv[cols.clone()] } else { &[][..] };
    let xw = if KW > 0 { &xw[cols.clone()] } else { &[][..] };
    let x2: [&[f64]; K2] = std::array::from_fn(|j| &x2[j][cols.clone()]);
    let (mut ax, mut av, mut aw, mut a2) = (
        [[0.0; 2]; KX],
        [[0.0; 2]; KV],
        [[0.0; 2]; KW],
        [[0.0; 2]; K2],
    );
    let mut c = 0;
    while c + 2 <= len {
        for l in 0..2 {
            let cc = c + l;
            for k in 0..KX {
                ax[k][l] += w[k][cc] * x[cc];
            }
            for k in 0..KV {
                av[k][l] += w[k][cc] * xv[cc];
            }
            for k in 0..KW {
                aw[k][l] += w[k][cc] * xw[cc];
            }
            for j in 0..K2 {
                a2[j][l] += w[0][cc] * x2[j][cc];
            }
        }
        c += 2;
    }
    if c < len {
        for k in 0..KX {
            ax[k][0] += w[k][c] * x[c];
        }
        for k in 0..KV {
            av[k][0] += w[k][c] * xv[c];
        }
        for k in 0..KW {
            aw[k][0] += w[k][c] * xw[c];
        }
        for j in 0..K2 {
            a2[j][0] += w[0][c] * x2[j][c];
        }
    }
    for (s, a) in sx.iter_mut().zip(&ax) {
        *s += a[0] + a[1];
    }
    for (s, a) in sv.iter_mut().zip(&av) {
        *s += a[0] + a[1];
    }
    for (s, a) in sw.iter_mut().zip(&aw) {
        *s += a[0] + a[1];
    }
    for (s, a) in s2.iter_mut().zip(&a2) {
        *s += a[0] + a[1];
    }
}
