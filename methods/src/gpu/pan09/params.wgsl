// The run's constants (per frame): the struct Params (params.rs's Params, field for field),
// read from the binding `params` (binding 0) that every stage including this file declares,
// and the Setup that setup() makes of it.

// screen::WorldPlane as a buffer holds it (params.rs's PlaneData).
struct PlaneData {
    n: Xyz,
    c: f64,
    n_ox: f64,
    n_oy: f64,
    n_dx: f64,
    n_dy: f64,
}

struct Params {
    light: ProjectorData,
    camera: ProjectorData,
    constant: f64,
    slope_bias: f64,
    max_slope: f64,
    offset: f64,
    inf: f64,
    // The light and eye models' vectors (kinds in light_kind, eye_kind).
    light_v: Xyz,
    eye_v: Xyz,
    // screen::CameraBasis.
    o0: Xyz,
    ox: Xyz,
    oy: Xyz,
    d0: Xyz,
    dx: Xyz,
    dy: Xyz,
    // facets::LightPlanes; pw and pnear zero where absent (has_w, has_near).
    px: PlaneData,
    py: PlaneData,
    pw: PlaneData,
    pnear: PlaneData,
    res: u32,
    width: u32,
    height: u32,
    words: u32,
    rate: u32,
    // 0: the lookup table; 1: exact.
    mode: u32,
    curved: u32,
    light_kind: u32,
    eye_kind: u32,
    perspective: u32,
    has_w: u32,
    has_near: u32,
    // Masks, four words, lowest first.
    all: array<u32, 4>,
    centre: array<u32, 4>,
    // The pattern's offsets from the pixel's centre, `rate` of them (at most 128).
    pattern_x: array<f64, 128>,
    pattern_y: array<f64, 128>,
}

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

fn plane_load(p: PlaneData) -> WorldPlane {
    return WorldPlane(xyz(p.n), p.c, p.n_ox, p.n_oy, p.n_dx, p.n_dy);
}

fn mask_load(m: array<u32, 4>) -> vec4<u32> {
    return vec4<u32>(m[0], m[1], m[2], m[3]);
}

fn setup() -> Setup {
    var s: Setup;
    s.light = proj_load(params.light);
    s.camera = proj_load(params.camera);
    s.constant = params.constant;
    s.slope_bias = params.slope_bias;
    s.max_slope = params.max_slope;
    s.offset = params.offset;
    s.inf = params.inf;
    s.lm = LightModel(params.light_kind, xyz(params.light_v));
    s.eye = LightModel(params.eye_kind, xyz(params.eye_v));
    s.cam = Basis(
        xyz(params.o0), xyz(params.ox), xyz(params.oy),
        xyz(params.d0), xyz(params.dx), xyz(params.dy),
        params.perspective == 1u,
    );
    s.px = plane_load(params.px);
    s.py = plane_load(params.py);
    s.pw = plane_load(params.pw);
    s.pnear = plane_load(params.pnear);
    s.res = params.res;
    s.width = params.width;
    s.height = params.height;
    s.words = params.words;
    s.rate = params.rate;
    s.mode = params.mode;
    s.curved = params.curved;
    s.has_w = params.has_w == 1u;
    s.has_near = params.has_near == 1u;
    s.all = mask_load(params.all);
    s.centre = mask_load(params.centre);
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
