//! Cost of one exact evaluation of the clipped-LQG dynamic-programming oracle (`lqg` and
//! `lqg1d`, H = 20): the mean over a grid of the SEPG range (v ∈ {−1.2, −0.9, −0.6, −0.3,
//! −0.1}, σ ∈ {0.05, 0.1, 0.2, 0.5, 1}) for each request level (`J` only; `J`, `∇_v J`,
//! `∇_w J`, `∇_w∇_v J` as SEPG uses; everything with the Hessian), and single points at the
//! cheap and expensive ends of the range. Throughput is in evaluations.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use sepg_mdp::lqg_model::LqgModel;
use sepg_mdp::oracle::{ClippedDpOracle, ExactOracle, Exploration, Horizon, Needs};
use std::hint::black_box;

const V: [f64; 5] = [-1.2, -0.9, -0.6, -0.3, -0.1];
const SIGMA: [f64; 5] = [0.05, 0.1, 0.2, 0.5, 1.0];

fn presets() -> [(&'static str, LqgModel); 2] {
    [("lqg", LqgModel::thesis()), ("lqg1d", LqgModel::lqg1d())]
}

fn eval(o: &ClippedDpOracle, v: f64, sigma: f64, needs: Needs) -> f64 {
    let ex = Exploration::Gaussian {
        w: vec![sigma.ln()],
    };
    o.evaluate_with(&[v], &ex, Horizon::Finite(20), needs)
        .expect("valid evaluation")
        .j
}

fn grid(c: &mut Criterion) {
    let mut group = c.benchmark_group("oracle/clipped_dp/grid");
    group.sample_size(10);
    group.throughput(Throughput::Elements((V.len() * SIGMA.len()) as u64));
    for (name, model) in presets() {
        let o = ClippedDpOracle::new(&model).expect("clipped preset");
        for (label, needs) in [
            ("value", Needs::VALUE),
            ("sepg", Needs::SEPG),
            ("all", Needs::ALL),
        ] {
            group.bench_function(BenchmarkId::new(label, name), |b| {
                b.iter(|| {
                    let mut total = 0.0;
                    for v in V {
                        for sigma in SIGMA {
                            total += eval(&o, v, sigma, needs);
                        }
                    }
                    black_box(total)
                })
            });
        }
    }
    group.finish();
}

fn points(c: &mut Criterion) {
    let mut group = c.benchmark_group("oracle/clipped_dp/point");
    group.throughput(Throughput::Elements(1));
    for (name, model) in presets() {
        let o = ClippedDpOracle::new(&model).expect("clipped preset");
        for (v, sigma) in [(-0.6, 1.0), (-0.6, 0.05), (-0.1, 0.2), (-1.2, 0.2)] {
            group.bench_function(
                BenchmarkId::new(format!("sepg/{name}"), format!("v{v}_s{sigma}")),
                |b| b.iter(|| black_box(eval(&o, v, sigma, Needs::SEPG))),
            );
        }
    }
    group.finish();
}

criterion_group!(benches, grid, points);
criterion_main!(benches);
