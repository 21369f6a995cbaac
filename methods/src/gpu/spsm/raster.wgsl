// Stage "conservative rasterization" (spsm::raster::rasterize_conservative) on the GPU. One
// invocation per item, a (prepared triangle, texel row) pair of the triangle's rectangle:
// the row's columns as strip_columns gives them, each texel tested with TriSetup::touches
// (orient2d's filter; the texels it cannot decide are listed for the CPU). `count` counts
// the tests and the touching texels (per texel), `scatter` writes each touching triangle
// into its texel's list (after the scan of the counts), and `resolve`, one invocation per
// texel, keeps the triangle of least minimum conservative depth, ties to the lower index,
// as the CPU's in-order `<` does.

// raster::Dims: the map's resolution, the items, the undecided list's capacity.
struct Dims {
    res: u32,
    items: u32,
    capacity: u32,
}

@group(0) @binding(0) var<storage, read> dims: Dims;
// Per prepared triangle (setup.wgsl).
@group(0) @binding(1) var<storage, read> setups: array<SetupData>;
// Per prepared triangle: its rectangle's columns x0, x1 (rows come with the items).
@group(0) @binding(2) var<storage, read> cols: array<u32>;
// Per item: prepared triangle, row.
@group(0) @binding(3) var<storage, read> items: array<u32>;
// Per texel (and one more): touching triangles, then (scanned) the first of its list.
@group(0) @binding(4) var<storage, read_write> texel_count: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> cursor: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> list: array<u32>;
// [tested low, high, fragments low, high, undecided]
@group(0) @binding(7) var<storage, read_write> counters: array<atomic<u32>>;
// Undecided (triangle, x, y).
@group(0) @binding(8) var<storage, read_write> undecided: array<u32>;
@group(0) @binding(9) var<storage, read_write> out_texel: array<u32>;
@group(0) @binding(10) var<storage, read_write> out_depth: array<f64>;

// robust's orient2d filter bound (CCWERRBOUNDA).
const THETA: f64 = 3.3306690621773722e-16lf;
const NONE: u32 = 0xffffffffu;

fn bind_all() {
    _ = dims.res;
    _ = setups[0];
    _ = cols[0];
    _ = items[0];
    _ = atomicLoad(&texel_count[0]);
    _ = atomicLoad(&cursor[0]);
    _ = arrayLength(&list);
    _ = atomicLoad(&counters[0]);
    _ = arrayLength(&undecided);
    _ = arrayLength(&out_texel);
    _ = arrayLength(&out_depth);
}

fn vertex(s: u32, i: u32) -> vec2<f64> {
    return vec2<f64>(setups[s].v[2u * i], setups[s].v[2u * i + 1u]);
}

// TriSetup::strip_columns for the strip y0 <= y <= y1 within columns c0..=c1; x > y when
// none.
fn strip_columns(s: u32, y0: f64, y1: f64, c0: u32, c1: u32) -> vec2<u32> {
    // The vertices and the crossings between them are finite: the largest f64 stands for
    // the CPU's infinity.
    var lo = 1.7976931348623157e308lf;
    var hi = -1.7976931348623157e308lf;
    for (var e = 0u; e < 3u; e++) {
        let a = vertex(s, e);
        let b = vertex(s, (e + 1u) % 3u);
        if a.y >= y0 && a.y <= y1 {
            lo = min(lo, a.x);
            hi = max(hi, a.x);
        }
        for (var k = 0u; k < 2u; k++) {
            let yy = select(y1, y0, k == 0u);
            if (a.y - yy) * (b.y - yy) < 0.0lf {
                let x = a.x + (yy - a.y) * (b.x - a.x) / (b.y - a.y);
                lo = min(lo, x);
                hi = max(hi, x);
            }
        }
    }
    if lo > hi {
        return vec2<u32>(1u, 0u);
    }
    let margin = 1e-9lf * (1.0lf + max(abs(lo), abs(hi)));
    let first = max(ceil(lo - margin) - 1.0lf, f64(c0));
    let last = min(floor(hi + margin), f64(c1));
    if last < first {
        return vec2<u32>(1u, 0u);
    }
    return vec2<u32>(u32(first), u32(last));
}

// TriSetup::touches with orient2d's filter: 0 apart, 1 touching, 2 undecided.
fn touches(s: u32, i: u32, j: u32) -> u32 {
    var undecided = false;
    for (var e = 0u; e < 3u; e++) {
        let a = vertex(s, e);
        let b = vertex(s, (e + 1u) % 3u);
        let x = select(f64(i), f64(i) + 1.0lf, b.y - a.y < 0.0lf);
        let y = select(f64(j), f64(j) + 1.0lf, b.x - a.x > 0.0lf);
        let detleft = (a.x - x) * (b.y - y);
        let detright = (a.y - y) * (b.x - x);
        let det = detleft - detright;
        let bound = THETA * abs(detleft + detright);
        if det >= bound || -det >= bound {
            if det < 0.0lf {
                return 0u;
            }
        } else {
            undecided = true;
        }
    }
    return select(1u, 2u, undecided);
}

// `v`, through a choice the compiler cannot see through (the map is never 0 texels wide), so
// that `a + kept(b + c)` is evaluated as written: Mesa's llvmpipe was seen to reassociate
// `a + (b + c)` in f64, one ulp off the CPU's `TriSetup::plane`.
fn kept(v: f64) -> f64 {
    return select(v, 0.0lf, dims.res == 0u);
}

// TriSetup::conservative_depth over texel (i, j).
fn conservative_depth(s: u32, i: u32, j: u32) -> f64 {
    let t = setups[s];
    let dz = vec2<f64>(t.dz[0], t.dz[1]);
    let x = select(f64(i) + 1.0lf, f64(i), dz.x > 0.0lf);
    let y = select(f64(j) + 1.0lf, f64(j), dz.y > 0.0lf);
    let v0 = vertex(s, 0u);
    let plane = t.z[0] + kept((x - v0.x) * dz.x + (y - v0.y) * dz.y);
    return min(max(plane, t.z_min), t.z_max);
}

// Adds n to the 64-bit counter at words c, c + 1.
fn add64(c: u32, n: u32) {
    if n == 0u { return; }
    let old = atomicAdd(&counters[c], n);
    if old > 0xffffffffu - n {
        atomicAdd(&counters[c + 1u], 1u);
    }
}

// An item: prepared triangle `s`, row `y`, its columns `x0..=x1` (x0 > x1: none, or no item).
struct Item {
    s: u32,
    y: u32,
    x0: u32,
    x1: u32,
}

fn item_of(it: u32) -> Item {
    if it >= dims.items {
        return Item(0u, 0u, 1u, 0u);
    }
    let s = items[2u * it];
    let y = items[2u * it + 1u];
    let span = strip_columns(s, f64(y), f64(y) + 1.0lf, cols[2u * s], cols[2u * s + 1u]);
    return Item(s, y, span.x, span.y);
}

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    bind_all();
    let item = item_of(gid.x + gid.y * (groups.x * 64u));
    if item.x0 > item.x1 { return; }
    let s = item.s;
    let y = item.y;
    let res = dims.res;
    var tested = 0u;
    var fragments = 0u;
    for (var x = item.x0; x <= item.x1; x++) {
        tested += 1u;
        let t = touches(s, x, y);
        if t == 1u {
            fragments += 1u;
            atomicAdd(&texel_count[y * res + x], 1u);
        } else if t == 2u {
            let at = atomicAdd(&counters[4], 1u);
            if at < dims.capacity {
                undecided[3u * at] = s;
                undecided[3u * at + 1u] = x;
                undecided[3u * at + 2u] = y;
            }
        }
    }
    add64(0u, tested);
    add64(2u, fragments);
}

@compute @workgroup_size(64)
fn scatter(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    bind_all();
    let item = item_of(gid.x + gid.y * (groups.x * 64u));
    if item.x0 > item.x1 { return; }
    let s = item.s;
    let y = item.y;
    let res = dims.res;
    for (var x = item.x0; x <= item.x1; x++) {
        if touches(s, x, y) == 1u {
            let k = y * res + x;
            list[atomicLoad(&texel_count[k]) + atomicAdd(&cursor[k], 1u)] = s;
        }
    }
}

@compute @workgroup_size(64)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    bind_all();
    let k = gid.x + gid.y * (groups.x * 64u);
    let res = dims.res;
    if k >= res * res { return; }
    let first = atomicLoad(&texel_count[k]);
    let last = atomicLoad(&texel_count[k + 1u]);
    if first == last {
        // out_depth keeps its infinity.
        out_texel[k] = NONE;
        return;
    }
    var at = list[first];
    var best = conservative_depth(at, k % res, k / res);
    for (var f = first + 1u; f < last; f++) {
        let s = list[f];
        let d = conservative_depth(s, k % res, k / res);
        if d < best || (d == best && s < at) {
            best = d;
            at = s;
        }
    }
    out_texel[k] = at;
    out_depth[k] = best;
}
