//! Value stability: exact output bits of the estimators on a fixed synthetic batch, so that a
//! change of algorithm, summation order or dependency cannot alter results silently.

use rand::RngCore;
use rand::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;
use sepg_estimators::{Estimate, Estimator, GradientSpec, Param, SurrogateEstimate, Width};
use sepg_mdp::Batch;

/// Uniform on [lo, hi) from the top 53 bits of one Xoshiro256++ output.
fn uniform(rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * ((rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64))
}

/// Six trajectories of four steps, two features, one action, σ = 0.7, from seed 42.
fn synthetic() -> Batch {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(42);
    let (n, h, p) = (6, 4, 2);
    let mut b = Batch::zeros(n, h, p, 1, 0.9);
    b.sigma[0] = 0.7;
    for i in 0..n {
        let mut cv = [0.0; 2];
        let mut cw = 0.0;
        for t in 0..h {
            b.disc_rewards[i * h + t] = 0.9f64.powi(t as i32) * uniform(&mut rng, -2.0, 0.0);
            for (k, c) in cv.iter_mut().enumerate() {
                *c += uniform(&mut rng, -1.0, 1.0);
                b.cum_score_v[(i * h + t) * p + k] = *c;
            }
            cw += uniform(&mut rng, -1.0, 2.0);
            b.cum_score_w[i * h + t] = cw;
        }
    }
    b
}

fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

#[test]
fn pinned_outputs() {
    let b = synthetic();
    let mut est = Estimator::new();
    let mut out = Estimate::new();
    let mut got = Vec::new();
    est.value(&b, &mut out).unwrap();
    got.extend(bits(out.mean()));
    est.gradient(&b, Param::V, GradientSpec::default(), &mut out)
        .unwrap();
    got.extend(bits(out.mean()));
    got.extend(bits(out.variance()));
    est.gradient(&b, Param::W, GradientSpec::default(), &mut out)
        .unwrap();
    got.extend(bits(out.mean()));
    est.mixed(&b, GradientSpec::default(), &mut out).unwrap();
    got.extend(bits(out.mean()));
    let mut sur = SurrogateEstimate::new();
    est.surrogate_gradient(&b, GradientSpec::default(), 2.0, &[-3.0], &mut sur)
        .unwrap();
    got.extend(bits(sur.grad_w_l().mean()));
    got.extend(bits(sur.grad_w_l().variance()));
    got.push(sur.surrogate().to_bits());
    // Ĵ; ∇_v J and its sample variance; ∇_w J; ∂_σ∇_v J; ∇_w L, its variance; L̂.
    let expected: Vec<u64> = vec![
        0xc007fd670d152316,
        0xbfb16da6af8f31eb,
        0x3fdc588ca4bb5168,
        0x3fe963c9a11e1316,
        0x3fe0c66297f479e4,
        0xbfa83e52b25d3c49,
        0x3fe44ebdc3e83477,
        0xbff3a887c8bec71d,
        0x3f72511b79740f51,
        0x3fc3d18ff91e2154,
        0xbf8998cabd07a58e,
    ];
    assert_eq!(got, expected, "{got:#018x?}");
}

#[test]
fn pinned_skew_corrected_interval() {
    let b = synthetic();
    let mut out = Estimate::new();
    Estimator::new()
        .gradient(&b, Param::V, GradientSpec::default(), &mut out)
        .unwrap();
    let (mut lo, mut hi) = ([0.0; 2], [0.0; 2]);
    out.intervals_into(Width::SkewCorrectedT, 0.1, &mut lo, &mut hi)
        .unwrap();
    let mut eps = [0.0; 2];
    out.widths_into(Width::SkewCorrectedT, 0.1, &mut eps)
        .unwrap();
    let got: Vec<u64> = [lo, hi, eps].iter().flat_map(|x| bits(x)).collect();
    // Lower ends, upper ends, symmetric widths of the two components of ∇_v J (δ = 0.1).
    let expected: Vec<u64> = vec![
        0xbfec49d0bdd34026,
        0xbfb9ffbe4468ed50,
        0x3fe34ad4f870c9e6,
        0x3ff1b98a1304ad56,
        0x3fea1c1be7e159e9,
        0x3fe546cdd3abb1f8,
    ];
    assert_eq!(got, expected, "{got:#018x?}");
}
