//! Stage "sample footprints" (Wyman et al., I3D 2015, section 4.1; TVCG 2016, section 5.1):
//! every covered pixel enters the light-space grid's lists in each texel its footprint meets,
//! and the pixel's sub-samples are placed on its receiver's tangent plane ([`SubSamples`]).
//!
//! **The footprint** is the pixel square seen on the tangent plane of the pixel's G-buffer
//! point and face normal, limited to a bounded region at grazing angles, projected to the
//! light's image: `pan09`'s facet ([`project_facet`], whose module doc gives the region), a
//! convex polygon holding the light image point of every valid sub-sample. A pixel enters each
//! texel whose closed square the polygon meets ([`Footprint::touches_texel`], conservative by a
//! rounding margin); a footprint reaching beyond the grid enters every border texel of its
//! clamped rectangle. A pixel whose tangent plane the camera sees exactly edge-on at its
//! centre enters the texel of its centre alone; a pixel whose centre a spot light cannot
//! project enters none (lit, as in `sm`).
//!
//! **The sub-samples** ([`SubSamples::pixel`]): sub-sample `s` of the shared pattern lies where
//! the camera ray through it meets the tangent plane, if that point is in the facet's region
//! (depth at most [`FACET_DEPTH_RATIO`] times the centre's for perspective cameras, within
//! [`FACET_ORTHO_SPAN`] pixel widths of it for orthographic ones, beyond a spot light's near
//! plane); the centre sub-sample is the G-buffer's point itself and always valid. Each becomes
//! a sample on the light's image plane with `afsm`'s threshold depth
//! ([`crate::afsm::samples::threshold_depth`], the shadow offset of the ray tracer).

use super::grid::{Grid, TexelLists};
use crate::{
    afsm::{
        samples::{threshold_depth, Sample},
        shadow_offset,
    },
    frame::Frame,
    gbuffer::GBuffer,
    method::MethodError,
    pan09::{
        facets::{project_facet, LightPlanes, FACET_DEPTH_RATIO, FACET_ORTHO_SPAN},
        footprint::{Footprint, MAX_CORNERS},
        screen::{CameraBasis, FacetMap, HalfPlane},
    },
    pattern::SamplePattern,
};
use glam::DVec2;
use rayon::prelude::*;
use scenes::{Projector, Ray};

/// The pixels' lists: for every texel of the `res x res` grid, the pixels whose footprint
/// meets it, in row-major order; an error when they would hold `u32::MAX` entries or more.
pub fn footprints(
    frame: &Frame<'_>,
    light: &Projector,
    grid: Grid,
) -> Result<TexelLists, MethodError> {
    let g = &frame.gbuffer;
    let res = grid.res;
    let camera = CameraBasis::new(&frame.camera);
    let planes = LightPlanes::new(light, &camera);
    let w = g.width as usize;
    let keys: Vec<Vec<u64>> = (0..g.height as usize)
        .into_par_iter()
        .map(|row| {
            let mut keys = Vec::new();
            for k in row * w..(row + 1) * w {
                if !g.covered(k) {
                    continue;
                }
                let Some(footprint) = footprint(g, k, &camera, light, &planes, &grid) else {
                    continue;
                };
                let Some((x0, y0, x1, y1)) = grid.rect(footprint.lo, footprint.hi) else {
                    continue;
                };
                let inside = grid.holds(footprint.lo, footprint.hi);
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        if !inside || footprint.touches_texel(x as usize, y as usize) {
                            keys.push(Grid::key(grid.index(x, y), k as u32));
                        }
                    }
                }
            }
            keys
        })
        .collect();
    let keys = keys.concat();
    let entries = keys.len();
    TexelLists::from_keys(res as usize * res as usize, keys).ok_or_else(|| {
        MethodError::NotApplicable(format!(
            "ftizb: the pixels' footprints meet {entries} texels of the {res} x {res} grid, \
             more than its lists can index (2^32); lower --izb-res or the frame size"
        ))
    })
}

/// The footprint of pixel `k` on the light's image, in the grid's texel units; `None` when
/// the light cannot project its centre.
fn footprint(
    g: &GBuffer,
    k: usize,
    camera: &CameraBasis,
    light: &Projector,
    planes: &LightPlanes,
    grid: &Grid,
) -> Option<Footprint> {
    let w = g.width as usize;
    let pixel = ((k % w) as u32, (k / w) as u32);
    let (t, p, n) = (g.triangle[k], g.position[k], g.normal[k]);
    match project_facet(camera, light, planes, pixel, g.width, t, p, n) {
        Some(pf) => {
            let mut corners = [DVec2::ZERO; MAX_CORNERS];
            let c = pf.footprint.corners();
            for (out, &q) in corners.iter_mut().zip(c) {
                *out = grid.texels(q);
            }
            Footprint::new(&corners[..c.len()])
        }
        None => {
            let (xy, _) = light.project(p)?;
            Footprint::new(&[grid.texels(xy)])
        }
    }
}

/// The sub-samples of a frame's pixels on their tangent planes (see the module doc).
#[derive(Debug, Clone, Copy)]
pub struct SubSamples<'a> {
    g: &'a GBuffer,
    camera: &'a Projector,
    light: &'a Projector,
    pattern: &'a SamplePattern,
    basis: CameraBasis,
    planes: LightPlanes,
    /// Orthographic cameras: the region's reach in depth (64 pixel widths).
    ortho_span: f64,
}

/// Where a pixel's sub-samples fall on the light's image, to within rounding: the facet's
/// projective map from the pixel to the light image (three affine functions and a division a
/// sub-sample, `pan09`'s footprint map), cheaper than placing the sub-sample
/// ([`SubSamples::sample`]), which is done only where a texel owns it.
#[derive(Debug, Clone, Copy)]
pub struct Approximate {
    x: HalfPlane,
    y: HalfPlane,
    w: HalfPlane,
}

impl Approximate {
    /// The light image point of the sub-sample at pixel-local point `u` (`u = offset - 1/2`).
    #[inline]
    pub fn at(&self, u: DVec2) -> DVec2 {
        let inv = 1.0 / self.w.at(u);
        DVec2::new(self.x.at(u) * inv, self.y.at(u) * inv)
    }
}

impl<'a> SubSamples<'a> {
    /// The sub-samples of `frame`'s pixels under `light` at `pattern`.
    pub fn new(frame: &'a Frame<'a>, light: &'a Projector, pattern: &'a SamplePattern) -> Self {
        let basis = CameraBasis::new(&frame.camera);
        let pixel = basis.ox.length().max(basis.oy.length());
        Self {
            g: &frame.gbuffer,
            camera: &frame.camera,
            light,
            pattern,
            basis,
            planes: LightPlanes::new(light, &basis),
            ortho_span: FACET_ORTHO_SPAN * pixel,
        }
    }

    /// Pixels of the frame.
    #[inline]
    pub fn pixels(&self) -> usize {
        self.g.triangle.len()
    }

    /// The light the sub-samples are projected by.
    #[inline]
    pub fn light(&self) -> &'a Projector {
        self.light
    }

    /// The pattern.
    #[inline]
    pub fn pattern(&self) -> &'a SamplePattern {
        self.pattern
    }

    /// The G-buffer triangle of pixel `k`.
    #[inline]
    pub fn triangle(&self, k: usize) -> u32 {
        self.g.triangle[k]
    }

    /// Sub-samples per pixel.
    #[inline]
    pub fn rate(&self) -> usize {
        self.pattern.rate() as usize
    }

    /// Sub-sample `s` of pixel `k` (covered) on the light's image plane, `None` when it is not
    /// valid: its camera ray misses the tangent plane or meets it outside the facet's region,
    /// or the light cannot project the point, or its coordinates or threshold are not finite.
    /// The centre sub-sample is the G-buffer's point itself.
    #[inline]
    pub fn sample(&self, k: usize, s: usize) -> Option<Sample> {
        let g = self.g;
        let (ray, x) = if s == self.pattern.centre_index() {
            (self.ray(k, s), g.position[k])
        } else {
            let (ray, t) = self.tangent_point(k, s)?;
            (ray, ray.at(t))
        };
        let (xy, z) = self.light.project(x)?;
        let zt = threshold_depth(self.light, xy, z, shadow_offset(ray.origin, x));
        (zt.is_finite() && xy.is_finite()).then_some(Sample {
            x: xy.x,
            y: xy.y,
            zt,
            id: s as u32,
            tri: g.triangle[k],
        })
    }

    /// The camera ray through sub-sample `s` of pixel `k`.
    #[inline]
    pub fn ray(&self, k: usize, s: usize) -> Ray {
        let w = self.g.width as usize;
        self.camera.ray(self.pattern.point((k % w) as u32, (k / w) as u32, s))
    }

    /// The camera ray through sub-sample `s` of pixel `k` and the parameter where it meets the
    /// pixel's tangent plane, when that point is in the facet's region.
    #[inline]
    pub fn tangent_point(&self, k: usize, s: usize) -> Option<(Ray, f64)> {
        let g = self.g;
        let (p0, n) = (g.position[k], g.normal[k]);
        let ray = self.ray(k, s);
        let t = ray.intersect_plane(n, n.dot(p0)).filter(|&t| self.in_region(t, g.depth[k]))?;
        Some((ray, t))
    }

    /// The approximate light image points of pixel `k`'s sub-samples; `None` when the camera
    /// sees its tangent plane edge-on at the centre (only the centre is then valid).
    #[inline]
    pub fn approximate(&self, k: usize) -> Option<Approximate> {
        let g = self.g;
        let w = g.width as usize;
        let centre = DVec2::new((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
        let (p0, n) = (g.position[k], g.normal[k]);
        let map = FacetMap::new(&self.basis, centre, n, n.dot(p0))?;
        let [a0, ax, ay] = map.a;
        let hw = match &self.planes.w {
            Some(w) => map.half_plane(w),
            None => HalfPlane { g0: a0, gx: ax, gy: ay },
        };
        Some(Approximate {
            x: map.half_plane(&self.planes.x),
            y: map.half_plane(&self.planes.y),
            w: hw,
        })
    }

    /// Writes pixel `k`'s sub-samples into `out` (`rate` of them; an invalid one gets a
    /// threshold of minus infinity, which no caster passes) and returns the mask of the valid
    /// ones: none for a background pixel or one whose centre is not valid (the centre always
    /// counts when the pixel does).
    pub fn pixel(&self, k: usize, out: &mut [Sample]) -> u128 {
        if !self.g.covered(k) || self.sample(k, self.pattern.centre_index()).is_none() {
            return 0;
        }
        let tri = self.g.triangle[k];
        let mut valid = 0u128;
        for (s, slot) in out.iter_mut().enumerate().take(self.rate()) {
            *slot = match self.sample(k, s) {
                Some(sample) => {
                    valid |= 1 << s;
                    sample
                }
                None => Sample { x: 0.0, y: 0.0, zt: f64::NEG_INFINITY, id: s as u32, tri },
            };
        }
        valid
    }

    /// Whether camera depth `t` lies in the facet's region around the centre's depth `dc`.
    #[inline]
    fn in_region(&self, t: f64, dc: f64) -> bool {
        if self.camera.is_perspective() {
            t > 0.0 && t <= FACET_DEPTH_RATIO * dc
        } else {
            (t - dc).abs() <= self.ortho_span
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::PatternKind;
    use instrumentation::Recorder;

    /// Every valid sub-sample is owned (its approximate light image point lies in the region)
    /// by a texel that lists its pixel, and the approximate point is the placed one to within
    /// rounding.
    #[test]
    fn every_valid_sub_sample_is_owned_by_a_texel_of_its_pixel() {
        for name in ["plane-square", "spheres", "spot-spheres", "grazing"] {
            let Some(Ok(scene)) = scenes::registry::load_builtin(name) else { continue };
            let frame = Frame::new(&scene, 48, 36, &mut Recorder::default());
            let grid = Grid::new(64);
            let light = crate::afsm::light_projector(&frame);
            let pattern = SamplePattern::new(16, PatternKind::Rotated).expect("valid");
            let lists = footprints(&frame, &light, grid).expect("few entries");
            let subs = SubSamples::new(&frame, &light, &pattern);
            let mut out = vec![Sample::default(); 16];
            let mut checked = 0;
            for k in 0..frame.gbuffer.triangle.len() {
                let valid = subs.pixel(k, &mut out);
                let approximate = subs.approximate(k);
                for (s, sample) in out.iter().enumerate() {
                    if valid >> s & 1 == 0 {
                        continue;
                    }
                    let exact = DVec2::new(sample.x, sample.y);
                    let p = match &approximate {
                        Some(a) => a.at(pattern.offsets()[s] - DVec2::splat(0.5)),
                        None => exact,
                    };
                    let scale = 1.0 + exact.abs().max_element();
                    assert!((p - exact).abs().max_element() <= 1e-9 * scale, "{name}: {p} {exact}");
                    let q = grid.texels(p);
                    let (x0, y0, x1, y1) = grid.rect(q, q).expect("finite");
                    let owned = (y0..=y1).any(|y| {
                        (x0..=x1).any(|x| {
                            let t = grid.index(x, y);
                            grid.region_holds(t, p) && lists.of(t).contains(&(k as u32))
                        })
                    });
                    assert!(owned, "{name}: pixel {k} sub-sample {s} at {p} is owned by no texel");
                    checked += 1;
                }
            }
            assert!(checked > 1000, "{name}: {checked}");
        }
    }
}
