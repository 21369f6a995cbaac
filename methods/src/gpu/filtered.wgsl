// Shared by the filtered shadow maps' kernels (gpu::filtered): their parameters, the rounding
// of stored values to a storage precision (filtered_map::Precision), the light-bleeding
// reduction and the written lit value, exact in f64. Needs receiver.wgsl (round_half_up) and
// common.wgsl (is_finite64) before it; each kernel declares `fparams`.

// Mirrors gpu::filtered::FParams (Rust): f64 fields first, then 32-bit ones.
struct FParams {
    // The scene's nearest light depth and its light depth range (normalised depths).
    near: f64,
    range: f64,
    // The box filter's weight, 1 / width.
    weight: f64,
    pad0: f64,
    // The method's parameters (FilteredMap::wgsl_params).
    p0: f64,
    p1: f64,
    p2: f64,
    p3: f64,
    // Texels, map resolution, values per texel, the filter's half-width.
    texels: u32,
    res: u32,
    n: u32,
    half: u32,
    // Precision::code; the filter pass's axis (1: along rows, 0: along columns).
    precision_code: u32,
    along_rows: u32,
    pad1: u32,
    pad2: u32,
}

// The index of invocation gid among `groups` workgroups of 64 (GpuContext::groups_1d).
fn flat_index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * (groups.x * 64u);
}

// x in [0, 2] (or NaN) rounded to the nearest float (ties to even) whose significand has
// 1 / ulp_at_one steps per binade and whose least normal is least_normal (below it, steps of
// least_normal * ulp_at_one): the binade by halving or doubling, then the step count rounded
// by floor and the remainder, every operation exact in f64.
fn round_float(x: f64, ulp_at_one: f64, least_normal: f64) -> f64 {
    if !(x > 0.0lf) {
        return x;
    }
    var p = 1.0lf;
    for (var i = 0u; i < 2u; i++) {
        if p * 2.0lf <= x {
            p = p * 2.0lf;
        }
    }
    for (var i = 0u; i < 200u; i++) {
        if !(p > x && p > least_normal) {
            break;
        }
        p = p * 0.5lf;
    }
    let q = p * ulp_at_one;
    let m = x / q;
    let f = floor(m);
    let d = m - f;
    var r = f;
    if d > 0.5lf || (d == 0.5lf && f - 2.0lf * floor(f * 0.5lf) == 1.0lf) {
        r = f + 1.0lf;
    }
    return r * q;
}

// Precision::F32's rounding (Rust's `as f32`).
fn round_f32(x: f64) -> f64 {
    return round_float(x, 0x1p-23lf, 0x1p-126lf);
}

// Precision::F16's rounding: the f32 value rounded to a half (filtered_map::f16_bits).
fn round_f16(x: f64) -> f64 {
    return round_float(round_f32(x), 0x1p-10lf, 0x1p-14lf);
}

// Precision::U16's rounding (filtered_map::unorm16 and unorm16_value).
fn round_unorm16(v: f64) -> f64 {
    var c = 0.0lf;
    if v > 0.0lf {
        c = 1.0lf;
        if v < 1.0lf {
            c = v;
        }
    }
    return round_half_up(c * 65535.0lf) / 65535.0lf;
}

// Precision::round at the kernel's precision.
fn quantize(v: f64) -> f64 {
    switch fparams.precision_code {
        case 1u: { return round_f32(v); }
        case 2u: { return round_f16(v); }
        case 3u: { return round_unorm16(v); }
        default: { return v; }
    }
}

// filtered_map::reduce_bleeding.
fn reduce_bleeding(lit: f64, a: f64) -> f64 {
    let v = (lit - a) / (1.0lf - a);
    if v < 0.0lf {
        return 0.0lf;
    }
    if v > 1.0lf {
        return 1.0lf;
    }
    return v;
}

// filtered_map::lit_value: clamped to [0, 1], below the least normal f32 0, else the nearest
// f32 (computed exactly, so the conversion does not round).
fn lit_value(v: f64) -> f32 {
    if v >= 0x1p-126lf {
        if v < 1.0lf {
            return f32(round_f32(v));
        }
        return 1.0f;
    }
    return 0.0f;
}
