// Rasterization on the GPU, around a hardware render pass: `setup` (per triangle: plane and
// depth range as methods::raster's setup makes them, f64), `project` (per corner: clip
// coordinates for the hardware, f64 then rounded to f32), and `resolve` (per sample: the depth
// where the sample's ray meets the plane of the triangle the hardware kept, f64, as the CPU
// rasterizer computes it; for the G-buffer also the position and the normal).

struct Params {
    // Samples per row and rows.
    width: u32,
    height: u32,
    // Triangles, and whether only casters are drawn (1) or every triangle (0).
    triangles: u32,
    casters_only: u32,
    // u32 words per row of the id image (rows padded to 256 bytes).
    row_words: u32,
    // 1: write position and normal (G-buffer).
    gbuffer: u32,
    pad0: u32,
    pad1: u32,
    // Sample shift in texels.
    shift_x: f64,
    shift_y: f64,
    // Depth mapped to clip z 0..1: [znear, zfar].
    znear: f64,
    zfar: f64,
}

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read> proj_data: ProjectorData;
@group(0) @binding(2) var<storage, read> corners: array<f64>;
@group(0) @binding(3) var<storage, read> casters: array<u32>;
@group(0) @binding(4) var<storage, read_write> planes: array<f64>;
@group(0) @binding(5) var<storage, read_write> clip: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> ids: array<u32>;
@group(0) @binding(7) var<storage, read_write> out_triangle: array<u32>;
@group(0) @binding(8) var<storage, read_write> out_depth: array<f64>;
@group(0) @binding(9) var<storage, read_write> out_position: array<f64>;
@group(0) @binding(10) var<storage, read_write> out_normal: array<f64>;

fn corner(t: u32, i: u32) -> vec3<f64> {
    let k = 9u * t + 3u * i;
    return vec3<f64>(corners[k], corners[k + 1u], corners[k + 2u]);
}

fn index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * (groups.x * 64u);
}

// Per triangle: unit normal, plane offset, depth range of the (near-clipped) corners.
@compute @workgroup_size(64)
fn setup(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let t = index(gid, groups);
    if t >= prm.triangles { return; }
    let p = proj_load(proj_data);
    let c0 = corner(t, 0u);
    let c1 = corner(t, 1u);
    let c2 = corner(t, 2u);
    let n = normalize_or_zero(cross3(c1 - c0, c2 - c0));
    let offset = dot3(n, c0);
    var dmin = 1.7976931348623157e308lf;
    var dmax = -dmin;
    let cs = array<vec3<f64>, 3>(c0, c1, c2);
    var w: Clipped;
    if p.kind == 1u {
        let d = array<f64, 3>(proj_depth_of(p, c0), proj_depth_of(p, c1), proj_depth_of(p, c2));
        w = clip_near(cs, d, p.near);
    } else {
        w.p = array<vec3<f64>, 4>(c0, c1, c2, c0);
        w.n = 3u;
    }
    for (var i = 0u; i < w.n; i++) {
        let d = proj_unclipped(p, w.p[i]).z;
        dmin = min(dmin, d);
        dmax = max(dmax, d);
    }
    planes[6u * t] = n.x;
    planes[6u * t + 1u] = n.y;
    planes[6u * t + 2u] = n.z;
    planes[6u * t + 3u] = offset;
    planes[6u * t + 4u] = dmin;
    planes[6u * t + 5u] = dmax;
}

// Per corner: clip coordinates. Triangles not drawn collapse to a point (no fragments).
@compute @workgroup_size(64)
fn project(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = index(gid, groups);
    if k >= 3u * prm.triangles { return; }
    let t = k / 3u;
    if prm.casters_only == 1u && casters[t] == 0u {
        clip[k] = vec4<f32>(2.0, 2.0, 2.0, 1.0);
        return;
    }
    let p = proj_load(proj_data);
    let v = corner(t, k % 3u) - p.origin;
    let depth = dot3(v, p.forward);
    var x = dot3(v, p.right) / p.a;
    var y = dot3(v, p.up) / p.b;
    var w = 1.0lf;
    var z: f64;
    if p.kind == 1u {
        w = depth;
        z = prm.zfar / (prm.zfar - prm.znear) * (depth - prm.znear);
    } else {
        z = (depth - prm.znear) / (prm.zfar - prm.znear);
    }
    // Samples at i + 0.5 + shift: the geometry moves by -shift (image y points down).
    x = x - 2.0lf * prm.shift_x / p.width * w;
    y = y + 2.0lf * prm.shift_y / p.height * w;
    clip[k] = vec4<f32>(f32(x), f32(y), f32(z), f32(w));
}

// Per sample: the triangle the hardware kept and the f64 depth (and G-buffer attributes).
@compute @workgroup_size(64)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = index(gid, groups);
    if k >= prm.width * prm.height { return; }
    let sx = k % prm.width;
    let sy = k / prm.width;
    let id = ids[sy * prm.row_words + sx];
    out_triangle[k] = id;
    if id == NO_TRIANGLE { return; }
    let p = proj_load(proj_data);
    let n = vec3<f64>(planes[6u * id], planes[6u * id + 1u], planes[6u * id + 2u]);
    let offset = planes[6u * id + 3u];
    let dmin = planes[6u * id + 4u];
    let dmax = planes[6u * id + 5u];
    // Projector::ray through the (shifted) sample.
    let px = f64(sx) + 0.5lf + prm.shift_x;
    let py = f64(sy) + 0.5lf + prm.shift_y;
    let ndx = 2.0lf * px / p.width - 1.0lf;
    let ndy = 1.0lf - 2.0lf * py / p.height;
    var origin = p.origin;
    var dir = p.forward;
    if p.kind == 1u {
        dir = p.forward + p.right * (ndx * p.a) + p.up * (ndy * p.b);
    } else {
        origin = p.origin + p.right * (ndx * p.a) + p.up * (ndy * p.b);
    }
    // Ray::intersect_plane, unwrap_or(depth_min), clamp to the corners' range.
    let denom = dot3(n, dir);
    let t = (offset - dot3(n, origin)) / denom;
    var d = dmin;
    if denom != 0.0lf && is_finite64(t) {
        d = t;
    }
    d = min(max(d, dmin), dmax);
    out_depth[k] = d;
    if prm.gbuffer == 1u {
        let pos = origin + d * dir;
        out_position[3u * k] = pos.x;
        out_position[3u * k + 1u] = pos.y;
        out_position[3u * k + 2u] = pos.z;
        out_normal[3u * k] = n.x;
        out_normal[3u * k + 1u] = n.y;
        out_normal[3u * k + 2u] = n.z;
    }
}
