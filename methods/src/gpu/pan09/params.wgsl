// The run's constants (per frame), read from the bindings `P` (f64) and `U` (u32) that every
// stage including this file declares; layouts in params.rs.

struct Setup {
    light: Proj,
    camera: Proj,
    constant: f64,
    slope_bias: f64,
    max_slope: f64,
    // afsm::SHADOW_OFFSET; visibility::occluder_offset scales it per triangle.
    offset: f64,
    inf: f64,
    lm: LightModel,
    eye: LightModel,
    cam: Basis,
    px: WorldPlane,
    py: WorldPlane,
    pw: WorldPlane,
    pnear: WorldPlane,
    res: u32,
    width: u32,
    height: u32,
    words: u32,
    rate: u32,
    mode: u32,
    curved: u32,
    has_w: bool,
    has_near: bool,
    all: vec4<u32>,
    centre: vec4<u32>,
}

fn load_proj(o: u32) -> Proj {
    let x = array<Xyz, 4>(
        Xyz(P[o], P[o + 1u], P[o + 2u]),
        Xyz(P[o + 3u], P[o + 4u], P[o + 5u]),
        Xyz(P[o + 6u], P[o + 7u], P[o + 8u]),
        Xyz(P[o + 9u], P[o + 10u], P[o + 11u]),
    );
    return proj_load(ProjectorData(
        x[0], x[1], x[2], x[3], u32(P[o + 12u]), 0u,
        P[o + 13u], P[o + 14u], P[o + 15u], P[o + 16u], P[o + 17u],
    ));
}

fn load_v3(o: u32) -> vec3<f64> {
    return vec3<f64>(P[o], P[o + 1u], P[o + 2u]);
}

fn load_plane(o: u32) -> WorldPlane {
    return WorldPlane(load_v3(o), P[o + 3u], P[o + 4u], P[o + 5u], P[o + 6u], P[o + 7u]);
}

fn setup() -> Setup {
    var s: Setup;
    s.light = load_proj(0u);
    s.camera = load_proj(18u);
    s.constant = P[36];
    s.slope_bias = P[37];
    s.max_slope = P[38];
    s.offset = P[39];
    s.inf = P[40];
    s.lm = LightModel(U[7], load_v3(41u));
    s.eye = LightModel(U[8], load_v3(44u));
    s.cam = Basis(load_v3(47u), load_v3(50u), load_v3(53u), load_v3(56u), load_v3(59u), load_v3(62u), U[9] == 1u);
    s.px = load_plane(65u);
    s.py = load_plane(73u);
    s.pw = load_plane(81u);
    s.pnear = load_plane(89u);
    s.res = U[0];
    s.width = U[1];
    s.height = U[2];
    s.words = U[3];
    s.rate = U[4];
    s.mode = U[5];
    s.curved = U[6];
    s.has_w = U[10] == 1u;
    s.has_near = U[11] == 1u;
    s.all = vec4<u32>(U[12], U[13], U[14], U[15]);
    s.centre = vec4<u32>(U[16], U[17], U[18], U[19]);
    return s;
}

// DepthTester::receiver's slope (depth_test::depth_slope); `ok` false where the point does
// not project.
struct Receiver {
    xy: vec2<f64>,
    depth: f64,
    slope: vec2<f64>,
    ok: bool,
}

fn receiver(s: Setup, position: vec3<f64>, normal: vec3<f64>) -> Receiver {
    var r: Receiver;
    let q = proj_project(s.light, position);
    r.ok = q.w != 0.0lf;
    if !r.ok { return r; }
    r.xy = q.xy;
    r.depth = q.z;
    let dir = proj_ray(s.light, r.xy).direction;
    let n_dir = abs(dot3(normal, dir));
    var rx = abs(dot3(normal, s.light.right)) / n_dir;
    var ry = abs(dot3(normal, s.light.up)) / n_dir;
    rx = select(s.max_slope, fmin64(rx, s.max_slope), is_finite64(rx));
    ry = select(s.max_slope, fmin64(ry, s.max_slope), is_finite64(ry));
    var steps: vec2<f64>;
    if s.light.kind == 1u {
        steps = vec2<f64>(r.depth * 2.0lf * s.light.a / s.light.width, r.depth * 2.0lf * s.light.b / s.light.height);
    } else {
        steps = vec2<f64>(2.0lf * s.light.a / s.light.width, 2.0lf * s.light.b / s.light.height);
    }
    r.slope = vec2<f64>(rx * steps.x, ry * steps.y);
    return r;
}
