//! The constant baseline (`Baseline::Constant`), the centre of the proven widths: samples by
//! hand (with an early termination), exact unbiasedness against the LQG oracle, and
//! unbiasedness under a score-dependent early termination, where subtracting the baseline on
//! the live steps only would be biased.
//!
//! The Monte Carlo comparisons use the two-sided Bonferroni critical value for a family-wise
//! false-alarm rate of 1e-3 over every comparison of this file (`COMPARISONS`); seeds are
//! fixed.

use sepg_estimators::{
    Baseline, BaselineFit, Estimate, Estimator, EstimatorError, GradientSpec, Kind, Param,
    SurrogateEstimate,
};
use sepg_mdp::Batch;
use sepg_mdp::lqg_model::LqgModel;
use sepg_mdp::rng::{rng_from_seed, standard_normal};

use crate::support::{Moments, Setup, bonferroni_z};

const ALPHA: f64 = 1e-3;
/// 2 set-ups × (3 kinds × 2 parameters + mixed + ∇_w L) + 2 (termination, v and w).
const COMPARISONS: usize = 2 * 8 + 2;

fn spec(kind: Kind, b: f64, fit: BaselineFit) -> GradientSpec {
    GradientSpec {
        kind,
        baseline: Baseline::Constant(b),
        fit,
    }
}

/// Two trajectories of three steps, γ = 1/2; the second ends after two steps (reward 0 and
/// frozen scores on the padding). With b = 2 the discounted baselines are γ^t b = 2, 1, 1/2.
fn hand_batch() -> Batch {
    let mut batch = Batch::zeros(2, 3, 1, 1, 0.5);
    // r = [1, 2, 3] and [−1, 4, (pad) 0].
    batch
        .disc_rewards
        .copy_from_slice(&[1.0, 1.0, 0.75, -1.0, 2.0, 0.0]);
    batch
        .cum_score_v
        .copy_from_slice(&[1.0, 2.0, -1.0, 0.5, 1.5, 1.5]);
    batch
        .cum_score_w
        .copy_from_slice(&[0.5, 0.5, 1.0, 1.0, -1.0, -1.0]);
    batch.lengths.copy_from_slice(&[3, 2]);
    batch
}

#[test]
fn constant_baseline_samples_by_hand() {
    let batch = hand_batch();
    let mut est = Estimator::new();
    let mut out = Estimate::new();
    // G(PO)MDP: Σ_t S_t (F_t − γ^t b):  1(1−2) + 2(1−1) − 1(0.75−0.5) = −1.25;
    //           0.5(−1−2) + 1.5(2−1) + 1.5(0−0.5) = −0.75 (the padding step counts).
    // PGT gives the same by the summation theorem. REINFORCE: S_last (R − b Σγ^t), Σγ^t b =
    // 3.5: −1(2.75 − 3.5) = 0.75 and 1.5(1 − 3.5) = −3.75.
    for (kind, expected) in [
        (Kind::Gpomdp, [-1.25, -0.75]),
        (Kind::Pgt, [-1.25, -0.75]),
        (Kind::Reinforce, [0.75, -3.75]),
    ] {
        for fit in [BaselineFit::PlugIn, BaselineFit::LeaveOneOut] {
            est.gradient(&batch, Param::V, spec(kind, 2.0, fit), &mut out)
                .unwrap();
            assert_eq!(out.samples(), &expected, "{kind:?} {fit:?}");
        }
    }
    // ĥ: Σ_t G H (F − γ^t b), H the w-score / σ (σ = 1): G H = [0.5, 1, −1] and
    // [0.5, −1.5, −1.5]: −0.5 + 0 − 0.25 = −0.75 and −1.5 − 1.5 + 0.75 = −2.25.
    est.h(
        &batch,
        Baseline::Constant(2.0),
        BaselineFit::LeaveOneOut,
        &mut out,
    )
    .unwrap();
    assert_eq!(out.samples(), &[-0.75, -2.25]);
    // A non-finite constant is an error, not a NaN estimate.
    for b in [f64::NAN, f64::INFINITY] {
        let s = spec(Kind::Gpomdp, b, BaselineFit::PlugIn);
        assert!(matches!(
            est.gradient(&batch, Param::V, s, &mut out),
            Err(EstimatorError::NonFinite { .. })
        ));
        assert!(matches!(
            est.mixed(&batch, s, &mut out),
            Err(EstimatorError::NonFinite { .. })
        ));
        assert!(matches!(
            est.h(&batch, Baseline::Constant(b), BaselineFit::PlugIn, &mut out),
            Err(EstimatorError::NonFinite { .. })
        ));
    }
}

#[test]
fn constant_baseline_is_unbiased() {
    const N: usize = 100;
    const BATCHES: u64 = 3000;
    let z = bonferroni_z(ALPHA, COMPARISONS);
    let mut failures = Vec::new();
    for (seed, model) in [(41u64, LqgModel::thesis()), (42, LqgModel::lqg1d())] {
        let (v, sigma, h) = (-0.3, 0.5, 10);
        let setup = Setup::new(model, &[v], &[sigma], h);
        let task = setup.task();
        // The proven widths' baseline for rewards declared non-positive.
        let b = -0.5 * task.r_max();
        let exact = &setup.exact;
        let c = sepg_bounds::constants::c(&task, sigma).unwrap();
        let dc = sepg_bounds::constants::dc_dsigma(&task, sigma).unwrap();
        let exact_wl =
            sepg_bounds::surrogate::grad_w(&task, sigma, &exact.grad_v, &exact.mixed_sigma_v())
                .unwrap();
        let kinds = [Kind::Gpomdp, Kind::Pgt, Kind::Reinforce];
        let mut names = Vec::new();
        let mut exacts = Vec::new();
        for kind in kinds {
            names.push(format!("{kind:?} grad_v"));
            exacts.push(exact.grad_v[0]);
            names.push(format!("{kind:?} grad_w"));
            exacts.push(exact.grad_w[0]);
        }
        names.push("mixed".to_string());
        exacts.push(exact.mixed_sigma_v()[0]);
        names.push("grad_w L".to_string());
        exacts.push(exact_wl);
        let mut moments = vec![Moments::default(); names.len()];
        let mut batch = Batch::zeros(0, 0, 0, 0, 0.0);
        let mut est = Estimator::new();
        let mut out = Estimate::new();
        let mut sur = SurrogateEstimate::new();
        for index in 0..BATCHES {
            setup.batch_into(N, seed, index, &mut batch);
            let mut slot = 0;
            for kind in kinds {
                for param in [Param::V, Param::W] {
                    let s = spec(kind, b, BaselineFit::LeaveOneOut);
                    est.gradient(&batch, param, s, &mut out).unwrap();
                    moments[slot].push(out.mean()[0]);
                    slot += 1;
                }
            }
            let s = spec(Kind::Gpomdp, b, BaselineFit::PlugIn);
            est.mixed(&batch, s, &mut out).unwrap();
            moments[slot].push(out.mean()[0]);
            est.surrogate_gradient(&batch, s, c, &[dc], &mut sur)
                .unwrap();
            moments[slot + 1].push(sur.grad_w_l().mean()[0]);
        }
        for ((name, e), m) in names.iter().zip(&exacts).zip(&moments) {
            let score = (m.mean() - e) / m.se();
            eprintln!(
                "seed {seed} {name}: mean {:.6e} exact {e:.6e} z {score:+.2}",
                m.mean()
            );
            if score.abs() > z {
                failures.push(format!("seed {seed} {name}: z = {score:.2}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "biased beyond z = {z:.2}: {failures:?}"
    );
}

#[test]
fn constant_baseline_is_unbiased_under_early_termination() {
    // Rewards 0, so the exact gradient is 0 and the samples of the constant baseline b = 1
    // are −Σ_{t<H} γ^t S_t with the padded (frozen) cumulative score. The trajectory stops
    // after step t when its v-score S_t = Σ_{k≤t} ξ_k exceeds 1 (a stopping time). The
    // baseline subtracted on the live steps only, −Σ_{t<L} γ^t S_t, is biased (it is the
    // gradient of −E Σ_{t<L} γ^t); its z-score shows that the comparison has the power to
    // see that bias.
    const H: usize = 15;
    const N: usize = 200;
    const BATCHES: usize = 1000;
    let gamma = 0.95;
    let z = bonferroni_z(ALPHA, COMPARISONS);
    let mut rng = rng_from_seed(77);
    let mut batch = Batch::zeros(N, H, 1, 1, gamma);
    let mut est = Estimator::new();
    let mut out = Estimate::new();
    let (mut mv, mut mw, mut live) = (Moments::default(), Moments::default(), Moments::default());
    let s = spec(Kind::Gpomdp, 1.0, BaselineFit::PlugIn);
    for _ in 0..BATCHES {
        for i in 0..N {
            let (mut sv, mut sw) = (0.0, 0.0);
            let mut len = H;
            let (mut live_sum, mut disc) = (0.0, 1.0);
            for t in 0..H {
                if t < len {
                    let xi = standard_normal(&mut rng);
                    sv += xi;
                    sw += xi * xi - 1.0;
                    live_sum -= disc * sv;
                    if sv > 1.0 {
                        len = t + 1;
                    }
                }
                batch.cum_score_v[i * H + t] = sv;
                batch.cum_score_w[i * H + t] = sw;
                disc *= gamma;
            }
            batch.lengths[i] = len;
            live.push(live_sum);
        }
        est.gradient(&batch, Param::V, s, &mut out).unwrap();
        out.samples().iter().for_each(|x| mv.push(*x));
        est.gradient(&batch, Param::W, s, &mut out).unwrap();
        out.samples().iter().for_each(|x| mw.push(*x));
    }
    let (zv, zw, zl) = (
        mv.mean() / mv.se(),
        mw.mean() / mw.se(),
        live.mean() / live.se(),
    );
    eprintln!(
        "termination: v mean {:.4e} (z {zv:+.2}), w mean {:.4e} (z {zw:+.2}), \
         live-steps-only mean {:.4e} (z {zl:+.2})",
        mv.mean(),
        mw.mean(),
        live.mean()
    );
    assert!(zv.abs() < z && zw.abs() < z, "biased: z = {zv:.2}, {zw:.2}");
    assert!(
        zl.abs() > z,
        "the live-steps-only bias is not detected: z = {zl:.2}"
    );
}

/// G(PO)MDP with a constant baseline (summed in one pass) gives the samples of G(PO)MDP
/// without baseline on the rewards shifted by `γ^t b`, bit for bit: batches of 1 to 9
/// trajectories (whole and partial blocks of four), two mean components, early terminations
/// (padding), both parameters.
#[test]
fn one_pass_constant_baseline_equals_the_shifted_rewards_bit_for_bit() {
    let (h, gamma, b) = (7, 0.97, -3.25);
    let mut rng = rng_from_seed(5);
    let mut est = Estimator::new();
    let (mut got, mut expected) = (Estimate::new(), Estimate::new());
    for n in 2..=9 {
        let mut batch = Batch::zeros(n, h, 2, 1, gamma);
        for x in batch
            .disc_rewards
            .iter_mut()
            .chain(batch.cum_score_v.iter_mut())
            .chain(batch.cum_score_w.iter_mut())
        {
            *x = standard_normal(&mut rng);
        }
        for (i, len) in batch.lengths.iter_mut().enumerate() {
            *len = h - i % 3;
            batch.disc_rewards[i * h + *len..(i + 1) * h].fill(0.0);
        }
        let mut shifted = batch.clone();
        for row in shifted.disc_rewards.chunks_exact_mut(h) {
            let mut discount = 1.0;
            for f in row {
                *f -= discount * b;
                discount *= gamma;
            }
        }
        let none = GradientSpec {
            kind: Kind::Gpomdp,
            baseline: Baseline::None,
            fit: BaselineFit::PlugIn,
        };
        for param in [Param::V, Param::W] {
            est.gradient(
                &batch,
                param,
                spec(Kind::Gpomdp, b, BaselineFit::PlugIn),
                &mut got,
            )
            .unwrap();
            est.gradient(&shifted, param, none, &mut expected).unwrap();
            let bits = |e: &Estimate| e.samples().iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&got), bits(&expected), "n = {n}, {param:?}");
        }
    }
}
