//! Seeded random draws as pure functions of (seed, sample, axis): no generator state, so any node
//! draws any run's values, in any order, and a retry or a resume draws the same. SplitMix64's
//! finaliser (Steele, Lea & Flood 2014) hashes the counters; it is written out here so the draws
//! never change with a dependency's version.

/// SplitMix64's output function: a bijection of u64 with full avalanche.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// 64 random bits for (seed, sample, axis, stream).
pub fn bits(seed: u64, sample: u64, axis: u64, stream: u64) -> u64 {
    mix(mix(mix(mix(seed) ^ sample) ^ axis) ^ stream)
}

/// Uniform in (0, 1) (never 0 or 1: 53 bits, offset by half a step).
pub fn uniform(seed: u64, sample: u64, axis: u64, stream: u64) -> f64 {
    ((bits(seed, sample, axis, stream) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
}

/// Standard normal by Box–Muller from two uniforms.
pub fn normal(seed: u64, sample: u64, axis: u64) -> f64 {
    let u1 = uniform(seed, sample, axis, 1);
    let u2 = uniform(seed, sample, axis, 2);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}
