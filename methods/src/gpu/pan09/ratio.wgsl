// Stage "occlusion ratio": each silhouette facet's valid sub-samples (region half-planes,
// the validity mask, and the centre) and its lit value `1 - |occluded & valid| / |valid|`
// written to its pixel; counts the boundary pixels and, with curved receivers, their valid
// sub-samples. dims: facets.

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> dims: array<u32>;
@group(0) @binding(2) var<storage, read> FF: array<FacetF>;
@group(0) @binding(3) var<storage, read> FU: array<FacetU>;
@group(0) @binding(4) var<storage, read> lut: array<u32>;
@group(0) @binding(5) var<storage, read> masks: array<u32>;
@group(0) @binding(6) var<storage, read_write> valid: array<u32>;
@group(0) @binding(7) var<storage, read_write> lit: array<f32>;
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let f = flat_index(gid, groups);
    if f >= dims[0] { return; }
    let s = setup();
    var region = s.all;
    for (var i = 0u; i < FU[f].regions; i++) {
        region &= coverage(s, facet_region(f, i), false);
    }
    var v = vec4<u32>(0u);
    var o = vec4<u32>(0u);
    for (var w = 0u; w < s.words; w++) {
        v[w] = valid[f * s.words + w];
        o[w] = masks[f * s.words + w];
    }
    v = (region & v) | s.centre;
    let dark = f64(popcount4(o & v)) / f64(popcount4(v));
    let l = f32(clamp(1.0lf - dark, 0.0lf, 1.0lf));
    lit[FU[f].pixel] = l;
    for (var w = 0u; w < s.words; w++) {
        valid[f * s.words + w] = v[w];
    }
    if l > 0.0 && l < 1.0 {
        atomicAdd(&counters[C_BOUNDARY], 1u);
        if s.curved == 1u {
            atomicAdd(&counters[C_VALID_SAMPLES], popcount4(v));
        }
    }
}
