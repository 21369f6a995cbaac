// pcf-gems16 / pcf-gems4: GPU Gems' 4x4-region percentage-closer filtering with bilinear
// lookups (pcf_gems::bilinear_pcf, pcf_gems::filter), one thread a pixel. After pixel.wgsl (its
// bindings 0 to 4) and counters.wgsl.

@group(0) @binding(5) var<storage, read> map_depth: array<f64>;
@group(0) @binding(6) var<storage, read_write> lit: array<f32>;
@group(0) @binding(7) var<storage, read_write> counters: array<atomic<u32>, 4>;

struct Filtered {
    lit: f64,
    compares: u32,
}

// pcf_gems::bilinear_pcf: one bilinear lookup at map point q.
fn bilinear_pcf(q: vec2<f64>, depth: f64, tol: f64) -> Filtered {
    let u = q - vec2<f64>(0.5lf);
    let x0 = floor(u.x);
    let y0 = floor(u.y);
    let fx = u.x - x0;
    let fy = u.y - y0;
    let r = f64(params.res);
    var compares = 0u;
    // l[2 * dy + dx]
    var l = array<f64, 4>(1.0lf, 1.0lf, 1.0lf, 1.0lf);
    for (var c = 0u; c < 4u; c++) {
        let x = x0 + f64(c & 1u);
        let y = y0 + f64(c >> 1u);
        if x >= 0.0lf && y >= 0.0lf && x < r && y < r {
            compares += 1u;
            if map_depth[u32(y) * params.res + u32(x)] < depth - tol {
                l[c] = 0.0lf;
            }
        }
    }
    let top = l[0] + fx * (l[1] - l[0]);
    let bottom = l[2] + fx * (l[3] - l[2]);
    return Filtered(clamp(top + fy * (bottom - top), 0.0lf, 1.0lf), compares);
}

// pcf_gems::OFFSETS_4.
const OFFSETS_4 = array<vec2<f64>, 4>(
    vec2<f64>(-1.5lf, 0.5lf),
    vec2<f64>(0.5lf, 0.5lf),
    vec2<f64>(-1.5lf, -1.5lf),
    vec2<f64>(0.5lf, -1.5lf),
);

@compute @workgroup_size(64)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let k = pixel_index(gid, groups);
    var compares = 0u;
    var lookups = 0u;
    if k < params.pixels {
        var v = 1.0lf;
        let r = pixel_receiver(k);
        if r.ok {
            let tol = tolerance(params, r, vec2<f64>(params.reach, params.reach));
            var sum = 0.0lf;
            if params.dithered == 0u {
                // pcf_gems::OFFSETS_16, row by row.
                for (var s = 0u; s < 16u; s++) {
                    let o = vec2<f64>(-1.5lf + f64(s % 4u), -1.5lf + f64(s / 4u));
                    let f = bilinear_pcf(r.xy + o, r.depth, tol);
                    sum += f.lit;
                    compares += f.compares;
                }
                v = sum / 16.0lf;
                lookups = 16u;
            } else {
                // pcf_gems::dither_offset of pixel (x, y).
                let x = k % params.width;
                let y = k / params.width;
                let ox = x % 2u;
                let d = vec2<f64>(f64(ox), f64((y % 2u) ^ ox));
                for (var s = 0u; s < 4u; s++) {
                    let f = bilinear_pcf(r.xy + (OFFSETS_4[s] + d), r.depth, tol);
                    sum += f.lit;
                    compares += f.compares;
                }
                v = sum / 4.0lf;
                lookups = 4u;
            }
        }
        lit[k] = f32(v);
    }
    count(local, compares, lookups);
}
