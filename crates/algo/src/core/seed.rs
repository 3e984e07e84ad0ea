//! The blocks of an iteration and the seed keys of their trajectory batches.
//!
//! Every batch is keyed by `(seed, iteration, block)` ([`sepg_mdp::rng::SeedKey`]) and the
//! rollout engine derives one stream per trajectory index from the key, so a trajectory
//! depends only on `(seed, iteration, block, index)` and never on the number of threads.
use sepg_mdp::rng::SeedKey;

/// The block of an iteration a batch of trajectories belongs to (Algorithm 4.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Block {
    /// The v-block: estimates J(vᵗ, wᵗ) and ∇_v J (lines 5–9). Also the single block of the
    /// comparison algorithms and the merged block of SIM-ν.
    V,
    /// The target block: evaluates the target policy (lines 10–12).
    Target,
    /// The w-block: estimates J(vᵗ⁺¹, wᵗ), ∇_w J and ∇_w L (lines 14–18).
    W,
    /// The reference batch of J(θ⁰), run once before the first iteration.
    Reference,
    /// The reference batch of the first target policy's J, run once before the first
    /// iteration.
    ReferenceTarget,
}

impl Block {
    /// The seed key of this block's batch at `iteration` of a run seeded with `seed`.
    ///
    /// # Formula
    /// ```text
    /// key = (seed, iteration, tag),   tag = 0 (v), 1 (target), 2 (w),
    ///                                       3 (reference), 4 (reference target)
    /// ```
    ///
    /// # Examples
    /// ```
    /// use sepg_algo::core::seed::Block;
    /// assert_eq!(Block::W.key(7, 3).block, 2);
    /// assert_ne!(Block::V.key(7, 3), Block::W.key(7, 3));
    /// ```
    pub fn key(self, seed: u64, iteration: u64) -> SeedKey {
        let tag = match self {
            Block::V => 0,
            Block::Target => 1,
            Block::W => 2,
            Block::Reference => 3,
            Block::ReferenceTarget => 4,
        };
        SeedKey::new(seed, iteration, tag)
    }
}
