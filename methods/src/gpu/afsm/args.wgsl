// The indirect dispatch of `test`: one invocation per (triangle, cell) item, in workgroups
// of 64 laid out as (x, y, 1) with x at most 65535.

@group(0) @binding(0) var<storage, read> uparams: UParams;
@group(0) @binding(1) var<storage, read> item_start: array<u32>;
@group(0) @binding(2) var<storage, read_write> args: array<u32>;

@compute @workgroup_size(1)
fn args_main() {
    let total = item_start[uparams.triangles];
    let groups = (total + 63u) / 64u;
    let x = min(groups, 65535u);
    args[0] = x;
    args[1] = max((groups + x - 1u) / max(x, 1u), 1u);
    args[2] = 1u;
}
