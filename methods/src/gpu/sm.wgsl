// sm: the standard depth test (sm::depth_test) of every G-buffer pixel, one thread a pixel.
// Needs common.wgsl, receiver.wgsl and counters.wgsl before it.

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> light: array<f64, 18>;
@group(0) @binding(2) var<storage, read> g_triangle: array<u32>;
@group(0) @binding(3) var<storage, read> g_position: array<f64>;
@group(0) @binding(4) var<storage, read> g_normal: array<f64>;
@group(0) @binding(5) var<storage, read> map_depth: array<f64>;
@group(0) @binding(6) var<storage, read_write> lit: array<f32>;
@group(0) @binding(7) var<storage, read_write> counters: array<atomic<u32>, 4>;

@compute @workgroup_size(64)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let k = gid.x + gid.y * (groups.x * 64u);
    var compares = 0u;
    if k < params.pixels {
        var v = 1.0f;
        if g_triangle[k] != NO_TRIANGLE {
            let p = vec3<f64>(g_position[3u * k], g_position[3u * k + 1u], g_position[3u * k + 2u]);
            let n = vec3<f64>(g_normal[3u * k], g_normal[3u * k + 1u], g_normal[3u * k + 2u]);
            let r = receiver(proj_load(light), p, n, params.max_slope);
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
        }
        lit[k] = v;
    }
    count(local, compares, 0u);
}
