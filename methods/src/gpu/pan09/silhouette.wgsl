// Stage "silhouette extraction" (silhouette::silhouette_edges), one invocation per edge of the
// adjacency; silhouette edges are appended to `edges` (6 f64 each) in any order (the mask
// map marks with OR, so the order does not matter).

@group(0) @binding(0) var<storage, read> params: Params;
@group(0) @binding(1) var<storage, read> positions: array<f64>;
@group(0) @binding(2) var<storage, read> adjacency: array<u32>;
@group(0) @binding(3) var<storage, read_write> edges: array<f64>;
@group(0) @binding(4) var<storage, read_write> counters: array<atomic<u32>>;

fn vertex(v: u32) -> vec3<f64> {
    return vec3<f64>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let e = flat_index(gid, groups);
    // adjacency: per edge a, b, faces, c1, c2.
    if e >= arrayLength(&adjacency) / 5u { return; }
    let s = setup();
    let a = vertex(adjacency[5u * e]);
    let b = vertex(adjacency[5u * e + 1u]);
    var silhouette = true;
    if adjacency[5u * e + 2u] == 2u {
        let c1 = vertex(adjacency[5u * e + 3u]);
        let c2 = vertex(adjacency[5u * e + 4u]);
        let n = cross3(b - a, towards(s.lm, a));
        let s1 = dot3(n, c1 - a);
        let s2 = dot3(n, c2 - a);
        let tiny1 = abs(s1) <= 1e-12lf * len3(n) * len3(c1 - a);
        let tiny2 = abs(s2) <= 1e-12lf * len3(n) * len3(c2 - a);
        let opposite = s1 * s2 < 0.0lf;
        silhouette = !opposite || tiny1 || tiny2;
    }
    if silhouette {
        let i = atomicAdd(&counters[C_EDGES], 1u);
        edges[6u * i] = a.x;
        edges[6u * i + 1u] = a.y;
        edges[6u * i + 2u] = a.z;
        edges[6u * i + 3u] = b.x;
        edges[6u * i + 4u] = b.y;
        edges[6u * i + 5u] = b.z;
    }
}
