//! Stage "pixel facets" (sections 3.1, 3.3 and 4): a facet per covered pixel on the tangent
//! plane of its G-buffer surface (the pixel-centre position and the *face* normal, "to prevent
//! normal interpolation which causes incorrect facet orientation"), projected to the light and
//! classified by the summed-area table of the silhouette mask map.
//!
//! **The facet** is the pixel square seen on the tangent plane: the camera rays through the
//! square's points meet the plane at the facet's points; sub-sample `s` of the pixel sees the
//! facet point on its own ray. A plane seen nearly edge-on would make that region unbounded,
//! so the facet is limited to its **region**: for perspective cameras the points at most
//! [`FACET_DEPTH_RATIO`] times the centre's camera depth (which also keeps it in front of the
//! camera), for orthographic cameras the points within [`FACET_ORTHO_SPAN`] pixel widths of
//! the centre's depth; for spot lights, the points the light can project (beyond its `near`
//! plane). Each limit is a screen half-plane ([`super::screen`]); only those that cut the
//! pixel square are kept, and sub-samples outside the region are left out of the pixel's
//! ratio (they do not see the facet). On a planar receiver a limit cuts a pixel whose
//! sub-samples all see the plane only where the plane is seen within `δ / (ratio - 1)` of its
//! horizon (`δ` the pixel's angular size: 0.025° at 800 x 600 and 45°), the sub-samples'
//! depths then varying fourfold across the pixel.
//!
//! **The footprint** on the light's image plane is the projection of the facet's corners (the
//! pixel square clipped to the region); the map between screen and light image restricted to
//! the plane is projective and regular over the region, so the footprint is the convex polygon
//! of those corners and holds the light image point of every sub-sample.
//!
//! **Classification** ("if there are no silhouette texels in the bounding rectangle of a
//! projected facet, it is not on the silhouette"): the rectangle of texels whose closed
//! squares meet the footprint's bounding box, counted with four SAT references. Pixels whose
//! centre a spot light cannot project are lit, as in `sm`.

use super::footprint::{Footprint, MAX_CORNERS};
use super::sat::SummedAreaTable;
use super::screen::{CameraBasis, Crossing, FacetMap, HalfPlane, WorldPlane};
use crate::frame::Frame;
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use scenes::{projection::ProjectionKind, Projector};

/// A perspective camera's facet holds the points up to this multiple of the centre's depth.
pub const FACET_DEPTH_RATIO: f64 = 4.0;

/// An orthographic camera's facet holds the points within this many pixel widths of the
/// centre's depth.
pub const FACET_ORTHO_SPAN: f64 = 64.0;

/// Most region half-planes: two for orthographic cameras, one more for a spot light.
pub const MAX_REGION: usize = 3;

/// How a pixel's shadow is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PixelClass {
    /// No surface, or a surface the spot light cannot project: lit.
    Lit,
    /// Not on the silhouette: the standard depth test.
    DepthTest,
    /// On the silhouette: visibility evaluation of facet number `.0`.
    Silhouette(u32),
}

/// A silhouette pixel's facet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Facet {
    /// Pixel index (row-major).
    pub pixel: u32,
    /// The G-buffer triangle; it never shadows its own facet.
    pub triangle: u32,
    /// Unit normal of the tangent plane.
    pub normal: DVec3,
    /// Offset of the tangent plane (`normal·X = offset`).
    pub offset: f64,
    /// The screen mapping.
    pub map: FacetMap,
    /// Half-planes limiting the region (those that cut the pixel square).
    pub region: [HalfPlane; MAX_REGION],
    /// Number of region half-planes.
    pub region_count: u8,
}

impl Facet {
    /// The region's half-planes.
    pub fn region(&self) -> &[HalfPlane] {
        &self.region[..self.region_count as usize]
    }
}

/// The facets of a frame and the class of every pixel.
#[derive(Debug, Clone, PartialEq)]
pub struct Facets {
    /// Class of each pixel.
    pub class: Vec<PixelClass>,
    /// The silhouette facets, in pixel order.
    pub facets: Vec<Facet>,
    /// Their footprints on the light's image plane.
    pub footprints: Vec<Footprint>,
    /// Their texel rectangles `(x0, y0, x1, y1)`, inclusive.
    pub rects: Vec<[u32; 4]>,
}

/// A facet with its footprint, before classification.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProjectedFacet {
    /// The facet.
    pub facet: Facet,
    /// Its footprint on the light's image plane.
    pub footprint: Footprint,
}

/// Clips the convex polygon `poly[..n]` (pixel-local screen points) to `h >= 0` into `out`;
/// returns the corners kept (at most `n + 1`).
fn clip(poly: &[DVec2], h: &HalfPlane, out: &mut [DVec2; MAX_CORNERS]) -> usize {
    let mut m = 0;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (ga, gb) = (h.at(a), h.at(b));
        if ga >= 0.0 {
            out[m] = a;
            m += 1;
        }
        if (ga >= 0.0) != (gb >= 0.0) {
            out[m] = a + (b - a) * (ga / (ga - gb));
            m += 1;
        }
    }
    m
}

/// The light's view of the screen: light image coordinates are ratios of world-plane values
/// (`x = X_num / W`, `y = Y_num / W` with `W` the light depth for a spot light, 1 for a
/// directional one), so on a facet they are ratios of screen half-plane functions
/// ([`FacetMap::half_plane`] scales every plane by the same `a(u)`), and a footprint corner
/// costs three affine evaluations and a division.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightPlanes {
    pub(crate) x: WorldPlane,
    pub(crate) y: WorldPlane,
    /// The depth plane of a spot light; `None` for directional lights (denominator `a(u)`).
    pub(crate) w: Option<WorldPlane>,
    /// A spot light's near plane (points in front of it project).
    pub(crate) near: Option<WorldPlane>,
}

impl LightPlanes {
    /// The planes of `light` seen by `camera`.
    pub fn new(light: &Projector, camera: &CameraBasis) -> Self {
        let (o, r, up, f) = (light.origin, light.right, light.up, light.forward);
        let (w, h) = (0.5 * light.width, 0.5 * light.height);
        let plane = |n: DVec3, c: f64| WorldPlane::new(n, c, camera);
        match light.kind {
            ProjectionKind::Orthographic { half_width, half_height } => {
                // x = w + w (X - o)·r / hw, y = h - h (X - o)·up / hh.
                let (nx, ny) = (r * (w / half_width), -up * (h / half_height));
                Self {
                    x: plane(nx, nx.dot(o) - w),
                    y: plane(ny, ny.dot(o) - h),
                    w: None,
                    near: None,
                }
            }
            ProjectionKind::Perspective { tan_half_x, tan_half_y } => {
                // x = w + w (X - o)·r / (tx (X - o)·f), likewise y; numerators over the depth.
                let nx = r * (w / tan_half_x) + f * w;
                let ny = -up * (h / tan_half_y) + f * h;
                Self {
                    x: plane(nx, nx.dot(o)),
                    y: plane(ny, ny.dot(o)),
                    w: Some(plane(f, f.dot(o))),
                    near: Some(plane(f, light.near + f.dot(o))),
                }
            }
        }
    }
}

/// The facet of the surface `position`, `normal`, `triangle` seen through pixel `(i, j)`, and
/// its footprint; `None` when the light cannot project the pixel's centre point (lit).
#[allow(clippy::too_many_arguments)]
pub fn project_facet(
    camera: &CameraBasis,
    light: &Projector,
    planes: &LightPlanes,
    pixel: (u32, u32),
    width: u32,
    triangle: u32,
    position: DVec3,
    normal: DVec3,
) -> Option<ProjectedFacet> {
    if light.is_perspective() {
        light.project(position)?;
    }
    let centre = DVec2::new(f64::from(pixel.0) + 0.5, f64::from(pixel.1) + 0.5);
    let offset = normal.dot(position);
    let map = FacetMap::new(camera, centre, normal, offset)?;
    let [a0, ax, ay] = map.a;
    let [bx, by] = map.b;
    let mut limits = [HalfPlane { g0: 0.0, gx: 0.0, gy: 0.0 }; MAX_REGION];
    let mut n = if camera.perspective {
        limits[0] = HalfPlane { g0: a0 * (1.0 - 1.0 / FACET_DEPTH_RATIO), gx: ax, gy: ay };
        1
    } else {
        let span = FACET_ORTHO_SPAN * camera.ox.length().max(camera.oy.length()) * a0;
        limits[0] = HalfPlane { g0: span, gx: -bx, gy: -by };
        limits[1] = HalfPlane { g0: span, gx: bx, gy: by };
        2
    };
    if let Some(near) = &planes.near {
        limits[n] = map.half_plane(near);
        n += 1;
    }
    let mut region = [HalfPlane { g0: 0.0, gx: 0.0, gy: 0.0 }; MAX_REGION];
    let mut count = 0;
    for h in &limits[..n] {
        if h.crossing() != Crossing::All {
            region[count] = *h;
            count += 1;
        }
    }
    // The pixel square, clipped by each region half-plane (4 corners, one more per clip).
    let mut poly = [DVec2::ZERO; MAX_CORNERS];
    poly[..4].copy_from_slice(&[
        DVec2::new(-0.5, -0.5),
        DVec2::new(0.5, -0.5),
        DVec2::new(0.5, 0.5),
        DVec2::new(-0.5, 0.5),
    ]);
    let mut corners = 4;
    let mut scratch = [DVec2::ZERO; MAX_CORNERS];
    for h in &region[..count] {
        corners = clip(&poly[..corners], h, &mut scratch);
        std::mem::swap(&mut poly, &mut scratch);
    }
    if corners == 0 {
        corners = 1; // the centre always belongs to the facet
        poly[0] = DVec2::ZERO;
    }
    let (hx, hy) = (map.half_plane(&planes.x), map.half_plane(&planes.y));
    let hw = match &planes.w {
        Some(w) => map.half_plane(w),
        None => HalfPlane { g0: a0, gx: ax, gy: ay },
    };
    for u in &mut poly[..corners] {
        let inv = 1.0 / hw.at(*u);
        *u = DVec2::new(hx.at(*u) * inv, hy.at(*u) * inv);
    }
    let footprint = Footprint::new(&poly[..corners])?;
    let facet = Facet {
        pixel: pixel.1 * width + pixel.0,
        triangle,
        normal,
        offset,
        map,
        region,
        region_count: count as u8,
    };
    Some(ProjectedFacet { facet, footprint })
}

/// Builds every covered pixel's facet, projects it to the light and classifies it with the
/// summed-area table `sat` of the `res x res` silhouette mask map.
///
/// Two passes: every pixel is classified (its facet and footprint are built and dropped),
/// then the silhouette pixels' facets are built again and kept, so that no per-pixel record
/// is stored for the many pixels off the silhouette.
pub fn classify_facets(
    frame: &Frame<'_>,
    light: &Projector,
    res: u32,
    sat: &SummedAreaTable,
) -> Facets {
    let g = &frame.gbuffer;
    let camera = CameraBasis::new(&frame.camera);
    let planes = LightPlanes::new(light, &camera);
    let w = g.width;
    let facet_of = |k: usize| {
        let pixel = ((k % w as usize) as u32, (k / w as usize) as u32);
        let (t, p, n) = (g.triangle[k], g.position[k], g.normal[k]);
        project_facet(&camera, light, &planes, pixel, w, t, p, n)
    };
    let rect_of = |pf: &ProjectedFacet| {
        let (x0, y0, x1, y1) = pf.footprint.texel_rect(res)?;
        (sat.count(x0, y0, x1, y1) > 0).then_some([x0 as u32, y0 as u32, x1 as u32, y1 as u32])
    };
    let mut class = vec![PixelClass::Lit; g.triangle.len()];
    class.par_iter_mut().enumerate().with_min_len(256).for_each(|(k, c)| {
        if !g.covered(k) {
            return;
        }
        *c = match facet_of(k) {
            Some(pf) if rect_of(&pf).is_some() => PixelClass::Silhouette(0),
            Some(_) => PixelClass::DepthTest,
            // The centre does not project: lit. A facet the camera meets edge-on at the
            // centre keeps the depth test, as in `sm`.
            None if light.project(g.position[k]).is_some() => PixelClass::DepthTest,
            None => PixelClass::Lit,
        };
    });
    let mut pixels = Vec::new();
    for (k, c) in class.iter_mut().enumerate() {
        if let PixelClass::Silhouette(i) = c {
            *i = pixels.len() as u32;
            pixels.push(k);
        }
    }
    // Built again and written straight into the three lists (an indexed unzip, no copy).
    let (facets, (footprints, rects)): (Vec<_>, (Vec<_>, Vec<_>)) = pixels
        .par_iter()
        .map(|&k| {
            let pf = facet_of(k).expect("classified as a silhouette facet");
            let rect = rect_of(&pf).expect("classified as a silhouette facet");
            (pf.facet, (pf.footprint, rect))
        })
        .unzip();
    Facets { class, facets, footprints, rects }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scenes::projection::{look_basis, ProjectionKind};

    fn camera() -> Projector {
        let (right, up, forward) = look_basis(DVec3::new(0.0, -0.5, -1.0), DVec3::Y);
        Projector {
            origin: DVec3::new(0.0, 3.0, 6.0),
            right,
            up,
            forward,
            kind: ProjectionKind::Perspective { tan_half_x: 0.5, tan_half_y: 0.4 },
            near: 0.01,
            width: 80.0,
            height: 64.0,
        }
    }

    fn light() -> Projector {
        let (right, up, forward) = look_basis(DVec3::new(-0.3, -1.0, -0.2), DVec3::Y);
        Projector {
            origin: DVec3::new(2.0, 10.0, 2.0),
            right,
            up,
            forward,
            kind: ProjectionKind::Orthographic { half_width: 8.0, half_height: 8.0 },
            near: f64::NEG_INFINITY,
            width: 256.0,
            height: 256.0,
        }
    }

    /// The facet of the ground plane seen through pixel (i, j).
    fn ground_facet(i: u32, j: u32, normal: DVec3) -> Option<ProjectedFacet> {
        let cam = camera();
        let basis = CameraBasis::new(&cam);
        let ray = cam.ray(DVec2::new(f64::from(i) + 0.5, f64::from(j) + 0.5));
        let t = ray.intersect_plane(DVec3::Y, 0.0)?;
        let planes = LightPlanes::new(&light(), &basis);
        project_facet(&basis, &light(), &planes, (i, j), 80, 0, ray.at(t), normal)
    }

    #[test]
    fn ground_facets_are_whole_pixels_holding_every_sub_sample() {
        let pattern = crate::pattern::SamplePattern::new(32, crate::pattern::PatternKind::Rotated)
            .expect("valid");
        let (cam, l) = (camera(), light());
        for (i, j) in [(40, 40), (3, 60), (77, 33)] {
            let pf = ground_facet(i, j, DVec3::Y).expect("the ground is in front");
            assert_eq!(pf.facet.region_count, 0);
            assert_eq!(pf.footprint.corners().len(), 4);
            for s in 0..32 {
                let p = pattern.point(i, j, s);
                let ray = cam.ray(p);
                let x = ray.at(ray.intersect_plane(DVec3::Y, 0.0).expect("hits"));
                let (q, _) = l.project(x).expect("projects");
                let (x0, y0, x1, y1) = pf.footprint.texel_rect(256).expect("in the map");
                let (tx, ty) = (q.x.floor() as usize, q.y.floor() as usize);
                assert!((x0..=x1).contains(&tx) && (y0..=y1).contains(&ty));
                assert!(pf.footprint.touches_texel(tx, ty));
            }
        }
    }

    #[test]
    fn light_planes_reproduce_the_light_projection() {
        let cam = camera();
        let basis = CameraBasis::new(&cam);
        let (right, up, forward) = look_basis(DVec3::new(-0.3, -1.0, -0.2), DVec3::Y);
        let spot = Projector {
            origin: DVec3::new(2.0, 9.0, 1.0),
            right,
            up,
            forward,
            kind: ProjectionKind::Perspective { tan_half_x: 0.9, tan_half_y: 0.9 },
            near: 0.5,
            width: 256.0,
            height: 256.0,
        };
        for l in [light(), spot] {
            let planes = LightPlanes::new(&l, &basis);
            for (i, j) in [(40, 40), (3, 60), (77, 33)] {
                let centre = DVec2::new(f64::from(i) + 0.5, f64::from(j) + 0.5);
                let ray = cam.ray(centre);
                let x0 = ray.at(ray.intersect_plane(DVec3::Y, 0.0).expect("hits"));
                let normal = DVec3::new(0.1, 1.0, -0.2).normalize();
                let map = FacetMap::new(&basis, centre, normal, normal.dot(x0)).expect("in front");
                let (hx, hy) = (map.half_plane(&planes.x), map.half_plane(&planes.y));
                let hw =
                    planes.w.map_or(HalfPlane { g0: map.a[0], gx: map.a[1], gy: map.a[2] }, |w| {
                        map.half_plane(&w)
                    });
                for u in [DVec2::ZERO, DVec2::new(-0.5, 0.5), DVec2::new(0.5, 0.25)] {
                    let (want, _) = l.project_unclipped(map.point_at(&basis, u));
                    let got = DVec2::new(hx.at(u), hy.at(u)) / hw.at(u);
                    assert!((got - want).length() < 1e-9, "{got} vs {want}");
                }
            }
        }
    }

    #[test]
    fn edge_on_facets_are_bounded_by_their_region() {
        // A plane through the pixel-centre point containing the centre ray's direction almost
        // exactly: seen edge-on; its facet is cut at four times the depth.
        let cam = camera();
        let ray = cam.ray(DVec2::new(40.5, 40.5));
        let t = ray.intersect_plane(DVec3::Y, 0.0).expect("hits");
        let side = ray.direction.cross(DVec3::X).normalize();
        let normal = (side + ray.direction.normalize() * 1e-4).normalize();
        let basis = CameraBasis::new(&cam);
        let planes = LightPlanes::new(&light(), &basis);
        let pf = project_facet(&basis, &light(), &planes, (40, 40), 80, 0, ray.at(t), normal)
            .expect("the centre projects");
        assert_eq!(pf.facet.region_count, 1);
        let extent = pf.footprint.hi - pf.footprint.lo;
        assert!(extent.is_finite() && extent.max_element() < 256.0, "{extent}");
        let h = pf.facet.region()[0];
        assert!(h.g0 > 0.0, "the centre lies in the region");
    }
}
