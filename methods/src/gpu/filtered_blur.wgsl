// One pass of filtered_map::box_filter: one thread a texel, the sum of the filter's texels
// along one axis (the border repeated), in order, times the weight.

@group(0) @binding(0) var<uniform> fparams: FParams;
@group(0) @binding(1) var<storage, read> src: array<f64>;
@group(0) @binding(2) var<storage, read_write> dst: array<f64>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = flat_index(gid, groups);
    if i >= fparams.texels {
        return;
    }
    let x = i32(i % fparams.res);
    let y = i32(i / fparams.res);
    let h = i32(fparams.half);
    let last = i32(fparams.res) - 1;
    let n = fparams.n;
    var sum = array<f64, 4>(0.0lf, 0.0lf, 0.0lf, 0.0lf);
    for (var k = -h; k <= h; k++) {
        var sx = x;
        var sy = y;
        if fparams.along_rows == 1u {
            sx = clamp(x + k, 0, last);
        } else {
            sy = clamp(y + k, 0, last);
        }
        let s = u32(sy) * fparams.res + u32(sx);
        for (var c = 0u; c < n; c++) {
            sum[c] = sum[c] + src[n * s + c];
        }
    }
    for (var c = 0u; c < n; c++) {
        dst[n * i + c] = sum[c] * fparams.weight;
    }
}
