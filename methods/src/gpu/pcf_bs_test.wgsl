// Brabec and Seidel, one shadow-test pass (pcf_bs::shadow_test): the point's code against the
// four codes of the packed texel it looks up; the lit count is added into the pixel's
// accumulator and the lit fraction rewritten from it. Needs common.wgsl, receiver.wgsl and
// counters.wgsl before it.

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> light: array<f64, 18>;
@group(0) @binding(2) var<storage, read> g_triangle: array<u32>;
@group(0) @binding(3) var<storage, read> g_position: array<f64>;
@group(0) @binding(4) var<storage, read> g_normal: array<f64>;
@group(0) @binding(5) var<storage, read> packed: array<vec4<u32>>;
@group(0) @binding(6) var<storage, read_write> accumulator: array<u32>;
@group(0) @binding(7) var<storage, read_write> lit: array<f32>;
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>, 4>;

@compute @workgroup_size(64)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let k = gid.x + gid.y * (groups.x * 64u);
    var compares = 0u;
    if k < params.pixels {
        var add = 4u;
        if g_triangle[k] != NO_TRIANGLE {
            let p = vec3<f64>(g_position[3u * k], g_position[3u * k + 1u], g_position[3u * k + 2u]);
            let n = vec3<f64>(g_normal[3u * k], g_normal[3u * k + 1u], g_normal[3u * k + 2u]);
            let r = receiver(proj_load(light), p, n, params.max_slope);
            if r.ok {
                // pcf_bs::lookup_index, then PackedMap::get.
                var q = r.xy;
                if params.half_offset == 1u {
                    q = r.xy - vec2<f64>(0.5lf);
                }
                let x = floor(q.x) - f64(params.origin);
                let y = floor(q.y) - f64(params.origin);
                let s = f64(params.side);
                if x >= 0.0lf && y >= 0.0lf && x < s && y < s {
                    let texel = packed[u32(y) * params.side + u32(x)];
                    let code = f64(code_encode(params, r.depth));
                    let depth_tol = tolerance(params, r, vec2<f64>(params.reach, params.reach));
                    let threshold = code - depth_tol / params.code_span * params.code_max;
                    add = 0u;
                    for (var c = 0u; c < 4u; c++) {
                        if f64(texel[c]) >= threshold {
                            add += 1u;
                        }
                    }
                    compares = 4u;
                }
            }
        }
        let acc = accumulator[k] + add;
        accumulator[k] = acc;
        lit[k] = f32(min(f64(acc) / f64(params.levels), 1.0lf));
    }
    count(local, compares, 0u);
}
