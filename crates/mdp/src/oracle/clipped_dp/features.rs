//! The features of the value function that the grids resolve: exact kinks and smoothed
//! clipping zones.

use super::*;

/// A smoothed feature of the value function: centre and scale.
#[derive(Debug, Clone, Copy)]
pub(super) struct Zone {
    pub(super) centre: f64,
    pub(super) scale: f64,
}

impl ClippedDpOracle {
    /// Exact kinks of `V_t` from the clipped-action branches (no transition noise): the
    /// points where `A s + B a_bound` hits a state bound, and their preimages under the same
    /// maps for `horizon` steps. Each kink carries the probability of the chain of clipped
    /// actions that produces it (times `γ` per step); kinks below [`KINK_WEIGHT`] change the
    /// value function by less than rounding and are not tracked.
    pub(super) fn exact_kinks(
        &self,
        v: f64,
        sigma: f64,
        horizon: usize,
    ) -> Result<Vec<f64>, OracleError> {
        let mut kinks: Vec<f64> = Vec::new();
        if self.a == 0.0 {
            return Ok(kinks);
        }
        let eps = 1e-12 * (self.s_hi - self.s_lo);
        let inside = |x: f64| x > self.s_lo + eps && x < self.s_hi - eps;
        let tail = |ab: f64, s: f64| {
            if ab == self.a_lo {
                norm_cdf((self.a_lo - v * s) / sigma)
            } else {
                norm_cdf((v * s - self.a_hi) / sigma)
            }
        };
        let mut frontier = vec![(self.s_lo, 1.0), (self.s_hi, 1.0)];
        for _ in 0..horizon {
            if crate::cancel::requested() {
                break;
            }
            let mut next = Vec::new();
            for &(k, weight) in &frontier {
                for ab in [self.a_lo, self.a_hi] {
                    let s = (k - self.b * ab) / self.a;
                    let w = weight * self.gamma * tail(ab, s);
                    if inside(s) && w >= KINK_WEIGHT && !kinks.iter().any(|x| (x - s).abs() <= eps)
                    {
                        kinks.push(s);
                        next.push((s, w));
                    }
                }
            }
            if kinks.len() > MAX_KINKS {
                return Err(OracleError::ResolutionExceeded {
                    needed: kinks.len(),
                    max: MAX_KINKS,
                });
            }
            if next.is_empty() {
                break;
            }
            frontier = next;
        }
        Ok(kinks)
    }

    /// Zones of the smoothed clipping features of `V_t` and the global scale of features
    /// created by an expanding closed loop (`|A + Bv| > 1`).
    pub(super) fn zones(&self, v: f64, sigma: f64, horizon: usize) -> (Vec<Zone>, f64) {
        let mut zones = Vec::new();
        let lam = self.a + self.b * v;
        let spread = (self.b * self.b * sigma * sigma + self.noise * self.noise).sqrt();
        if sigma > 0.0 && v != 0.0 {
            for ab in [self.a_lo, self.a_hi] {
                zones.push(Zone {
                    centre: ab / v,
                    scale: sigma / v.abs(),
                });
            }
        }
        if lam != 0.0 && spread > 0.0 {
            for sb in [self.s_lo, self.s_hi] {
                zones.push(Zone {
                    centre: sb / lam,
                    scale: spread / lam.abs(),
                });
            }
        }
        // Earlier steps see each feature through the closed loop `s ↦ λ s + spread · ξ`: at
        // `c/λ`, widened to `√(ℓ² + spread²)/|λ|`. With `|λ| > 1` the global scale covers
        // these; with `|λ| ≤ 1` they leave the box or widen beyond the base resolution,
        // except near `λ = 1`, where the features at the state bounds pile up with scales
        // `spread·√k` (a diffusion). Only zones that refine the base grid are kept.
        let coarse = (self.s_hi - self.s_lo) / self.config.min_elements as f64
            * self.config.elements_per_scale;
        if lam != 0.0 && lam.abs() <= 1.0 && spread > 0.0 {
            let base = zones.len();
            for z in 0..base {
                let Zone {
                    mut centre,
                    mut scale,
                } = zones[z];
                for _ in 1..horizon {
                    if crate::cancel::requested() {
                        break;
                    }
                    centre /= lam;
                    scale = scale.hypot(spread) / lam.abs();
                    if scale >= coarse {
                        break;
                    }
                    let reach = ZONE_HALF_WIDTH * scale;
                    if centre - reach < self.s_hi && centre + reach > self.s_lo {
                        zones.push(Zone { centre, scale });
                    }
                }
            }
        }
        if self.noise > 0.0 && self.a != 0.0 {
            for sb in [self.s_lo, self.s_hi] {
                for ab in [self.a_lo, self.a_hi] {
                    zones.push(Zone {
                        centre: (sb - self.b * ab) / self.a,
                        scale: self.noise / self.a.abs(),
                    });
                }
            }
        }
        let global = if lam.abs() > 1.0 && spread > 0.0 {
            spread / (lam * lam - 1.0).sqrt()
        } else {
            f64::INFINITY
        };
        (zones, global)
    }

    /// Range of the pre-noise next state `A s + B a_c` over the boxes.
    pub(super) fn pre_noise_range(&self) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for s in [self.s_lo, self.s_hi] {
            for a in [self.a_lo, self.a_hi] {
                let y = self.a * s + self.b * a;
                lo = lo.min(y);
                hi = hi.max(y);
            }
        }
        (lo, hi)
    }

    /// Grids of `V` (state box) and, with transition noise, of `W` (pre-noise range).
    pub(super) fn grids(
        &self,
        v: f64,
        sigma: f64,
        horizon: usize,
    ) -> Result<(Grid, Option<Grid>), OracleError> {
        let (zones, global) = self.zones(v, sigma, horizon);
        let mut kinks = if self.noise == 0.0 && sigma > 0.0 {
            self.exact_kinks(v, sigma, horizon)?
        } else {
            Vec::new()
        };
        if sigma == 0.0 && v != 0.0 {
            kinks.extend([self.a_lo / v, self.a_hi / v]);
        }
        let vgrid = self.grid(self.breaks(self.s_lo, self.s_hi, &kinks, &zones, global)?);
        if self.noise == 0.0 {
            return Ok((vgrid, None));
        }
        let mut wz: Vec<Zone> = zones
            .iter()
            .map(|z| Zone {
                centre: z.centre,
                scale: (z.scale * z.scale + self.noise * self.noise).sqrt(),
            })
            .collect();
        for c in [self.s_lo, self.s_hi].iter().chain(&kinks) {
            wz.push(Zone {
                centre: *c,
                scale: self.noise,
            });
        }
        let (lo, hi) = self.pre_noise_range();
        let (lo, hi) = if hi - lo > 0.0 {
            (lo, hi)
        } else {
            (lo - 1.0, hi + 1.0)
        };
        let wgrid = self.grid(self.breaks(lo, hi, &[], &wz, global)?);
        Ok((vgrid, Some(wgrid)))
    }
}
