// Shared by every kernel: the projector of scenes::projection and the geometry helpers the
// CPU code uses (glam's cross and normalize_or_zero, raster::clip_near), in f64 with the
// CPU's operations in the CPU's order (glam's dot is ((x*x') + (y*y')) + (z*z')).

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

// Three f64 as a buffer holds them (frame::Xyz): vec3<f64> is aligned to 32 bytes.
struct Xyz {
    x: f64,
    y: f64,
    z: f64,
}

fn xyz(v: Xyz) -> vec3<f64> {
    return vec3<f64>(v.x, v.y, v.z);
}

// A projector as a buffer holds it (frame::ProjectorData, field for field); kind, a and b
// as in Proj, pad zero.
struct ProjectorData {
    origin: Xyz,
    right: Xyz,
    up: Xyz,
    forward: Xyz,
    kind: u32,
    pad: u32,
    a: f64,
    b: f64,
    near: f64,
    width: f64,
    height: f64,
}

fn proj_load(d: ProjectorData) -> Proj {
    return Proj(
        xyz(d.origin), xyz(d.right), xyz(d.up), xyz(d.forward),
        d.kind, d.a, d.b, d.near, d.width, d.height,
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

fn cross3(a: vec3<f64>, b: vec3<f64>) -> vec3<f64> {
    return vec3<f64>(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}

// glam's normalize_or_zero.
fn normalize_or_zero(v: vec3<f64>) -> vec3<f64> {
    let rcp = 1.0lf / sqrt(dot3(v, v));
    if is_finite64(rcp) && rcp > 0.0lf {
        return v * rcp;
    }
    return vec3<f64>(0.0lf, 0.0lf, 0.0lf);
}

// Lexicographic (x, y, z) < as Rust's tuple comparison.
fn lex_less(a: vec3<f64>, b: vec3<f64>) -> bool {
    if a.x != b.x { return a.x < b.x; }
    if a.y != b.y { return a.y < b.y; }
    return a.z < b.z;
}

// Projector::depth_of.
fn proj_depth_of(p: Proj, x: vec3<f64>) -> f64 {
    return dot3(x - p.origin, p.forward);
}

// Projector::ray(xy): origin and direction (parameterised by depth).
struct Ray {
    origin: vec3<f64>,
    direction: vec3<f64>,
}

fn proj_ray(p: Proj, xy: vec2<f64>) -> Ray {
    let sx = 2.0lf * xy.x / p.width - 1.0lf;
    let sy = 1.0lf - 2.0lf * xy.y / p.height;
    if p.kind == 1u {
        return Ray(p.origin, p.forward + p.right * (sx * p.a) + p.up * (sy * p.b));
    }
    return Ray(p.origin + p.right * (sx * p.a) + p.up * (sy * p.b), p.forward);
}

// raster::clip_near: the part of triangle `c` (corner depths `d`) at depth >= near, at most
// 4 corners; an edge's crossing point is computed from its corners in canonical order.
struct Clipped {
    p: array<vec3<f64>, 4>,
    n: u32,
}

fn clip_near(c: array<vec3<f64>, 3>, d: array<f64, 3>, near: f64) -> Clipped {
    var out: Clipped;
    out.n = 0u;
    for (var i = 0u; i < 3u; i++) {
        let j = (i + 1u) % 3u;
        let in_i = d[i] >= near;
        if in_i {
            out.p[out.n] = c[i];
            out.n += 1u;
        }
        if in_i != (d[j] >= near) {
            var p = c[j];
            var dp = d[j];
            var q = c[i];
            var dq = d[i];
            if lex_less(c[i], c[j]) {
                p = c[i];
                dp = d[i];
                q = c[j];
                dq = d[j];
            }
            let t = (near - dp) / (dq - dp);
            out.p[out.n] = p + (q - p) * t;
            out.n += 1u;
        }
    }
    return out;
}
