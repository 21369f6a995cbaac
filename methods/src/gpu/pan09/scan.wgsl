// Exclusive prefix sums of `data[..n]` in place, in three passes: each invocation scans a
// chunk of CHUNK values (`chunks`), one invocation scans the chunk totals (`totals`, the
// grand total lands in sums[chunk count]), and every value adds its chunk's offset (`add`).
// dims: n.

@group(0) @binding(0) var<storage, read> dims: array<u32>;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> sums: array<u32>;

const CHUNK: u32 = 256u;

@compute @workgroup_size(64)
fn chunks(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let c = gid.x + gid.y * (groups.x * 64u);
    let n = dims[0];
    if c * CHUNK >= n { return; }
    var acc = 0u;
    for (var i = c * CHUNK; i < min(n, (c + 1u) * CHUNK); i++) {
        let v = data[i];
        data[i] = acc;
        acc += v;
    }
    sums[c] = acc;
}

@compute @workgroup_size(1)
fn totals() {
    let m = (dims[0] + CHUNK - 1u) / CHUNK;
    _ = arrayLength(&data);
    var acc = 0u;
    for (var c = 0u; c < m; c++) {
        let v = sums[c];
        sums[c] = acc;
        acc += v;
    }
    sums[m] = acc;
}

@compute @workgroup_size(64)
fn add(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * (groups.x * 64u);
    if i >= dims[0] { return; }
    data[i] += sums[i / CHUNK];
}
