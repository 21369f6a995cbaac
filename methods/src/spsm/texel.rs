//! The SPSM texel (Lecocq et al. 2014, section 3.3): the closest triangle of a texel as its
//! three 2D vertices in map space, the depth at the texel centre and the two depth
//! derivatives, either packed into 128 bits or kept as `f32`.
//!
//! # Map depth
//!
//! Equation 1 extrapolates depth linearly across the map, so the stored depth `z̃` must be
//! affine in map coordinates on a triangle: [`LightSpace`] uses the light depth itself for
//! orthographic (directional) lights and `z̃ = -1/depth` for perspective (spot) lights (affine
//! in the image plane, increasing with depth, like a hardware depth buffer). Comparisons and
//! tolerances are made in `z̃` units.
//!
//! # Packed layout (128 bits, four `u32` words: R, G, B, A)
//!
//! - R, G, B: vertex `k` as `x | y << 16`, each coordinate a 16-bit fixed-point number over
//!   `[-R/2, 3R/2]` texels for an `R x R` map (a step of `2R / 65535` texels: 1/32 texel at 1K,
//!   1/8 at 4K). The codes are absolute, so a vertex shared by two triangles decodes to the
//!   same point in every texel that holds either (no cracks between them). Vertices beyond
//!   that range are clamped to it (the run record notes it); on directional lights the map is
//!   fitted to the scene, so no vertex leaves `[0, R]`.
//! - A: the centre depth as 16 bits over the scene's light depth range `[z_lo, z_hi]` in the
//!   high half; the derivative codes of `∂z̃/∂x` and `∂z̃/∂y` (section 3.4, [`DerivativeCode`])
//!   in bits 8..16 and 0..8.
//! - An empty texel is all ones (the encoder never writes it: it never writes the derivative
//!   code 255).
//!
//! Derivatives are encoded as the *angle* of the surface: the per-texel derivative divided by
//! [`LightSpace::slope_scale`], the depth change per texel of a 45° surface (the texel's world
//! size for orthographic lights; for perspective lights, the same at the decoded centre depth,
//! so encoder and decoder use the same scale).
//!
//! # Error bounds
//!
//! Every decoded triangle carries bounds on its depth errors ([`Tri::error_at`]): half a depth
//! code and the derivative code's error ([`DerivativeCode::error`]) times the distance from the
//! texel centre for the packed texel; the `f32` rounding of the same numbers for the `f32`
//! texel. Tests that compare depths add them to their tolerance, so a packed texel never turns
//! a lit surface dark through its own quantization.

use super::quantize::DerivativeCode;
use glam::DVec2;
use robust::{orient2d, Coord};
use scenes::projection::{ProjectionKind, Projector};

/// How a texel is stored.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum TexelFormat {
    /// 128 bits: 16-bit vertices and depth, 8-bit derivative codes (the paper's texel).
    #[default]
    Packed,
    /// Unpacked `f32` vertices, depth and derivatives (32 bytes), to measure what packing costs.
    F32,
}

impl TexelFormat {
    /// The name used in run records: `packed` or `f32`.
    pub fn name(self) -> &'static str {
        match self {
            TexelFormat::Packed => "packed",
            TexelFormat::F32 => "f32",
        }
    }
}

/// The map's coordinate system: map depth `z̃`, its range, and the scales the texel codes use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightSpace {
    /// Map resolution `R`.
    pub res: u32,
    /// Whether `z̃ = -1/depth` (perspective light) rather than the depth.
    pub perspective: bool,
    /// Lateral world size of one texel per unit of depth (perspective) or absolute
    /// (orthographic), along x and y.
    texel_size: DVec2,
    /// Range of `z̃` covered by the 16-bit depth code.
    pub z_lo: f64,
    /// Upper end of that range.
    pub z_hi: f64,
}

impl LightSpace {
    /// The space of a map seen through `projector`, for a scene whose light depths span
    /// `depth_bounds` (nearest, farthest).
    pub fn new(projector: &Projector, depth_bounds: (f64, f64)) -> Self {
        let r = projector.width;
        let (perspective, texel_size) = match projector.kind {
            ProjectionKind::Orthographic { half_width, half_height } => {
                (false, DVec2::new(2.0 * half_width / r, 2.0 * half_height / projector.height))
            }
            ProjectionKind::Perspective { tan_half_x, tan_half_y } => {
                (true, DVec2::new(2.0 * tan_half_x / r, 2.0 * tan_half_y / projector.height))
            }
        };
        let (near, far) = depth_bounds;
        let (near, far) = if perspective {
            let near = near.max(projector.near).max(f64::MIN_POSITIVE);
            (near, far.max(near))
        } else {
            (near, far.max(near))
        };
        let mut space = Self { res: r as u32, perspective, texel_size, z_lo: 0.0, z_hi: 0.0 };
        space.z_lo = space.z(near);
        space.z_hi = space.z(far).max(space.z_lo);
        space
    }

    /// Map depth of light depth `d`.
    #[inline]
    pub fn z(&self, d: f64) -> f64 {
        if self.perspective {
            -1.0 / d
        } else {
            d
        }
    }

    /// A depth tolerance `tol` at light depth `d`, in map-depth units.
    #[inline]
    pub fn z_tolerance(&self, tol: f64, d: f64) -> f64 {
        if self.perspective {
            tol / (d * d)
        } else {
            tol
        }
    }

    /// Map-depth change per texel of a 45° surface at map depth `z`, along x and y.
    #[inline]
    pub fn slope_scale(&self, z: f64) -> DVec2 {
        if self.perspective {
            self.texel_size * (-z).max(f64::MIN_POSITIVE)
        } else {
            self.texel_size
        }
    }

    /// World size of a texel at light depth `d`, along x and y.
    #[inline]
    pub fn texel_world_size(&self, d: f64) -> DVec2 {
        if self.perspective {
            self.texel_size * d.abs()
        } else {
            self.texel_size
        }
    }

    /// Step of the 16-bit vertex code, in texels.
    #[inline]
    pub fn vertex_step(&self) -> f64 {
        2.0 * f64::from(self.res) / 65535.0
    }

    /// Step of the 16-bit depth code, in map-depth units.
    #[inline]
    pub fn depth_step(&self) -> f64 {
        (self.z_hi - self.z_lo) / 65535.0
    }
}

#[inline]
fn coord(p: DVec2) -> Coord<f64> {
    Coord { x: p.x, y: p.y }
}

/// A decoded texel: the stored triangle and its depth plane, with error bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tri {
    /// Vertices in map coordinates (texels from the top-left corner).
    pub v: [DVec2; 3],
    /// The texel centre the plane is anchored at.
    pub centre: DVec2,
    /// Map depth at the centre.
    pub z: f64,
    /// `(∂z̃/∂x, ∂z̃/∂y)` per texel.
    pub dz: DVec2,
    /// Bound on the error of `z`.
    pub err_z: f64,
    /// Bounds on the errors of `dz`.
    pub err_dz: DVec2,
    /// Bound on the error of each vertex coordinate, texels.
    pub err_v: f64,
}

impl Tri {
    /// Map depth of the stored plane at map point `q` (equation 1).
    #[inline]
    pub fn depth_at(&self, q: DVec2) -> f64 {
        self.z + (q - self.centre).dot(self.dz)
    }

    /// Bound on the error of [`depth_at`](Self::depth_at) at `q`.
    #[inline]
    pub fn error_at(&self, q: DVec2) -> f64 {
        self.err_z + (q - self.centre).abs().dot(self.err_dz)
    }

    /// Whether `q` lies in the closed triangle with every edge moved inwards by `margin`
    /// texels (outwards when negative); exact predicates when `margin` is 0. A triangle of
    /// zero area contains nothing.
    #[inline]
    pub fn contains_within(&self, q: DVec2, margin: f64) -> bool {
        let orientation = self.orientation();
        if orientation == 0.0 {
            return false;
        }
        let sign = orientation.signum();
        (0..3).all(|e| {
            let (a, b) = (self.v[e], self.v[(e + 1) % 3]);
            let s = orient2d(coord(a), coord(b), coord(q)) * sign;
            if margin == 0.0 {
                s >= 0.0
            } else {
                s >= margin * (b - a).length()
            }
        })
    }

    /// Whether `q` lies in the closed triangle (exact predicates).
    #[inline]
    pub fn contains(&self, q: DVec2) -> bool {
        self.contains_within(q, 0.0)
    }

    /// Whether `q` lies in the stored triangle whatever the vertex error: inside the
    /// triangle shrunk by the largest distance a vertex error can move an edge.
    #[inline]
    pub fn surely_contains(&self, q: DVec2) -> bool {
        self.contains_within(q, self.err_v * std::f64::consts::SQRT_2)
    }

    /// Whether `q` may lie in the stored triangle given the vertex error: inside the
    /// triangle grown by the same distance.
    #[inline]
    pub fn may_contain(&self, q: DVec2) -> bool {
        self.contains_within(q, -self.err_v * std::f64::consts::SQRT_2)
    }

    /// Twice the signed area (positive for counter-clockwise in the predicate's sense).
    #[inline]
    pub fn orientation(&self) -> f64 {
        orient2d(coord(self.v[0]), coord(self.v[1]), coord(self.v[2]))
    }
}

/// What the rasterizer hands to the packing stage for one texel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TexelData {
    /// Vertices in map coordinates.
    pub v: [DVec2; 3],
    /// Map depth at the texel centre (the triangle's plane, extrapolated if need be).
    pub z: f64,
    /// `(∂z̃/∂x, ∂z̃/∂y)` per texel.
    pub dz: DVec2,
}

/// The all-ones empty packed texel.
pub const EMPTY_PACKED: [u32; 4] = [u32::MAX; 4];

/// The triangle's share of a packed texel (see [`Packer::pack_triangle`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PackedTriangle {
    /// Words R, G, B: the vertices.
    pub words: [u32; 3],
    /// Whether a vertex was clamped to the 16-bit range.
    pub clamped: bool,
    /// Derivative codes, when they do not depend on the texel.
    pub codes: Option<(u8, u8)>,
}

/// The 128-bit codec of one map.
#[derive(Debug, Clone, PartialEq)]
pub struct Packer {
    /// The map's space.
    pub space: LightSpace,
    /// The derivative code.
    pub code: DerivativeCode,
}

impl Packer {
    #[inline]
    fn vertex_code(&self, x: f64) -> (u32, bool) {
        let r = f64::from(self.space.res);
        let q = ((x + 0.5 * r) / self.space.vertex_step()).round();
        let clamped = q.clamp(0.0, 65535.0);
        // NaN compares false: report it as clamped, code 0.
        (if clamped.is_nan() { 0 } else { clamped as u32 }, q != clamped)
    }

    #[inline]
    fn vertex(&self, code: u32) -> f64 {
        f64::from(code) * self.space.vertex_step() - 0.5 * f64::from(self.space.res)
    }

    #[inline]
    fn depth_code(&self, z: f64) -> u32 {
        let s = self.space.depth_step();
        if s <= 0.0 {
            return 0;
        }
        let q = ((z - self.space.z_lo) / s).round().clamp(0.0, 65535.0);
        if q.is_nan() {
            0
        } else {
            q as u32
        }
    }

    /// The parts of a packed texel that depend on the triangle only: the three vertex words,
    /// whether a vertex was clamped, and the derivative codes when the slope scale does not
    /// depend on depth (orthographic lights).
    pub fn pack_triangle(&self, v: &[DVec2; 3], dz: DVec2) -> PackedTriangle {
        let mut words = [0u32; 3];
        let mut clamped = false;
        for (k, p) in v.iter().enumerate() {
            let (x, cx) = self.vertex_code(p.x);
            let (y, cy) = self.vertex_code(p.y);
            clamped |= cx || cy;
            words[k] = x | (y << 16);
        }
        let codes = (!self.space.perspective).then(|| self.derivative_codes(dz, 0.0));
        PackedTriangle { words, clamped, codes }
    }

    fn derivative_codes(&self, dz: DVec2, z: f64) -> (u8, u8) {
        let k = self.space.slope_scale(z);
        (self.code.encode(dz.x / k.x), self.code.encode(dz.y / k.y))
    }

    /// The texel holding triangle `t` with map depth `z` at its centre.
    #[inline]
    pub fn pack_texel(&self, t: &PackedTriangle, z: f64, dz: DVec2) -> [u32; 4] {
        let zq = self.depth_code(z);
        let (qx, qy) = t.codes.unwrap_or_else(|| {
            self.derivative_codes(dz, self.space.z_lo + f64::from(zq) * self.space.depth_step())
        });
        let [a, b, c] = t.words;
        [a, b, c, (zq << 16) | (u32::from(qx) << 8) | u32::from(qy)]
    }

    /// Packs a texel; also says whether a vertex had to be clamped.
    pub fn pack(&self, d: &TexelData) -> ([u32; 4], bool) {
        let t = self.pack_triangle(&d.v, d.dz);
        (self.pack_texel(&t, d.z, d.dz), t.clamped)
    }

    /// Decodes the packed texel at `centre`; `None` for an empty texel.
    #[inline]
    pub fn unpack(&self, w: &[u32; 4], centre: DVec2) -> Option<Tri> {
        if *w == EMPTY_PACKED {
            return None;
        }
        let v = [0, 1, 2].map(|k| DVec2::new(self.vertex(w[k] & 0xffff), self.vertex(w[k] >> 16)));
        let step = self.space.depth_step();
        let z = self.space.z_lo + f64::from(w[3] >> 16) * step;
        let (qx, qy) = (((w[3] >> 8) & 0xff) as u8, (w[3] & 0xff) as u8);
        let k = self.space.slope_scale(z);
        Some(Tri {
            v,
            centre,
            z,
            dz: DVec2::new(self.code.decode(qx) * k.x, self.code.decode(qy) * k.y),
            err_z: 0.5 * step,
            err_dz: DVec2::new(self.code.error(qx) * k.x, self.code.error(qy) * k.y),
            err_v: 0.5 * self.space.vertex_step(),
        })
    }
}

/// The unpacked texel: `f32` vertices, depth and derivatives; empty when `z` is NaN.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct F32Texel {
    /// Vertices, map coordinates.
    pub v: [[f32; 2]; 3],
    /// Map depth at the centre; NaN for an empty texel.
    pub z: f32,
    /// Derivatives per texel.
    pub dz: [f32; 2],
}

impl F32Texel {
    /// The empty texel.
    pub const EMPTY: F32Texel = F32Texel { v: [[0.0; 2]; 3], z: f32::NAN, dz: [0.0; 2] };

    /// Rounds the texel's data to `f32`.
    pub fn new(d: &TexelData) -> Self {
        Self {
            v: d.v.map(|p| [p.x as f32, p.y as f32]),
            z: d.z as f32,
            dz: [d.dz.x as f32, d.dz.y as f32],
        }
    }

    /// Decodes the texel at `centre`; `None` for an empty texel.
    #[inline]
    pub fn unpack(&self, centre: DVec2) -> Option<Tri> {
        if self.z.is_nan() {
            return None;
        }
        let half_ulp = f64::from(f32::EPSILON) * 0.5;
        let z = f64::from(self.z);
        let dz = DVec2::new(f64::from(self.dz[0]), f64::from(self.dz[1]));
        let v = self.v.map(|p| DVec2::new(f64::from(p[0]), f64::from(p[1])));
        let largest = v.iter().fold(0.0f64, |m, p| m.max(p.abs().max_element()));
        Some(Tri {
            v,
            centre,
            z,
            dz,
            err_z: z.abs() * half_ulp,
            err_dz: dz.abs() * half_ulp,
            err_v: largest * half_ulp,
        })
    }
}

/// The map's texels in one of the two formats.
#[derive(Debug, Clone, PartialEq)]
pub enum Texels {
    /// 128-bit texels and their codec.
    Packed(Vec<[u32; 4]>, Box<Packer>),
    /// `f32` texels.
    F32(Vec<F32Texel>),
}

/// The stored texels of an `res x res` map, decoded on lookup.
#[derive(Debug, Clone, PartialEq)]
pub struct SpsmMap {
    /// Map resolution.
    pub res: u32,
    /// The map's space.
    pub space: LightSpace,
    /// The texels, row by row.
    pub texels: Texels,
}

impl SpsmMap {
    /// The decoded triangle of texel `(x, y)`; `None` when empty or outside the map.
    #[inline]
    pub fn get(&self, x: i64, y: i64) -> Option<Tri> {
        let r = i64::from(self.res);
        if x < 0 || y < 0 || x >= r || y >= r {
            return None;
        }
        let k = (y * r + x) as usize;
        let centre = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
        match &self.texels {
            Texels::Packed(t, p) => p.unpack(&t[k], centre),
            Texels::F32(t) => t[k].unpack(centre),
        }
    }

    /// Bound on the depth error of a plane with map depth `z` and gradient `grad` stored in
    /// this map's format, as `(at the centre, per texel of offset along x and y)`: the
    /// quantization a receiver's own surface would suffer in a texel.
    pub fn plane_error(&self, z: f64, grad: DVec2) -> (f64, DVec2) {
        match &self.texels {
            Texels::Packed(_, p) => {
                let k = self.space.slope_scale(z);
                let code_error = |g: f64, k: f64| p.code.error(p.code.encode(g / k)) * k;
                (
                    0.5 * self.space.depth_step(),
                    DVec2::new(code_error(grad.x, k.x), code_error(grad.y, k.y)),
                )
            }
            Texels::F32(_) => {
                let half_ulp = 0.5 * f64::from(f32::EPSILON);
                (z.abs() * half_ulp, grad.abs() * half_ulp)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scenes::projection::look_basis;

    fn ortho(res: u32) -> Projector {
        let (right, up, forward) = look_basis(-glam::DVec3::Y, glam::DVec3::Z);
        Projector {
            origin: glam::DVec3::new(0.0, 10.0, 0.0),
            right,
            up,
            forward,
            kind: ProjectionKind::Orthographic { half_width: 8.0, half_height: 8.0 },
            near: f64::NEG_INFINITY,
            width: f64::from(res),
            height: f64::from(res),
        }
    }

    #[test]
    fn packing_round_trips_within_its_steps() {
        let space = LightSpace::new(&ortho(1024), (0.0, 12.0));
        let packer = Packer { space, code: DerivativeCode::new(5) };
        let centre = DVec2::new(100.5, 200.5);
        let d = TexelData {
            v: [DVec2::new(99.3, 201.01), DVec2::new(130.0, 180.25), DVec2::new(-3.0, 1030.0)],
            z: 7.123456,
            dz: DVec2::new(0.004, -0.02),
        };
        let (w, clamped) = packer.pack(&d);
        assert!(!clamped);
        let t = packer.unpack(&w, centre).expect("not empty");
        for k in 0..3 {
            assert!((t.v[k] - d.v[k]).abs().max_element() <= 0.5 * space.vertex_step() + 1e-12);
        }
        assert!((t.z - d.z).abs() <= t.err_z * (1.0 + 1e-9));
        for q in [centre, DVec2::new(101.9, 199.2), DVec2::new(98.6, 202.0)] {
            let exact = d.z + (q - centre).dot(d.dz);
            assert!((t.depth_at(q) - exact).abs() <= t.error_at(q) * (1.0 + 1e-9));
        }
        assert_eq!(packer.unpack(&EMPTY_PACKED, centre), None);
    }

    #[test]
    fn vertices_outside_the_range_are_clamped_and_reported() {
        let space = LightSpace::new(&ortho(64), (0.0, 12.0));
        let packer = Packer { space, code: DerivativeCode::new(5) };
        let d = TexelData {
            v: [DVec2::new(10.0, 10.0), DVec2::new(500.0, 10.0), DVec2::new(10.0, 12.0)],
            z: 1.0,
            dz: DVec2::ZERO,
        };
        let (w, clamped) = packer.pack(&d);
        assert!(clamped);
        let t = packer.unpack(&w, DVec2::new(10.5, 10.5)).expect("not empty");
        assert!((t.v[1].x - 96.0).abs() < 1e-9);
    }

    #[test]
    fn f32_texels_keep_the_data_to_rounding() {
        let d = TexelData {
            v: [DVec2::new(1.0, 2.0), DVec2::new(3.0, 2.0), DVec2::new(1.0, 5.0)],
            z: 7.1,
            dz: DVec2::new(0.25, -1.0 / 3.0),
        };
        let centre = DVec2::new(1.5, 2.5);
        let t = F32Texel::new(&d).unpack(centre).expect("not empty");
        assert!((t.z - d.z).abs() <= t.err_z);
        assert!((t.dz - d.dz).abs().cmple(t.err_dz).all());
        assert_eq!(F32Texel::EMPTY.unpack(centre), None);
    }

    #[test]
    fn exact_containment_is_closed_and_rejects_degenerate_triangles() {
        let t = |v: [DVec2; 3]| Tri {
            v,
            centre: DVec2::ZERO,
            z: 0.0,
            dz: DVec2::ZERO,
            err_z: 0.0,
            err_dz: DVec2::ZERO,
            err_v: 0.25,
        };
        let tri = t([DVec2::ZERO, DVec2::new(4.0, 0.0), DVec2::new(0.0, 4.0)]);
        assert!(tri.contains(DVec2::new(1.0, 1.0)));
        assert!(tri.contains(DVec2::new(2.0, 2.0)), "on the hypotenuse");
        assert!(tri.contains(DVec2::ZERO), "at a vertex");
        assert!(!tri.contains(DVec2::new(2.0, 2.0 + 1e-15)));
        let flipped = t([tri.v[0], tri.v[2], tri.v[1]]);
        assert!(flipped.contains(DVec2::new(1.0, 1.0)));
        let line = t([DVec2::ZERO, DVec2::new(1.0, 1.0), DVec2::new(2.0, 2.0)]);
        assert!(!line.contains(DVec2::new(1.0, 1.0)));
        assert!(!line.contains(DVec2::new(0.5, 0.7)));
        // Vertex error 0.25: the surely/maybe margins are 0.25 sqrt 2 from each edge.
        assert!(tri.surely_contains(DVec2::new(1.0, 1.0)));
        assert!(!tri.surely_contains(DVec2::new(0.3, 1.0)));
        assert!(tri.may_contain(DVec2::new(-0.3, 1.0)));
        assert!(!tri.may_contain(DVec2::new(-0.4, 1.0)));
        assert!(!line.may_contain(DVec2::new(1.0, 1.0)));
    }
}
