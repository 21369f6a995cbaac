// Exponential shadow maps (registry/esm.rs): the twins of its exp, store and test, for the
// filtered maps' kernels (gpu/filtered.wgsl: quantize, fparams), with the CPU's operations in
// the CPU's order. fparams.p0: the exponent c.

// esm::exp: fdlibm's reduction and rational approximation, times 2^k as a product of powers
// of two (WGSL has no f64 exp). 0 below -708, exp(709) above 709.
const POW2_UP = array<f64, 10>(0x1p1lf, 0x1p2lf, 0x1p4lf, 0x1p8lf, 0x1p16lf, 0x1p32lf, 0x1p64lf,
    0x1p128lf, 0x1p256lf, 0x1p512lf);
const POW2_DOWN = array<f64, 10>(0x1p-1lf, 0x1p-2lf, 0x1p-4lf, 0x1p-8lf, 0x1p-16lf, 0x1p-32lf,
    0x1p-64lf, 0x1p-128lf, 0x1p-256lf, 0x1p-512lf);

fn exp64(x_in: f64) -> f64 {
    if !(x_in >= -708.0lf) {
        return 0.0lf;
    }
    var x = x_in;
    if x > 709.0lf {
        x = 709.0lf;
    }
    let k = floor(x * 1.4426950408889634lf + 0.5lf);
    let hi = x - k * 0.6931471803691238lf;
    let lo = k * 1.9082149292705877e-10lf;
    let r = hi - lo;
    let t = r * r;
    let c = r - t * (0.16666666666666602lf + t * (-0.0027777777777015593lf + t
        * (6.613756321437934e-05lf + t * (-1.6533902205465252e-06lf
        + t * 4.1381367970572385e-08lf))));
    var y = 1.0lf - ((lo - (r * c) / (2.0lf - c)) - hi);
    let n = u32(abs(k));
    for (var i = 0u; i < 10u; i++) {
        if (n & (1u << i)) != 0u {
            if k < 0.0lf {
                y = y * POW2_DOWN[i];
            } else {
                y = y * POW2_UP[i];
            }
        }
    }
    return y;
}

// ExponentialShadowMap::store: exp(c (z - 1)) rounded to the storage precision.
fn store(z: f64) -> array<f64, 4> {
    return array<f64, 4>(quantize(exp64(fparams.p0 * (z - 1.0lf))), 0.0lf, 0.0lf, 0.0lf);
}

// ExponentialShadowMap::test: 1 where F >= exp(c (d - 1)), else the quotient.
fn test(v: array<f64, 4>, z: f64) -> f64 {
    let e = exp64(fparams.p0 * (z - 1.0lf));
    if v[0] >= e {
        return 1.0lf;
    }
    return v[0] / e;
}
