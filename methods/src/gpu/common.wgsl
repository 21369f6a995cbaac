// Shared by every kernel: the projector of scenes::projection in f64, with the CPU's
// operations in the CPU's order (glam's dot is ((x*x') + (y*y')) + (z*z')).

const NO_TRIANGLE: u32 = 0xffffffffu;

struct Proj {
    origin: vec3<f64>,
    right: vec3<f64>,
    up: vec3<f64>,
    forward: vec3<f64>,
    // 0: orthographic (a, b = half width, half height); 1: perspective (a, b = tan half x, y).
    kind: u32,
    a: f64,
    b: f64,
    near: f64,
    width: f64,
    height: f64,
}

fn proj_load(v: array<f64, 18>) -> Proj {
    return Proj(
        vec3<f64>(v[0], v[1], v[2]),
        vec3<f64>(v[3], v[4], v[5]),
        vec3<f64>(v[6], v[7], v[8]),
        vec3<f64>(v[9], v[10], v[11]),
        u32(v[12]),
        v[13], v[14], v[15], v[16], v[17],
    );
}

fn dot3(a: vec3<f64>, b: vec3<f64>) -> f64 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

// Projector::project_unclipped: (x, y, depth).
fn proj_unclipped(p: Proj, x: vec3<f64>) -> vec3<f64> {
    let v = x - p.origin;
    let depth = dot3(v, p.forward);
    var sx: f64;
    var sy: f64;
    if p.kind == 1u {
        sx = dot3(v, p.right) / (depth * p.a);
        sy = dot3(v, p.up) / (depth * p.b);
    } else {
        sx = dot3(v, p.right) / p.a;
        sy = dot3(v, p.up) / p.b;
    }
    return vec3<f64>((1.0lf + sx) * 0.5lf * p.width, (1.0lf - sy) * 0.5lf * p.height, depth);
}

fn is_finite64(x: f64) -> bool {
    // NaN fails both comparisons; infinities fail the bound.
    return abs(x) <= 1.7976931348623157e308lf;
}

// Projector::project: (x, y, depth, 1) or w = 0 where the point does not project.
fn proj_project(p: Proj, x: vec3<f64>) -> vec4<f64> {
    let depth = dot3(x - p.origin, p.forward);
    if p.kind == 1u && !(depth >= p.near) {
        return vec4<f64>(0.0lf, 0.0lf, 0.0lf, 0.0lf);
    }
    let r = proj_unclipped(p, x);
    if !(is_finite64(r.x) && is_finite64(r.y)) {
        return vec4<f64>(0.0lf, 0.0lf, 0.0lf, 0.0lf);
    }
    return vec4<f64>(r, 1.0lf);
}
