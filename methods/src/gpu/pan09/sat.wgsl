// Stage "summed-area table" (sat::SummedAreaTable): `(res + 1)^2` sums with a zero first row
// and column; `rows` scans each row of the mask, then `cols` runs down each column.
// dims: res.

@group(0) @binding(0) var<storage, read> dims: array<u32>;
@group(0) @binding(1) var<storage, read> mask: array<u32>;
@group(0) @binding(2) var<storage, read_write> sums: array<u32>;

@compute @workgroup_size(64)
fn rows(@builtin(global_invocation_id) gid: vec3<u32>) {
    let res = dims[0];
    let y = gid.x;
    if y >= res { return; }
    let stride = res + 1u;
    var acc = 0u;
    for (var x = 0u; x < res; x++) {
        acc += select(0u, 1u, mask[y * res + x] != 0u);
        sums[(y + 1u) * stride + x + 1u] = acc;
    }
}

@compute @workgroup_size(64)
fn cols(@builtin(global_invocation_id) gid: vec3<u32>) {
    let res = dims[0];
    let x = gid.x;
    if x > res { return; }
    let stride = res + 1u;
    // The mask is bound so that both entry points share one layout.
    _ = arrayLength(&mask);
    for (var y = 1u; y <= res; y++) {
        sums[y * stride + x] += sums[(y - 1u) * stride + x];
    }
}
