// afsm's per-frame constants and blocker records as the kernels read them (afsm.rs's
// `FParams`, `UParams`, `BlockerOutline`, `BlockerPlane` and `BlockerU`, checked against
// these structs).

// The shadow offset ratio (afsm::SHADOW_OFFSET), the grid's cells per light-image unit along
// x and y, orient2d's filter bound, and the sub-sample's offset in its pixel.
struct FParams {
    offset: f64,
    cell_x: f64,
    cell_y: f64,
    filter_bound: f64,
    sub_x: f64,
    sub_y: f64,
}

// Pixels, grid cells a side, triangles, image width, and 1 in a pass whose sample tests
// mark hidden sub-samples (ftizb's sub-samples but the centre), else 0.
struct UParams {
    pixels: u32,
    grid: u32,
    triangles: u32,
    width: u32,
    hidden: u32,
}

// A blocker's outline (up to four corners, x then y) and bounding box.
struct BlockerOutline {
    outline: array<f64, 8>,
    lo: array<f64, 2>,
    hi: array<f64, 2>,
}

// A blocker's plane depth function (numerator and denominator coefficients) and depth range.
struct BlockerPlane {
    num: array<f64, 3>,
    den: array<f64, 3>,
    dmin: f64,
    dmax: f64,
}

// A blocker's corner count (| ORIENTATION_UNDECIDED) and its grid cell range.
struct BlockerU {
    flags: u32,
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}
