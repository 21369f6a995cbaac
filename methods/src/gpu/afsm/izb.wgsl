// Stage "IZB construction": the samples binned into the light-space grid. `count` gives each
// sample its cell and its rank there (atomicAdd on the cell's count); after the exclusive
// scan of the counts, `scatter` writes each sample to its cell's run of the sample array.
// Appended to common.wgsl and grid.wgsl.

@group(0) @binding(0) var<storage, read> fparams: FParams;
@group(0) @binding(1) var<storage, read> uparams: UParams;
@group(0) @binding(2) var<storage, read> sample_f: array<f64>;
@group(0) @binding(3) var<storage, read> sample_tri: array<u32>;
// Per pixel: (cell, rank in the cell).
@group(0) @binding(4) var<storage, read_write> slot: array<u32>;
// count: per cell, samples so far; scatter: per cell, its first sample (scanned).
@group(0) @binding(5) var<storage, read_write> cells: array<atomic<u32>>;
// scatter only: the binned samples, 3 f64 (x, y, threshold) and 2 u32 (pixel, triangle).
@group(0) @binding(6) var<storage, read_write> izb_f: array<f64>;
@group(0) @binding(7) var<storage, read_write> izb_u: array<u32>;

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    _ = arrayLength(&izb_f);
    _ = arrayLength(&izb_u);
    let k = gid.x + gid.y * (nwg.x * 64u);
    if k >= uparams.pixels || sample_tri[k] == NO_TRIANGLE {
        return;
    }
    let g = uparams.grid;
    let cx = cell_axis(sample_f[3u * k], fparams.cell_x, g);
    let cy = cell_axis(sample_f[3u * k + 1u], fparams.cell_y, g);
    let cell = cy * g + cx;
    slot[2u * k] = cell;
    slot[2u * k + 1u] = atomicAdd(&cells[cell], 1u);
}

@compute @workgroup_size(64)
fn scatter(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    _ = fparams.offset;
    let k = gid.x + gid.y * (nwg.x * 64u);
    if k >= uparams.pixels || sample_tri[k] == NO_TRIANGLE {
        return;
    }
    let at = atomicLoad(&cells[slot[2u * k]]) + slot[2u * k + 1u];
    izb_f[3u * at] = sample_f[3u * k];
    izb_f[3u * at + 1u] = sample_f[3u * k + 1u];
    izb_f[3u * at + 2u] = sample_f[3u * k + 2u];
    izb_u[2u * at] = k;
    izb_u[2u * at + 1u] = sample_tri[k];
}
