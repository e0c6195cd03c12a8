//! Counter-based random numbers: every draw is a pure function of (key, counter),
//! so slices can be drawn in any order, on any thread, on the CPU or the GPU
//! (`glsl/fsot/common.glsl` mirrors these functions bit for bit), and give the same
//! values.

/// 32-bit integer finaliser with good avalanche (the "lowbias32" constants).
#[inline]
pub fn mix32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// One draw from the stream `key` at position `counter`.
#[inline]
pub fn hash2(key: u32, counter: u32) -> u32 {
    mix32(key ^ mix32(counter.wrapping_add(0x9e37_79b9)))
}

/// A uniform float in [0, 1) from the top 24 bits (exactly representable).
#[inline]
pub fn unit_f32(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// A uniform double in [0, 1) from two draws (53 bits).
#[inline]
pub fn unit_f64(hi: u32, lo: u32) -> f64 {
    let bits = ((hi as u64) << 21) ^ (lo as u64 >> 11);
    (bits & ((1u64 << 53) - 1)) as f64 * (1.0 / 9_007_199_254_740_992.0)
}

/// Derives the key of a sub-stream from a parent key and a label, so that
/// independent uses of one seed never share draws.
#[inline]
pub fn derive(key: u32, label: u32) -> u32 {
    mix32(key.wrapping_mul(0x2c1b_3c6d) ^ mix32(label ^ 0x85eb_ca6b))
}

/// A key from a 64-bit user seed.
pub fn seed_key(seed: u64) -> u32 {
    derive(mix32(seed as u32), mix32((seed >> 32) as u32 ^ 0x68e3_1da4))
}

/// A sequential generator over one counter-based stream (for code that wants a
/// plain `next()`; the sequence is still a pure function of key and start).
#[derive(Clone, Debug)]
pub struct Stream {
    key: u32,
    counter: u32,
}

impl Stream {
    pub fn new(key: u32) -> Self {
        Self { key, counter: 0 }
    }
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let v = hash2(self.key, self.counter);
        self.counter = self.counter.wrapping_add(1);
        v
    }
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        unit_f32(self.next_u32())
    }
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        let hi = self.next_u32();
        let lo = self.next_u32();
        unit_f64(hi, lo)
    }
    /// Uniform integer in [0, n), n > 0 (multiply-shift; bias below 2^-32 * n).
    #[inline]
    pub fn below(&mut self, n: u32) -> u32 {
        ((self.next_u32() as u64 * n as u64) >> 32) as u32
    }
    /// Standard normal by Box-Muller (one of the pair).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.next_f64(); // (0, 1]
        let u2 = self.next_f64();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_values_stay_in_half_open_interval() {
        assert_eq!(unit_f32(u32::MAX), 16_777_215.0 / 16_777_216.0);
        assert!(unit_f32(u32::MAX) < 1.0);
        assert!(unit_f64(u32::MAX, u32::MAX) < 1.0);
        assert_eq!(unit_f32(0), 0.0);
    }

    #[test]
    fn streams_are_roughly_uniform_and_keys_independent() {
        let mut a = Stream::new(derive(1, 2));
        let mut b = Stream::new(derive(1, 3));
        let n = 200_000;
        let mut buckets = [0u32; 16];
        let mut same = 0;
        for _ in 0..n {
            let x = a.next_u32();
            buckets[(x >> 28) as usize] += 1;
            if x == b.next_u32() {
                same += 1;
            }
        }
        let expect = n as f64 / 16.0;
        let chi2: f64 = buckets.iter().map(|&c| (c as f64 - expect).powi(2) / expect).sum();
        assert!(chi2 < 40.0, "chi2 {chi2}"); // 15 dof, p ~ 5e-4
        assert!(same < 3);
    }
}
