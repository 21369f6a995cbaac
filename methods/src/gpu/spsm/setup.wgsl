// spsm::raster::TriSetup as the kernels read it (raster::SetupData, checked against this
// struct): the vertices (x, y), their depths, the depth gradient, the least and largest vertex
// depth.
struct SetupData {
    v: array<f64, 6>,
    z: array<f64, 3>,
    dz: array<f64, 2>,
    z_min: f64,
    z_max: f64,
}
