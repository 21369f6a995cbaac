// spsm::recover::Resolved on the GPU: the occluding triangles of one recovered silhouette
// (their vertices and their orientation's sign, distinct triangles only) and the origin of
// its tangent frames, as the kernel fills them for the pixel at hand, and the silhouette
// function along one tangent (Resolved::shadowed_along; Lecocq et al. 2014, section 4.2,
// Fig. 10). The kernel defines `kept` (see texel.wgsl).

var<private> occ_v: array<vec2<f64>, 27>;
var<private> occ_sign: array<f64, 9>;
var<private> occ_n: u32;
var<private> occ_origin: vec2<f64>;

fn dot2(a: vec2<f64>, b: vec2<f64>) -> f64 {
    return kept(a.x * b.x) + kept(a.y * b.y);
}

// Resolved::shadowed_along: whether q lies beyond the boundary along the tangent of normal n.
fn shadowed_along(n: vec2<f64>, q: vec2<f64>) -> bool {
    let origin = occ_origin;
    let tangent = vec2<f64>(-n.y, n.x);
    let tq = dot2(q - origin, tangent);
    let dq = dot2(q - origin, n);
    var covered = 0.0lf;
    var has_covered = false;
    var left = vec2<f64>(0.0lf);
    var has_left = false;
    var right = vec2<f64>(0.0lf);
    var has_right = false;
    for (var k = 0u; k < occ_n; k++) {
        let sign = occ_sign[k];
        for (var e = 0u; e < 3u; e++) {
            let a = occ_v[3u * k + e];
            let b = occ_v[3u * k + (e + 1u) % 3u];
            let d = b - a;
            let outward = vec2<f64>(d.y, -d.x) * sign;
            if dot2(outward, n) >= 0.0lf {
                continue;
            }
            let pa = vec2<f64>(dot2(a - origin, tangent), dot2(a - origin, n));
            let pb = vec2<f64>(dot2(b - origin, tangent), dot2(b - origin, n));
            var p0 = pb;
            var p1 = pa;
            if pa.x <= pb.x {
                p0 = pa;
                p1 = pb;
            }
            if tq >= p0.x && tq <= p1.x {
                var at = min(p0.y, p1.y);
                if p1.x > p0.x {
                    at = p0.y + (p1.y - p0.y) * (tq - p0.x) / (p1.x - p0.x);
                }
                if !has_covered || at < covered {
                    covered = at;
                    has_covered = true;
                }
            }
            for (var m = 0u; m < 2u; m++) {
                let p = select(p1, p0, m == 0u);
                if p.x <= tq && (!has_left || p.x > left.x || (p.x == left.x && p.y < left.y)) {
                    left = p;
                    has_left = true;
                }
                if p.x >= tq && (!has_right || p.x < right.x || (p.x == right.x && p.y < right.y)) {
                    right = p;
                    has_right = true;
                }
            }
        }
    }
    if has_covered {
        return dq > covered;
    }
    if has_left && has_right && right.x > left.x {
        return dq > left.y + (right.y - left.y) * (tq - left.x) / (right.x - left.x);
    }
    return false;
}

