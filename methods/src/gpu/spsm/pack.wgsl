// Stage "packing" (spsm::texel::pack_map) on the GPU, one invocation per texel: the texel's
// triangle (from the conservative map) stored as the CPU stores it. `pack_packed`: the
// triangle's three vertex words and, per texel, the 16-bit depth code of the plane at the
// texel's centre and the two 8-bit derivative codes (the triangle's when the light is
// orthographic, else taken at the decoded depth, through the code's thresholds, encode.wgsl);
// `pack_f32`: vertices, centre depth and derivatives rounded to f32.

// The map's resolution.
@group(0) @binding(0) var<storage, read> res: u32;
@group(0) @binding(1) var<storage, read> fparams: PackParams;
// Per prepared triangle (setup.wgsl), as raster.wgsl reads them.
@group(0) @binding(2) var<storage, read> setups: array<SetupData>;
// Per prepared triangle: vertex words R, G, B and its derivative codes (qx << 8 | qy), or
// NO_CODES when they depend on the texel's depth.
@group(0) @binding(3) var<storage, read> tri_words: array<u32>;
// Per texel: the prepared triangle, NONE where none.
@group(0) @binding(4) var<storage, read> texel: array<u32>;
// The derivative code's tables (texel::code_tables; encode.wgsl reads the thresholds).
@group(0) @binding(5) var<storage, read> tables: array<f64>;
// Packed: four words a texel. F32: the six vertex coordinates' f32 bits.
@group(0) @binding(6) var<storage, read_write> out_words: array<u32>;
// F32: the depth's and derivatives' f32 bits (three a texel).
@group(0) @binding(7) var<storage, read_write> out_planes: array<u32>;

// pack::PackParams: the light space's depth origin and step, and its texel's world size at
// unit depth (LightSpace::slope_scale).
struct PackParams {
    z_lo: f64,
    depth_step: f64,
    size_x: f64,
    size_y: f64,
}

const NONE: u32 = 0xffffffffu;
const NO_CODES: u32 = 0xffffffffu;
const F32_NAN: u32 = 0x7fc00000u;
const MIN_POSITIVE: f64 = 2.2250738585072014e-308lf;

fn bind_all() {
    _ = res;
    _ = fparams.z_lo;
    _ = setups[0];
    _ = tri_words[0];
    _ = texel[0];
    _ = tables[0];
    _ = arrayLength(&out_words);
    _ = arrayLength(&out_planes);
}

// `v`, through a choice the compiler cannot see through (see raster.wgsl's `kept`).
fn kept(v: f64) -> f64 {
    return select(v, 0.0lf, res == 0u);
}

// f64::round: halves away from zero (WGSL's round takes them to even).
fn round_away(x: f64) -> f64 {
    let t = trunc(x);
    if abs(x - t) >= 0.5lf {
        return t + sign(x);
    }
    return t;
}

// TriSetup::plane at the centre of texel k.
fn centre_depth(s: u32, k: u32) -> f64 {
    let t = setups[s];
    let cx = f64(k % res) + 0.5lf;
    let cy = f64(k / res) + 0.5lf;
    return t.z[0] + kept((cx - t.v[0]) * t.dz[0] + (cy - t.v[1]) * t.dz[1]);
}

// Packer::depth_code.
fn depth_code(z: f64) -> u32 {
    let s = fparams.depth_step;
    if s <= 0.0lf {
        return 0u;
    }
    let q = round_away((z - fparams.z_lo) / s);
    if q != q {
        return 0u;
    }
    return u32(min(max(q, 0.0lf), 65535.0lf));
}

@compute @workgroup_size(64)
fn pack_packed(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    bind_all();
    let k = gid.x + gid.y * (groups.x * 64u);
    if k >= res * res { return; }
    let s = texel[k];
    if s == NONE {
        for (var w = 0u; w < 4u; w++) {
            out_words[4u * k + w] = 0xffffffffu;
        }
        return;
    }
    let zq = depth_code(centre_depth(s, k));
    var codes = tri_words[4u * s + 3u];
    if codes == NO_CODES {
        // Packer::derivative_codes at the decoded depth, through LightSpace::slope_scale.
        let z = fparams.z_lo + kept(f64(zq) * fparams.depth_step);
        let m = max(-z, MIN_POSITIVE);
        let kx = fparams.size_x * m;
        let ky = fparams.size_y * m;
        codes = (encode(setups[s].dz[0] / kx) << 8u) | encode(setups[s].dz[1] / ky);
    }
    for (var w = 0u; w < 3u; w++) {
        out_words[4u * k + w] = tri_words[4u * s + w];
    }
    out_words[4u * k + 3u] = (zq << 16u) | codes;
}

@compute @workgroup_size(64)
fn pack_f32(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    bind_all();
    let k = gid.x + gid.y * (groups.x * 64u);
    if k >= res * res { return; }
    let s = texel[k];
    if s == NONE {
        for (var w = 0u; w < 6u; w++) {
            out_words[6u * k + w] = 0u;
        }
        out_planes[3u * k] = F32_NAN;
        out_planes[3u * k + 1u] = 0u;
        out_planes[3u * k + 2u] = 0u;
        return;
    }
    let t = setups[s];
    for (var w = 0u; w < 6u; w++) {
        out_words[6u * k + w] = bitcast<u32>(f32(setups[s].v[w]));
    }
    out_planes[3u * k] = bitcast<u32>(f32(centre_depth(s, k)));
    out_planes[3u * k + 1u] = bitcast<u32>(f32(t.dz[0]));
    out_planes[3u * k + 2u] = bitcast<u32>(f32(t.dz[1]));
}
