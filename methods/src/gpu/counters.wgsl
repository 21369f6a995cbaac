// Counters of the shadow-map kernels, summed per workgroup then added to 64-bit totals kept
// as two u32 words (low, high) in `counters`: [shadow_map_lookups, bilinear_lookups]. The
// including kernel declares `counters: array<atomic<u32>, 4>` and a workgroup size of 64,
// and calls `count` from uniform control flow (it has a barrier).

var<workgroup> wg_lookups: atomic<u32>;
var<workgroup> wg_bilinear: atomic<u32>;

fn add64(slot: u32, v: u32) {
    if v == 0u {
        return;
    }
    let old = atomicAdd(&counters[slot], v);
    if old > 0xffffffffu - v {
        atomicAdd(&counters[slot + 1u], 1u);
    }
}

fn count(local: u32, lookups: u32, bilinear: u32) {
    atomicAdd(&wg_lookups, lookups);
    atomicAdd(&wg_bilinear, bilinear);
    workgroupBarrier();
    if local == 0u {
        add64(0u, atomicLoad(&wg_lookups));
        add64(2u, atomicLoad(&wg_bilinear));
    }
}
