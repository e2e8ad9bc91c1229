//! A deterministic stream of numbers for the unit tests (a linear congruential generator): the same seed
//! gives the same numbers on every machine, so a test's random cases are fixed.

/// The stream's state; `Stream(seed)` starts it.
pub(crate) struct Stream(pub(crate) u64);

impl Stream {
    /// The next number in `[0, 1)`.
    pub(crate) fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// The next number in `[lo, hi)`.
    pub(crate) fn within(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}
