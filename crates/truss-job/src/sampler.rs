//! The random stream of one sample, and the order in which it is drawn.
//!
//! ## Contract
//!
//! Sample `k` (counted within its case) of case `c` of a job with seed `s` draws from the
//! ChaCha20 stream with
//!
//! ```text
//! key    = SHA-256("truss-mc sample stream v1" ‖ 0x00 ‖ s as 8 little-endian bytes ‖ c's name in UTF-8)
//! stream = k            (rand_chacha's 64-bit stream id; the word position starts at 0)
//! ```
//!
//! and takes its 64-bit words (`next_u64`) in this order: two words for each member of the
//! case's model, in model order, whether or not its group has a distribution (a member
//! without one leaves its two words unused, so that adding a distribution to one group never
//! changes another group's draws); then, if the case draws backlash clearances, two words
//! for each joint of the model, in model order. [`crate::distribution`] says how two words
//! become a number. A group with a production lot's shared part draws it from its own
//! stream ([`crate::lot`]: two words per lot, in lot order), added to each member's own
//! draw, so adding a lot moves no other draw. So a sample's draws depend on the seed, the
//! case name, `k` and the model, and on nothing else: not the shard split, the thread count,
//! the other cases, or the machine.

use crate::job::Case;
use rand_chacha::ChaCha20Rng;
use rand_core::{Rng, SeedableRng};
use sha2::{Digest, Sha256};

/// Domain separator of the stream key.
const DOMAIN: &[u8] = b"truss-mc sample stream v1";

/// The ChaCha20 key of a case's streams.
pub fn stream_key(seed: u64, case: &str) -> [u8; 32] {
    let mut h = Sha256::new();
    h.update(DOMAIN);
    h.update([0u8]);
    h.update(seed.to_le_bytes());
    h.update(case.as_bytes());
    h.finalize().into()
}

/// The stream of sample `k` of a case with key `key`.
pub fn sample_stream(key: &[u8; 32], k: u64) -> ChaCha20Rng {
    let mut rng = ChaCha20Rng::from_seed(*key);
    rng.set_stream(k);
    rng
}

/// Draws the length errors \[mm\] of sample `k` of `case` into `errors` (one per member,
/// model order; zero where the member's group has no distribution).
pub fn draw_length_errors(key: &[u8; 32], case: &Case, k: u64, errors: &mut Vec<f64>) {
    let mut clearances = Vec::new();
    draw_sample(key, case, k, errors, &mut clearances);
}

/// Draws everything sample `k` of `case` draws: the length errors \[mm\] (one per member,
/// model order) into `errors`, then the joint clearances \[mm\] (one per joint, model order;
/// left empty when the case draws none, so the model's own apply) into `clearances`.
pub fn draw_sample(
    key: &[u8; 32],
    case: &Case,
    k: u64,
    errors: &mut Vec<f64>,
    clearances: &mut Vec<f64>,
) {
    let mut lots = Vec::new();
    draw_sample_with_lots(key, case, k, errors, clearances, &mut lots);
}

/// [`draw_sample`], keeping each lot's shared part \[mm\] in `lots` (numbered over the
/// case's lots in order, as [`Case::member_lot`] numbers them; empty without lots). The
/// length errors are the members' own draws plus their lots' parts.
pub fn draw_sample_with_lots(
    key: &[u8; 32],
    case: &Case,
    k: u64,
    errors: &mut Vec<f64>,
    clearances: &mut Vec<f64>,
    lots: &mut Vec<f64>,
) {
    let mut rng = sample_stream(key, k);
    errors.clear();
    errors.extend(case.member_errors.iter().map(|dist| {
        let (w1, w2) = (rng.next_u64(), rng.next_u64());
        dist.map_or(0.0, |d| d.from_words(w1, w2))
    }));
    clearances.clear();
    if let Some(b) = &case.backlash {
        clearances.extend(case.model.joints().iter().map(|_| {
            let (w1, w2) = (rng.next_u64(), rng.next_u64());
            b.clearance.from_words(w1, w2)
        }));
    }
    lots.clear();
    for lot in &case.lots {
        let mut rng = sample_stream(&lot.key, k);
        lots.extend(lot.lots.iter().map(|_| {
            let (w1, w2) = (rng.next_u64(), rng.next_u64());
            lot.distribution.from_words(w1, w2)
        }));
    }
    if !lots.is_empty() {
        for (e, l) in errors.iter_mut().zip(&case.member_lot) {
            if let Some(l) = l {
                *e += lots[*l];
            }
        }
    }
}
