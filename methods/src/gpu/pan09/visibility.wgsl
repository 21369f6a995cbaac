// Stage "visibility evaluation" (visibility::occlusion_masks), one invocation per TT-pair:
// its triangle as an Occluder against every facet of its texel's PT list (less the pixel's
// own triangle), the occluded sub-samples ORed into the facet's mask word by word. With
// curved receivers (`curved`) it also appends the validity candidates (facet, triangle) to
// `candidates`, up to dims[1] of them (the TT stage's bound on the evaluations). dims: pairs,
// candidate capacity.

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> dims: array<u32>;
@group(0) @binding(2) var<storage, read> tt: array<u32>;
@group(0) @binding(3) var<storage, read> corners: array<f64>;
@group(0) @binding(4) var<storage, read> toff: array<u32>;
@group(0) @binding(5) var<storage, read> items: array<u32>;
@group(0) @binding(6) var<storage, read> FF: array<FacetF>;
@group(0) @binding(7) var<storage, read> FU: array<FacetU>;
@group(0) @binding(8) var<storage, read> lut: array<u32>;
@group(0) @binding(9) var<storage, read_write> masks: array<atomic<u32>>;
@group(0) @binding(10) var<storage, read_write> candidates: array<u32>;
@group(0) @binding(11) var<storage, read_write> counters: array<atomic<u32>>;

fn max_element(v: vec3<f64>) -> f64 {
    return max(max(v.x, v.y), v.z);
}

// visibility::occluder_offset: `ratio` (afsm::SHADOW_OFFSET) times the magnitude of the
// triangle's corners seen from `eye`.
fn occluder_offset(eye: vec3<f64>, c: array<vec3<f64>, 3>, ratio: f64) -> f64 {
    var m = max_element(abs(eye));
    var d = 0.0lf;
    for (var i = 0u; i < 3u; i++) {
        m = max(m, max_element(abs(c[i])));
        d = max(d, max_element(abs(c[i] - eye)));
    }
    return ratio * (m + d);
}

fn corner(t: u32, i: u32) -> vec3<f64> {
    let o = 9u * t + 3u * i;
    return vec3<f64>(corners[o], corners[o + 1u], corners[o + 2u]);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = flat_index(gid, groups);
    _ = arrayLength(&candidates);
    if i >= dims[0] { return; }
    let s = setup();
    let texel = tt[2u * i];
    let t = tt[2u * i + 1u];
    let c = array<vec3<f64>, 3>(corner(t, 0u), corner(t, 1u), corner(t, 2u));
    let o = occluder(c, s.lm, occluder_offset(s.camera.origin, c, s.offset), s.cam);
    if !o.ok { return; }
    var evaluations = 0u;
    for (var j = toff[texel]; j < toff[texel + 1u]; j++) {
        let f = items[j];
        if FU[f].triangle == t { continue; }
        evaluations += 1u;
        let map = facet_map_of(f);
        let m = occlusion(s, o, map);
        for (var w = 0u; w < s.words; w++) {
            if m[w] != 0u {
                atomicOr(&masks[f * s.words + w], m[w]);
            }
        }
        if s.curved == 1u {
            let depth = half_plane(map, o.p[3]);
            if depth.x <= 0.0lf && crossing(depth) == SPLIT {
                let slot = atomicAdd(&counters[C_CANDIDATES], 1u);
                if slot < dims[1] {
                    candidates[2u * slot] = f;
                    candidates[2u * slot + 1u] = t;
                }
            }
        }
    }
    atomicAdd(&counters[C_EVALUATIONS], evaluations);
}
