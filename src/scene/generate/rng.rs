//! The generator's own pseudo-random numbers: SplitMix64 (Steele, Lea and Flood, "Fast splittable
//! pseudorandom number generators", 2014), pure 64-bit integer arithmetic, so a seed gives the same numbers
//! on every machine. No OS seeding: every stream starts from a seed the caller gives.

/// The golden-ratio increment of SplitMix64 (2^64 / phi, odd).
const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's output function: a bijection of `u64` that mixes every input bit into every output bit.
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A SplitMix64 stream.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// The stream that starts from `seed`.
    pub fn new(seed: u64) -> Self {
        SplitMix64 { state: seed }
    }

    /// The stream of item `index` of the family drawn with `seed`: depends only on the pair, so item `k`
    /// is the same whatever the number of items drawn.
    pub fn for_item(seed: u64, index: u64) -> Self {
        SplitMix64::new(mix64(seed) ^ mix64(index.wrapping_add(GOLDEN_GAMMA)))
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN_GAMMA);
        mix64(self.state)
    }

    /// A number in `0..n` (`n > 0`; 0 for `n = 0`), by the high half of a 128-bit product (Lemire): the
    /// bias is below `n / 2^64`, far under anything a sample of scenes could show.
    pub fn below(&mut self, n: u64) -> u64 {
        ((u128::from(self.next_u64()) * u128::from(n)) >> 64) as u64
    }

    /// A number in `lo..=hi`, each equally likely (`lo` when `hi < lo`).
    pub fn in_range(&mut self, lo: u32, hi: u32) -> u32 {
        let span = u64::from(hi.saturating_sub(lo)) + 1;
        lo + self.below(span) as u32
    }

    /// One of `items`, each equally likely; `None` for an empty slice.
    pub fn pick<T: Copy>(&mut self, items: &[T]) -> Option<T> {
        let i = self.below(items.len() as u64) as usize;
        items.get(i).copied()
    }

    /// A fair coin.
    pub fn coin(&mut self) -> bool {
        self.next_u64() >> 63 == 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix64_matches_the_reference_sequence() {
        // The reference implementation (Vigna, splitmix64.c) seeded with 1234567.
        let mut r = SplitMix64::new(1_234_567);
        let got: Vec<u64> = (0..3).map(|_| r.next_u64()).collect();
        assert_eq!(
            got,
            [
                6457827717110365317,
                3203168211198807973,
                9817491932198370423
            ]
        );
    }

    #[test]
    fn ranges_are_inclusive_and_cover_every_value() {
        let mut r = SplitMix64::new(7);
        let mut seen = [0u32; 5];
        for _ in 0..5000 {
            let v = r.in_range(3, 7);
            assert!((3..=7).contains(&v), "{v}");
            seen[(v - 3) as usize] += 1;
        }
        // Each of the five values about 1000 times (a binomial's 6 sigma is 170).
        assert!(seen.iter().all(|&n| (830..1170).contains(&n)), "{seen:?}");
        assert_eq!(r.in_range(4, 4), 4);
        assert_eq!(r.pick::<u32>(&[]), None);
    }

    #[test]
    fn item_streams_differ_by_seed_and_index() {
        let first = |s, k| SplitMix64::for_item(s, k).next_u64();
        assert_ne!(first(1, 0), first(1, 1));
        assert_ne!(first(1, 0), first(2, 0));
        assert_ne!(first(0, 0), first(0, 1));
        assert_eq!(first(5, 3), first(5, 3));
    }
}
