// spsm consistent min depth, first pass: marks the 3x3 neighbourhood of every uncertain
// pixel's texel (spsm::depth::consistent_depths' index set), one thread an uncertain pixel.
// Needs common.wgsl and texel.wgsl before it.

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> centres: array<u32>;
@group(0) @binding(2) var<storage, read_write> marks: array<atomic<u32>>;
// texel.wgsl's decoding reads these; this pass does not (they stay out of its layout).
@group(0) @binding(3) var<storage, read> texels: array<u32>;
@group(0) @binding(4) var<storage, read> planes: array<u32>;
@group(0) @binding(5) var<storage, read> tables: array<f64>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = gid.x + gid.y * (groups.x * 64u);
    if k >= params.count {
        return;
    }
    let r = i32(params.res);
    let x = i32(centres[k] % params.res);
    let y = i32(centres[k] / params.res);
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let tx = x + dx;
            let ty = y + dy;
            if tx >= 0 && ty >= 0 && tx < r && ty < r {
                atomicStore(&marks[u32(ty * r + tx)], 1u);
            }
        }
    }
}
