// pcf_reeves::jitter: the SplitMix64 hash on 64-bit integers emulated as (low, high) u32
// pairs, so that the samples are the CPU's bit for bit.

// High 32 bits of the 64-bit product of two u32.
fn mul_hi(a: u32, b: u32) -> u32 {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let p11 = a1 * b1;
    let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
    return p11 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u);
}

// u64 wrapping_mul on (low, high) pairs.
fn mul64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    return vec2<u32>(a.x * b.x, mul_hi(a.x, b.x) + a.x * b.y + a.y * b.x);
}

// u64 >> s for 0 < s < 32.
fn shr64(a: vec2<u32>, s: u32) -> vec2<u32> {
    return vec2<u32>((a.x >> s) | (a.y << (32u - s)), a.y >> s);
}

// pcf_reeves::jitter: a uniform number in [0, 1) from (seed, pixel, sample, axis).
fn jitter(seed: vec2<u32>, pixel: u32, sample: u32, axis: u32) -> f64 {
    var z = seed ^ mul64(vec2<u32>(pixel, 0u), vec2<u32>(0x7F4A7C15u, 0x9E3779B9u))
        ^ mul64(vec2<u32>(axis, sample), vec2<u32>(0xD192ED03u, 0xD1B54A32u));
    z = mul64(z ^ shr64(z, 30u), vec2<u32>(0x1CE4E5B9u, 0xBF58476Du));
    z = mul64(z ^ shr64(z, 27u), vec2<u32>(0x133111EBu, 0x94D049BBu));
    z = z ^ shr64(z, 31u);
    let m = shr64(z, 11u);
    // (z >> 11) < 2^53: high word times 2^32 plus low word is exact, as is the scaling.
    return (f64(m.y) * 4294967296.0lf + f64(m.x)) * (1.0lf / 9007199254740992.0lf);
}
