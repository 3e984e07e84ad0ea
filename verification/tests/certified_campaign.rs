//! The exact-arithmetic campaign for certified safe steps (`sepg_verification::campaign`).
//!
//! CI runs `campaign_small` (512 random configurations and the adversarial grid of 1,440,
//! each in all 13 bound forms: about 15 s of CPU). The full campaign, 10⁶ random
//! configurations per bound form (about 72 CPU-minutes, 36 minutes on two idle cores; run it
//! niced, its running totals go to stderr after each of 40 blocks, its table to stdout):
//!
//! ```text
//! cargo test --release -p sepg-verification --test certified_campaign -- --ignored --nocapture
//! ```
use sepg_verification::campaign::{
    CampaignConfig, FormTally, adversarial_len, merge, run, run_adversarial, run_random,
};

fn print(tallies: &[FormTally]) {
    println!(
        "| form | cases | uncertified steps | violated exactly | certified steps | tight constants | by error bound | by interval | moved | max ulps | uncertifiable | certified violations | undecided | enclosure failures | outcome mismatches |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for t in tallies {
        println!(
            "| {} | {} | {} | {} ({:.1}%) | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            t.form,
            t.cases,
            t.uncertified_steps,
            t.uncertified_violations,
            100.0 * t.uncertified_violations as f64 / t.uncertified_steps.max(1) as f64,
            t.certified_steps,
            t.tight_certified_steps,
            t.by_error_bound,
            t.by_interval,
            t.moved,
            t.max_ulps,
            t.uncertifiable,
            t.certified_violations,
            t.undecided,
            t.enclosure_failures,
            t.outcome_mismatches
        );
    }
    println!();
    println!(
        "| form | rounded updates | violated exactly | realised updates | realised violations | unmet (nothing moved) |"
    );
    println!("|---|---|---|---|---|---|");
    for t in tallies {
        println!(
            "| {} | {} | {} ({:.1}%) | {} | {} | {} |",
            t.form,
            t.raw_updates,
            t.raw_violations,
            100.0 * t.raw_violations as f64 / t.raw_updates.max(1) as f64,
            t.realised,
            t.realised_violations,
            t.realised_unmet
        );
    }
    for t in tallies {
        println!("{}: largest move {:?}", t.form, t.largest_move);
    }
}

fn assert_clean(tallies: &[FormTally]) {
    for t in tallies {
        assert!(t.clean(), "{}: {:?}", t.form, t.counterexample);
    }
}

#[test]
fn campaign_small() {
    const RANDOM: u64 = 512;
    let tallies = run(&CampaignConfig {
        seed: 16,
        random: RANDOM,
        adversarial: true,
    });
    print(&tallies);
    assert_clean(&tallies);
    let expected_cases = RANDOM + adversarial_len();
    assert!(tallies.iter().all(|t| t.cases == expected_cases));
    // the campaign has teeth: uncertified largest steps are violated in exact arithmetic,
    // and certification had to move steps to avoid that
    let violated: u64 = tallies.iter().map(|t| t.uncertified_violations).sum();
    let moved: u64 = tallies.iter().map(|t| t.moved).sum();
    assert!(
        violated > 100 && moved > 100,
        "violated {violated}, moved {moved}"
    );
    // rounding the applied update breaks certified step sizes, and the realised updates are
    // checked (every form that SEPG applies to one coordinate)
    let raw: u64 = tallies.iter().map(|t| t.raw_violations).sum();
    let realised: u64 = tallies.iter().map(|t| t.realised).sum();
    assert!(
        raw > 100 && realised > 1000,
        "raw violations {raw}, realised {realised}"
    );
    // both paths of the certificate are exercised: the a-priori error bound accepts most
    // steps, interval arithmetic takes the rest (rigorous forms, extreme inputs, C near C_max)
    let fast: u64 = tallies.iter().map(|t| t.by_error_bound).sum();
    let fallback: u64 = tallies.iter().map(|t| t.by_interval).sum();
    assert!(
        fast > 1000 && fallback > 100,
        "fast {fast}, fallback {fallback}"
    );
    // the tight constants are certified in every form (about half of the configurations)
    for t in &tallies {
        assert!(
            t.tight_certified_steps > 100,
            "{}: {} certified steps with the tight constants",
            t.form,
            t.tight_certified_steps
        );
    }
    let quadratic_fallback: u64 = tallies[..8].iter().map(|t| t.by_interval).sum();
    assert!(
        quadratic_fallback > 10,
        "fallback of the quadratic forms {quadratic_fallback}"
    );
}

#[test]
#[ignore = "full campaign, minutes: see the module docs"]
fn campaign_full() {
    const RANDOM: u64 = 1_000_000;
    // 40 blocks of 25,000 configurations (chunks of 256 each, the same streams as one `run`):
    // each block's running totals go to stderr, so that an interrupted campaign says how far
    // it got
    const CHUNKS: u64 = RANDOM.div_ceil(256);
    const BLOCKS: u64 = 40;
    let block = |b: u64| CHUNKS * b / BLOCKS..CHUNKS * (b + 1) / BLOCKS;
    let mut tallies = run_random(16, RANDOM, block(0));
    for b in 0..BLOCKS {
        if b > 0 {
            merge(&mut tallies, run_random(16, RANDOM, block(b)));
        }
        let sum = |f: fn(&FormTally) -> u64| tallies.iter().map(f).sum::<u64>();
        eprintln!(
            "random configurations done: {} of {RANDOM}; certified steps {}, certified violations {}, undecided {}, enclosure failures {}, outcome mismatches {}, realised updates {}, realised violations {}",
            (block(b).end * 256).min(RANDOM),
            sum(|t| t.certified_steps),
            sum(|t| t.certified_violations),
            sum(|t| t.undecided),
            sum(|t| t.enclosure_failures),
            sum(|t| t.outcome_mismatches),
            sum(|t| t.realised),
            sum(|t| t.realised_violations)
        );
    }
    merge(&mut tallies, run_adversarial(RANDOM));
    print(&tallies);
    assert_clean(&tallies);
    assert!(
        tallies
            .iter()
            .all(|t| t.cases == RANDOM + adversarial_len())
    );
}
