// The light-space grid of the irregular z-buffer, shared by the binning of samples and of
// triangles.

// The grid cell along one axis: floor(v * scale) clamped to the grid (monotone in v, so a
// box's cell range holds the cells of the points in it).
fn cell_axis(v: f64, scale: f64, g: u32) -> u32 {
    return u32(clamp(floor(v * scale), 0.0lf, f64(g - 1u)));
}
