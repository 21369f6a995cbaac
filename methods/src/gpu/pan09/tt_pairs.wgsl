// Stage "triangle-texel pairs" (pairs::triangle_texel_pairs): `busy` marks the texels with a
// PT list (their SAT is built next), `count` sizes each caster's busy texels over its
// footprint's row spans and its rows (both scanned afterwards: the rows into row items),
// `count_rows` sizes each row item (scanned into write offsets), `emit` writes a (texel,
// triangle) key per busy texel of a row item's span, `test` keeps the keys whose texel the footprint
// touches (flags scanned into compacted positions afterwards) and `compact` writes the kept
// pairs in triangle order. The CPU sorts them by PT-list length for load balance; every pair
// ORs into masks (and notes validity candidates that are ANDed), so the order changes no
// result and the GPU keeps the emission order. dims: n (texels, triangles or keys), res.

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> dims: array<u32>;
@group(0) @binding(2) var<storage, read> corners: array<f64>;
@group(0) @binding(3) var<storage, read> casters: array<u32>;
@group(0) @binding(4) var<storage, read> toff: array<u32>;
@group(0) @binding(5) var<storage, read_write> busy: array<u32>;
@group(0) @binding(6) var<storage, read_write> bsat: array<u32>;
@group(0) @binding(7) var<storage, read_write> counts: array<u32>;
@group(0) @binding(8) var<storage, read_write> keys: array<u32>;
@group(0) @binding(9) var<storage, read_write> flags: array<u32>;
@group(0) @binding(10) var<storage, read_write> tt: array<u32>;
@group(0) @binding(11) var<storage, read_write> counters: array<atomic<u32>>;
// First row of each triangle's rectangle.
@group(0) @binding(12) var<storage, read_write> rows: array<u32>;
// Rows of each triangle's rectangle that hold keys (0 for none), scanned into each triangle's
// first row item; then the keys of each row item, scanned into its first key's slot.
@group(0) @binding(13) var<storage, read_write> row_off: array<u32>;
@group(0) @binding(14) var<storage, read_write> row_keys: array<u32>;

fn bind_all() {
    _ = params.res;
    _ = arrayLength(&corners);
    _ = arrayLength(&casters);
    _ = arrayLength(&toff);
    _ = arrayLength(&busy);
    _ = arrayLength(&bsat);
    _ = arrayLength(&counts);
    _ = arrayLength(&keys);
    _ = arrayLength(&flags);
    _ = arrayLength(&tt);
    _ = atomicLoad(&counters[0]);
    _ = arrayLength(&rows);
    _ = arrayLength(&row_off);
    _ = arrayLength(&row_keys);
}

fn corner(t: u32, i: u32) -> vec3<f64> {
    let o = 9u * t + 3u * i;
    return vec3<f64>(corners[o], corners[o + 1u], corners[o + 2u]);
}

// pairs::triangle_footprint.
fn triangle_footprint(s: Setup, t: u32) -> Footprint {
    let c = array<vec3<f64>, 3>(corner(t, 0u), corner(t, 1u), corner(t, 2u));
    var pts: array<vec2<f64>, 8>;
    var n = 3u;
    if s.light.kind == 1u {
        let d = array<f64, 3>(proj_depth_of(s.light, c[0]), proj_depth_of(s.light, c[1]), proj_depth_of(s.light, c[2]));
        let w = clip_near(c, d, s.light.near);
        for (var i = 0u; i < w.n; i++) {
            pts[i] = proj_unclipped(s.light, w.p[i]).xy;
        }
        n = w.n;
    } else {
        for (var i = 0u; i < 3u; i++) {
            pts[i] = proj_unclipped(s.light, c[i]).xy;
        }
    }
    var f: Footprint;
    f.ok = false;
    if n < 3u { return f; }
    f = footprint(pts, n, s.inf);
    if !f.ok { return f; }
    var area = 0.0lf;
    for (var i = 0u; i < n; i++) {
        area += perp_dot(pts[i], pts[(i + 1u) % n]);
    }
    f.ok = area != 0.0lf;
    return f;
}

fn bsat_at(res: u32, x: u32, y: u32) -> u32 {
    return bsat[y * (res + 1u) + x];
}

@compute @workgroup_size(64)
fn mark_busy(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    bind_all();
    let k = flat_index(gid, groups);
    if k >= dims[0] { return; }
    busy[k] = select(0u, 1u, toff[k + 1u] != toff[k]);
}

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    bind_all();
    let t = flat_index(gid, groups);
    if t >= dims[0] { return; }
    counts[t] = 0u;
    row_off[t] = 0u;
    if casters[t] == 0u { return; }
    let s = setup();
    let f = triangle_footprint(s, t);
    if !f.ok { return; }
    let r = texel_rect(f, s.res);
    if !r.ok { return; }
    var c = 0u;
    for (var y = r.r.y; y <= r.r.w; y++) {
        c += row_key_count(f, y, s.res, s.inf);
    }
    counts[t] = c;
    if c > 0u {
        rows[t] = r.r.y;
        row_off[t] = r.r.w - r.r.y + 1u;
    }
}

// The triangle of row item `j`: the last triangle whose first row item is at most `j`
// (triangles without rows take no items). dims[1] holds the number of triangles.
fn item_triangle(j: u32) -> u32 {
    var lo = 0u;
    var hi = dims[1] - 1u;
    while lo < hi {
        let mid = (lo + hi + 1u) / 2u;
        if row_off[mid] <= j {
            lo = mid;
        } else {
            hi = mid - 1u;
        }
    }
    return lo;
}

// Keys of one busy row span (counted with the busy texels' SAT, as `count` does).
fn row_key_count(f: Footprint, y: u32, res: u32, inf: f64) -> u32 {
    let span = row_texels(f, y, res, inf);
    if !span.ok { return 0u; }
    let a = span.x.x;
    let b = span.x.y;
    return bsat_at(res, b + 1u, y + 1u) + bsat_at(res, a, y) - bsat_at(res, a, y + 1u) - bsat_at(res, b + 1u, y);
}

// One invocation per row item (dims[0] items): its key count.
@compute @workgroup_size(64)
fn count_rows(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    bind_all();
    let j = flat_index(gid, groups);
    if j >= dims[0] { return; }
    let t = item_triangle(j);
    let y = rows[t] + (j - row_off[t]);
    let s = setup();
    row_keys[j] = row_key_count(triangle_footprint(s, t), y, s.res, s.inf);
}

// One invocation per row item (dims[0] items): the row's keys, from its scanned first slot,
// so keys come in triangle order and, within a triangle, row by row.
@compute @workgroup_size(64)
fn emit(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    bind_all();
    let j = flat_index(gid, groups);
    if j >= dims[0] { return; }
    var slot = row_keys[j];
    if row_keys[j + 1u] == slot { return; }
    let t = item_triangle(j);
    let y = rows[t] + (j - row_off[t]);
    let s = setup();
    let span = row_texels(triangle_footprint(s, t), y, s.res, s.inf);
    if !span.ok { return; }
    for (var x = span.x.x; x <= span.x.y; x++) {
        let k = y * s.res + x;
        if busy[k] != 0u {
            keys[2u * slot] = k;
            keys[2u * slot + 1u] = t;
            slot += 1u;
        }
    }
}

@compute @workgroup_size(64)
fn test(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    bind_all();
    let i = flat_index(gid, groups);
    if i >= dims[0] { return; }
    let s = setup();
    let k = keys[2u * i];
    let keep = touches_texel(triangle_footprint(s, keys[2u * i + 1u]), k % s.res, k / s.res);
    flags[i] = select(0u, 1u, keep);
    if keep {
        atomicAdd(&counters[C_TT_PAIRS], 1u);
        atomicAdd(&counters[C_EVALUATION_BOUND], toff[k + 1u] - toff[k]);
    }
}

@compute @workgroup_size(64)
fn compact(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    bind_all();
    let i = flat_index(gid, groups);
    if i >= dims[0] { return; }
    let slot = flags[i];
    if flags[i + 1u] == slot { return; }
    tt[2u * slot] = keys[2u * i];
    tt[2u * slot + 1u] = keys[2u * i + 1u];
}
