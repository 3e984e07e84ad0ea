use sepg_mdp::lqg_model::LqgModel;
use sepg_mdp::oracle::{ClippedDpOracle, ExactOracle, Exploration, Horizon};
struct Instant(f64);
impl Instant {
    fn now() -> Self { Instant(cpu()) }
    fn elapsed(&self) -> Dur { Dur(cpu() - self.0) }
}
struct Dur(f64);
impl Dur { fn as_secs_f64(&self) -> f64 { self.0 } }
fn cpu() -> f64 {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").unwrap();
    s.split_whitespace().next().unwrap().parse::<f64>().unwrap() * 1e-9
}

#[test]
#[ignore]
fn profile_grid() {
    let vs = [-1.5, -1.0, -0.6, -0.3, -0.1, 0.0, 0.2];
    let ss = [0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0];
    for (name, model) in [("lqg", LqgModel::thesis()), ("lqg1d", LqgModel::lqg1d())] {
        let o = ClippedDpOracle::new(&model).unwrap();
        let mut tot = 0.0; let mut cnt = 0; let mut worst = (0.0, 0.0, 0.0);
        for &v in &vs { for &s in &ss {
            let ex = Exploration::Gaussian { w: vec![f64::ln(s)] };
            let mut dt = f64::INFINITY;
            for _ in 0..5 { let t = Instant::now(); let _ = o.evaluate(&[v], &ex, Horizon::Finite(20)); dt = dt.min(t.elapsed().as_secs_f64()); }
            tot += dt; cnt += 1;
            if dt > worst.0 { worst = (dt, v, s); }
            print!("{:7.3} ", dt * 1e3);
        } println!(" v={v}"); }
        println!("{name}: mean {:.3} ms, worst {:.3} ms at v={} s={}", tot / cnt as f64 * 1e3, worst.0 * 1e3, worst.1, worst.2);
    }
}

#[test]
#[ignore]
fn profile_point() {
    let v: f64 = std::env::var("PV").unwrap().parse().unwrap();
    let s: f64 = std::env::var("PS").unwrap().parse().unwrap();
    let reps: usize = std::env::var("PR").unwrap().parse().unwrap();
    let model = if std::env::var("PM").is_ok() { LqgModel::lqg1d() } else { LqgModel::thesis() };
    let o = ClippedDpOracle::new(&model).unwrap();
    let ex = Exploration::Gaussian { w: vec![f64::ln(s)] };
    let t = Instant::now();
    let mut acc = 0.0;
    for _ in 0..reps { acc += o.evaluate(&[v], &ex, Horizon::Finite(20)).unwrap().j; }
    println!("pts per eval {}", sepg_mdp::oracle::clipped_dp::DBG_PTS.load(std::sync::atomic::Ordering::Relaxed) / reps);
    println!("{} ms/eval {acc}", t.elapsed().as_secs_f64() * 1e3 / reps as f64);
}

fn cases() -> Vec<(usize, f64, f64)> {
    let mut c = Vec::new();
    for m in 0..2 { for &v in &[-1.5, -1.0, -0.6, -0.3, -0.1, 0.0, 0.2] { for &s in &[0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0] { c.push((m, v, s)); } } }
    c
}
fn model(m: usize) -> LqgModel { if m == 0 { LqgModel::thesis() } else { LqgModel::lqg1d() } }

#[test]
#[ignore]
fn make_reference() {
    let cfg = sepg_mdp::oracle::DpConfig { nodes_per_element: 16, quad_points: 24, min_elements: 16, elements_per_scale: 4.0, max_elements: 100_000 };
    let mut out = String::new();
    for (m, v, s) in cases() {
        let o = ClippedDpOracle::with_config(&model(m), cfg).unwrap();
        let e = o.evaluate(&[v], &Exploration::Gaussian { w: vec![f64::ln(s)] }, Horizon::Finite(20)).unwrap();
        out += &format!("{m} {v} {s} {:e} {:e} {:e} {:e}\n", e.j, e.grad_v[0], e.grad_w[0], e.mixed_wv[0]);
    }
    std::fs::write("/work/scratch-oracle/ref.txt", out).unwrap();
}

#[test]
#[ignore]
fn sweep() {
    let refs: Vec<Vec<f64>> = std::fs::read_to_string("/work/scratch-oracle/ref.txt").unwrap().lines().map(|l| l.split(' ').map(|x| x.parse().unwrap()).collect()).collect();
    let p: usize = std::env::var("SP").map(|x| x.parse().unwrap()).unwrap_or(10);
    let q: usize = std::env::var("SQ").map(|x| x.parse().unwrap()).unwrap_or(10);
    let me: usize = std::env::var("SM").map(|x| x.parse().unwrap()).unwrap_or(8);
    let eps: f64 = std::env::var("SE").map(|x| x.parse().unwrap()).unwrap_or(1.0);
    let cfg = sepg_mdp::oracle::DpConfig { nodes_per_element: p, quad_points: q, min_elements: me, elements_per_scale: eps, max_elements: 100_000 };
    let mut worst = [0.0f64; 4]; let mut tt = 0.0; let mut tmax = 0.0f64; let mut cnt = 0;
    for r in &refs {
        let (m, v, s) = (r[0] as usize, r[1], r[2]);
        let o = ClippedDpOracle::with_config(&model(m), cfg).unwrap();
        let ex = Exploration::Gaussian { w: vec![f64::ln(s)] };
        let mut dt = f64::INFINITY; let mut e = None;
        for _ in 0..3 { let t = Instant::now(); e = Some(o.evaluate(&[v], &ex, Horizon::Finite(20)).unwrap()); dt = dt.min(t.elapsed().as_secs_f64()); }
        let e = e.unwrap();
        let sc = r[3].abs().max(1.0);
        let d = [(e.j - r[3]).abs() / sc, (e.grad_v[0] - r[4]).abs() / sc, (e.grad_w[0] - r[5]).abs() / sc, (e.mixed_wv[0] - r[6]).abs() / sc];
        let mx = d.iter().cloned().fold(0.0, f64::max);
        if std::env::var("SV").is_ok() { println!("m={m} v={v} s={s}: err {mx:.1e} (J {:.1e}) t {:.3} ms", d[0], dt * 1e3); }
        if v != 0.0 { for i in 0..4 { worst[i] = worst[i].max(d[i]); } }
        tt += dt; tmax = tmax.max(dt); cnt += 1;
    }
    println!("p={p} q={q} min={me} eps={eps}: worst rel err J {:.1e} dv {:.1e} dw {:.1e} dvw {:.1e}; mean {:.3} ms max {:.3} ms", worst[0], worst[1], worst[2], worst[3], tt / cnt as f64 * 1e3, tmax * 1e3);
}

#[test]
#[ignore]
fn small_v() {
    let cfgs = [sepg_mdp::oracle::DpConfig::default(),
        sepg_mdp::oracle::DpConfig { nodes_per_element: 16, quad_points: 24, min_elements: 16, elements_per_scale: 4.0, max_elements: 100_000 },
        sepg_mdp::oracle::DpConfig { nodes_per_element: 20, quad_points: 30, min_elements: 64, elements_per_scale: 8.0, max_elements: 100_000 }];
    for &v in &[0.0, 1e-3, -1e-3, -0.01, -0.03, 0.03] {
        for &s in &[0.02, 0.05] {
            for c in &cfgs {
                let o = ClippedDpOracle::with_config(&model(1), *c).unwrap();
                let e = o.evaluate(&[v], &Exploration::Gaussian { w: vec![f64::ln(s)] }, Horizon::Finite(20)).unwrap();
                println!("v={v} s={s} p={}: {:.12e} {:.12e} {:.12e} {:.12e}", c.nodes_per_element, e.j, e.grad_v[0], e.grad_w[0], e.mixed_wv[0]);
            }
        }
    }
}

#[test]
#[ignore]
fn grid_work() {
    let reps: usize = std::env::var("PR").map(|x| x.parse().unwrap()).unwrap_or(5);
    let wide = std::env::var("WIDE").is_ok();
    let vs: Vec<f64> = if wide { vec![-1.5, -1.0, 0.0, 0.2] } else { vec![-1.2, -0.9, -0.6, -0.3, -0.1] };
    let ss = [0.05, 0.1, 0.2, 0.5, 1.0];
    let mut acc = 0.0; let mut cnt = 0;
    for m in 0..2 {
        let o = ClippedDpOracle::new(&model(m)).unwrap();
        for _ in 0..reps { for &v in &vs { for &s in &ss {
            let needs = match std::env::var("NEEDS").as_deref() { Ok("sepg") => sepg_mdp::oracle::Needs::SEPG, Ok("value") => sepg_mdp::oracle::Needs::VALUE, _ => sepg_mdp::oracle::Needs::ALL };
            acc += o.evaluate_with(&[v], &Exploration::Gaussian { w: vec![f64::ln(s)] }, Horizon::Finite(20), needs).unwrap().j; cnt += 1;
        } } }
    }
    println!("COUNT {cnt} {acc}");
}
