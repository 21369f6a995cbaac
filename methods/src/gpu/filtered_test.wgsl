// The filtered maps' test (filtered_map::run's second stage) of every G-buffer pixel, one
// thread a pixel: the receiver's normalised depth after the bias tolerance with the filter's
// reach, the method's test (its WGSL) of its texel's filtered values, lit_value. After
// pixel.wgsl (its bindings 0 to 4), counters.wgsl and filtered.wgsl.

@group(0) @binding(5) var<uniform> fparams: FParams;
@group(0) @binding(6) var<storage, read> filtered: array<f64>;
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
        var v = 1.0f;
        let r = pixel_receiver(k);
        if r.ok {
            let t = texel_at(r.xy, params.res);
            if t >= 0 {
                compares = 1u;
                let reach = vec2<f64>(params.reach, params.reach);
                let z = (r.depth - tolerance(params, r, reach) - fparams.near) / fparams.range;
                let n = fparams.n;
                var values = array<f64, 4>(0.0lf, 0.0lf, 0.0lf, 0.0lf);
                for (var c = 0u; c < n; c++) {
                    values[c] = filtered[n * u32(t) + c];
                }
                v = lit_value(test(values, z));
            }
        }
        lit[k] = v;
    }
    count(local, compares, 0u);
}
