// spsm classification (Lecocq et al. 2014, section 4.1, Algorithm 1), one thread a pixel:
// spsm::classify::Lookup::classify with the texels decoded as spsm::texel decodes them, in f64
// with the CPU's operations in the CPU's order. Needs common.wgsl and texel.wgsl before it.
//
// The CPU's orient2d is exact (robust crate); here its f64 filter decides when the CPU's does
// (then both return the same f64 determinant) and the pixel is handed back (class 5) otherwise.

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> light: ProjectorData;
@group(0) @binding(2) var<storage, read> g_triangle: array<u32>;
@group(0) @binding(3) var<storage, read> g_position: array<f64>;
@group(0) @binding(4) var<storage, read> g_normal: array<f64>;
// The texels (texel.wgsl).
@group(0) @binding(5) var<storage, read> texels: array<u32>;
@group(0) @binding(6) var<storage, read> planes: array<u32>;
// [0, 256): decoded slopes; [256, 512): their error bounds; [512, 768): encode thresholds.
@group(0) @binding(7) var<storage, read> tables: array<f64>;
// Per pixel: class, texel.
@group(0) @binding(8) var<storage, read_write> result: array<u32>;
// lit by one lookup, shadowed by one lookup, by the neighbourhood, uncertain, lookups,
// handed back.
@group(0) @binding(9) var<storage, read_write> counters: array<atomic<u32>, 8>;

var<private> undecided: bool;

struct MapPoint {
    xy: vec2<f64>,
    depth: f64,
    z: f64,
    tol: f64,
    position: vec3<f64>,
    normal: vec3<f64>,
}

// robust::orient2d where its filter decides; else flags the pixel undecided.
fn orient2d(a: vec2<f64>, b: vec2<f64>, c: vec2<f64>) -> f64 {
    let detleft = (a.x - c.x) * (b.y - c.y);
    let detright = (a.y - c.y) * (b.x - c.x);
    let det = detleft - detright;
    let detsum = abs(detleft + detright);
    let errbound = THETA * detsum;
    if det >= errbound || -det >= errbound {
        return det;
    }
    undecided = true;
    return 0.0lf;
}

fn space_z(d: f64) -> f64 {
    if params.perspective == 1u {
        return -1.0lf / d;
    }
    return d;
}

// Tri::contains_within (undecided orientations end it, flagged).
fn contains_within(t: Tri, q: vec2<f64>, margin: f64) -> bool {
    let o = orient2d(t.v[0], t.v[1], t.v[2]);
    if undecided || o == 0.0lf {
        return false;
    }
    let sign = select(-1.0lf, 1.0lf, o > 0.0lf);
    for (var e = 0; e < 3; e++) {
        let a = t.v[e];
        let b = t.v[(e + 1) % 3];
        let s = orient2d(a, b, q) * sign;
        if undecided {
            return false;
        }
        if margin == 0.0lf {
            if !(s >= 0.0lf) {
                return false;
            }
        } else {
            let d = b - a;
            if !(s >= margin * sqrt(d.x * d.x + d.y * d.y)) {
                return false;
            }
        }
    }
    return true;
}

const SQRT_2: f64 = 1.4142135623730951lf;

fn intersects(t: Tri, p: MapPoint) -> bool {
    return depth_at(t, p.xy) < p.z - p.tol - error_at(t, p.xy)
        && contains_within(t, p.xy, t.err_v * SQRT_2);
}


fn is_finite(x: f64) -> bool {
    return abs(x) <= 1.7976931348623157e308lf;
}

// Lookup::gradient; w = 0 where None.
fn gradient(p: MapPoint) -> vec3<f64> {
    let n = p.normal;
    let neg = n.z < 0.0lf || (n.z == 0.0lf && 1.0lf / n.z < 0.0lf);
    let sign = select(1.0lf, -1.0lf, neg);
    let a = -1.0lf / (sign + n.z);
    let b = n.x * n.y * a;
    let t1 = vec3<f64>(1.0lf + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let t2 = vec3<f64>(b, sign + n.y * n.y * a, -n.y);
    var size = vec2<f64>(params.size_x, params.size_y);
    if params.perspective == 1u {
        size = vec2<f64>(params.size_x * abs(p.depth), params.size_y * abs(p.depth));
    }
    let s = max(size.x, size.y);
    let proj = proj_load(light);
    let r1 = proj_project(proj, p.position + t1 * s);
    if r1.w == 0.0lf {
        return vec3<f64>(0.0lf, 0.0lf, 0.0lf);
    }
    let r2 = proj_project(proj, p.position + t2 * s);
    if r2.w == 0.0lf {
        return vec3<f64>(0.0lf, 0.0lf, 0.0lf);
    }
    let qa = r1.xy - p.xy;
    let qb = r2.xy - p.xy;
    let z1 = space_z(r1.z) - p.z;
    let z2 = space_z(r2.z) - p.z;
    let det = qa.x * qb.y - qa.y * qb.x;
    let g = vec2<f64>((z1 * qb.y - z2 * qa.y) / det, (qa.x * z2 - qb.x * z1) / det);
    if !(is_finite(g.x) && is_finite(g.y)) {
        return vec3<f64>(0.0lf, 0.0lf, 0.0lf);
    }
    return vec3<f64>(g, 1.0lf);
}

// Lookup::lies_on.
fn lies_on(t: Tri, p: MapPoint) -> bool {
    let err = error_at(t, p.xy);
    if abs(depth_at(t, p.xy) - p.z) > p.tol + err {
        return false;
    }
    if contains_within(t, p.xy, -t.err_v * SQRT_2) {
        return true;
    }
    let g = gradient(p);
    if g.z == 0.0lf {
        return false;
    }
    // SpsmMap::plane_error.
    var at_centre: f64;
    var per_texel: vec2<f64>;
    if params.packed == 1u {
        let k = slope_scale(p.z);
        at_centre = 0.5lf * params.depth_step;
        per_texel = vec2<f64>(
            tables[256u + encode(g.x / k.x)] * k.x,
            tables[256u + encode(g.y / k.y)] * k.y,
        );
    } else {
        at_centre = abs(p.z) * params.half_ulp;
        per_texel = vec2<f64>(abs(g.x) * params.half_ulp, abs(g.y) * params.half_ulp);
    }
    let d = abs(p.xy - t.centre);
    return err <= p.tol + at_centre + (d.x * per_texel.x + d.y * per_texel.y);
}

const RING = array<vec2<i32>, 8>(
    vec2<i32>(-1, -1), vec2<i32>(0, -1), vec2<i32>(1, -1), vec2<i32>(1, 0),
    vec2<i32>(1, 1), vec2<i32>(0, 1), vec2<i32>(-1, 1), vec2<i32>(-1, 0),
);

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = gid.x + gid.y * (groups.x * 64u);
    if k >= params.pixels {
        return;
    }
    undecided = false;
    var cls = 0u;
    var lookups = 0u;
    var texel = 0u;
    if g_triangle[k] != NO_TRIANGLE {
        let position = vec3<f64>(g_position[3u * k], g_position[3u * k + 1u], g_position[3u * k + 2u]);
        let normal = vec3<f64>(g_normal[3u * k], g_normal[3u * k + 1u], g_normal[3u * k + 2u]);
        let r = proj_project(proj_load(light), position);
        if r.w != 0.0lf {
            var tol = params.constant;
            if params.perspective == 1u {
                tol = params.constant / (r.z * r.z);
            }
            let p = MapPoint(r.xy, r.z, space_z(r.z), tol, position, normal);
            let fx = floor(p.xy.x);
            let fy = floor(p.xy.y);
            let res = f64(params.res);
            if fx >= 0.0lf && fy >= 0.0lf && fx < res && fy < res {
                let x = i32(fx);
                let y = i32(fy);
                texel = u32(y) * params.res + u32(x);
                lookups = 1u;
                let t = texel_tri(x, y);
                if !t.ok || lies_on(t, p) {
                    cls = 1u;
                } else if intersects(t, p) {
                    cls = 2u;
                } else {
                    cls = 4u;
                    for (var i = 0; i < 8; i++) {
                        lookups += 1u;
                        let n = texel_tri(x + RING[i].x, y + RING[i].y);
                        if n.ok && intersects(n, p) {
                            cls = 3u;
                            break;
                        }
                    }
                }
            }
        }
    }
    if undecided {
        cls = 5u;
        atomicAdd(&counters[5], 1u);
    } else {
        if cls >= 1u {
            atomicAdd(&counters[cls - 1u], 1u);
        }
        atomicAdd(&counters[4], lookups);
    }
    result[2u * k] = cls;
    result[2u * k + 1u] = texel;
}
