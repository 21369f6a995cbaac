// Stage "validity mask" (validity::validity_masks), one invocation per candidate (facet,
// triangle) noted by the visibility evaluation: a triangle whose section with the facet's
// plane meets the pixel hides from the camera the sub-samples it covers as seen from the
// eye; they are ANDed out of the facet's validity mask (the centre always stays). dims: n.

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> dims: array<u32>;
@group(0) @binding(2) var<storage, read> candidates: array<u32>;
@group(0) @binding(3) var<storage, read> corners: array<f64>;
@group(0) @binding(4) var<storage, read> FF: array<FacetF>;
@group(0) @binding(5) var<storage, read> FU: array<FacetU>;
@group(0) @binding(6) var<storage, read> lut: array<u32>;
@group(0) @binding(7) var<storage, read_write> valid: array<atomic<u32>>;

fn corner(t: u32, i: u32) -> vec3<f64> {
    let o = 9u * t + 3u * i;
    return vec3<f64>(corners[o], corners[o + 1u], corners[o + 2u]);
}

// validity::meets_pixel.
fn meets_pixel(s: Setup, c: array<vec3<f64>, 3>, f: u32) -> bool {
    let normal = facet_normal(f);
    let offset = facet_offset(f);
    let d = array<f64, 3>(dot3(normal, c[0]) - offset, dot3(normal, c[1]) - offset, dot3(normal, c[2]) - offset);
    if d[0] == 0.0lf && d[1] == 0.0lf && d[2] == 0.0lf { return false; }
    var pts: array<vec3<f64>, 3>;
    var n = 0u;
    for (var i = 0u; i < 3u; i++) {
        let j = (i + 1u) % 3u;
        if d[i] == 0.0lf {
            pts[n] = c[i];
            n += 1u;
        } else if d[i] * d[j] < 0.0lf && n < 3u {
            pts[n] = c[i] + (c[j] - c[i]) * (d[i] / (d[i] - d[j]));
            n += 1u;
        }
    }
    if n == 0u { return false; }
    let b = select(pts[0], pts[1], n >= 2u);
    let pa = proj_project(s.camera, pts[0]);
    let pb = proj_project(s.camera, b);
    if pa.w == 0.0lf || pb.w == 0.0lf { return false; }
    let pixel = FU[f].pixel;
    let lo = vec2<f64>(f64(pixel % s.width), f64(pixel / s.width));
    return clip_segment(pa.xy, pb.xy, lo, lo + vec2<f64>(1.0lf, 1.0lf), 0.0lf).z != 0.0lf;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = flat_index(gid, groups);
    if i >= dims[0] { return; }
    let s = setup();
    let f = candidates[2u * i];
    let t = candidates[2u * i + 1u];
    let c = array<vec3<f64>, 3>(corner(t, 0u), corner(t, 1u), corner(t, 2u));
    if !meets_pixel(s, c, f) { return; }
    let viewer = occluder(c, s.eye, 0.0lf, s.cam);
    if !viewer.ok { return; }
    let hidden = occlusion(s, viewer, facet_map_of(f));
    if is_zero4(hidden) { return; }
    for (var w = 0u; w < s.words; w++) {
        atomicAnd(&valid[f * s.words + w], ~hidden[w] | s.centre[w]);
    }
}
