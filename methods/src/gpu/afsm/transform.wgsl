// Stage "transformation of samples" (afsm::samples::transform_samples) for one sub-sample of
// every pixel: the surface point of the sub-sample's G-buffer moved to the light's image
// plane, with its shadow threshold depth. Appended to common.wgsl and sample.wgsl.

@group(0) @binding(0) var<storage, read> light_data: ProjectorData;
@group(0) @binding(1) var<storage, read> fparams: FParams;
@group(0) @binding(2) var<storage, read> uparams: UParams;
@group(0) @binding(3) var<storage, read> g_triangle: array<u32>;
// The sub-sample's depth: the parameter of the camera ray through it.
@group(0) @binding(4) var<storage, read> g_depth: array<f64>;
// Per pixel: light image x, y and threshold depth.
@group(0) @binding(5) var<storage, read_write> sample_f: array<f64>;
// Per pixel: the sample's triangle, NO_TRIANGLE where the pixel has no sample.
@group(0) @binding(6) var<storage, read_write> sample_tri: array<u32>;
@group(0) @binding(7) var<storage, read> camera_data: ProjectorData;

// samples::threshold_depth.
fn threshold_depth(p: Proj, x: f64, y: f64, z: f64, offset: f64) -> f64 {
    if p.kind == 0u {
        return z - offset;
    }
    // Projector::ray(xy).direction and its length, in glam's order.
    let sx = 2.0lf * x / p.width - 1.0lf;
    let sy = 1.0lf - 2.0lf * y / p.height;
    let d = p.forward + p.right * (sx * p.a) + p.up * (sy * p.b);
    return z - offset / sqrt(dot3(d, d));
}

@compute @workgroup_size(64)
fn transform(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = gid.x + gid.y * (nwg.x * 64u);
    if k >= uparams.pixels {
        return;
    }
    var tri = g_triangle[k];
    var r = vec4<f64>(0.0lf, 0.0lf, 0.0lf, 0.0lf);
    if tri != NO_TRIANGLE {
        let p = proj_load(light_data);
        // The surface point is Ray::at(depth) on the camera ray through the sub-sample, as
        // transform_samples takes it.
        let ray = sample_ray(k);
        let position = ray.origin + g_depth[k] * ray.direction;
        r = proj_project(p, position);
        if r.w == 0.0lf {
            tri = NO_TRIANGLE;
        } else {
            let zt = threshold_depth(p, r.x, r.y, r.z, shadow_offset(ray.origin, position));
            r.z = zt;
            if !is_finite64(zt) {
                tri = NO_TRIANGLE;
            }
        }
    }
    sample_f[3u * k] = r.x;
    sample_f[3u * k + 1u] = r.y;
    sample_f[3u * k + 2u] = r.z;
    sample_tri[k] = tri;
}
