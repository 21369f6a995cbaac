// spsm::depth's clipping: a decoded triangle clipped to a texel square (Sutherland-Hodgman in
// f64, clip_to_texel), the consistent minimum depth over the texel (consistent_min_depth) and
// Hasselgren's conservative corner depth (conservative_depth). Needs texel.wgsl before it.

// f64's min and max, which return the other operand where one is NaN.
fn min_num(a: f64, b: f64) -> f64 {
    if a != a {
        return b;
    }
    if b != b {
        return a;
    }
    return min(a, b);
}

fn max_num(a: f64, b: f64) -> f64 {
    if a != a {
        return b;
    }
    if b != b {
        return a;
    }
    return max(a, b);
}

// f64 infinity, made at run time: WGSL has no infinite literal, and a constant that
// overflows is an error.
fn infinity() -> f64 {
    return f64(bitcast<f32>(0x7f800000u + u32(params.res == 0u)));
}

// At most 7 corners, `n` of them.
struct Polygon {
    p: array<vec2<f64>, 7>,
    n: u32,
}

// clip_to_texel.
fn clip_to_texel(v: array<vec2<f64>, 3>, x0: f64, y0: f64) -> Polygon {
    var poly: array<vec2<f64>, 7>;
    poly[0] = v[0];
    poly[1] = v[1];
    poly[2] = v[2];
    var n = 3u;
    for (var side = 0u; side < 4u; side++) {
        let axis = side / 2u;
        var bound = y0;
        if axis == 0u {
            bound = x0;
        }
        var sign = 1.0lf;
        if side % 2u == 1u {
            bound = bound + 1.0lf;
            sign = -1.0lf;
        }
        var clipped: array<vec2<f64>, 7>;
        var m = 0u;
        for (var i = 0u; i < n; i++) {
            let a = poly[i];
            let b = poly[(i + 1u) % n];
            let da = sign * (a[axis] - bound);
            let db = sign * (b[axis] - bound);
            if da >= 0.0lf && m < 7u {
                clipped[m] = a;
                m += 1u;
            }
            if (da >= 0.0lf) != (db >= 0.0lf) && m < 7u {
                let s = da / (da - db);
                var p = a + (b - a) * s;
                p[axis] = bound;
                clipped[m] = p;
                m += 1u;
            }
        }
        poly = clipped;
        n = m;
        if n == 0u {
            break;
        }
    }
    return Polygon(poly, n);
}

fn conservative_depth(t: Tri, x: f64, y: f64) -> f64 {
    var cx = x + 1.0lf;
    if t.dz.x > 0.0lf {
        cx = x;
    }
    var cy = y + 1.0lf;
    if t.dz.y > 0.0lf {
        cy = y;
    }
    let z0 = depth_at(t, t.v[0]);
    let z1 = depth_at(t, t.v[1]);
    let z2 = depth_at(t, t.v[2]);
    let lo = min_num(min_num(z0, z1), z2);
    let hi = max_num(max_num(z0, z1), z2);
    let d = depth_at(t, vec2<f64>(cx, cy));
    // f64::clamp (a NaN stays NaN); unclamped where every vertex depth is NaN.
    if lo != lo {
        return d;
    }
    if d < lo {
        return lo;
    }
    if d > hi {
        return hi;
    }
    return d;
}

// consistent_min_depth: the smallest plane value at the clipped polygon's corners (NaN
// values passed over, infinity where all are NaN, as the twin's fold of f64::min from
// infinity); the conservative corner depth where the polygon is empty.
fn consistent_min_depth(t: Tri, x0: f64, y0: f64) -> f64 {
    let poly = clip_to_texel(t.v, x0, y0);
    if poly.n == 0u {
        return conservative_depth(t, x0, y0);
    }
    var z = infinity();
    for (var i = 0u; i < poly.n; i++) {
        let v = depth_at(t, poly.p[i]);
        if v < z {
            z = v;
        }
    }
    return z;
}
