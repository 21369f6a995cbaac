// Shared by the shadow-map kernels (sm, pcf-*): the receiver of depth_test::DepthTester, the
// nearest-texel lookup and Brabec and Seidel's depth codes, in f64 with the CPU's operations
// in the CPU's order. Needs common.wgsl before it.

// Mirrors gpu::sm::Params (Rust): f64 fields first, then 32-bit ones.
struct Params {
    // DepthTester::constant, slope_bias, max_slope.
    constant: f64,
    slope_bias: f64,
    max_slope: f64,
    // Reach of the method's compares, texels per axis (both axes alike).
    reach: f64,
    // DepthCode: near, span, largest code.
    code_near: f64,
    code_span: f64,
    code_max: f64,
    pad0: f64,
    // Image width, pixel count, map resolution.
    width: u32,
    pixels: u32,
    res: u32,
    // pcf-reeves: samples, grid columns and rows, seed (low, high word).
    samples: u32,
    grid_x: u32,
    grid_y: u32,
    seed_lo: u32,
    seed_hi: u32,
    // Brabec-Seidel: packing offset, first packed index and packed side, half-texel lookup
    // offset (1) or none (0), shadow levels of the result.
    offset_x: i32,
    offset_y: i32,
    origin: i32,
    side: u32,
    half_offset: u32,
    levels: u32,
    // GPU Gems: 1 for the four dithered lookups, 0 for sixteen.
    dithered: u32,
    pad1: u32,
}

// One ratio |n·axis| / |n·dir| of depth_test::depth_slope, clamped to max_slope.
fn slope_ratio(n: vec3<f64>, axis: vec3<f64>, n_dir: f64, max_slope: f64) -> f64 {
    let r = abs(dot3(n, axis)) / n_dir;
    if is_finite64(r) {
        return min(r, max_slope);
    }
    return max_slope;
}

// depth_test::depth_slope.
fn depth_slope(p: Proj, n: vec3<f64>, xy: vec2<f64>, t: f64, max_slope: f64) -> vec2<f64> {
    let dir = proj_ray(p, xy).direction;
    let n_dir = abs(dot3(n, dir));
    var step: vec2<f64>;
    if p.kind == 1u {
        step = vec2<f64>(t * 2.0lf * p.a / p.width, t * 2.0lf * p.b / p.height);
    } else {
        step = vec2<f64>(2.0lf * p.a / p.width, 2.0lf * p.b / p.height);
    }
    return vec2<f64>(
        slope_ratio(n, p.right, n_dir, max_slope) * step.x,
        slope_ratio(n, p.up, n_dir, max_slope) * step.y,
    );
}

// depth_test::Receiver; ok is false where the point does not project.
struct Receiver {
    xy: vec2<f64>,
    depth: f64,
    slope: vec2<f64>,
    ok: bool,
}

// DepthTester::receiver.
fn receiver(light: Proj, position: vec3<f64>, normal: vec3<f64>, max_slope: f64) -> Receiver {
    let q = proj_project(light, position);
    if q.w == 0.0lf {
        return Receiver(vec2<f64>(0.0lf), 0.0lf, vec2<f64>(0.0lf), false);
    }
    let xy = q.xy;
    return Receiver(xy, q.z, depth_slope(light, normal, xy, q.z, max_slope), true);
}

// DepthTester::tolerance with reach (reach_x, reach_y).
fn tolerance(params: Params, r: Receiver, reach: vec2<f64>) -> f64 {
    return params.constant + params.slope_bias * (reach.x * r.slope.x + reach.y * r.slope.y);
}

// depth_test::texel_at: the texel index (y * res + x) of a nearest lookup, or -1 outside.
fn texel_at(xy: vec2<f64>, res: u32) -> i32 {
    let x = floor(xy.x);
    let y = floor(xy.y);
    let r = f64(res);
    if x >= 0.0lf && y >= 0.0lf && x < r && y < r {
        return i32(u32(y) * res + u32(x));
    }
    return -1;
}

// f64::round for x >= 0 (half away from zero; WGSL's round goes half to even).
fn round_half_up(x: f64) -> f64 {
    let f = floor(x);
    if x - f >= 0.5lf {
        return f + 1.0lf;
    }
    return f;
}

// DepthCode::encode: infinity (no caster) and NaN give the far code.
fn code_encode(params: Params, t: f64) -> u32 {
    let n = (t - params.code_near) / params.code_span;
    if !(n == n) {
        return u32(params.code_max);
    }
    return u32(round_half_up(clamp(n, 0.0lf, 1.0lf) * params.code_max));
}
