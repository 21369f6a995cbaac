// The per-pixel kernels' shared prologue (sm, pcf-*): their first five bindings, the pixel
// an invocation shades, and the receiver of its G-buffer surface point. A kernel's own
// bindings follow from 5.

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> light: ProjectorData;
@group(0) @binding(2) var<storage, read> g_triangle: array<u32>;
@group(0) @binding(3) var<storage, read> g_position: array<f64>;
@group(0) @binding(4) var<storage, read> g_normal: array<f64>;

// The pixel of invocation `gid` among `groups` workgroups of 64 (GpuContext::groups_1d).
fn pixel_index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * (groups.x * 64u);
}

fn pixel_position(k: u32) -> vec3<f64> {
    return vec3<f64>(g_position[3u * k], g_position[3u * k + 1u], g_position[3u * k + 2u]);
}

fn pixel_normal(k: u32) -> vec3<f64> {
    return vec3<f64>(g_normal[3u * k], g_normal[3u * k + 1u], g_normal[3u * k + 2u]);
}

// DepthTester::receiver of pixel k's surface point; not ok where the pixel sees no surface.
fn pixel_receiver(k: u32) -> Receiver {
    if g_triangle[k] == NO_TRIANGLE {
        return Receiver(vec2<f64>(0.0lf), 0.0lf, vec2<f64>(0.0lf), false);
    }
    return receiver(proj_load(light), pixel_position(k), pixel_normal(k), params.max_slope);
}
