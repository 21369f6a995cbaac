// Stage "silhouette mask map" (mask_map::silhouette_mask with mask_map::HiddenDepths), one
// invocation per silhouette edge: the texels its projection touches, each unless the edge is
// hidden there behind all nine depth-map surfaces around the texel. The hidden depths are
// computed where needed instead of remembered (same values).

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> edges: array<f64>;
@group(0) @binding(2) var<storage, read> count: array<u32>;
@group(0) @binding(3) var<storage, read> depth: array<f64>;
@group(0) @binding(4) var<storage, read> map_triangle: array<u32>;
@group(0) @binding(5) var<storage, read> corners: array<f64>;
@group(0) @binding(6) var<storage, read_write> marks: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> counters: array<atomic<u32>>;

const EDGE_MARGIN: f64 = 1e-7lf;

fn corner(t: u32, i: u32) -> vec3<f64> {
    let o = 9u * t + 3u * i;
    return vec3<f64>(corners[o], corners[o + 1u], corners[o + 2u]);
}

// HiddenDepths::reach: depth plus tolerance (reach 1.5 texels) of texel k's surface.
fn reach(s: Setup, k: u32) -> f64 {
    let z = depth[k];
    let t = map_triangle[k];
    if t == NO_TRIANGLE || !is_finite64(z) { return s.inf; }
    let xy = vec2<f64>(f64(k % s.res) + 0.5lf, f64(k / s.res) + 0.5lf);
    let a = corner(t, 0u);
    let normal = normalize_or_zero(cross3(corner(t, 1u) - a, corner(t, 2u) - a));
    let ray = proj_ray(s.light, xy);
    let r = receiver(s, ray.origin + z * ray.direction, normal);
    if !r.ok { return s.inf; }
    return z + (s.constant + s.slope_bias * (1.5lf * r.slope.x + 1.5lf * r.slope.y));
}

// HiddenDepths::get.
fn hidden(s: Setup, x: u32, y: u32) -> f64 {
    if x == 0u || y == 0u || x + 1u >= s.res || y + 1u >= s.res { return s.inf; }
    var d = -s.inf;
    for (var j = y - 1u; j <= y + 1u; j++) {
        for (var i = x - 1u; i <= x + 1u; i++) {
            d = fmax64(d, reach(s, j * s.res + i));
        }
    }
    return d;
}

fn depth_at(p: bool, d0: f64, d1: f64, t: f64) -> f64 {
    if p { return 1.0lf / (1.0lf / d0 + t * (1.0lf / d1 - 1.0lf / d0)); }
    return d0 + t * (d1 - d0);
}

// `v.floor().clamp(0.0, r - 1.0) as usize` (NaN gives 0).
fn col(v: f64, r: f64) -> u32 {
    let f = floor(v);
    if isnan64(f) { return 0u; }
    return to_index(min(f, r - 1.0lf), 4e9lf);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let e = flat_index(gid, groups);
    if e >= count[0] { return; }
    let s = setup();
    var a = vec3<f64>(edges[6u * e], edges[6u * e + 1u], edges[6u * e + 2u]);
    var b = vec3<f64>(edges[6u * e + 3u], edges[6u * e + 4u], edges[6u * e + 5u]);
    let perspective = s.light.kind == 1u;
    if perspective {
        let da = proj_depth_of(s.light, a);
        let db = proj_depth_of(s.light, b);
        if da < s.light.near && db < s.light.near { return; }
        let c = clip_near(array<vec3<f64>, 3>(a, b, b), array<f64, 3>(da, db, db), s.light.near);
        let first = c.p[0];
        var last = first;
        for (var i = 0u; i < c.n; i++) {
            if any(c.p[i] != first) {
                last = c.p[i];
                break;
            }
        }
        a = first;
        b = last;
    }
    let qa = proj_unclipped(s.light, a);
    let qb = proj_unclipped(s.light, b);
    if !(finite3(qa) && finite3(qb)) { return; }
    let p0 = qa.xy;
    let p1 = qb.xy;
    let lo = vmin2(p0, p1);
    let hi = vmax2(p0, p1);
    let r = f64(s.res);
    if hi.x < -EDGE_MARGIN || hi.y < -EDGE_MARGIN || lo.x > r + EDGE_MARGIN || lo.y > r + EDGE_MARGIN {
        return;
    }
    for (var x = col(lo.x - EDGE_MARGIN, r); x <= col(hi.x + EDGE_MARGIN, r); x++) {
        let cl = clip_segment(p0, p1, vec2<f64>(f64(x), 0.0lf), vec2<f64>(f64(x) + 1.0lf, r), EDGE_MARGIN);
        if cl.z == 0.0lf { continue; }
        let y0 = p0.y + cl.x * (p1.y - p0.y);
        let y1 = p0.y + cl.y * (p1.y - p0.y);
        for (var y = col(fmin64(y0, y1) - EDGE_MARGIN, r); y <= col(fmax64(y0, y1) + EDGE_MARGIN, r); y++) {
            let k = y * s.res + x;
            if atomicLoad(&marks[k]) != 0u { continue; }
            let lo_t = vec2<f64>(f64(x), f64(y));
            let u = clip_segment(p0, p1, lo_t, lo_t + vec2<f64>(1.0lf, 1.0lf), EDGE_MARGIN);
            if u.z == 0.0lf { continue; }
            let nearest = fmin64(depth_at(perspective, qa.z, qb.z, u.x), depth_at(perspective, qa.z, qb.z, u.y));
            if nearest <= hidden(s, x, y) || isnan64(nearest) {
                if atomicExchange(&marks[k], 1u) == 0u {
                    atomicAdd(&counters[C_SILHOUETTE_TEXELS], 1u);
                }
            }
        }
    }
}
