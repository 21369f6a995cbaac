// A silhouette facet's record as the later stages read it: FF (FacetF) and FU (FacetU) per
// facet (facet_layout.wgsl).

fn facet_normal(f: u32) -> vec3<f64> {
    return xyz(FF[f].normal);
}

fn facet_offset(f: u32) -> f64 {
    return FF[f].offset;
}

fn facet_map_of(f: u32) -> FacetMap {
    let r = FF[f];
    return FacetMap(xyz(r.origin), xyz(r.dir), xyz(r.a), vec2<f64>(r.b[0], r.b[1]), r.k, true);
}

fn facet_region(f: u32, i: u32) -> vec3<f64> {
    return xyz(FF[f].region[i]);
}

fn facet_footprint(f: u32) -> Footprint {
    let r = FF[f];
    var fp: Footprint;
    fp.n = FU[f].corners;
    for (var i = 0u; i < 8u; i++) {
        fp.c[i] = vec2<f64>(r.footprint[2u * i], r.footprint[2u * i + 1u]);
    }
    fp.lo = vec2<f64>(r.lo[0], r.lo[1]);
    fp.hi = vec2<f64>(r.hi[0], r.hi[1]);
    fp.orientation = r.orientation;
    fp.ok = true;
    return fp;
}
