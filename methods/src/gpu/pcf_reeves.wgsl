// pcf-reeves: Reeves et al.'s stochastic percentage-closer filtering (pcf_reeves::footprint,
// pcf_reeves::filter), one thread a pixel. After pixel.wgsl (its bindings 0 to 4),
// counters.wgsl and pcf_jitter.wgsl.

@group(0) @binding(5) var<storage, read> camera: ProjectorData;
@group(0) @binding(6) var<storage, read> map_depth: array<f64>;
@group(0) @binding(7) var<storage, read_write> lit: array<f32>;
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>, 4>;

const MAX_FOOTPRINT: f64 = 16.0lf;

struct Footprint {
    lo: vec2<f64>,
    hi: vec2<f64>,
}

// pcf_reeves::footprint of pixel (i, j).
fn footprint(cam: Proj, lp: Proj, i: u32, j: u32, p: vec3<f64>, n: vec3<f64>, xy: vec2<f64>) -> Footprint {
    let limit = Footprint(xy - vec2<f64>(MAX_FOOTPRINT), xy + vec2<f64>(MAX_FOOTPRINT));
    var lo = xy;
    var hi = xy;
    let d = dot3(n, p);
    for (var c = 0u; c < 4u; c++) {
        let corner = vec2<f64>(f64(i + (c & 1u)), f64(j + (c >> 1u)));
        let ray = proj_ray(cam, corner);
        // Ray::intersect_plane.
        let denom = dot3(n, ray.direction);
        let t = (d - dot3(n, ray.origin)) / denom;
        if !(denom != 0.0lf && is_finite64(t)) {
            return limit;
        }
        if t <= 0.0lf || (cam.kind == 1u && t < cam.near) {
            return limit;
        }
        let q = proj_project(lp, ray.origin + ray.direction * t);
        if q.w == 0.0lf {
            return limit;
        }
        lo = min(lo, q.xy);
        hi = max(hi, q.xy);
    }
    return Footprint(max(lo, limit.lo), min(hi, limit.hi));
}

struct Filtered {
    lit: f64,
    compares: u32,
}

// pcf_reeves::filter.
fn reeves_filter(r: Receiver, fp: Footprint, pixel: u32) -> Filtered {
    let nx = params.grid_x;
    let ny = params.grid_y;
    let reach = max(r.xy - fp.lo, fp.hi - r.xy) + vec2<f64>(0.5lf);
    let threshold = r.depth - tolerance(params, r, reach);
    let size = fp.hi - fp.lo;
    let seed = vec2<u32>(params.seed_lo, params.seed_hi);
    let dims = vec2<f64>(f64(nx), f64(ny));
    var n_lit = 0u;
    var compares = 0u;
    for (var s = 0u; s < params.samples; s++) {
        let cell = vec2<f64>(f64(s % nx), f64(s / nx));
        let u = vec2<f64>(jitter(seed, pixel, s, 0u), jitter(seed, pixel, s, 1u));
        let q = fp.lo + (cell + u) / dims * size;
        let t = texel_at(q, params.res);
        if t >= 0 {
            compares += 1u;
            if map_depth[t] >= threshold {
                n_lit += 1u;
            }
        } else {
            n_lit += 1u;
        }
    }
    return Filtered(f64(n_lit) / f64(params.samples), compares);
}

@compute @workgroup_size(64)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let k = pixel_index(gid, groups);
    var compares = 0u;
    if k < params.pixels {
        var v = 1.0lf;
        let r = pixel_receiver(k);
        if r.ok {
            let x = k % params.width;
            let y = k / params.width;
            let p = pixel_position(k);
            let n = pixel_normal(k);
            let fp = footprint(proj_load(camera), proj_load(light), x, y, p, n, r.xy);
            let f = reeves_filter(r, fp, k);
            v = f.lit;
            compares = f.compares;
        }
        lit[k] = f32(v);
    }
    count(local, compares, 0u);
}
