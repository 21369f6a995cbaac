// A silhouette facet's record: FF (f64, FACET_F per facet) and FU (u32, FACET_U per facet).
// FF: normal 0..3, offset 3, map origin 4..7, dir 7..10, a 10..13, b 13..15, k 15, region
// 16..25, footprint corners 25..41, lo 41..43, hi 43..45, orientation 45.
// FU: pixel, triangle, region count, corner count, rectangle x0 y0 x1 y1.

const FACET_F: u32 = 48u;
const FACET_U: u32 = 8u;

fn ff3(o: u32) -> vec3<f64> {
    return vec3<f64>(FF[o], FF[o + 1u], FF[o + 2u]);
}

fn facet_normal(f: u32) -> vec3<f64> {
    return ff3(f * FACET_F);
}

fn facet_offset(f: u32) -> f64 {
    return FF[f * FACET_F + 3u];
}

fn facet_map_of(f: u32) -> FacetMap {
    let o = f * FACET_F;
    return FacetMap(ff3(o + 4u), ff3(o + 7u), ff3(o + 10u), vec2<f64>(FF[o + 13u], FF[o + 14u]), FF[o + 15u], true);
}

fn facet_region(f: u32, i: u32) -> vec3<f64> {
    return ff3(f * FACET_F + 16u + 3u * i);
}

fn facet_footprint(f: u32) -> Footprint {
    let o = f * FACET_F;
    var fp: Footprint;
    fp.n = FU[f * FACET_U + 3u];
    for (var i = 0u; i < 8u; i++) {
        fp.c[i] = vec2<f64>(FF[o + 25u + 2u * i], FF[o + 26u + 2u * i]);
    }
    fp.lo = vec2<f64>(FF[o + 41u], FF[o + 42u]);
    fp.hi = vec2<f64>(FF[o + 43u], FF[o + 44u]);
    fp.orientation = FF[o + 45u];
    fp.ok = true;
    return fp;
}
