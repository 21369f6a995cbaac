// Stage "depth test" of the non-silhouette pixels (sm::depth_test): the texel the surface
// point falls in against its depth less the tolerance (reach half a texel). Writes every
// pixel's lit value (1 for lit and silhouette pixels; the occlusion ratio overwrites those).

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> g_position: array<f64>;
@group(0) @binding(2) var<storage, read> g_normal: array<f64>;
@group(0) @binding(3) var<storage, read> pixel_class: array<u32>;
@group(0) @binding(4) var<storage, read> depth: array<f64>;
@group(0) @binding(5) var<storage, read_write> lit: array<f32>;
@group(0) @binding(6) var<storage, read_write> counters: array<atomic<u32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = flat_index(gid, groups);
    if k >= arrayLength(&pixel_class) { return; }
    var l = 1.0;
    if pixel_class[k] == 1u {
        let s = setup();
        let position = vec3<f64>(g_position[3u * k], g_position[3u * k + 1u], g_position[3u * k + 2u]);
        let normal = vec3<f64>(g_normal[3u * k], g_normal[3u * k + 1u], g_normal[3u * k + 2u]);
        let r = receiver(s, position, normal);
        if r.ok {
            let x = floor(r.xy.x);
            let y = floor(r.xy.y);
            let res = f64(s.res);
            if x >= 0.0lf && y >= 0.0lf && x < res && y < res {
                let stored = depth[u32(y) * s.res + u32(x)];
                let tolerance = s.constant + s.slope_bias * (0.5lf * r.slope.x + 0.5lf * r.slope.y);
                if stored < r.depth - tolerance {
                    l = 0.0;
                }
                atomicAdd(&counters[C_LOOKUPS], 1u);
            }
        }
    }
    lit[k] = l;
}
