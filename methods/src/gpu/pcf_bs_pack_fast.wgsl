// Brabec and Seidel, section 4, texel packing (pcf_bs::pack_neighbourhood): packed texel k
// holds the 2x2 codes from k + offset to k + offset + (1, 1), the far code beyond the map;
// packed indices run over -1..res. Needs common.wgsl and receiver.wgsl before it.

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> codes: array<u32>;
@group(0) @binding(2) var<storage, read_write> packed: array<vec4<u32>>;

fn code_at(x: i32, y: i32) -> u32 {
    let r = i32(params.res);
    if x >= 0 && y >= 0 && x < r && y < r {
        return codes[u32(y * r + x)];
    }
    return u32(params.code_max);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = gid.x + gid.y * (groups.x * 64u);
    let side = params.side;
    if k < side * side {
        let x = i32(k % side) - 1 + params.offset_x;
        let y = i32(k / side) - 1 + params.offset_y;
        packed[k] = vec4<u32>(code_at(x, y), code_at(x + 1, y), code_at(x, y + 1), code_at(x + 1, y + 1));
    }
}
