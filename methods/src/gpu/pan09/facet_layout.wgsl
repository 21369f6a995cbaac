// A silhouette facet's record, in two parts (facets::FacetF and facets::FacetU, checked
// against these structs), written by facets.wgsl and read through facet_record.wgsl.

// The f64 part: the facet's plane (normal, offset), its map (facets::FacetMap: origin, dir,
// a, b, k), its region's three planes, its footprint's corners (x, y; `corners` of them,
// up to eight), bounding box and orientation.
struct FacetF {
    normal: Xyz,
    offset: f64,
    origin: Xyz,
    dir: Xyz,
    a: Xyz,
    b: array<f64, 2>,
    k: f64,
    region: array<Xyz, 3>,
    footprint: array<f64, 16>,
    lo: array<f64, 2>,
    hi: array<f64, 2>,
    orientation: f64,
}

// The u32 part: the facet's pixel and triangle, its region's plane count, its footprint's
// corner count, and its texel rectangle (x0, y0, x1, y1).
struct FacetU {
    pixel: u32,
    triangle: u32,
    regions: u32,
    corners: u32,
    rect: array<u32, 4>,
}
