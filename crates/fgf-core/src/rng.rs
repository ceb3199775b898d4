//! Stream keys for counter-based random numbers.
//!
//! Every independent stream of random numbers in fgf (one camera sample of
//! the renderer, one grid row of a synthesized field, one realization of an
//! ensemble) is seeded from a 64-bit key derived from the user's seed and
//! the stream's indices only, never from a shared generator. Which thread
//! draws a stream, and in which order, then cannot change a single bit of
//! the result.
//!
//! Keys form a tree: [`stream_key`]`(parent, index)` is the key of child
//! `index` of `parent`. Chaining (rather than xor-ing independent hashes of
//! the indices) makes `(a, b)` and `(b, a)` give unrelated keys.
//!
//! ```
//! use fgf_core::rng::{mix64, stream_key, SECOND_WORD};
//! // A stream named by (seed, pixel, sample), and a second 64-bit word
//! // from its key (e.g. a PCG stream selector):
//! let key = stream_key(stream_key(mix64(7), 42), 3);
//! let word = stream_key(key, SECOND_WORD);
//! assert_ne!(key, word);
//! assert_ne!(stream_key(stream_key(mix64(7), 3), 42), key);
//! ```

/// The SplitMix64 finaliser (Steele, Lea & Flood 2014): a bijection of
/// `u64` with full avalanche, so neighbouring inputs give unrelated outputs.
#[inline]
pub const fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Key of stream `index` under `parent`: `mix64(parent ^ index)`.
#[inline]
pub const fn stream_key(parent: u64, index: u64) -> u64 {
    mix64(parent ^ index)
}

/// The odd constant (PCG's 64-bit LCG multiplier) used as the index that
/// derives a second, independent 64-bit word from a key, e.g.
/// `stream_key(key, SECOND_WORD)` for a generator that takes a state and a
/// stream selector.
pub const SECOND_WORD: u64 = 0x5851_F42D_4C95_7F2D;

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference outputs of SplitMix64's finaliser (the first outputs of the
    /// SplitMix64 generator seeded with 0 are `mix64(0)`, `mix64(γ)`, ...,
    /// `γ = 0x9E37_79B9_7F4A_7C15`), pinned so that no stream moves.
    #[test]
    fn mix64_values_are_pinned() {
        assert_eq!(mix64(0), 0xE220_A839_7B1D_CDAF);
        assert_eq!(mix64(0x9E37_79B9_7F4A_7C15), 0x6E78_9E6A_A1B9_65F4);
        assert_eq!(stream_key(5, 5), mix64(0));
    }

    #[test]
    fn chained_keys_depend_on_order() {
        let ab = stream_key(stream_key(1, 2), 3);
        let ba = stream_key(stream_key(1, 3), 2);
        assert_ne!(ab, ba);
    }
}
