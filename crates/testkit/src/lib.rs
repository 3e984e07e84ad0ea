//! Helpers shared by the test suites of the sepg workspace, written once: a thread pool of a
//! given size (to run the same computation with different thread counts), relative closeness
//! with an absolute floor, and the composite Simpson rule for reference integrals.
//!
//! ```
//! use sepg_testkit::{close, simpson};
//! let third = simpson(|x| x * x, 0.0, 1.0, 2);
//! assert!(close(third, 1.0 / 3.0, 1e-15, 1e-300));
//! ```

#![deny(missing_docs)]

/// A pool of `threads` worker threads (at least one), to run the same computation with
/// different thread counts.
///
/// # Panics
/// When the operating system refuses to start the threads: a test cannot go on without them.
pub fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
}

/// Relative closeness with an absolute floor given by `scale`:
/// |a − b| ≤ rel · max(|a|, |b|) or |a − b| ≤ rel · scale.
pub fn close(a: f64, b: f64, rel: f64, scale: f64) -> bool {
    approx::relative_eq!(a, b, epsilon = rel * scale, max_relative = rel)
}

/// ∫ f over [a, b] by the composite Simpson rule with `n` panels (`n` even; an odd `n` is
/// rounded up), exact for cubics; the error is O(((b − a)/n)⁴) for smooth f.
pub fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let n = (n + n % 2).max(2);
    let h = (b - a) / n as f64;
    let mut sum = f(a) + f(b);
    for i in 1..n {
        let w = if i % 2 == 1 { 4.0 } else { 2.0 };
        sum += w * f(a + i as f64 * h);
    }
    sum * h / 3.0
}
