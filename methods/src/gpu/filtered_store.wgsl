// The filtered maps' stored values: one thread a texel, the method's store (its WGSL, after
// filtered.wgsl) of the texel's normalised depth (filtered_map::normalised_depth), N values
// of n written.

@group(0) @binding(0) var<uniform> fparams: FParams;
@group(0) @binding(1) var<storage, read> map_depth: array<f64>;
@group(0) @binding(2) var<storage, read_write> stored: array<f64>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let t = flat_index(gid, groups);
    if t >= fparams.texels {
        return;
    }
    let d = map_depth[t];
    var z = 1.0lf;
    if is_finite64(d) {
        // f64::clamp(0, 1).
        z = (d - fparams.near) / fparams.range;
        if z < 0.0lf {
            z = 0.0lf;
        }
        if z > 1.0lf {
            z = 1.0lf;
        }
    }
    let v = store(z);
    for (var i = 0u; i < fparams.n; i++) {
        stored[fparams.n * t + i] = v[i];
    }
}
