//! The crate's one source of pseudo-random numbers, shared by the procedural scenes, the scene
//! set's generator and the randomized tests.

/// A small deterministic generator (xorshift*), so scenes do not change between runs or machines
/// (and the crate's randomized tests name a failing case by its number).
pub(crate) struct Rng(pub(crate) u64);

impl Rng {
    /// The next 64 bits.
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// A float in [0, 1), from the top 24 bits.
    pub(crate) fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
}
