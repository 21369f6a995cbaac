// spsm classification (Lecocq et al. 2014, section 4.1, Algorithm 1), one thread a pixel:
// spsm::classify::Lookup::classify with the texels decoded as spsm::texel decodes them, in f64
// with the CPU's operations in the CPU's order (lookup.wgsl). A pixel whose containment tests
// the f64 filter leaves undecided is handed back (class 5).

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> light: ProjectorData;
@group(0) @binding(2) var<storage, read> g_triangle: array<u32>;
@group(0) @binding(3) var<storage, read> g_position: array<f64>;
@group(0) @binding(4) var<storage, read> g_normal: array<f64>;
// The texels (texel.wgsl).
@group(0) @binding(5) var<storage, read> texels: array<u32>;
@group(0) @binding(6) var<storage, read> planes: array<u32>;
// [0, 256): decoded slopes; [256, 512): their error bounds; [512, 768): encode thresholds.
@group(0) @binding(7) var<storage, read> tables: array<f64>;
// Per pixel: class, texel.
@group(0) @binding(8) var<storage, read_write> result: array<u32>;
// lit by one lookup, shadowed by one lookup, by the neighbourhood, uncertain, lookups,
// handed back.
@group(0) @binding(9) var<storage, read_write> counters: array<atomic<u32>, 8>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = gid.x + gid.y * (groups.x * 64u);
    if k >= params.pixels {
        return;
    }
    undecided = false;
    var cls = 0u;
    var lookups = 0u;
    var texel = 0u;
    if g_triangle[k] != NO_TRIANGLE {
        let position = vec3<f64>(g_position[3u * k], g_position[3u * k + 1u], g_position[3u * k + 2u]);
        let normal = vec3<f64>(g_normal[3u * k], g_normal[3u * k + 1u], g_normal[3u * k + 2u]);
        let m = map_point(position, normal);
        if m.ok {
            let p = m.p;
            let fx = floor(p.xy.x);
            let fy = floor(p.xy.y);
            let res = f64(params.res);
            if fx >= 0.0lf && fy >= 0.0lf && fx < res && fy < res {
                let x = i32(fx);
                let y = i32(fy);
                texel = u32(y) * params.res + u32(x);
                lookups = 1u;
                let t = texel_tri(x, y);
                if !t.ok || lies_on(t, p) {
                    cls = 1u;
                } else if intersects(t, p) {
                    cls = 2u;
                } else {
                    cls = 4u;
                    for (var i = 0; i < 8; i++) {
                        lookups += 1u;
                        let n = texel_tri(x + NEIGHBOURHOOD[i].x, y + NEIGHBOURHOOD[i].y);
                        if n.ok && intersects(n, p) {
                            cls = 3u;
                            break;
                        }
                    }
                }
            }
        }
    }
    if undecided {
        cls = 5u;
        atomicAdd(&counters[5], 1u);
    } else {
        if cls >= 1u {
            atomicAdd(&counters[cls - 1u], 1u);
        }
        atomicAdd(&counters[4], lookups);
    }
    result[2u * k] = cls;
    result[2u * k + 1u] = texel;
}
