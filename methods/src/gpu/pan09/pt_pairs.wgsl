// Stage "pixel-texel pairs" (pairs::pixel_texel_pairs): `count` sizes each silhouette facet's
// texel rectangle (scanned into write offsets afterwards), `emit` writes a (texel, facet) key
// per texel of the rectangle, `test` keeps the keys whose texel the footprint touches and
// counts them per texel (scanned into the lists' offsets afterwards), `scatter` writes the
// kept facets into their texel's list. Within a texel's list the facets come in the order
// the atomics hand out slots: the lists are only ever read whole, and every use ORs or ANDs
// into masks, so the order changes nothing. dims: n (facets or keys), res.

@group(0) @binding(0) var<storage, read> dims: array<u32>;
@group(0) @binding(1) var<storage, read> FF: array<FacetF>;
@group(0) @binding(2) var<storage, read> FU: array<FacetU>;
@group(0) @binding(3) var<storage, read_write> counts: array<u32>;
@group(0) @binding(4) var<storage, read_write> keys: array<u32>;
@group(0) @binding(5) var<storage, read_write> flags: array<u32>;
@group(0) @binding(6) var<storage, read_write> texel_count: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> cursor: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> items: array<u32>;
@group(0) @binding(9) var<storage, read_write> counters: array<atomic<u32>>;

// Every entry point binds the same buffers.
fn bind_all() {
    _ = arrayLength(&FF);
    _ = arrayLength(&FU);
    _ = arrayLength(&counts);
    _ = arrayLength(&keys);
    _ = arrayLength(&flags);
    _ = atomicLoad(&texel_count[0]);
    _ = atomicLoad(&cursor[0]);
    _ = arrayLength(&items);
    _ = atomicLoad(&counters[0]);
}

fn rect_of(f: u32) -> vec4<u32> {
    let r = FU[f].rect;
    return vec4<u32>(r[0], r[1], r[2], r[3]);
}

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    bind_all();
    let f = flat_index(gid, groups);
    if f >= dims[0] { return; }
    let r = rect_of(f);
    counts[f] = (r.z - r.x + 1u) * (r.w - r.y + 1u);
}

@compute @workgroup_size(64)
fn emit(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    bind_all();
    let f = flat_index(gid, groups);
    if f >= dims[0] { return; }
    let res = dims[1];
    let r = rect_of(f);
    var slot = counts[f];
    for (var y = r.y; y <= r.w; y++) {
        for (var x = r.x; x <= r.z; x++) {
            keys[2u * slot] = y * res + x;
            keys[2u * slot + 1u] = f;
            slot += 1u;
        }
    }
}

@compute @workgroup_size(64)
fn test(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    bind_all();
    let i = flat_index(gid, groups);
    if i >= dims[0] { return; }
    let res = dims[1];
    let texel = keys[2u * i];
    let f = keys[2u * i + 1u];
    let keep = touches_texel(facet_footprint(f), texel % res, texel / res);
    flags[i] = select(0u, 1u, keep);
    if keep {
        atomicAdd(&texel_count[texel], 1u);
        atomicAdd(&counters[C_PT_PAIRS], 1u);
    }
}

@compute @workgroup_size(64)
fn scatter(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    bind_all();
    let i = flat_index(gid, groups);
    if i >= dims[0] || flags[i] == 0u { return; }
    let texel = keys[2u * i];
    let slot = atomicLoad(&texel_count[texel]) + atomicAdd(&cursor[texel], 1u);
    items[slot] = keys[2u * i + 1u];
}
