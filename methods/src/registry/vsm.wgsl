// Variance shadow maps (registry/vsm.rs): the twins of VarianceShadowMap's store and test, for
// the filtered maps' kernels (gpu/filtered.wgsl: quantize, reduce_bleeding, fparams), with the
// CPU's operations in the CPU's order. fparams.p0: the least variance; p1: the light-bleeding
// reduction.

// VarianceShadowMap::store: the two moments, each rounded to the storage precision.
fn store(z: f64) -> array<f64, 4> {
    return array<f64, 4>(quantize(z), quantize(z * z), 0.0lf, 0.0lf);
}

// VarianceShadowMap::test: Chebyshev's upper bound, remapped by the bleeding reduction.
fn test(v: array<f64, 4>, z: f64) -> f64 {
    let mu = v[0];
    if z <= mu {
        return 1.0lf;
    }
    let d = v[1] - mu * mu;
    var variance = fparams.p0;
    if d > fparams.p0 {
        variance = d;
    }
    if !(variance > 0.0lf) {
        return 0.0lf;
    }
    let over = z - mu;
    return reduce_bleeding(variance / (variance + over * over), fparams.p1);
}
