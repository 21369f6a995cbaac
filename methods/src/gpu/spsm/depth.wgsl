// spsm consistent min depth (Lecocq et al. 2014, section 4, Fig. 9), second pass, one thread
// a texel: for the marked texels, spsm::depth::consistent_min_depth (the decoded triangle
// clipped to the texel square, Sutherland-Hodgman in f64, the smallest plane value at the
// clipped polygon's vertices; the conservative corner depth where the polygon is empty) and
// whether it lies above the conservative corner depth by more than the texel's own error
// bound. Needs common.wgsl, texel.wgsl and clip.wgsl before it.

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> texels: array<u32>;
@group(0) @binding(2) var<storage, read> planes: array<u32>;
@group(0) @binding(3) var<storage, read> tables: array<f64>;
// 0: not read by recovery; 1: marked; the pass writes 2 where the texel is empty.
@group(0) @binding(4) var<storage, read_write> marks: array<u32>;
@group(0) @binding(5) var<storage, read_write> depth: array<f64>;
@group(0) @binding(6) var<storage, read_write> counters: array<atomic<u32>, 8>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = gid.x + gid.y * (groups.x * 64u);
    if k >= params.res * params.res || marks[k] == 0u {
        return;
    }
    let x = k % params.res;
    let y = k / params.res;
    let t = texel_tri(i32(x), i32(y));
    if !t.ok {
        marks[k] = 2u;
        return;
    }
    let x0 = f64(x);
    let y0 = f64(y);
    let z = consistent_min_depth(t, x0, y0);
    depth[k] = z;
    let corner = conservative_depth(t, x0, y0);
    let slack = error_at(t, t.centre + vec2<f64>(0.5lf, 0.5lf));
    if z > corner + slack {
        atomicAdd(&counters[0], 1u);
    }
}
