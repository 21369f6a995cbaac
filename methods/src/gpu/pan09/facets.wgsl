// Stage "pixel facets" (facets::classify_facets and facets::project_facet): `classify` builds
// every covered pixel's facet and footprint and classifies it by the SAT count of its texel
// rectangle (class 0 lit, 1 depth test, 2 silhouette; index[k] = 1 for silhouettes, scanned
// into facet numbers in pixel order afterwards); `build` builds the silhouette facets again
// and writes their records (facet_record.wgsl) and their initial validity masks (all).

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> g_triangle: array<u32>;
@group(0) @binding(2) var<storage, read> g_position: array<f64>;
@group(0) @binding(3) var<storage, read> g_normal: array<f64>;
@group(0) @binding(4) var<storage, read> sat: array<u32>;
@group(0) @binding(5) var<storage, read_write> pixel_class: array<u32>;
@group(0) @binding(6) var<storage, read_write> index: array<u32>;
@group(0) @binding(7) var<storage, read_write> FF: array<FacetF>;
@group(0) @binding(8) var<storage, read_write> FU: array<FacetU>;
@group(0) @binding(9) var<storage, read_write> valid: array<u32>;
@group(0) @binding(10) var<storage, read_write> counters: array<atomic<u32>>;


struct Projected {
    map: FacetMap,
    normal: vec3<f64>,
    offset: f64,
    region: array<vec3<f64>, 3>,
    count: u32,
    fp: Footprint,
    ok: bool,
}

fn clip_poly(poly: array<vec2<f64>, 8>, n: u32, h: vec3<f64>) -> array<vec2<f64>, 9> {
    // The last slot holds the corner count.
    var out: array<vec2<f64>, 9>;
    var m = 0u;
    for (var i = 0u; i < n; i++) {
        let a = poly[i];
        let b = poly[(i + 1u) % n];
        let ga = hp_at(h, a);
        let gb = hp_at(h, b);
        if ga >= 0.0lf {
            out[m] = a;
            m += 1u;
        }
        if (ga >= 0.0lf) != (gb >= 0.0lf) {
            out[m] = a + (b - a) * (ga / (ga - gb));
            m += 1u;
        }
    }
    out[8] = vec2<f64>(f64(m), 0.0lf);
    return out;
}

fn project_facet(s: Setup, i: u32, j: u32, position: vec3<f64>, normal: vec3<f64>) -> Projected {
    var out: Projected;
    out.ok = false;
    if s.light.kind == 1u && proj_project(s.light, position).w == 0.0lf { return out; }
    let centre = vec2<f64>(f64(i) + 0.5lf, f64(j) + 0.5lf);
    let offset = dot3(normal, position);
    let map = facet_map(s.cam, centre, normal, offset);
    if !map.ok { return out; }
    var limits: array<vec3<f64>, 3>;
    var n = 0u;
    if s.cam.perspective {
        limits[0] = vec3<f64>(map.a.x * 0.75lf, map.a.y, map.a.z);
        n = 1u;
    } else {
        let span = 64.0lf * fmax64(len3(s.cam.ox), len3(s.cam.oy)) * map.a.x;
        limits[0] = vec3<f64>(span, -map.b.x, -map.b.y);
        limits[1] = vec3<f64>(span, map.b.x, map.b.y);
        n = 2u;
    }
    if s.has_near {
        limits[n] = half_plane(map, s.pnear);
        n += 1u;
    }
    var count = 0u;
    for (var k = 0u; k < n; k++) {
        if crossing(limits[k]) != ALL {
            out.region[count] = limits[k];
            count += 1u;
        }
    }
    var poly: array<vec2<f64>, 8>;
    poly[0] = vec2<f64>(-0.5lf, -0.5lf);
    poly[1] = vec2<f64>(0.5lf, -0.5lf);
    poly[2] = vec2<f64>(0.5lf, 0.5lf);
    poly[3] = vec2<f64>(-0.5lf, 0.5lf);
    var corners = 4u;
    for (var k = 0u; k < count; k++) {
        let c = clip_poly(poly, corners, out.region[k]);
        for (var q = 0u; q < 8u; q++) {
            poly[q] = c[q];
        }
        corners = u32(c[8].x);
    }
    if corners == 0u {
        corners = 1u;
        poly[0] = vec2<f64>(0.0lf, 0.0lf);
    }
    let hx = half_plane(map, s.px);
    let hy = half_plane(map, s.py);
    var hw = map.a;
    if s.has_w {
        hw = half_plane(map, s.pw);
    }
    for (var k = 0u; k < corners; k++) {
        let u = poly[k];
        let inv = 1.0lf / hp_at(hw, u);
        poly[k] = vec2<f64>(hp_at(hx, u) * inv, hp_at(hy, u) * inv);
    }
    out.fp = footprint(poly, corners, s.inf);
    if !out.fp.ok { return out; }
    out.map = map;
    out.normal = normal;
    out.offset = offset;
    out.count = count;
    out.ok = true;
    return out;
}

fn g3(buf: u32, k: u32) -> vec3<f64> {
    if buf == 0u {
        return vec3<f64>(g_position[3u * k], g_position[3u * k + 1u], g_position[3u * k + 2u]);
    }
    return vec3<f64>(g_normal[3u * k], g_normal[3u * k + 1u], g_normal[3u * k + 2u]);
}

fn sat_at(res: u32, x: u32, y: u32) -> u32 {
    return sat[y * (res + 1u) + x];
}

// The texel rectangle of a facet with a silhouette texel in it; ok false otherwise.
fn silhouette_rect(s: Setup, p: Projected) -> Rect {
    let r = texel_rect(p.fp, s.res);
    if !r.ok { return r; }
    let q = r.r;
    let c = sat_at(s.res, q.z + 1u, q.w + 1u) + sat_at(s.res, q.x, q.y) - sat_at(s.res, q.x, q.w + 1u) - sat_at(s.res, q.z + 1u, q.y);
    return Rect(q, c > 0u);
}

@compute @workgroup_size(64)
fn classify(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = flat_index(gid, groups);
    _ = arrayLength(&FF);
    _ = arrayLength(&FU);
    _ = arrayLength(&valid);
    if k >= arrayLength(&g_triangle) { return; }
    let s = setup();
    var c = 0u;
    let t = g_triangle[k];
    if t != NO_TRIANGLE {
        let position = g3(0u, k);
        let p = project_facet(s, k % s.width, k / s.width, position, g3(1u, k));
        if p.ok {
            c = select(1u, 2u, silhouette_rect(s, p).ok);
        } else if proj_project(s.light, position).w != 0.0lf {
            c = 1u;
        }
    }
    pixel_class[k] = c;
    index[k] = select(0u, 1u, c == 2u);
    if c == 2u {
        atomicAdd(&counters[C_SILHOUETTE_PIXELS], 1u);
    }
}

@compute @workgroup_size(64)
fn build(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = flat_index(gid, groups);
    _ = atomicLoad(&counters[0]);
    _ = arrayLength(&sat);
    if k >= arrayLength(&g_triangle) || pixel_class[k] != 2u { return; }
    let s = setup();
    let f = index[k];
    let p = project_facet(s, k % s.width, k / s.width, g3(0u, k), g3(1u, k));
    let rect = silhouette_rect(s, p);
    var r: FacetF;
    r.normal = Xyz(p.normal.x, p.normal.y, p.normal.z);
    r.offset = p.offset;
    r.origin = Xyz(p.map.origin.x, p.map.origin.y, p.map.origin.z);
    r.dir = Xyz(p.map.dir.x, p.map.dir.y, p.map.dir.z);
    r.a = Xyz(p.map.a.x, p.map.a.y, p.map.a.z);
    r.b = array<f64, 2>(p.map.b.x, p.map.b.y);
    r.k = p.map.k;
    for (var i = 0u; i < 3u; i++) {
        r.region[i] = Xyz(p.region[i].x, p.region[i].y, p.region[i].z);
    }
    for (var i = 0u; i < 8u; i++) {
        r.footprint[2u * i] = p.fp.c[i].x;
        r.footprint[2u * i + 1u] = p.fp.c[i].y;
    }
    r.lo = array<f64, 2>(p.fp.lo.x, p.fp.lo.y);
    r.hi = array<f64, 2>(p.fp.hi.x, p.fp.hi.y);
    r.orientation = p.fp.orientation;
    FF[f] = r;
    FU[f] = FacetU(k, g_triangle[k], p.count, p.fp.n, array<u32, 4>(rect.r.x, rect.r.y, rect.r.z, rect.r.w));
    for (var w = 0u; w < s.words; w++) {
        valid[f * s.words + w] = s.all[w];
    }
}
