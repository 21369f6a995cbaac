// spsm::classify::Lookup on the GPU: the map point of a surface point, the exact containment
// tests through orient2d's f64 filter, the receiver's gradient and its plane's quantization
// bound, lies_on and intersects; in f64 with the CPU's operations in the CPU's order. Needs
// common.wgsl, texel.wgsl and encode.wgsl before it and, in the kernel, the bindings
// `params`, `light` and `tables`.
//
// The CPU's orient2d is exact (robust crate); here its f64 filter decides when the CPU's does
// (then both return the same f64 determinant) and `undecided` is set otherwise: the kernel
// hands the pixel back to the CPU code.

var<private> undecided: bool;

// classify::MapPoint, but `facing` (faces_light: recovery alone reads it).
struct MapPoint {
    xy: vec2<f64>,
    depth: f64,
    z: f64,
    tol: f64,
    position: vec3<f64>,
    normal: vec3<f64>,
}

// glam's normalize_or.
fn normalize_or(v: vec3<f64>, fallback: vec3<f64>) -> vec3<f64> {
    let rcp = 1.0lf / sqrt(dot3(v, v));
    if is_finite64(rcp) && rcp > 0.0lf {
        return v * rcp;
    }
    return fallback;
}

// Lookup::point: `ok` false where the point does not project.
struct Mapped {
    p: MapPoint,
    ok: bool,
}

fn map_point(position: vec3<f64>, normal: vec3<f64>) -> Mapped {
    var m: Mapped;
    m.ok = false;
    let proj = proj_load(light);
    let r = proj_project(proj, position);
    if r.w == 0.0lf {
        return m;
    }
    var tol = params.constant;
    if params.perspective == 1u {
        tol = params.constant / (r.z * r.z);
    }
    m.p = MapPoint(r.xy, r.z, space_z(r.z), tol, position, normal);
    m.ok = true;
    return m;
}

// MapPoint::facing: whether the surface at `p` faces the light (Projector::direction_to).
fn faces_light(p: MapPoint) -> bool {
    let proj = proj_load(light);
    var towards = -proj.forward;
    if proj.kind == 1u {
        towards = normalize_or(proj.origin - p.position, -proj.forward);
    }
    return dot3(p.normal, towards) > 0.0lf;
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
    if !(is_finite64(g.x) && is_finite64(g.y)) {
        return vec3<f64>(0.0lf, 0.0lf, 0.0lf);
    }
    return vec3<f64>(g, 1.0lf);
}

// SpsmMap::plane_error: the quantization bound of a plane of gradient `g` at map depth `z` in
// a texel of this map, at the texel's centre (x) and per texel away from it (y, z).
fn plane_error(z: f64, g: vec2<f64>) -> vec3<f64> {
    if params.packed == 1u {
        let k = slope_scale(z);
        return vec3<f64>(
            0.5lf * params.depth_step,
            tables[256u + encode(g.x / k.x)] * k.x,
            tables[256u + encode(g.y / k.y)] * k.y,
        );
    }
    return vec3<f64>(abs(z) * params.half_ulp, abs(g.x) * params.half_ulp, abs(g.y) * params.half_ulp);
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
    let e = plane_error(p.z, g.xy);
    let d = abs(p.xy - t.centre);
    return err <= p.tol + e.x + (d.x * e.y + d.y * e.z);
}

// neighbourhood::NEIGHBOURHOOD: the ring (neighbourhood::RING), then the centre.
const NEIGHBOURHOOD = array<vec2<i32>, 9>(
    vec2<i32>(-1, -1), vec2<i32>(0, -1), vec2<i32>(1, -1), vec2<i32>(1, 0),
    vec2<i32>(1, 1), vec2<i32>(0, 1), vec2<i32>(-1, 1), vec2<i32>(-1, 0), vec2<i32>(0, 0),
);

