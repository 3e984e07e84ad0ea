//! The cost of the proven widths (docs/THEOREMS.md, "Proven confidence widths"): the proven
//! half-widths of `∇̂_v J`, `∇̂_w J` and `Ĵ` at `N = 50` trajectories and the per-statement
//! level `δ' = 0.2/(10000 · 2)` of a 10 000-iteration run with two statements per iteration,
//! beside the Student-t half-widths `t(1 − δ'/2, N − 1) √(Var/N)` at the same level, for the
//! `lqg1d` and `lqg` presets (rewards declared non-positive, policy mean parameter
//! `v = −0.1`, the default `v⁰`) at `σ ∈ {0.1, 0.5, 1}`.
//!
//! `Var` is the per-trajectory sample variance measured on one rollout of 200 000
//! trajectories (seed 2024), for the proven widths' centre (G(PO)MDP with the constant
//! baseline `−R/2`) and for the default estimator (G(PO)MDP, leave-one-out optimal baseline).
//!
//! Also prints `∇_v J` and `∇_w J` (means of the rollout) and the number of trajectories at
//! which the proven widths fall to their size. Prints Markdown tables; "ratios" are proven / Student-t (b) and proven / Student-t (opt).
//! Run with `cargo run --release -p sepg-estimators --example proven_widths`.

use sepg_estimators::proven::ProvenWidths;
use sepg_estimators::{Estimate, Estimator, EstimatorError, GradientSpec, Param, Width, width};
use sepg_mdp::env::{Environment, Preset};
use sepg_mdp::policy::GaussianPolicy;
use sepg_mdp::rng::SeedKey;
use sepg_mdp::rollout::rollout;

const N: usize = 50;
const ROLLOUT: usize = 200_000;
const V0: f64 = -0.1;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let delta = 0.2 / (10_000.0 * 2.0);
    println!("N = {N}, δ' = {delta:e}, v = {V0}; Student-t widths from {ROLLOUT} trajectories");
    println!();
    println!(
        "| preset | σ | proven ε_v | t ε_v (b) | t ε_v (opt) | ratios | proven ε_w | t ε_w (b) \
         | t ε_w (opt) | ratios | proven ε_J | t ε_J | ratio |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut scale = Vec::new();
    for preset in [Preset::Lqg1d, Preset::Lqg] {
        let env = preset.build();
        let k = env.constants();
        let proven = ProvenWidths::new(k.r_max, true, k.m_phi, k.gamma, k.horizon)?;
        for sigma in [0.1f64, 0.5, 1.0] {
            let policy = GaussianPolicy::new(vec![V0], vec![sigma.ln()], 1)?;
            let batch = rollout(&env, &policy, ROLLOUT, k.horizon, SeedKey::new(2024, 0, 0))?;
            let mut est = Estimator::new();
            let mut out = Estimate::new();
            let mut means = Vec::new();
            let mut t_width = |param: Option<Param>, spec: GradientSpec| {
                match param {
                    Some(p) => est.gradient(&batch, p, spec, &mut out)?,
                    None => est.value(&batch, &mut out)?,
                }
                means.push(out.mean()[0]);
                width(Width::StudentT, out.variance()[0], N, delta)
            };
            let centre = proven.gradient_spec();
            let default = GradientSpec::default();
            let tv = t_width(Some(Param::V), centre)?;
            let tv_opt = t_width(Some(Param::V), default)?;
            let tw = t_width(Some(Param::W), centre)?;
            let tw_opt = t_width(Some(Param::W), default)?;
            let tj = t_width(None, default)?;
            let (pv, pw, pj) = (
                proven.v_width(sigma, N, delta)?,
                proven.w_width(N, delta)?,
                proven.j_width(N, delta)?,
            );
            println!(
                "| {} | {sigma} | {pv:.3e} | {tv:.3e} | {tv_opt:.3e} | {:.1}, {:.1} | {pw:.3e} \
                 | {tw:.3e} | {tw_opt:.3e} | {:.1}, {:.1} | {pj:.2} | {tj:.2} | {:.1} |",
                preset.name(),
                pv / tv,
                pv / tv_opt,
                pw / tw,
                pw / tw_opt,
                pj / tj
            );
            // Trajectories needed for the proven widths to fall to |∇J|.
            let (gv, gw) = (means[0], means[2]);
            let nv = needed(&|n| proven.v_width(sigma, n, delta), gv)?;
            let nw = needed(&|n| proven.w_width(n, delta), gw)?;
            scale.push((preset.name(), sigma, gv, gw, nv, nw));
        }
    }
    println!();
    println!(
        "| preset | σ | ∇_v J | ∇_w J | N for proven ε_v = abs(∇_v J) | N for proven ε_w = abs(∇_w J) |"
    );
    println!("|---|---|---|---|---|---|");
    for (name, sigma, gv, gw, nv, nw) in scale {
        println!("| {name} | {sigma} | {gv:.4} | {gw:.4} | {nv} | {nw} |");
    }
    Ok(())
}

/// The least N at which the width `w(N)` falls to |g| (doubling, then bisection; the widths
/// decrease in N).
fn needed(
    w: &dyn Fn(usize) -> Result<f64, EstimatorError>,
    g: f64,
) -> Result<usize, EstimatorError> {
    let mut n = 1usize;
    while w(n)? > g.abs() {
        n *= 2;
    }
    let (mut lo, mut hi) = (n / 2, n);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if w(mid)? > g.abs() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(hi)
}
