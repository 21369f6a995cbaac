// The hardware pass: every triangle drawn from its clip coordinates; the fragment keeps the
// triangle's id (the depth test keeps the nearest, ties to the first drawn: the lower id).

@group(0) @binding(0) var<storage, read> clip: array<vec4<f32>>;

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) id: u32,
}

@vertex
fn vs(@builtin(vertex_index) k: u32) -> VertexOut {
    return VertexOut(clip[k], k / 3u);
}

@fragment
fn fs(v: VertexOut) -> @location(0) u32 {
    return v.id;
}
