//! What the unit tests share.

/// Marsaglia's xorshift generator on 64 bits (shifts 13, 7, 17): a fixed pseudo-random
/// sequence for each seed, the same on every run and machine, for tests that sweep many inputs.
pub struct XorShift64(u64);

impl XorShift64 {
    /// A generator from `seed`, which must not be 0 (the sequence of 0 is all zeros).
    pub fn new(seed: u64) -> Self {
        assert_ne!(seed, 0, "xorshift stays at 0 from 0");
        XorShift64(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        let state = &mut self.0;
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        *state
    }
}

/// Marsaglia's xorshift generator on 32 bits (shifts 13, 17, 5).
pub struct XorShift32(u32);

impl XorShift32 {
    /// A generator from `seed`, which must not be 0.
    pub fn new(seed: u32) -> Self {
        assert_ne!(seed, 0, "xorshift stays at 0 from 0");
        XorShift32(seed)
    }

    pub fn next_u32(&mut self) -> u32 {
        let state = &mut self.0;
        *state ^= *state << 13;
        *state ^= *state >> 17;
        *state ^= *state << 5;
        *state
    }
}
