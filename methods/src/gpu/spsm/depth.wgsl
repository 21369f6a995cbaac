// spsm consistent min depth (Lecocq et al. 2014, section 4, Fig. 9), second pass, one thread
// a texel: for the marked texels, spsm::depth::consistent_min_depth (the decoded triangle
// clipped to the texel square, Sutherland-Hodgman in f64, the smallest plane value at the
// clipped polygon's vertices; the conservative corner depth where the polygon is empty) and
// whether it lies above the conservative corner depth by more than the texel's own error
// bound. Needs common.wgsl and texel.wgsl before it.

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> texels: array<u32>;
@group(0) @binding(2) var<storage, read> planes: array<u32>;
@group(0) @binding(3) var<storage, read> tables: array<f64>;
// 0: not read by recovery; 1: marked; the pass writes 2 where the texel is empty.
@group(0) @binding(4) var<storage, read_write> marks: array<u32>;
@group(0) @binding(5) var<storage, read_write> depth: array<f64>;
@group(0) @binding(6) var<storage, read_write> counters: array<atomic<u32>, 8>;

fn conservative_depth(t: Tri, x: f64, y: f64) -> f64 {
    var cx = x + 1.0lf;
    if t.dz.x > 0.0lf {
        cx = x;
    }
    var cy = y + 1.0lf;
    if t.dz.y > 0.0lf {
        cy = y;
    }
    let z0 = depth_at(t, t.v[0]);
    let z1 = depth_at(t, t.v[1]);
    let z2 = depth_at(t, t.v[2]);
    let lo = min(min(z0, z1), z2);
    let hi = max(max(z0, z1), z2);
    let d = depth_at(t, vec2<f64>(cx, cy));
    // f64::clamp: the bounds are ordered, and a NaN stays NaN.
    if d < lo {
        return lo;
    }
    if d > hi {
        return hi;
    }
    return d;
}

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
    var poly: array<vec2<f64>, 7>;
    poly[0] = t.v[0];
    poly[1] = t.v[1];
    poly[2] = t.v[2];
    var n = 3u;
    for (var side = 0u; side < 4u; side++) {
        let axis = side / 2u;
        var bound = y0;
        if axis == 0u {
            bound = x0;
        }
        var sign = 1.0lf;
        if side % 2u == 1u {
            bound = bound + 1.0lf;
            sign = -1.0lf;
        }
        var clipped: array<vec2<f64>, 7>;
        var m = 0u;
        for (var i = 0u; i < n; i++) {
            let a = poly[i];
            let b = poly[(i + 1u) % n];
            let da = sign * (a[axis] - bound);
            let db = sign * (b[axis] - bound);
            if da >= 0.0lf && m < 7u {
                clipped[m] = a;
                m += 1u;
            }
            if (da >= 0.0lf) != (db >= 0.0lf) && m < 7u {
                let s = da / (da - db);
                var p = a + (b - a) * s;
                p[axis] = bound;
                clipped[m] = p;
                m += 1u;
            }
        }
        poly = clipped;
        n = m;
        if n == 0u {
            break;
        }
    }
    let corner = conservative_depth(t, x0, y0);
    var z = corner;
    if n > 0u {
        z = depth_at(t, poly[0]);
        for (var i = 1u; i < n; i++) {
            z = min(z, depth_at(t, poly[i]));
        }
    }
    depth[k] = z;
    let slack = error_at(t, t.centre + vec2<f64>(0.5lf, 0.5lf));
    if z > corner + slack {
        atomicAdd(&counters[0], 1u);
    }
}
