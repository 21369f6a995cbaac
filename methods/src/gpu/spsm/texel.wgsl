// spsm texels: the Params of the per-pixel and per-texel kernels, and SpsmMap::get (packed
// texels through the uploaded decode tables, f32 texels widened). Needs common.wgsl before it
// and, after it, the bindings `params`, `texels`, `planes` and `tables`. Packed texels: four
// words each in `texels`. F32 texels: the vertices' six f32 bits in `texels`, the depth and
// derivatives' three in `planes` (two buffers keep each within the binding size limit).

struct Params {
    constant: f64,
    z_lo: f64,
    depth_step: f64,
    vertex_step: f64,
    half_res: f64,
    half_ulp: f64,
    size_x: f64,
    size_y: f64,
    pixels: u32,
    res: u32,
    perspective: u32,
    packed: u32,
    count: u32,
    pad1: u32,
    pad2: u32,
    pad3: u32,
}

const THETA: f64 = 3.3306690621773722e-16lf;
const MIN_POSITIVE: f64 = 2.2250738585072014e-308lf;

struct Tri {
    v: array<vec2<f64>, 3>,
    centre: vec2<f64>,
    z: f64,
    dz: vec2<f64>,
    err_z: f64,
    err_dz: vec2<f64>,
    err_v: f64,
    ok: bool,
}

fn slope_scale(z: f64) -> vec2<f64> {
    if params.perspective == 1u {
        let m = max(-z, MIN_POSITIVE);
        return vec2<f64>(params.size_x * m, params.size_y * m);
    }
    return vec2<f64>(params.size_x, params.size_y);
}

fn vertex_at(code: u32) -> f64 {
    return f64(code) * params.vertex_step - params.half_res;
}

fn f32_word(k: u32) -> f64 {
    return f64(bitcast<f32>(texels[k]));
}

fn f32_plane(k: u32) -> f64 {
    return f64(bitcast<f32>(planes[k]));
}

// SpsmMap::get.
fn texel_tri(x: i32, y: i32) -> Tri {
    var t: Tri;
    t.ok = false;
    let r = i32(params.res);
    if x < 0 || y < 0 || x >= r || y >= r {
        return t;
    }
    let k = u32(y * r + x);
    t.centre = vec2<f64>(f64(x) + 0.5lf, f64(y) + 0.5lf);
    if params.packed == 1u {
        let w0 = texels[4u * k];
        let w1 = texels[4u * k + 1u];
        let w2 = texels[4u * k + 2u];
        let w3 = texels[4u * k + 3u];
        if w0 == 0xffffffffu && w1 == 0xffffffffu && w2 == 0xffffffffu && w3 == 0xffffffffu {
            return t;
        }
        t.v[0] = vec2<f64>(vertex_at(w0 & 0xffffu), vertex_at(w0 >> 16u));
        t.v[1] = vec2<f64>(vertex_at(w1 & 0xffffu), vertex_at(w1 >> 16u));
        t.v[2] = vec2<f64>(vertex_at(w2 & 0xffffu), vertex_at(w2 >> 16u));
        let step = params.depth_step;
        t.z = params.z_lo + f64(w3 >> 16u) * step;
        let qx = (w3 >> 8u) & 0xffu;
        let qy = w3 & 0xffu;
        let s = slope_scale(t.z);
        t.dz = vec2<f64>(tables[qx] * s.x, tables[qy] * s.y);
        t.err_z = 0.5lf * step;
        t.err_dz = vec2<f64>(tables[256u + qx] * s.x, tables[256u + qy] * s.y);
        t.err_v = 0.5lf * params.vertex_step;
    } else {
        // F32Texel::EMPTY: a NaN depth, told by its bits (a NaN through bitcast and the
        // widening to f64 is not kept as NaN everywhere; llvmpipe's was not).
        if (planes[3u * k] & 0x7fffffffu) > 0x7f800000u {
            return t;
        }
        let z = f32_plane(3u * k);
        let b = 6u * k;
        t.v[0] = vec2<f64>(f32_word(b), f32_word(b + 1u));
        t.v[1] = vec2<f64>(f32_word(b + 2u), f32_word(b + 3u));
        t.v[2] = vec2<f64>(f32_word(b + 4u), f32_word(b + 5u));
        t.z = z;
        t.dz = vec2<f64>(f32_plane(3u * k + 1u), f32_plane(3u * k + 2u));
        var largest = 0.0lf;
        for (var i = 0; i < 3; i++) {
            largest = max(largest, max(abs(t.v[i].x), abs(t.v[i].y)));
        }
        t.err_z = abs(z) * params.half_ulp;
        t.err_dz = vec2<f64>(abs(t.dz.x) * params.half_ulp, abs(t.dz.y) * params.half_ulp);
        t.err_v = largest * params.half_ulp;
    }
    t.ok = true;
    return t;
}

// `v`, through a choice the compiler cannot see through (no map has 0 texels a side), so
// that `a + kept(b) + kept(c)` is evaluated as the CPU writes it: Mesa's llvmpipe was seen
// to reassociate `a + (b + c)` in f64 (see raster.wgsl).
fn kept(v: f64) -> f64 {
    return select(v, 0.0lf, params.res == 0u);
}

// Tri::depth_at.
fn depth_at(t: Tri, q: vec2<f64>) -> f64 {
    return t.z + kept(kept((q.x - t.centre.x) * t.dz.x) + kept((q.y - t.centre.y) * t.dz.y));
}

// Tri::error_at.
fn error_at(t: Tri, q: vec2<f64>) -> f64 {
    let d = abs(q - t.centre);
    return t.err_z + kept(kept(d.x * t.err_dz.x) + kept(d.y * t.err_dz.y));
}

