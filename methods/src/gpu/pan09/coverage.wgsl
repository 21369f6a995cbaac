// coverage::{TableCoverage, ExactCoverage}: the sub-samples of a half-plane, from the lookup
// table `lut` (mode 0) or tested one by one (mode 1, the pattern's offsets in `params`).
// Reads the bindings params and lut of the stage.

fn cov_split(s: Setup, h: vec3<f64>, strict: bool) -> vec4<u32> {
    var m = vec4<u32>(0u);
    if s.mode == 0u {
        let i = lut_index(h);
        for (var w = 0u; w < s.words; w++) {
            m[w] = lut[i * s.words + w];
        }
        return m;
    }
    for (var i = 0u; i < s.rate; i++) {
        let x = params.pattern_x[i];
        let y = params.pattern_y[i];
        let g = h.x + h.y * x + h.z * y;
        if g > 0.0lf || (!strict && g == 0.0lf) {
            m[i / 32u] |= 1u << (i % 32u);
        }
    }
    return m;
}

// Closed (ties covered) when `strict` is false, open otherwise; the table ignores ties.
fn coverage(s: Setup, h: vec3<f64>, strict: bool) -> vec4<u32> {
    switch crossing(h) {
        case 0u: { return s.all; }
        case 1u: { return vec4<u32>(0u); }
        default: { return cov_split(s, h, strict); }
    }
}

// Occluder::occlusion_and_depth's mask.
fn occlusion(s: Setup, o: Occluder, m: FacetMap) -> vec4<u32> {
    var mask = coverage(s, half_plane(m, o.p[3]), true);
    for (var e = 0u; e < 3u; e++) {
        if is_zero4(mask) { break; }
        mask &= coverage(s, half_plane(m, o.p[e]), false);
    }
    return mask;
}
