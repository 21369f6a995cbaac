// Stage "rasterization of blockers", triangle setup (afsm::blockers::Blocker::new, mirrored
// in f64 with the CPU's operations in its order): the light's projection of each caster
// triangle (clipped at a spot light's near plane), wound positively, its bounding box, depth
// range and plane depth function, and the grid cells its bounding box covers. Appended to
// common.wgsl and grid.wgsl.

@group(0) @binding(0) var<storage, read> light_data: ProjectorData;
@group(0) @binding(1) var<storage, read> fparams: FParams;
@group(0) @binding(2) var<storage, read> uparams: UParams;
@group(0) @binding(3) var<storage, read> corners: array<f64>;
@group(0) @binding(4) var<storage, read> casters: array<u32>;
// Per triangle (layout.wgsl): outline and box, plane, corner count and cells.
@group(0) @binding(5) var<storage, read_write> blk_outline: array<BlockerOutline>;
@group(0) @binding(6) var<storage, read_write> blk_plane: array<BlockerPlane>;
@group(0) @binding(7) var<storage, read_write> blk_u: array<BlockerU>;
// Per triangle, the number of grid cells it visits (0: it casts nothing).
@group(0) @binding(8) var<storage, read_write> items: array<u32>;

const ORIENTATION_UNDECIDED: u32 = 256u;

fn corner(t: u32, i: u32) -> vec3<f64> {
    let b = 9u * t + 3u * i;
    return vec3<f64>(corners[b], corners[b + 1u], corners[b + 2u]);
}

// orient2d's filter (the robust crate's first stage): 1 or -1 when the sign of det is
// certain (and then det is the value orient2d returns), 0 when det is certainly 0, 2 when
// the filter cannot decide.
fn orient_filter(a: vec2<f64>, b: vec2<f64>, c: vec2<f64>) -> i32 {
    let detleft = (a.x - c.x) * (b.y - c.y);
    let detright = (a.y - c.y) * (b.x - c.x);
    let det = detleft - detright;
    let errbound = fparams.filter_bound * abs(detleft + detright);
    if det >= errbound || -det >= errbound {
        if det > 0.0lf {
            return 1;
        }
        if det < 0.0lf {
            return -1;
        }
        return 0;
    }
    return 2;
}

@compute @workgroup_size(64)
fn setup(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let t = gid.x + gid.y * (nwg.x * 64u);
    if t >= uparams.triangles {
        return;
    }
    items[t] = 0u;
    if casters[t] == 0u {
        return;
    }
    var c = array<vec3<f64>, 3>(corner(t, 0u), corner(t, 1u), corner(t, 2u));
    let normal = cross3(c[1] - c[0], c[2] - c[0]);
    if (normal.x == 0.0lf && normal.y == 0.0lf && normal.z == 0.0lf)
        || !(is_finite64(normal.x) && is_finite64(normal.y) && is_finite64(normal.z)) {
        return;
    }
    let p = proj_load(light_data);
    var world: array<vec3<f64>, 4>;
    var count = 3u;
    if p.kind == 1u {
        let d = array<f64, 3>(proj_depth_of(p, c[0]), proj_depth_of(p, c[1]), proj_depth_of(p, c[2]));
        let w = clip_near(c, d, p.near);
        world = w.p;
        count = w.n;
    } else {
        world[0] = c[0];
        world[1] = c[1];
        world[2] = c[2];
    }
    if count < 3u {
        return;
    }
    var outline: array<vec2<f64>, 4>;
    var depth: array<f64, 4>;
    for (var i = 0u; i < count; i = i + 1u) {
        let r = proj_unclipped(p, world[i]);
        if !(is_finite64(r.x) && is_finite64(r.y)) {
            return;
        }
        outline[i] = r.xy;
        depth[i] = r.z;
    }
    var dmin = depth[0];
    var dmax = depth[0];
    for (var i = 1u; i < count; i = i + 1u) {
        dmin = min(dmin, depth[i]);
        dmax = max(dmax, depth[i]);
    }
    if !(is_finite64(dmin) && is_finite64(dmax)) {
        return;
    }
    // The first fan triangle of non-zero orientation gives the winding.
    var orientation = 0;
    for (var i = 1u; i + 1u < count; i = i + 1u) {
        orientation = orient_filter(outline[0], outline[i], outline[i + 1u]);
        if orientation != 0 {
            break;
        }
    }
    if orientation == 0 {
        return;
    }
    if orientation == -1 {
        for (var i = 0u; i < count / 2u; i = i + 1u) {
            let s = outline[i];
            outline[i] = outline[count - 1u - i];
            outline[count - 1u - i] = s;
        }
    }
    var lo = outline[0];
    var hi = outline[0];
    for (var i = 1u; i < count; i = i + 1u) {
        lo = min(lo, outline[i]);
        hi = max(hi, outline[i]);
    }
    let offset = dot3(normal, c[0]);
    let nr = dot3(normal, p.right);
    let nu = dot3(normal, p.up);
    let nf = dot3(normal, p.forward);
    let no = dot3(normal, p.origin);
    var num = array<f64, 3>(offset - no, 0.0lf, 0.0lf);
    var den = array<f64, 3>(nf, 0.0lf, 0.0lf);
    if p.kind == 0u {
        num = array<f64, 3>(
            offset - no + nr * p.a - nu * p.b,
            -2.0lf * nr * p.a / p.width,
            2.0lf * nu * p.b / p.height,
        );
    } else {
        den = array<f64, 3>(
            nf - nr * p.a + nu * p.b,
            2.0lf * nr * p.a / p.width,
            -2.0lf * nu * p.b / p.height,
        );
    }
    var b: BlockerOutline;
    for (var i = 0u; i < 4u; i = i + 1u) {
        b.outline[2u * i] = outline[i].x;
        b.outline[2u * i + 1u] = outline[i].y;
    }
    b.lo = array<f64, 2>(lo.x, lo.y);
    b.hi = array<f64, 2>(hi.x, hi.y);
    blk_outline[t] = b;
    blk_plane[t] = BlockerPlane(num, den, dmin, dmax);
    let g = uparams.grid;
    let x0 = cell_axis(lo.x, fparams.cell_x, g);
    let y0 = cell_axis(lo.y, fparams.cell_y, g);
    let x1 = cell_axis(hi.x, fparams.cell_x, g);
    let y1 = cell_axis(hi.y, fparams.cell_y, g);
    var flags = count;
    if orientation == 2 {
        flags = flags | ORIENTATION_UNDECIDED;
    }
    blk_u[t] = BlockerU(flags, x0, y0, x1, y1);
    items[t] = (x1 - x0 + 1u) * (y1 - y0 + 1u);
}
