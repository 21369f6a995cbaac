// Stage "antialiasing" (spsm::antialias::antialias_pixels) on the GPU, one invocation per
// uncertain pixel whose recovered silhouette has tangents: each sub-sample's map position (the
// camera ray through it meets the plane of the surface seen at the pixel's centre, projected
// into the light's map; the centre's position where either fails) tested against the
// recovered silhouette function (recover::Resolved::lit). The pixel's value is its lit
// fraction. The silhouettes are recovered on the CPU and uploaded as records.

// antialias::Dims: the pixels to shade, the image width, the rate.
struct Dims {
    pixels: u32,
    width: u32,
    rate: u32,
}

@group(0) @binding(0) var<storage, read> dims: Dims;
@group(0) @binding(1) var<storage, read> camera_data: ProjectorData;
@group(0) @binding(2) var<storage, read> light_data: ProjectorData;
// The pattern's offsets, x then y per sub-sample.
@group(0) @binding(3) var<storage, read> offsets: array<f64>;
// Per pixel: its silhouette.
@group(0) @binding(4) var<storage, read> records: array<Record>;
@group(0) @binding(5) var<storage, read> rec_u: array<u32>;
@group(0) @binding(6) var<storage, read_write> out_lit: array<f32>;

// antialias::Record: the origin of the tangent frames, the surface's normal and plane
// offset, the light's projection of the point, the tangents' normals (x, y; up to four),
// then per triangle its vertices (x, y) and its orientation's sign (up to nine).
struct Record {
    origin: array<f64, 2>,
    normal: Xyz,
    offset: f64,
    centre: array<f64, 2>,
    normals: array<f64, 8>,
    tris: array<f64, 63>,
}

// `v`, through a choice the compiler cannot see through (see raster.wgsl's `kept`): keeps
// the products of a dot product apart from its sum.
fn kept(v: f64) -> f64 {
    return select(v, 0.0lf, dims.rate == 0u);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let j = gid.x + gid.y * (groups.x * 64u);
    if j >= dims.pixels { return; }
    let r = records[j];
    let pixel = rec_u[3u * j];
    let tangents = rec_u[3u * j + 1u];
    let tris = rec_u[3u * j + 2u];
    let w = dims.width;
    let rate = dims.rate;
    let normal = xyz(r.normal);
    let offset = r.offset;
    let centre = vec2<f64>(r.centre[0], r.centre[1]);
    occ_origin = vec2<f64>(r.origin[0], r.origin[1]);
    occ_n = tris;
    for (var k = 0u; k < tris; k++) {
        for (var e = 0u; e < 3u; e++) {
            occ_v[3u * k + e] = vec2<f64>(r.tris[7u * k + 2u * e], r.tris[7u * k + 2u * e + 1u]);
        }
        occ_sign[k] = r.tris[7u * k + 6u];
    }
    let camera = proj_load(camera_data);
    let light = proj_load(light_data);
    var lit = 0u;
    for (var s = 0u; s < rate; s++) {
        let point = vec2<f64>(f64(pixel % w) + offsets[2u * s], f64(pixel / w) + offsets[2u * s + 1u]);
        let ray = proj_ray(camera, point);
        // Ray::intersect_plane, then the light's projection of Ray::at.
        let denom = dot3(normal, ray.direction);
        let t = (offset - dot3(normal, ray.origin)) / denom;
        var q = centre;
        if denom != 0.0lf && is_finite64(t) {
            let m = proj_project(light, ray.origin + t * ray.direction);
            if m.w != 0.0lf {
                q = m.xy;
            }
        }
        var shadowed = true;
        for (var k = 0u; k < tangents; k++) {
            if !shadowed_along(vec2<f64>(r.normals[2u * k], r.normals[2u * k + 1u]), q) {
                shadowed = false;
            }
        }
        if !shadowed {
            lit += 1u;
        }
    }
    out_lit[j] = f32(lit) / f32(rate);
}
