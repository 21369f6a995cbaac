// sm: the standard depth test (sm::depth_test) of every G-buffer pixel, one thread a pixel.
// After pixel.wgsl (its bindings 0 to 4) and counters.wgsl.

@group(0) @binding(5) var<storage, read> map_depth: array<f64>;
@group(0) @binding(6) var<storage, read_write> lit: array<f32>;
@group(0) @binding(7) var<storage, read_write> counters: array<atomic<u32>, 4>;

@compute @workgroup_size(64)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let k = pixel_index(gid, groups);
    var compares = 0u;
    if k < params.pixels {
        var v = 1.0f;
        let r = pixel_receiver(k);
        if r.ok {
            let t = texel_at(r.xy, params.res);
            if t >= 0 {
                compares = 1u;
                let reach = vec2<f64>(params.reach, params.reach);
                if map_depth[t] < r.depth - tolerance(params, r, reach) {
                    v = 0.0f;
                }
            }
        }
        lit[k] = v;
    }
    count(local, compares, 0u);
}
