// Brabec and Seidel, depth encoding (pcf_bs::encode_map): each texel's depth through the
// linear ramp to its code. Needs common.wgsl and receiver.wgsl before it.

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> map_depth: array<f64>;
@group(0) @binding(2) var<storage, read_write> codes: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = gid.x + gid.y * (groups.x * 64u);
    if k < params.res * params.res {
        codes[k] = code_encode(params, map_depth[k]);
    }
}
