// Brabec and Seidel, section 3, texel packing (pcf_bs::pack_stratified): the codes of the four
// jittered maps into the RGBA channels of one packed texel. Needs common.wgsl and
// receiver.wgsl before it.

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> depth0: array<f64>;
@group(0) @binding(2) var<storage, read> depth1: array<f64>;
@group(0) @binding(3) var<storage, read> depth2: array<f64>;
@group(0) @binding(4) var<storage, read> depth3: array<f64>;
@group(0) @binding(5) var<storage, read_write> packed: array<vec4<u32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = gid.x + gid.y * (groups.x * 64u);
    if k < params.side * params.side {
        packed[k] = vec4<u32>(
            code_encode(params, depth0[k]),
            code_encode(params, depth1[k]),
            code_encode(params, depth2[k]),
            code_encode(params, depth3[k]),
        );
    }
}
