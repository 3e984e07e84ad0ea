//! The grids of the represented functions and the Gaussian integrals onto them.

use super::*;

/// The piecewise Chebyshev grid of one represented function.
#[derive(Debug, Clone)]
pub(super) struct Grid {
    pub(super) breaks: Vec<f64>,
    pub(super) nodes: Vec<f64>,
    pub(super) p: usize,
}

/// Largest number of fixed sub-pieces per element with a cached weight table.
pub(super) const MAX_SUB_PIECES: usize = 256;

/// Scratch of the quadrature: interpolation weights, cut points, and the interpolation
/// weights at the Gauss–Legendre nodes of an element split into `P` equal sub-pieces.
pub(super) struct Quad {
    pub(super) lw: Vec<f64>,
    pub(super) cuts: Vec<(f64, bool)>,
    /// `tables[P]`: `P · quad_points · p` weights (empty until first use), row
    /// `(i · quad_points + q)` for node `q` of sub-piece `i`.
    pub(super) tables: Vec<Vec<f64>>,
}

impl Quad {
    pub(super) fn new(p: usize) -> Self {
        Quad {
            lw: vec![0.0; p],
            cuts: Vec::new(),
            tables: Vec::new(),
        }
    }

    /// The table for `P = sub` sub-pieces (computed on first use).
    pub(super) fn table(&mut self, o: &ClippedDpOracle, sub: usize) -> Option<&[f64]> {
        if sub > MAX_SUB_PIECES {
            return None;
        }
        if self.tables.len() <= sub {
            self.tables.resize_with(sub + 1, Vec::new);
        }
        if self.tables[sub].is_empty() {
            let p = o.config.nodes_per_element;
            let mut tab = Vec::with_capacity(sub * o.gl.nodes.len() * p);
            for i in 0..sub {
                for x in &o.gl.nodes {
                    let tq = -1.0 + (2 * i + 1) as f64 / sub as f64 + x / sub as f64;
                    o.cheb.weights(tq, &mut self.lw);
                    tab.extend_from_slice(&self.lw[..p]);
                }
            }
            self.tables[sub] = tab;
        }
        Some(&self.tables[sub])
    }
}

/// The integrals `Σ weight · φ(z) z^k · l_j` of one segment of [`ClippedDpOracle::add_gauss`],
/// per power `k < kmax` and node `j < p` of its element.
pub(super) struct SegmentSums {
    pub(super) sums: [[f64; MAX_NODES]; 5],
    pub(super) kmax: usize,
    pub(super) p: usize,
}

impl SegmentSums {
    /// Adds the quadrature point `z` of weight `weight`, `l` the interpolation weights of
    /// the element's nodes at the point.
    pub(super) fn add(&mut self, z: f64, weight: f64, l: &[f64]) {
        let base = weight * norm_pdf(z);
        let mut coef = [0.0; 5];
        let mut zk = 1.0;
        for c in coef.iter_mut().take(self.kmax) {
            *c = base * zk;
            zk *= z;
        }
        for (lk, &ck) in self.sums.iter_mut().zip(&coef[..self.kmax]) {
            for (a, &lj) in lk[..self.p].iter_mut().zip(l) {
                *a += ck * lj;
            }
        }
    }
}

/// Where a Gaussian integral evaluates the represented function: on a grid, with the next
/// state clipped to the state box or not.
pub(super) struct Target<'g> {
    pub(super) grid: &'g Grid,
    pub(super) clip: Option<(f64, f64)>,
}

impl ClippedDpOracle {
    /// Breakpoints of a grid on `[lo, hi]`: the exact kinks, the ends of every zone, then a
    /// uniform subdivision of each sub-interval to the local target width.
    pub(super) fn breaks(
        &self,
        lo: f64,
        hi: f64,
        kinks: &[f64],
        zones: &[Zone],
        global_scale: f64,
    ) -> Result<Vec<f64>, OracleError> {
        let width = hi - lo;
        let eps = 1e-12 * width;
        let mut pts = vec![lo, hi];
        pts.extend(
            kinks
                .iter()
                .copied()
                .filter(|&k| k > lo + eps && k < hi - eps),
        );
        for z in zones {
            for e in [
                z.centre - ZONE_HALF_WIDTH * z.scale,
                z.centre + ZONE_HALF_WIDTH * z.scale,
            ] {
                if e > lo + eps && e < hi - eps {
                    pts.push(e);
                }
            }
        }
        pts.sort_by(f64::total_cmp);
        pts.dedup_by(|x, y| (*x - *y).abs() <= eps);
        let base = width / self.config.min_elements as f64;
        let per = self.config.elements_per_scale;
        let mut out = vec![lo];
        let mut needed = 0usize;
        for w in pts.windows(2) {
            let (x0, x1) = (w[0], w[1]);
            let mid = 0.5 * (x0 + x1);
            let mut h = base.min(global_scale / per);
            for z in zones {
                if (mid - z.centre).abs() <= ZONE_HALF_WIDTH * z.scale {
                    h = h.min(z.scale / per);
                }
            }
            let count = ((x1 - x0) / h).ceil();
            let count = if count.is_finite() && count >= 1.0 {
                count
            } else {
                f64::from(u32::MAX)
            };
            needed = needed.saturating_add(count as usize);
            if needed > self.config.max_elements {
                return Err(OracleError::ResolutionExceeded {
                    needed,
                    max: self.config.max_elements,
                });
            }
            let c = count as usize;
            for i in 1..c {
                out.push(x0 + (x1 - x0) * i as f64 / count);
            }
            out.push(x1);
        }
        Ok(out)
    }

    pub(super) fn grid(&self, breaks: Vec<f64>) -> Grid {
        let p = self.config.nodes_per_element;
        let mut nodes = Vec::with_capacity((breaks.len() - 1) * p);
        for w in breaks.windows(2) {
            let (mid, half) = (0.5 * (w[0] + w[1]), 0.5 * (w[1] - w[0]));
            nodes.extend(self.cheb.nodes.iter().map(|x| mid + half * x));
        }
        Grid { breaks, nodes, p }
    }

    /// Index of the element of the grid containing `y` (clamped to the grid).
    pub(super) fn element(grid: &Grid, y: f64) -> usize {
        let nel = grid.breaks.len() - 1;
        grid.breaks[1..nel]
            .partition_point(|&b| b <= y)
            .min(nel - 1)
    }

    /// Barycentric interpolation weights at `y` on element `e` into `out[..p]`.
    pub(super) fn weights_in(&self, grid: &Grid, e: usize, y: f64, out: &mut [f64]) {
        let (b0, b1) = (grid.breaks[e], grid.breaks[e + 1]);
        self.cheb
            .weights(((2.0 * y - b0 - b1) / (b1 - b0)).clamp(-1.0, 1.0), out);
    }

    /// Barycentric interpolation weights at `y` (clamped to the grid) into `out`; returns the
    /// index of the first node of the element.
    pub(super) fn interp(&self, grid: &Grid, y: f64, out: &mut [f64]) -> usize {
        let e = Self::element(grid, y);
        self.weights_in(grid, e, y, out);
        e * grid.p
    }

    /// Adds `coef[k] · f(clip(y))` (`k = 0..kmax`) to the row, `f` the interpolant on the grid.
    pub(super) fn add_point(
        &self,
        row: &mut RowAcc,
        t: &Target<'_>,
        y: f64,
        coef: &[f64],
        lw: &mut [f64],
    ) {
        let y = match t.clip {
            Some((lo, hi)) => y.clamp(lo, hi),
            None => y,
        };
        let first = self.interp(t.grid, y, lw);
        for (j, &l) in lw[..t.grid.p].iter().enumerate() {
            if l != 0.0 {
                for (k, &c) in coef.iter().enumerate() {
                    row.add(first + j, k, c * l);
                }
            }
        }
    }

    /// Adds `∫_{z0}^{z1} z^k φ(z) f(clip(y0 + y1 z)) dz` (`k < kmax`) to the row, the range
    /// truncated to `|z| ≤ Z_MAX`.
    ///
    /// The range is cut at the clip points and at the element boundaries ([`Self::cuts`]),
    /// and each piece is integrated by [`Self::add_segment`].
    #[allow(clippy::too_many_arguments)]
    pub(super) fn add_gauss(
        &self,
        row: &mut RowAcc,
        t: &Target<'_>,
        y0: f64,
        y1: f64,
        z0: f64,
        z1: f64,
        kmax: usize,
        quad: &mut Quad,
    ) {
        let hard0 = z0 > -Z_MAX;
        let hard1 = z1 < Z_MAX;
        let (z0, z1) = (z0.max(-Z_MAX), z1.min(Z_MAX));
        if z0 >= z1 {
            return;
        }
        if y1 == 0.0 {
            let m = normal_moments(z0, z1);
            self.add_point(row, t, y0, &m[..kmax], &mut quad.lw);
            return;
        }
        let mut cuts = std::mem::take(&mut quad.cuts);
        Self::cuts(t, (y0, y1), (z0, hard0), (z1, hard1), &mut cuts);
        for w in cuts.windows(2) {
            if w[1].0 <= w[0].0 {
                continue;
            }
            self.add_segment(row, t, (y0, y1), (w[0], w[1]), kmax, quad);
        }
        quad.cuts = cuts;
    }

    /// The points cutting `[z0, z1]` into `cuts`, sorted: the ends, where `y0 + y1 z` meets a
    /// clip point, and where it crosses an element boundary of the grid, each with whether
    /// the integrand is discontinuous there (the ends when inside the truncation range, the
    /// clip points).
    pub(super) fn cuts(
        t: &Target<'_>,
        (y0, y1): (f64, f64),
        (z0, hard0): (f64, bool),
        (z1, hard1): (f64, bool),
        cuts: &mut Vec<(f64, bool)>,
    ) {
        let zof = |y: f64| (y - y0) / y1;
        cuts.clear();
        cuts.extend([(z0, hard0), (z1, hard1)]);
        let (ya, yb) = {
            let (p, q) = (y0 + y1 * z0, y0 + y1 * z1);
            (p.min(q), p.max(q))
        };
        if let Some((lo, hi)) = t.clip {
            for c in [lo, hi] {
                let z = zof(c);
                if z > z0 && z < z1 {
                    cuts.push((z, true));
                }
            }
        }
        let br = &t.grid.breaks;
        let first = br.partition_point(|&b| b <= ya);
        let last = br.partition_point(|&b| b < yb);
        for &b in &br[first..last] {
            let z = zof(b);
            if z > z0 && z < z1 {
                cuts.push((z, false));
            }
        }
        cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
    }

    /// Adds the integral over one piece `[za, zb]` between two cuts (`ha`, `hb`: whether the
    /// integrand is discontinuous at its ends). A piece whose next state is clipped is a point
    /// mass; otherwise it lies in one element of the grid and is integrated with the element's
    /// fixed sub-pieces ([`Quad::table`], no per-point interpolation weights) when both ends
    /// are continuous, else with pieces at most [`PIECE_WIDTH`] wide in `z` and barycentric
    /// weights.
    pub(super) fn add_segment(
        &self,
        row: &mut RowAcc,
        t: &Target<'_>,
        (y0, y1): (f64, f64),
        ((za, ha), (zb, hb)): ((f64, bool), (f64, bool)),
        kmax: usize,
        quad: &mut Quad,
    ) {
        let ymid = y0 + y1 * 0.5 * (za + zb);
        if let Some((lo, hi)) = t.clip
            && (ymid < lo || ymid > hi)
        {
            let m = normal_moments(za, zb);
            self.add_point(row, t, ymid, &m[..kmax], &mut quad.lw);
            return;
        }
        // The segment lies in one element: accumulate locally, flush once.
        let e = Self::element(
            t.grid,
            ymid.clamp(t.grid.breaks[0], t.grid.breaks[t.grid.breaks.len() - 1]),
        );
        let p = t.grid.p;
        let mut local = SegmentSums {
            sums: [[0.0; MAX_NODES]; 5],
            kmax,
            p,
        };
        let (b0, b1) = (t.grid.breaks[e], t.grid.breaks[e + 1]);
        let sub = ((b1 - b0) / (y1.abs() * PIECE_WIDTH)).ceil();
        let table = if !ha && !hb && sub <= MAX_SUB_PIECES as f64 {
            quad.table(self, sub.max(1.0) as usize)
        } else {
            None
        };
        if let Some(table) = table {
            self.sum_sub_pieces(&mut local, (b0, b1), (y0, y1), (za, zb), sub, table);
        } else {
            let pieces = ((zb - za) / PIECE_WIDTH).ceil().max(1.0);
            let hz = (zb - za) / pieces;
            for i in 0..pieces as usize {
                let pa = za + hz * i as f64;
                let (mid, half) = (pa + 0.5 * hz, 0.5 * hz);
                for (x, wq) in self.gl.nodes.iter().zip(&self.gl.weights) {
                    let z = mid + half * x;
                    self.weights_in(t.grid, e, y0 + y1 * z, &mut quad.lw);
                    local.add(z, wq * half, &quad.lw[..p]);
                }
            }
        }
        for (k, lk) in local.sums[..kmax].iter().enumerate() {
            for (j, &x) in lk[..p].iter().enumerate() {
                row.add(e * p + j, k, x);
            }
        }
    }

    /// The fixed sub-pieces (`sub` of them, each at most one unit wide in `z`) of the element
    /// `[b0, b1]` that meet the segment `[za, zb]`, with the interpolation weights `table` of
    /// [`Quad::table`]. The ends of the segment are element boundaries or the truncation
    /// points, where the integrand is continuous and negligible respectively.
    pub(super) fn sum_sub_pieces(
        &self,
        local: &mut SegmentSums,
        (b0, b1): (f64, f64),
        (y0, y1): (f64, f64),
        (za, zb): (f64, f64),
        sub: f64,
        table: &[f64],
    ) {
        let p = local.p;
        let (mid_e, half_e) = (0.5 * (b0 + b1), 0.5 * (b1 - b0));
        let nsub = sub.max(1.0) as usize;
        let tof = |z: f64| ((y0 + y1 * z - mid_e) / half_e).clamp(-1.0, 1.0);
        let (ta, tb) = {
            let (u, v) = (tof(za), tof(zb));
            (u.min(v), u.max(v))
        };
        let scale = 0.5 * nsub as f64;
        let i0 = ((ta + 1.0) * scale).floor() as usize;
        let i1 = (((tb + 1.0) * scale).ceil() as usize).clamp(i0 + 1, nsub);
        let nq = self.gl.nodes.len();
        let dz = half_e / (nsub as f64 * y1.abs());
        for i in i0..i1 {
            for (q, (x, wq)) in self.gl.nodes.iter().zip(&self.gl.weights).enumerate() {
                let tq = -1.0 + (2 * i + 1) as f64 / nsub as f64 + x / nsub as f64;
                let z = (mid_e + half_e * tq - y0) / y1;
                local.add(z, wq * dz, &table[(i * nq + q) * p..][..p]);
            }
        }
    }
}
