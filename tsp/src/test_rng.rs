//! The random numbers of the unit tests.

/// Uniform numbers in `[0, 1)` from a 64-bit linear congruential generator
/// (Knuth's MMIX constants, the top 31 bits), deterministic per `seed`.
pub(crate) fn lcg(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed | 1;
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 33) as f64 / (1u64 << 31) as f64
    }
}
