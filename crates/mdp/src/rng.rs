//! Portable, reproducible random streams: one pair of `Xoshiro256PlusPlus` generators per
//! trajectory, seeded from `(seed, iteration, block, index)`.
//!
//! Every trajectory owns two independent streams, one for the environment (initial state and
//! transition noise) and one for the policy (action noise). A trajectory therefore depends only
//! on its own key, never on the thread that ran it, and two policies rolled out with the same
//! key see the same initial states and transition noise (common random numbers, used by
//! [`crate::monte_carlo`]).
//!
//! # Formula
//! ```text
//! mix(x)   = SplitMix64 finaliser of x + 0x9E3779B97F4A7C15
//! h        = mix(mix(mix(mix(mix(seed) ^ iteration) ^ block) ^ index) ^ stream)
//! state_k  = mix(h + k·0x9E3779B97F4A7C15),  k = 0..3      (SplitMix64 stream from h)
//! ```
//! with `stream = 0` for the environment and `1` for the policy. Normal variates use the
//! ziggurat of `rand_distr::StandardNormal`; uniform variates in `[0, 1)` use the top 53 bits.

use rand::{Rng, RngCore, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

/// The named portable generator used for every trajectory.
pub type TrajRng = Xoshiro256PlusPlus;

/// SplitMix64's golden-ratio increment `⌊2^64/φ⌋`.
const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// One SplitMix64 output for the state `x` (Steele, Lea and Flood, 2014): the state is advanced
/// by the golden-ratio increment, then finalised. A bijection of `u64`.
///
/// # Formula
/// ```text
/// z = x + 0x9E3779B97F4A7C15
/// z = (z ^ (z >> 30)) · 0xBF58476D1CE4E5B9
/// z = (z ^ (z >> 27)) · 0x94D049BB133111EB
/// return z ^ (z >> 31)                    (all arithmetic mod 2^64)
/// ```
///
/// ```
/// // The first output of the reference SplitMix64 generator seeded with 1234567.
/// assert_eq!(sepg_mdp::rng::splitmix64(1234567), 6457827717110365317);
/// ```
pub const fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(GOLDEN);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A `Xoshiro256PlusPlus` whose 256-bit state is the first four outputs of a SplitMix64
/// generator started at `seed` (the seeding recommended by the xoshiro authors; independent of
/// `rand_core`'s `seed_from_u64`, so it can never change with a dependency upgrade).
///
/// # Formula
/// ```text
/// state_k = splitmix64(seed + k · 0x9E3779B97F4A7C15),  k = 0, 1, 2, 3
/// ```
///
/// ```
/// use rand::RngCore;
/// let mut a = sepg_mdp::rng::rng_from_seed(7);
/// let mut b = sepg_mdp::rng::rng_from_seed(7);
/// assert_eq!(a.next_u64(), b.next_u64());
/// ```
#[inline]
pub fn rng_from_seed(seed: u64) -> TrajRng {
    let mut bytes = [0u8; 32];
    let mut state = seed;
    for chunk in bytes.chunks_exact_mut(8) {
        chunk.copy_from_slice(&splitmix64(state).to_le_bytes());
        state = state.wrapping_add(GOLDEN);
    }
    Xoshiro256PlusPlus::from_seed(bytes)
}

/// Which of the two per-trajectory streams a seed is derived for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Stream {
    /// Initial state and transition noise.
    Environment,
    /// Action noise of the policy.
    Policy,
}

impl Stream {
    #[inline]
    fn tag(self) -> u64 {
        match self {
            Stream::Environment => 0,
            Stream::Policy => 1,
        }
    }
}

/// The key of one batch of trajectories: the run seed, the algorithm iteration and the block
/// within the iteration (e.g. the v-, target- and w-blocks of SEPG, Algorithm 4.3). Trajectory
/// `index` of the batch gets its own streams from [`SeedKey::rngs`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SeedKey {
    /// Run seed.
    pub seed: u64,
    /// Iteration counter.
    pub iteration: u64,
    /// Block within the iteration.
    pub block: u64,
}

impl SeedKey {
    /// The key `(seed, iteration, block)`.
    ///
    /// ```
    /// let k = sepg_mdp::rng::SeedKey::new(1, 2, 3);
    /// assert_eq!((k.seed, k.iteration, k.block), (1, 2, 3));
    /// ```
    pub fn new(seed: u64, iteration: u64, block: u64) -> Self {
        SeedKey {
            seed,
            iteration,
            block,
        }
    }

    /// The 64-bit seed of trajectory `index` for `stream`, by a SplitMix64 chain.
    ///
    /// # Formula
    /// ```text
    /// mix(mix(mix(mix(mix(seed) ^ iteration) ^ block) ^ index) ^ stream_tag)
    /// ```
    ///
    /// ```
    /// use sepg_mdp::rng::{SeedKey, Stream};
    /// let k = SeedKey::new(1, 0, 0);
    /// assert_ne!(k.trajectory_seed(0, Stream::Policy), k.trajectory_seed(1, Stream::Policy));
    /// assert_ne!(k.trajectory_seed(0, Stream::Policy), k.trajectory_seed(0, Stream::Environment));
    /// ```
    pub fn trajectory_seed(&self, index: u64, stream: Stream) -> u64 {
        seed_from_prefix(self.prefix(), index, stream)
    }

    /// The part of the chain shared by all trajectories of the batch.
    #[inline]
    pub(crate) fn prefix(&self) -> u64 {
        let h = splitmix64(self.seed);
        let h = splitmix64(h ^ self.iteration);
        splitmix64(h ^ self.block)
    }

    /// The environment and policy streams of trajectory `index`.
    ///
    /// ```
    /// use rand::RngCore;
    /// use sepg_mdp::rng::SeedKey;
    /// let mut a = SeedKey::new(3, 1, 0).rngs(5);
    /// let mut b = SeedKey::new(3, 1, 0).rngs(5);
    /// assert_eq!(a.policy.next_u64(), b.policy.next_u64());
    /// ```
    pub fn rngs(&self, index: u64) -> TrajectoryRngs {
        rngs_from_prefix(self.prefix(), index)
    }
}

#[inline]
fn seed_from_prefix(prefix: u64, index: u64, stream: Stream) -> u64 {
    splitmix64(splitmix64(prefix ^ index) ^ stream.tag())
}

/// [`SeedKey::rngs`] from a precomputed [`SeedKey::prefix`].
#[inline]
pub(crate) fn rngs_from_prefix(prefix: u64, index: u64) -> TrajectoryRngs {
    let h = splitmix64(prefix ^ index);
    TrajectoryRngs {
        env: rng_from_seed(splitmix64(h ^ Stream::Environment.tag())),
        policy: rng_from_seed(splitmix64(h ^ Stream::Policy.tag())),
    }
}

/// The two random streams of one trajectory.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TrajectoryRngs {
    /// Initial state and transition noise.
    pub env: TrajRng,
    /// Action noise.
    pub policy: TrajRng,
}

/// A standard normal variate `N(0, 1)` (ziggurat of `rand_distr::StandardNormal`).
///
/// ```
/// let mut rng = sepg_mdp::rng::rng_from_seed(1);
/// assert!(sepg_mdp::rng::standard_normal(&mut rng).is_finite());
/// ```
#[inline(always)]
pub fn standard_normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    StandardNormal.sample(rng)
}

/// A uniform variate in `[0, 1)` with 53 random bits.
///
/// # Formula
/// ```text
/// u = (x >> 11) · 2^-53,   x the next 64-bit output
/// ```
///
/// ```
/// let mut rng = sepg_mdp::rng::rng_from_seed(1);
/// let u = sepg_mdp::rng::unit_f64(&mut rng);
/// assert!((0.0..1.0).contains(&u));
/// ```
#[inline(always)]
pub fn unit_f64<R: RngCore + ?Sized>(rng: &mut R) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A uniform variate in `[low, high)` (`low` when `low = high`).
///
/// # Formula
/// ```text
/// x = low + (high − low) · u,   u = unit_f64
/// ```
///
/// ```
/// let mut rng = sepg_mdp::rng::rng_from_seed(1);
/// let x = sepg_mdp::rng::uniform(&mut rng, -2.0, 2.0);
/// assert!((-2.0..2.0).contains(&x));
/// ```
#[inline(always)]
pub fn uniform<R: RngCore + ?Sized>(rng: &mut R, low: f64, high: f64) -> f64 {
    low + (high - low) * unit_f64(rng)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix64_matches_the_reference_stream() {
        // Reference SplitMix64 outputs for seed 1234567 (Vigna's splitmix64.c).
        let expected = [
            6457827717110365317u64,
            3203168211198807973,
            9817491932198370423,
            4593380528125082431,
            16408922859458223821,
        ];
        let mut state = 1234567u64;
        for e in expected {
            assert_eq!(splitmix64(state), e);
            state = state.wrapping_add(GOLDEN);
        }
        assert_eq!(splitmix64(0), 0xE220_A839_7B1D_CDAF);
    }

    #[test]
    fn streams_are_value_stable() {
        // Pinned outputs: a change of the mixing chain, the seeding or a dependency upgrade that
        // alters the generator makes this fail.
        let mut r = SeedKey::new(42, 7, 1).rngs(3);
        let got = [r.env.next_u64(), r.policy.next_u64()];
        assert_eq!(got, PINNED_RAW);
        let mut rng = rng_from_seed(2024);
        let z: Vec<u64> = (0..4)
            .map(|_| standard_normal(&mut rng).to_bits())
            .collect();
        assert_eq!(z, PINNED_NORMAL_BITS);
    }

    // First outputs of the environment and policy streams of SeedKey(42, 7, 1), trajectory 3,
    // reproduced by an independent Python implementation of the reference SplitMix64 and
    // xoshiro256++ algorithms (Vigna's C code):
    //   h = sm(sm(sm(sm(sm(42) ^ 7) ^ 1) ^ 3) ^ stream); state_k = sm(h + k·G);
    //   out = rotl(s0 + s3, 23) + s0.
    const PINNED_RAW: [u64; 2] = [4281573760387900518, 17683543231262930363];
    // Bits of the first four standard normals of rng_from_seed(2024) (ziggurat of rand_distr
    // 0.5), pinned for value stability.
    const PINNED_NORMAL_BITS: [u64; 4] = [
        4586935592441107467,
        13819391928086123455,
        13831270357854330268,
        13821768580223517882,
    ];

    #[test]
    fn uniform_covers_the_interval_evenly() {
        // 1e5 draws in [-2, 2): the sample mean has standard error 4/√12/√1e5 ≈ 3.65e-3; the
        // 5-sigma band has a false-alarm rate of 5.7e-7.
        let mut rng = rng_from_seed(9);
        let n = 100_000;
        let mean = (0..n).map(|_| uniform(&mut rng, -2.0, 2.0)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 5.0 * 4.0 / 12f64.sqrt() / (n as f64).sqrt());
    }
}
