// The camera side of a pixel's sub-sample, shared by the transformation of samples and the
// sample tests: the camera ray through it and the shadow offset of a point on that ray, in
// f64 with the CPU's operations in its order. Reads the kernel's `fparams` (the sub-sample's
// offset in its pixel, the shadow offset ratio), `uparams` (image width) and `camera_data`.

fn max_element(v: vec3<f64>) -> f64 {
    return max(max(v.x, v.y), v.z);
}

// afsm::shadow_offset: the offset of the surface point `p` hit by a camera ray from `origin`.
fn shadow_offset(origin: vec3<f64>, p: vec3<f64>) -> f64 {
    let magnitude = max_element(max(abs(origin), abs(p))) + max_element(abs(p - origin));
    return fparams.offset * magnitude;
}

// Projector::ray(SamplePattern::point): the camera ray through pixel k's corner plus the
// sub-sample's offset.
fn sample_ray(k: u32) -> Ray {
    let w = uparams.width;
    let point = vec2<f64>(f64(k % w) + fparams.sub_x, f64(k / w) + fparams.sub_y);
    return proj_ray(proj_load(camera_data), point);
}
