// pan09 on the GPU: the CPU's geometry of methods/src/pan09 in f64, operation for operation
// (glam's dot is ((x*x') + (y*y')) + (z*z'), written out; Rust's f64 min and max ignore a
// NaN argument, as fmin64 and fmax64 do; `as usize` truncates, saturates and maps NaN to 0,
// as to_index does). Functions here read no bindings: every stage passes what they need.

fn isnan64(x: f64) -> bool {
    return !(x <= 0.0lf || x > 0.0lf);
}

fn fmin64(a: f64, b: f64) -> f64 {
    if isnan64(a) { return b; }
    if isnan64(b) { return a; }
    if a < b { return a; }
    return b;
}

fn fmax64(a: f64, b: f64) -> f64 {
    if isnan64(a) { return b; }
    if isnan64(b) { return a; }
    if a > b { return a; }
    return b;
}

// glam's DVec2 min and max: `if a < b { a } else { b }` per component.
fn vmin2(a: vec2<f64>, b: vec2<f64>) -> vec2<f64> {
    return vec2<f64>(select(b.x, a.x, a.x < b.x), select(b.y, a.y, a.y < b.y));
}

fn vmax2(a: vec2<f64>, b: vec2<f64>) -> vec2<f64> {
    return vec2<f64>(select(b.x, a.x, a.x > b.x), select(b.y, a.y, a.y > b.y));
}

// `x as usize` for x below `cap` (NaN and negatives give 0).
fn to_index(x: f64, cap: f64) -> u32 {
    if !(x > 0.0lf) { return 0u; }
    return u32(min(x, cap));
}

fn sgn64(x: f64) -> f64 {
    if x < 0.0lf { return -1.0lf; }
    return 1.0lf;
}

fn len3(a: vec3<f64>) -> f64 {
    return sqrt(dot3(a, a));
}

fn finite3(a: vec3<f64>) -> bool {
    return is_finite64(a.x) && is_finite64(a.y) && is_finite64(a.z);
}

fn finite2(a: vec2<f64>) -> bool {
    return is_finite64(a.x) && is_finite64(a.y);
}

fn perp_dot(a: vec2<f64>, b: vec2<f64>) -> f64 {
    return a.x * b.y - a.y * b.x;
}

// The light of a projector (silhouette::LightModel): kind 0 towards `v`, 1 at `v`.
struct LightModel {
    kind: u32,
    v: vec3<f64>,
}

fn towards(l: LightModel, p: vec3<f64>) -> vec3<f64> {
    if l.kind == 0u { return l.v; }
    return l.v - p;
}

// screen::CameraBasis.
struct Basis {
    o0: vec3<f64>,
    ox: vec3<f64>,
    oy: vec3<f64>,
    d0: vec3<f64>,
    dx: vec3<f64>,
    dy: vec3<f64>,
    perspective: bool,
}

// screen::WorldPlane.
struct WorldPlane {
    n: vec3<f64>,
    c: f64,
    n_ox: f64,
    n_oy: f64,
    n_dx: f64,
    n_dy: f64,
}

fn world_plane(n: vec3<f64>, c: f64, cam: Basis) -> WorldPlane {
    return WorldPlane(n, c, dot3(n, cam.ox), dot3(n, cam.oy), dot3(n, cam.dx), dot3(n, cam.dy));
}

// screen::HalfPlane as (g0, gx, gy).
fn hp_at(h: vec3<f64>, u: vec2<f64>) -> f64 {
    return h.x + h.y * u.x + h.z * u.y;
}

const ALL: u32 = 0u;
const NONE: u32 = 1u;
const SPLIT: u32 = 2u;

fn crossing(h: vec3<f64>) -> u32 {
    let reach = 0.5lf * (abs(h.y) + abs(h.z));
    if h.x - reach > 0.0lf { return ALL; }
    if h.x + reach < 0.0lf { return NONE; }
    return SPLIT;
}

// screen::FacetMap.
struct FacetMap {
    origin: vec3<f64>,
    dir: vec3<f64>,
    a: vec3<f64>,
    b: vec2<f64>,
    k: f64,
    ok: bool,
}

fn facet_map(cam: Basis, centre: vec2<f64>, normal: vec3<f64>, offset: f64) -> FacetMap {
    var m: FacetMap;
    m.origin = cam.o0 + cam.ox * centre.x + cam.oy * centre.y;
    m.dir = cam.d0 + cam.dx * centre.x + cam.dy * centre.y;
    let nd = dot3(normal, m.dir);
    var s = 1.0lf;
    if nd < 0.0lf {
        s = -1.0lf;
    } else if !(nd > 0.0lf) {
        m.ok = false;
        return m;
    }
    m.k = s * (offset - dot3(normal, m.origin));
    m.a = vec3<f64>(s * nd, s * dot3(normal, cam.dx), s * dot3(normal, cam.dy));
    m.b = vec2<f64>(s * dot3(normal, cam.ox), s * dot3(normal, cam.oy));
    let finite = finite3(m.origin) && finite3(m.dir) && finite3(m.a);
    let in_front = m.k > 0.0lf || !cam.perspective;
    m.ok = finite && in_front && is_finite64(m.k) && finite2(m.b);
    return m;
}

fn half_plane(m: FacetMap, p: WorldPlane) -> vec3<f64> {
    let p0 = dot3(p.n, m.origin) - p.c;
    let q = dot3(p.n, m.dir);
    return vec3<f64>(
        p0 * m.a.x + m.k * q,
        p.n_ox * m.a.x + p0 * m.a.y - m.b.x * q + m.k * p.n_dx,
        p.n_oy * m.a.x + p0 * m.a.z - m.b.y * q + m.k * p.n_dy,
    );
}

// footprint::Footprint.
struct Footprint {
    c: array<vec2<f64>, 8>,
    n: u32,
    lo: vec2<f64>,
    hi: vec2<f64>,
    orientation: f64,
    ok: bool,
}

fn footprint(pts: array<vec2<f64>, 8>, n: u32, inf: f64) -> Footprint {
    var f: Footprint;
    f.c = pts;
    f.n = n;
    f.ok = false;
    if n == 0u || n > 8u { return f; }
    for (var i = 0u; i < n; i++) {
        if !finite2(pts[i]) { return f; }
    }
    f.lo = vec2<f64>(inf, inf);
    f.hi = vec2<f64>(-inf, -inf);
    for (var i = 0u; i < n; i++) {
        f.lo = vmin2(f.lo, pts[i]);
        f.hi = vmax2(f.hi, pts[i]);
    }
    var area = 0.0lf;
    for (var i = 0u; i < n; i++) {
        area += perp_dot(pts[i], pts[(i + 1u) % n]);
    }
    let e = f.hi - f.lo;
    let scale = fmax64(select(e.y, e.x, e.x > e.y), 2.2250738585072014e-308lf);
    if abs(area) <= 1e-12lf * scale * scale {
        f.orientation = 0.0lf;
    } else {
        f.orientation = sgn64(area);
    }
    f.ok = true;
    return f;
}

// Footprint::texel_rect: (x0, y0, x1, y1) and whether the box meets the map.
struct Rect {
    r: vec4<u32>,
    ok: bool,
}

fn texel_rect(f: Footprint, res: u32) -> Rect {
    let r = f64(res);
    if !(f.hi.x >= 0.0lf && f.hi.y >= 0.0lf && f.lo.x <= r && f.lo.y <= r) {
        return Rect(vec4<u32>(0u), false);
    }
    let x0 = to_index(fmax64(ceil(f.lo.x - 1.0lf), 0.0lf), 4e9lf);
    let y0 = to_index(fmax64(ceil(f.lo.y - 1.0lf), 0.0lf), 4e9lf);
    let x1 = to_index(fmin64(floor(f.hi.x), r - 1.0lf), 4e9lf);
    let y1 = to_index(fmin64(floor(f.hi.y), r - 1.0lf), 4e9lf);
    return Rect(vec4<u32>(x0, y0, x1, y1), true);
}

// Footprint::row_texels: (x0, x1) and whether the footprint meets the row.
struct Span {
    x: vec2<u32>,
    ok: bool,
}

fn row_texels(f: Footprint, y: u32, res: u32, inf: f64) -> Span {
    let lo = f64(y);
    let hi = f64(y) + 1.0lf;
    var xmin = inf;
    var xmax = -inf;
    for (var i = 0u; i < f.n; i++) {
        let a = f.c[i];
        let b = f.c[(i + 1u) % f.n];
        let ylo = fmax64(fmin64(a.y, b.y), lo);
        let yhi = fmin64(fmax64(a.y, b.y), hi);
        if ylo > yhi { continue; }
        var xs: vec2<f64>;
        if a.y == b.y {
            xs = vec2<f64>(fmin64(a.x, b.x), fmax64(a.x, b.x));
        } else {
            let p = a.x + (ylo - a.y) * (b.x - a.x) / (b.y - a.y);
            let q = a.x + (yhi - a.y) * (b.x - a.x) / (b.y - a.y);
            xs = vec2<f64>(fmin64(p, q), fmax64(q, p));
        }
        xmin = fmin64(xmin, xs.x);
        xmax = fmax64(xmax, xs.y);
    }
    if xmin > xmax { return Span(vec2<u32>(0u), false); }
    let margin = 1e-9lf * (1.0lf + fmax64(abs(xmin), abs(xmax)));
    let r = f64(res);
    let first = fmax64(ceil(xmin - margin - 1.0lf), 0.0lf);
    let last = fmin64(floor(xmax + margin), r - 1.0lf);
    if !(first <= last) { return Span(vec2<u32>(0u), false); }
    return Span(vec2<u32>(to_index(first, 4e9lf), to_index(last, 4e9lf)), true);
}

fn touches_texel(f: Footprint, x: u32, y: u32) -> bool {
    if f.orientation == 0.0lf { return true; }
    let lo = vec2<f64>(f64(x), f64(y));
    let hi = lo + vec2<f64>(1.0lf, 1.0lf);
    for (var i = 0u; i < f.n; i++) {
        let a = f.c[i];
        let b = f.c[(i + 1u) % f.n];
        let e = (b - a) * f.orientation;
        let px = select(lo.x, hi.x, e.y < 0.0lf);
        let py = select(lo.y, hi.y, e.x > 0.0lf);
        let u = e.x * (py - a.y);
        let v = e.y * (px - a.x);
        let margin = 1e-9lf * (abs(u) + abs(v)) + 1e-300lf;
        if u - v < -margin { return false; }
    }
    return true;
}

// footprint::clip_segment: (t0, t1, 1) or z = 0 when the segment misses the box.
fn clip_segment(p0: vec2<f64>, p1: vec2<f64>, lo: vec2<f64>, hi: vec2<f64>, margin: f64) -> vec3<f64> {
    let d = p1 - p0;
    var t0 = 0.0lf;
    var t1 = 1.0lf;
    var ps = array<f64, 4>(-d.x, d.x, -d.y, d.y);
    var qs = array<f64, 4>(
        p0.x - (lo.x - margin),
        (hi.x + margin) - p0.x,
        p0.y - (lo.y - margin),
        (hi.y + margin) - p0.y,
    );
    for (var i = 0u; i < 4u; i++) {
        let p = ps[i];
        let q = qs[i];
        if p == 0.0lf {
            if q < 0.0lf { return vec3<f64>(0.0lf, 0.0lf, 0.0lf); }
        } else {
            let r = q / p;
            if p < 0.0lf {
                t0 = fmax64(t0, r);
            } else {
                t1 = fmin64(t1, r);
            }
        }
    }
    if t0 <= t1 { return vec3<f64>(t0, t1, 1.0lf); }
    return vec3<f64>(0.0lf, 0.0lf, 0.0lf);
}

// visibility::Occluder: three edge planes (inside >= 0), then the depth plane.
struct Occluder {
    p: array<WorldPlane, 4>,
    ok: bool,
}

fn occluder(c: array<vec3<f64>, 3>, light: LightModel, offset: f64, cam: Basis) -> Occluder {
    var o: Occluder;
    o.ok = false;
    let normal = cross3(c[1] - c[0], c[2] - c[0]);
    for (var e = 0u; e < 3u; e++) {
        let p = c[e];
        let q = c[(e + 1u) % 3u];
        let r = c[(e + 2u) % 3u];
        let n0 = cross3(q - p, towards(light, p));
        let side = dot3(n0, r - p);
        if side == 0.0lf || !is_finite64(side) { return o; }
        let n = n0 * sgn64(side);
        o.p[e] = world_plane(n, dot3(n, p), cam);
    }
    let c0 = dot3(normal, c[0]);
    var n: vec3<f64>;
    var k: f64;
    if light.kind == 0u {
        let nw = dot3(normal, light.v);
        if nw == 0.0lf { return o; }
        let s = sgn64(nw);
        n = (-s) * normal;
        k = (-s) * (c0 - offset * nw);
    } else {
        let sl = dot3(normal, light.v) - c0;
        if sl == 0.0lf { return o; }
        let s = sgn64(sl);
        n = (-s) * normal;
        k = (-s) * c0 + offset * len3(normal);
    }
    if !(finite3(n) && is_finite64(k)) { return o; }
    o.p[3] = world_plane(n, k, cam);
    o.ok = true;
    return o;
}

// lut::index.
fn lut_index(h: vec3<f64>) -> u32 {
    let ax = abs(h.y);
    let ay = abs(h.z);
    let m = fmax64(ax, ay);
    let inv = 1.0lf / m;
    let dx = h.y * inv;
    let dy = h.z * inv;
    var tau: f64;
    if ax >= ay {
        if h.y > 0.0lf { tau = 1.0lf + dy; } else { tau = 5.0lf - dy; }
    } else if h.z > 0.0lf {
        tau = 3.0lf - dx;
    } else {
        tau = 7.0lf + dx;
    }
    let a = to_index(tau * 64.0lf, 1e9lf) % 512u;
    let r = h.x * inv;
    var b: u32;
    if r < 0.0lf {
        b = 127u - min(to_index(-r * 128.0lf, 1e9lf), 127u);
    } else {
        b = 128u + min(to_index(r * 128.0lf, 1e9lf), 127u);
    }
    return a * 256u + b;
}

// Masks of up to 128 sub-samples: word w holds sub-samples 32 w ..= 32 w + 31.
fn popcount4(m: vec4<u32>) -> u32 {
    let c = countOneBits(m);
    return c.x + c.y + c.z + c.w;
}

fn is_zero4(m: vec4<u32>) -> bool {
    return all(m == vec4<u32>(0u));
}

// The index of a 1D kernel (GpuContext::groups_1d) with workgroups of 64.
fn flat_index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * (groups.x * 64u);
}

// Counter slots (params.rs names them).
const C_EDGES: u32 = 0u;
const C_SILHOUETTE_TEXELS: u32 = 1u;
const C_SILHOUETTE_PIXELS: u32 = 2u;
const C_LOOKUPS: u32 = 3u;
const C_PT_PAIRS: u32 = 4u;
const C_TT_PAIRS: u32 = 5u;
const C_EVALUATIONS: u32 = 6u;
const C_CANDIDATES: u32 = 7u;
const C_VALID_SAMPLES: u32 = 8u;
const C_BOUNDARY: u32 = 9u;
const C_EVALUATION_BOUND: u32 = 10u;
