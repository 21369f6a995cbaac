// Stage "rasterization of blockers", sample tests: one invocation per (triangle, grid cell)
// item tests every sample of the cell with the CPU's predicate
// (afsm::blockers::Blocker::shadows): inside the triangle's bounding box (counted as a test),
// not on the triangle itself, caster depth in front of the sample's threshold, and inside the
// outline by orient2d with the top-left rule. Pairs the orient2d filter cannot decide go to
// the undecided list for the CPU. In a pass with uparams.hidden set (ftizb's sub-samples but
// the centre), a shadowed sample is also marked hidden when the caster hides it from the
// camera (ftizb::hidden::hides). Appended to common.wgsl and sample.wgsl.

@group(0) @binding(0) var<storage, read> fparams: FParams;
@group(0) @binding(1) var<storage, read> uparams: UParams;
@group(0) @binding(2) var<storage, read> item_start: array<u32>;
// The triangle records of setup.wgsl.
@group(0) @binding(3) var<storage, read> blk_outline: array<BlockerOutline>;
@group(0) @binding(4) var<storage, read> blk_plane: array<BlockerPlane>;
@group(0) @binding(5) var<storage, read> blk_u: array<BlockerU>;
@group(0) @binding(6) var<storage, read> cell_start: array<u32>;
@group(0) @binding(7) var<storage, read> izb_f: array<f64>;
@group(0) @binding(8) var<storage, read> izb_u: array<u32>;
// Per pixel: bit 1 when shadowed, bit 2 when also hidden (passes with uparams.hidden set).
@group(0) @binding(9) var<storage, read_write> shadow: array<atomic<u32>>;
// [tests (low word), tests (high word), undecided pairs]
@group(0) @binding(10) var<storage, read_write> counters: array<atomic<u32>>;
// Undecided pairs (as many as the list holds): 3 f64 (x, y, threshold) and 3 u32 (pixel, sample
// triangle, caster triangle) each.
@group(0) @binding(11) var<storage, read_write> und_f: array<f64>;
@group(0) @binding(12) var<storage, read_write> und_u: array<u32>;
// The hidden test's inputs: the camera, the triangles' corners (9 f64 each) and, per pixel,
// the sub-sample's depth (the parameter of its camera ray).
@group(0) @binding(13) var<storage, read> camera_data: ProjectorData;
@group(0) @binding(14) var<storage, read> corners: array<f64>;
@group(0) @binding(15) var<storage, read> s_depth: array<f64>;

const ORIENTATION_UNDECIDED: u32 = 256u;

// raster::inside_edge with orient2d's filter: 0 outside, 1 inside, 2 undecided.
fn inside_edge(a: vec2<f64>, b: vec2<f64>, p: vec2<f64>) -> u32 {
    let detleft = (a.x - p.x) * (b.y - p.y);
    let detright = (a.y - p.y) * (b.x - p.x);
    let det = detleft - detright;
    let errbound = fparams.filter_bound * abs(detleft + detright);
    if !(det >= errbound || -det >= errbound) {
        return 2u;
    }
    if det != 0.0lf {
        return select(0u, 1u, det > 0.0lf);
    }
    let d = b - a;
    return select(0u, 1u, d.y < 0.0lf || (d.y == 0.0lf && d.x > 0.0lf));
}

fn caster_corner(t: u32, i: u32) -> vec3<f64> {
    let b = 9u * t + 3u * i;
    return vec3<f64>(corners[b], corners[b + 1u], corners[b + 2u]);
}

// ftizb::hidden::hides: whether the triangle (a, b, c) hides the point at parameter t of
// `ray` from the camera: the ray meets the closed triangle (Moller and Trumbore's test) at a
// parameter in (0, t - offset / |direction|), offset the point's shadow offset.
fn hides(ray: Ray, t: f64, offset: f64, a: vec3<f64>, b: vec3<f64>, c: vec3<f64>) -> bool {
    let e1 = b - a;
    let e2 = c - a;
    let p = cross3(ray.direction, e2);
    let det = dot3(e1, p);
    if det == 0.0lf || !is_finite64(det) {
        return false;
    }
    let inv = 1.0lf / det;
    let tv = ray.origin - a;
    let u = dot3(tv, p) * inv;
    if !(u >= 0.0lf && u <= 1.0lf) {
        return false;
    }
    let q = cross3(tv, e1);
    let v = dot3(ray.direction, q) * inv;
    if v < 0.0lf || u + v > 1.0lf {
        return false;
    }
    let hit = dot3(e2, q) * inv;
    return hit > 0.0lf && hit < t - offset / sqrt(dot3(ray.direction, ray.direction));
}

// Whether caster t hides pixel k's sub-sample (at its depth on the camera ray through it)
// from the camera.
fn hides_sample(k: u32, t: u32) -> bool {
    let ray = sample_ray(k);
    let ts = s_depth[k];
    let offset = shadow_offset(ray.origin, ray.origin + ts * ray.direction);
    return hides(ray, ts, offset, caster_corner(t, 0u), caster_corner(t, 1u), caster_corner(t, 2u));
}

@compute @workgroup_size(64)
fn test(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * (nwg.x * 64u);
    let triangles = uparams.triangles;
    if i >= item_start[triangles] {
        return;
    }
    // The triangle: the last with item_start[t] <= i.
    var lo_t = 0u;
    var hi_t = triangles;
    while hi_t - lo_t > 1u {
        let mid = (lo_t + hi_t) / 2u;
        if item_start[mid] <= i {
            lo_t = mid;
        } else {
            hi_t = mid;
        }
    }
    let t = lo_t;
    let local = i - item_start[t];
    let bu = blk_u[t];
    let flags = bu.flags;
    let count = flags & 255u;
    let undecided_triangle = (flags & ORIENTATION_UNDECIDED) != 0u;
    let x0 = bu.x0;
    let width = bu.x1 - x0 + 1u;
    let cell = (bu.y0 + local / width) * uparams.grid + x0 + local % width;
    let b = blk_outline[t];
    var outline: array<vec2<f64>, 5>;
    for (var e = 0u; e < count; e = e + 1u) {
        outline[e] = vec2<f64>(b.outline[2u * e], b.outline[2u * e + 1u]);
    }
    outline[count] = outline[0];
    let lo = vec2<f64>(b.lo[0], b.lo[1]);
    let hi = vec2<f64>(b.hi[0], b.hi[1]);
    let pl = blk_plane[t];
    let n0 = pl.num[0];
    let n1 = pl.num[1];
    let n2 = pl.num[2];
    let d0 = pl.den[0];
    let d1 = pl.den[1];
    let d2 = pl.den[2];
    let dmin = pl.dmin;
    let dmax = pl.dmax;
    var tested = 0u;
    let end = cell_start[cell + 1u];
    for (var k = cell_start[cell]; k < end; k = k + 1u) {
        let x = izb_f[3u * k];
        let y = izb_f[3u * k + 1u];
        if !(x >= lo.x && x <= hi.x && y >= lo.y && y <= hi.y) {
            continue;
        }
        tested = tested + 1u;
        let tri = izb_u[2u * k + 1u];
        if tri == t {
            continue;
        }
        // Blocker::depth_at.
        var depth = (n0 + n1 * x + n2 * y) / (d0 + d1 * x + d2 * y);
        if is_finite64(depth) {
            depth = clamp(depth, dmin, dmax);
        } else {
            depth = dmin;
        }
        let zt = izb_f[3u * k + 2u];
        if !(depth < zt) {
            continue;
        }
        var inside = 1u;
        if undecided_triangle {
            inside = 2u;
        } else {
            let q = vec2<f64>(x, y);
            for (var e = 0u; e < count; e = e + 1u) {
                let s = inside_edge(outline[e], outline[e + 1u], q);
                if s == 0u {
                    inside = 0u;
                    break;
                }
                inside = max(inside, s);
            }
        }
        let pixel = izb_u[2u * k];
        if inside == 1u {
            var mark = 1u;
            if uparams.hidden != 0u && hides_sample(pixel, t) {
                mark = 3u;
            }
            atomicOr(&shadow[pixel], mark);
        } else if inside == 2u {
            let at = atomicAdd(&counters[2], 1u);
            if at < arrayLength(&und_u) / 3u {
                und_f[3u * at] = x;
                und_f[3u * at + 1u] = y;
                und_f[3u * at + 2u] = zt;
                und_u[3u * at] = pixel;
                und_u[3u * at + 1u] = tri;
                und_u[3u * at + 2u] = t;
            }
        }
    }
    if tested > 0u {
        let old = atomicAdd(&counters[0], tested);
        if old > 0xffffffffu - tested {
            atomicAdd(&counters[1], 1u);
        }
    }
}
