// spsm silhouette recovery (Lecocq et al. 2014, section 4.2, Figs. 7, 8 and 10), one thread
// an uncertain pixel: spsm::recover::silhouette (the depth-test pattern of the 3x3
// neighbourhood with the consistent minimum depths of stage 4, filtered by 4-connectivity)
// and Resolved::lit at the pixel's own map point, in f64 with the CPU's operations in the
// CPU's order. Needs common.wgsl, texel.wgsl, encode.wgsl, lookup.wgsl, clip.wgsl and
// silhouette.wgsl before it.
//
// A pixel whose containment tests or triangle orientations the f64 filter leaves undecided is
// handed back (status 2) and recovered by the CPU code.

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> light: ProjectorData;
@group(0) @binding(2) var<storage, read> g_position: array<f64>;
@group(0) @binding(3) var<storage, read> g_normal: array<f64>;
// The texels (texel.wgsl).
@group(0) @binding(4) var<storage, read> texels: array<u32>;
@group(0) @binding(5) var<storage, read> planes: array<u32>;
@group(0) @binding(6) var<storage, read> tables: array<f64>;
// The uncertain pixels (`params.count` of them).
@group(0) @binding(7) var<storage, read> pixels: array<u32>;
// Stage 4's texels, ascending, then u32::MAX; and their consistent minimum depths, stored as
// f32 as the CPU stores them.
@group(0) @binding(8) var<storage, read> consistent_index: array<u32>;
@group(0) @binding(9) var<storage, read> consistent_depth: array<f32>;
// [0, 512): the 4-connectivity table (recover::connectivity_table); [512, 768): the tangent
// count of each ring mask (recover::pattern_table).
@group(0) @binding(10) var<storage, read> patterns: array<u32>;
// The tangents' normals of each ring mask, four (x, y) per mask.
@group(0) @binding(11) var<storage, read> normals: array<f64>;
// Per uncertain pixel: status (0: no silhouette, lit; 1: recovered; 2: handed back), centre
// texel, kept pattern | facing away << 9 | lit << 10.
@group(0) @binding(12) var<storage, read_write> result: array<u32>;

// ConsistentDepths::get, or consistent_min_depth where stage 4 did not compute the texel.
fn consistent_at(t: Tri, x: i32, y: i32) -> f64 {
    let k = u32(y) * params.res + u32(x);
    var lo = 0u;
    var hi = arrayLength(&consistent_index);
    while lo < hi {
        let mid = (lo + hi) / 2u;
        let v = consistent_index[mid];
        if v == k {
            return f64(consistent_depth[mid]);
        }
        if v < k {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return consistent_min_depth(t, f64(x), f64(y));
}

// The quantization margin of `occludes`: the triangle's own error bound, but no more than the
// receiver's plane (error `e`, plane_error) would suffer in the texel.
fn margin(t: Tri, q: vec2<f64>, e: vec3<f64>) -> f64 {
    let d = abs(q - t.centre);
    return min(error_at(t, q), e.x + kept(kept(d.x * e.y) + kept(d.y * e.z)));
}

// recover::occludes: whether `t`, stored in texel (x, y) with consistent minimum depth
// `cmin`, occludes the neighbourhood of `p`, whose receiver plane has gradient `g` (w = 0:
// none) and quantization bound `e`.
fn occludes(t: Tri, x: i32, y: i32, cmin: f64, p: MapPoint, g: vec3<f64>, e: vec3<f64>) -> bool {
    let stored = abs(cmin) * 0.5lf * f64(1.1920928955078125e-7f);
    if cmin >= p.z - p.tol - margin(t, t.centre + vec2<f64>(0.5lf, 0.5lf), e) - stored {
        return false;
    }
    if lies_on(t, p) {
        return false;
    }
    if g.z == 0.0lf {
        return true;
    }
    let dg = t.dz - g.xy;
    let moved = t.err_v * SQRT_2 * sqrt(kept(dg.x * dg.x) + kept(dg.y * dg.y));
    let poly = clip_to_texel(t.v, f64(x), f64(y));
    for (var i = 0u; i < poly.n; i++) {
        let q = poly.p[i];
        let plane = p.z + kept(kept(g.x * (q.x - p.xy.x)) + kept(g.y * (q.y - p.xy.y)));
        if depth_at(t, q) < plane - p.tol - margin(t, q, e) - moved {
            return true;
        }
    }
    return false;
}

// Resolved::new: the distinct kept occluders of the silhouette centred on texel (x, y), with
// their orientation's sign, into silhouette.wgsl's occluders.
fn resolve(x: i32, y: i32, kept_mask: u32) {
    occ_origin = vec2<f64>(f64(x) + 0.5lf, f64(y) + 0.5lf);
    occ_n = 0u;
    for (var k = 0u; k < 9u; k++) {
        if (kept_mask & (1u << k)) == 0u {
            continue;
        }
        let t = texel_tri(x + NEIGHBOURHOOD[k].x, y + NEIGHBOURHOOD[k].y);
        if !t.ok {
            continue;
        }
        let o = orient2d(t.v[0], t.v[1], t.v[2]);
        if o == 0.0lf {
            continue;
        }
        var seen = false;
        for (var i = 0u; i < occ_n; i++) {
            if all(occ_v[3u * i] == t.v[0]) && all(occ_v[3u * i + 1u] == t.v[1])
                && all(occ_v[3u * i + 2u] == t.v[2]) {
                seen = true;
            }
        }
        if seen {
            continue;
        }
        occ_v[3u * occ_n] = t.v[0];
        occ_v[3u * occ_n + 1u] = t.v[1];
        occ_v[3u * occ_n + 2u] = t.v[2];
        occ_sign[occ_n] = select(-1.0lf, 1.0lf, o > 0.0lf);
        occ_n += 1u;
    }
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let j = gid.x + gid.y * (groups.x * 64u);
    if j >= params.count {
        return;
    }
    undecided = false;
    let k = pixels[j];
    let position = vec3<f64>(g_position[3u * k], g_position[3u * k + 1u], g_position[3u * k + 2u]);
    let normal = vec3<f64>(g_normal[3u * k], g_normal[3u * k + 1u], g_normal[3u * k + 2u]);
    var status = 0u;
    var texel = 0u;
    var word = 1u << 10u;
    let m = map_point(position, normal);
    let fx = floor(m.p.xy.x);
    let fy = floor(m.p.xy.y);
    let res = f64(params.res);
    if m.ok && fx >= 0.0lf && fy >= 0.0lf && fx < res && fy < res {
        let p = m.p;
        let x = i32(fx);
        let y = i32(fy);
        texel = u32(y) * params.res + u32(x);
        let g = gradient(p);
        var grad = vec2<f64>(0.0lf, 0.0lf);
        if g.z != 0.0lf {
            grad = g.xy;
        }
        let e = plane_error(p.z, grad);
        var mask = 0u;
        for (var i = 0u; i < 9u; i++) {
            let nx = x + NEIGHBOURHOOD[i].x;
            let ny = y + NEIGHBOURHOOD[i].y;
            let t = texel_tri(nx, ny);
            if t.ok && occludes(t, nx, ny, consistent_at(t, nx, ny), p, g, e) {
                mask |= 1u << i;
            }
        }
        let kept_mask = patterns[mask];
        let facing_away = kept_mask != 0u && !faces_light(p);
        let ring = kept_mask & 0xffu;
        // Silhouette::pattern, then Resolved::lit at the pixel's own map point.
        var lit = true;
        if facing_away || ring == 0xffu {
            lit = false;
        } else if ring != 0u {
            resolve(x, y, kept_mask);
            var shadowed = true;
            for (var i = 0u; i < patterns[512u + ring]; i++) {
                let o = 8u * ring + 2u * i;
                if !shadowed_along(vec2<f64>(normals[o], normals[o + 1u]), p.xy) {
                    shadowed = false;
                }
            }
            lit = !shadowed;
        }
        status = 1u;
        word = kept_mask | (select(0u, 1u, facing_away) << 9u) | (select(0u, 1u, lit) << 10u);
    }
    if undecided {
        status = 2u;
    }
    result[3u * j] = status;
    result[3u * j + 1u] = texel;
    result[3u * j + 2u] = word;
}
