// Stage "antialiasing" (spsm::antialias::antialias_pixels) on the GPU, one invocation per
// uncertain pixel whose recovered silhouette has tangents: each sub-sample's map position (the
// camera ray through it meets the plane of the surface seen at the pixel's centre, projected
// into the light's map; the centre's position where either fails) tested against the
// recovered silhouette function (recover::Resolved::lit). The pixel's value is its lit
// fraction. The silhouettes are recovered on the CPU and uploaded as records.

// [pixels to shade, image width, rate]
@group(0) @binding(0) var<storage, read> dims: array<u32>;
@group(0) @binding(1) var<storage, read> camera_data: ProjectorData;
@group(0) @binding(2) var<storage, read> light_data: ProjectorData;
// The pattern's offsets, x then y per sub-sample.
@group(0) @binding(3) var<storage, read> offsets: array<f64>;
// Per pixel, REC_F f64: see the offsets below.
@group(0) @binding(4) var<storage, read> rec_f: array<f64>;
// Per pixel: its index, tangents, occluding triangles.
@group(0) @binding(5) var<storage, read> rec_u: array<u32>;
@group(0) @binding(6) var<storage, read_write> out_lit: array<f32>;

const REC_F: u32 = 82u;
// origin (2), position (3), normal (3), plane offset (1), centre (2), tangent normals (8),
// then per triangle its vertices (6) and its orientation's sign (1), up to nine.
const AT_ORIGIN: u32 = 0u;
const AT_POSITION: u32 = 2u;
const AT_NORMAL: u32 = 5u;
const AT_OFFSET: u32 = 8u;
const AT_CENTRE: u32 = 9u;
const AT_NORMALS: u32 = 11u;
const AT_TRIS: u32 = 19u;
const TRI_F: u32 = 7u;

// `v`, through a choice the compiler cannot see through (see raster.wgsl's `kept`): keeps
// the products of a dot product apart from its sum.
fn kept(v: f64) -> f64 {
    return select(v, 0.0lf, dims[2] == 0u);
}

fn vec2_at(o: u32) -> vec2<f64> {
    return vec2<f64>(rec_f[o], rec_f[o + 1u]);
}

fn vec3_at(o: u32) -> vec3<f64> {
    return vec3<f64>(rec_f[o], rec_f[o + 1u], rec_f[o + 2u]);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let j = gid.x + gid.y * (groups.x * 64u);
    if j >= dims[0] { return; }
    let base = j * REC_F;
    let pixel = rec_u[3u * j];
    let tangents = rec_u[3u * j + 1u];
    let tris = rec_u[3u * j + 2u];
    let w = dims[1];
    let rate = dims[2];
    let position = vec3_at(base + AT_POSITION);
    let normal = vec3_at(base + AT_NORMAL);
    let offset = rec_f[base + AT_OFFSET];
    let centre = vec2_at(base + AT_CENTRE);
    occ_origin = vec2_at(base + AT_ORIGIN);
    occ_n = tris;
    for (var k = 0u; k < tris; k++) {
        let o = base + AT_TRIS + k * TRI_F;
        for (var e = 0u; e < 3u; e++) {
            occ_v[3u * k + e] = vec2_at(o + 2u * e);
        }
        occ_sign[k] = rec_f[o + 6u];
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
            if !shadowed_along(vec2_at(base + AT_NORMALS + 2u * k), q) {
                shadowed = false;
            }
        }
        if !shadowed {
            lit += 1u;
        }
    }
    out_lit[j] = f32(lit) / f32(rate);
}
