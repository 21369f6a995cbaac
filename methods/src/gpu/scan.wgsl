// Exclusive prefix sum of `n` u32 in place (three passes: per block of 256, over the block
// sums in one workgroup, then adding each block's offset); `total` gets the sum of all.

@group(0) @binding(0) var<storage, read> params: array<u32>;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> sums: array<u32>;
@group(0) @binding(3) var<storage, read_write> total: array<u32>;

const WG: u32 = 256u;
var<workgroup> sh: array<u32, 256>;

// Inclusive scan of sh (all 256 invocations take part).
fn scan_shared(li: u32) {
    for (var off = 1u; off < WG; off = off * 2u) {
        var add = 0u;
        if li >= off {
            add = sh[li - off];
        }
        workgroupBarrier();
        sh[li] = sh[li] + add;
        workgroupBarrier();
    }
}

@compute @workgroup_size(256)
fn scan_blocks(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    _ = arrayLength(&total);
    let n = params[0];
    let block = wid.x + wid.y * nwg.x;
    let i = block * WG + li;
    var v = 0u;
    if i < n {
        v = data[i];
    }
    sh[li] = v;
    workgroupBarrier();
    scan_shared(li);
    if i < n {
        data[i] = sh[li] - v;
    }
    if li == WG - 1u {
        sums[block] = sh[li];
    }
}

@compute @workgroup_size(256)
fn scan_sums(@builtin(local_invocation_index) li: u32) {
    _ = arrayLength(&data);
    let n = params[0];
    let blocks = (n + WG - 1u) / WG;
    let chunk = (blocks + WG - 1u) / WG;
    let first = li * chunk;
    let last = min(first + chunk, blocks);
    var s = 0u;
    for (var k = first; k < last; k = k + 1u) {
        s = s + sums[k];
    }
    sh[li] = s;
    workgroupBarrier();
    scan_shared(li);
    var run = sh[li] - s;
    for (var k = first; k < last; k = k + 1u) {
        let t = sums[k];
        sums[k] = run;
        run = run + t;
    }
    if li == WG - 1u {
        total[0] = sh[li];
    }
}

@compute @workgroup_size(256)
fn scan_add(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    _ = arrayLength(&total);
    let i = gid.x + gid.y * (nwg.x * WG);
    if i >= params[0] {
        return;
    }
    data[i] = data[i] + sums[i / WG];
}
