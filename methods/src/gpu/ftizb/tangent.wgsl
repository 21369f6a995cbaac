// Stage "sample footprints" for one sub-sample of every pixel (ftizb::footprints::SubSamples::
// pixel, mirrored in f64 with the CPU's operations in its order): the parameter t where the
// camera ray through the sub-sample meets the tangent plane of the pixel's G-buffer point and
// face normal (scenes::projection::Ray::intersect_plane), kept where it lies in the facet's
// region around the centre's depth (SubSamples::in_region). The result is the surface the
// irregular z-buffer's transformation of samples reads: the pixel's G-buffer triangle and t,
// or NO_TRIANGLE where the sub-sample has no point. Appended to common.wgsl.

// The region's depth ratio (pan09::facets::FACET_DEPTH_RATIO, perspective cameras), its
// reach in depth (FACET_ORTHO_SPAN pixel widths, orthographic cameras), and the sub-sample's
// offset in its pixel; pixels and image width.
struct TangentParams {
    depth_ratio: f64,
    ortho_span: f64,
    sub_x: f64,
    sub_y: f64,
    pixels: u32,
    width: u32,
}

@group(0) @binding(0) var<storage, read> params: TangentParams;
@group(0) @binding(1) var<storage, read> camera_data: ProjectorData;
@group(0) @binding(2) var<storage, read> g_triangle: array<u32>;
@group(0) @binding(3) var<storage, read> g_depth: array<f64>;
@group(0) @binding(4) var<storage, read> g_position: array<f64>;
@group(0) @binding(5) var<storage, read> g_normal: array<f64>;
// Per pixel: the sub-sample's triangle (NO_TRIANGLE where it has no point) and camera depth.
@group(0) @binding(6) var<storage, read_write> s_triangle: array<u32>;
@group(0) @binding(7) var<storage, read_write> s_depth: array<f64>;

// SubSamples::in_region: whether camera depth t lies in the facet's region around the
// centre's depth dc.
fn in_region(perspective: bool, t: f64, dc: f64) -> bool {
    if perspective {
        return t > 0.0lf && t <= params.depth_ratio * dc;
    }
    return abs(t - dc) <= params.ortho_span;
}

@compute @workgroup_size(64)
fn tangent(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = gid.x + gid.y * (nwg.x * 64u);
    if k >= params.pixels {
        return;
    }
    let g = g_triangle[k];
    var tri = NO_TRIANGLE;
    var t = 0.0lf;
    if g != NO_TRIANGLE {
        let camera = proj_load(camera_data);
        // SamplePattern::point: the pixel's corner plus the sub-sample's offset.
        let w = params.width;
        let point = vec2<f64>(f64(k % w) + params.sub_x, f64(k / w) + params.sub_y);
        let ray = proj_ray(camera, point);
        let n = vec3<f64>(g_normal[3u * k], g_normal[3u * k + 1u], g_normal[3u * k + 2u]);
        let p0 = vec3<f64>(g_position[3u * k], g_position[3u * k + 1u], g_position[3u * k + 2u]);
        let offset = dot3(n, p0);
        // Ray::intersect_plane.
        let denom = dot3(n, ray.direction);
        let at = (offset - dot3(n, ray.origin)) / denom;
        if denom != 0.0lf && is_finite64(at) && in_region(camera.kind == 1u, at, g_depth[k]) {
            tri = g;
            t = at;
        }
    }
    s_triangle[k] = tri;
    s_depth[k] = t;
}
