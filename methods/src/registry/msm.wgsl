// Moment shadow maps (registry/msm.rs): the twins of MomentShadowMap's store and test and of
// its Hamburger reconstruction, for the filtered maps' kernels (gpu/filtered.wgsl: quantize,
// reduce_bleeding, fparams), with the CPU's operations in the CPU's order. fparams.p0: the
// moment bias; p1: the light-bleeding reduction; fparams.precision_code 3 (u16) stores in the
// optimized basis (msm::FORWARD, OFFSET) and undoes it before the reconstruction
// (msm::INVERSE).

// msm::FORWARD and msm::INVERSE, row by row.
const FORWARD = array<f64, 16>(
    -2.07224649lf, 13.7948857237lf, 0.105877704lf, 9.7924062118lf,
    32.23703778lf, -59.4683975703lf, -1.9077466311lf, -33.7652110555lf,
    -68.571074599lf, 82.0359750338lf, 9.3496555107lf, 47.9456096605lf,
    39.3703274134lf, -35.364903257lf, -6.6543490743lf, -23.9728048165lf,
);
const INVERSE = array<f64, 16>(
    0.2227744146lf, 0.1549679261lf, 0.1451988946lf, 0.163127443lf,
    0.0771972861lf, 0.1394629426lf, 0.2120202157lf, 0.2591432266lf,
    0.7926986636lf, 0.7963415838lf, 0.7258694464lf, 0.6539092497lf,
    0.0319417555lf, -0.1722823173lf, -0.2758014811lf, -0.3376131734lf,
);
const OFFSET: f64 = 0.035955884801lf;
const PRECISION_U16: u32 = 3u;

// msm's times: the row vector v times the matrix m, each column summed in row order.
fn times(v: array<f64, 4>, forward: bool) -> array<f64, 4> {
    var m = INVERSE;
    if forward {
        m = FORWARD;
    }
    var out: array<f64, 4>;
    for (var j = 0u; j < 4u; j++) {
        out[j] = v[0] * m[j] + v[1] * m[4u + j] + v[2] * m[8u + j] + v[3] * m[12u + j];
    }
    return out;
}

// MomentShadowMap::store.
fn store(z: f64) -> array<f64, 4> {
    let z2 = z * z;
    var b = array<f64, 4>(z, z2, z2 * z, z2 * z2);
    if fparams.precision_code == PRECISION_U16 {
        b = times(b, true);
        b[0] = b[0] + OFFSET;
    }
    for (var i = 0u; i < 4u; i++) {
        b[i] = quantize(b[i]);
    }
    return b;
}

// msm's hamburger: the shadow intensity, and whether it is finite.
struct Shadow {
    g: f64,
    ok: bool,
}

fn hamburger(b_in: array<f64, 4>, zf: f64, alpha: f64) -> Shadow {
    var b: array<f64, 4>;
    for (var i = 0u; i < 4u; i++) {
        b[i] = (1.0lf - alpha) * b_in[i] + alpha * 0.5lf;
    }
    let l21 = b[0];
    let l31 = b[1];
    let d22 = b[1] - b[0] * b[0];
    let l32 = (b[2] - b[0] * b[1]) / d22;
    let d33 = b[3] - b[1] * b[1] - l32 * l32 * d22;
    let y1 = 1.0lf;
    let y2 = zf - l21 * y1;
    let y3 = zf * zf - l31 * y1 - l32 * y2;
    let c3 = y3 / d33;
    let c2 = y2 / d22 - l32 * c3;
    let c1 = y1 - l21 * c2 - l31 * c3;
    let q = c2 * c2 - 4.0lf * c3 * c1;
    var disc = 0.0lf;
    if q > 0.0lf {
        disc = sqrt(q);
    }
    let r1 = (-c2 - disc) / (2.0lf * c3);
    let r2 = (-c2 + disc) / (2.0lf * c3);
    var z2 = r2;
    var z3 = r1;
    if r1 <= r2 {
        z2 = r1;
        z3 = r2;
    }
    var g: f64;
    if zf <= z2 {
        g = 0.0lf;
    } else if zf <= z3 {
        g = (zf * z3 - b[0] * (zf + z3) + b[1]) / ((z3 - z2) * (zf - z2));
    } else {
        g = 1.0lf - (z2 * z3 - b[0] * (z2 + z3) + b[1]) / ((zf - z2) * (zf - z3));
    }
    return Shadow(g, is_finite64(g));
}

// MomentShadowMap::test.
fn test(v: array<f64, 4>, z: f64) -> f64 {
    var b = v;
    if fparams.precision_code == PRECISION_U16 {
        var o = v;
        o[0] = o[0] - OFFSET;
        b = times(o, false);
    }
    let h = hamburger(b, z, fparams.p0);
    var shadow = h.g;
    if !h.ok {
        shadow = 0.0lf;
        if z > b[0] {
            shadow = 1.0lf;
        }
    }
    return reduce_bleeding(1.0lf - shadow, fparams.p1);
}
