// Brabec and Seidel, one shadow-test pass (pcf_bs::shadow_test): the point's code against the
// four codes of the packed texel it looks up; the lit count is added into the pixel's
// accumulator and the lit fraction rewritten from it. After pixel.wgsl (its bindings 0 to
// 4) and counters.wgsl.

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
    let k = pixel_index(gid, groups);
    var compares = 0u;
    if k < params.pixels {
        var add = 4u;
        let r = pixel_receiver(k);
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
        let acc = accumulator[k] + add;
        accumulator[k] = acc;
        lit[k] = f32(min(f64(acc) / f64(params.levels), 1.0lf));
    }
    count(local, compares, 0u);
}
