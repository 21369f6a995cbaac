//! `exact`: the exact ground truth on every visible surface.
//!
//! A pixel's value is the lit fraction of the visible surface area in its square. Every
//! visible triangle is a planar receiver; what `exact` can vouch for is decided first, pixel by
//! pixel, from the camera's view of the triangles ([`classes`]: `planar`, `surface`, `edge`,
//! `uncovered`). `planar` and `surface` pixels, whose squares are tiled by known triangles of
//! one surface and see nothing else, are evaluated exactly; `edge` pixels (silhouettes, depth
//! discontinuities, several objects, background) are left to `raytrace` at the rate the
//! caller gives ([`ExactCoverage::edge`]), so that the camera's geometric aliasing stays out of
//! the shadow error; `uncovered` pixels see nothing and are lit.
//!
//! 1. **Pixel classes** ([`classes`]), with the triangles that tile each evaluated square.
//! 2. **Planar objects** (a mesh with one plane, `Mesh::plane`), for their `planar` pixels:
//!    every caster triangle of another object (of a closed object on the light's side of the
//!    plane, only those facing the light, whose shadows' union is the same: [`closed`]) is
//!    clipped to the part strictly between the light and the plane and projected along
//!    light rays onto the plane (directional:
//!    parallel; spot: central from the light), then through the camera onto the screen and
//!    clipped to the frame ([`shadow`](self)): both maps are composed in homogeneous
//!    coordinates, so every clip is a linear inequality on the triangle and happens before any
//!    division. The area the shadow polygons' union covers in each of the object's pixels is
//!    computed without building the union ([`coverage`]): a pixel wholly inside one polygon is
//!    covered; in the others, the uncovered part of the pixel square is kept as disjoint
//!    convex pieces from which each polygon reaching the pixel is cut away, exactly in `f64`,
//!    in parallel over bands of rows. `lit = 1 - shadowed`, clamped to `[0, 1]`. Stages
//!    `shadow polygons`, `pixel unions`.
//! 3. **Surface triangles**, for `surface` pixels ([`surface`]): every triangle tiling a
//!    `surface` pixel is a receiver of its own: the casters a light-space grid returns for it
//!    ([`casters`]; any triangle, its own mesh included: self-shadowing) are projected onto
//!    its plane by the same machinery, and the area their union covers within the receiver's
//!    screen polygon is computed in each pixel it tiles, by the same cuts; each pixel adds the
//!    areas of the triangles that tile it. A triangle facing away from the light on a closed
//!    object that its object's shadow provably covers asks for no caster ([`closed`]).
//!    Stages `caster grid`, `surface shadows`.
//! 4. **Edge pixels**: `raytrace` on the `edge` pixels only, when [`ExactCoverage::edge`] is
//!    set ([`edges`]). When their sub-samples are few beside the triangles, each ray is tested
//!    against the triangles overlapping its pixel, where every camera ray's hit lies, and the
//!    casters the light-space grid returns for its shadow ray's start, without BVHs (stage
//!    `ray tracing`; on `bunny-plane` at 800 x 600, 2,873 edge pixels: 19-28 ms of BVH build
//!    and tracing became 3.1-3.7). Otherwise, when the (pixel, triangle) overlaps are far fewer than
//!    the triangles (on `bumpy` at 64 sub-samples), the BVHs hold only the triangles those
//!    rays can meet (stage `edge casters`; `bumpy`'s BVH build went from 420 to 9 ms), else
//!    every triangle (stages `BVH build`, `ray tracing`). The lit fractions are those of a
//!    trace among all triangles, bit for bit (tested).
//! 5. **Image assembly**: every pixel's lit fraction from its class's result (stage `image
//!    assembly`).
//!
//! Every pass over the frame's pixels or triangles lies in a stage, so that the stages add up
//! to the reference's time: finding the planar objects in `shadow polygons`, the receivers in
//! `caster grid` (what is left outside, the checks that pick the stages and the memory freed
//! at the end, was 2-4 ms at 800 x 600; the receivers' list alone, made outside every stage,
//! had cost 30 ms on `bumpy` unseen).
//!
//! A stage with nothing to do (no `planar` pixels, no `surface` pixels, no `edge` pixels or no
//! edge reference) is not run and is listed as skipped.
//!
//! # Precision
//!
//! The only approximations are the `f64` rounding of the projections and clips, the
//! pieces of an uncovered part below `1e-24` px² that the cuts drop ([`coverage`]), and the
//! casters the light-space grid rules out for a receiver lying on their lit side within the
//! rounding of their plane ([`casters`]: shared corners lie in it exactly; a corner a
//! rounding beyond it could be shadowed over a sliver of that width at most). Every cut
//! is computed relative to its pixel's corner, on coordinates in `[0, 1]`; no union is snapped
//! to a grid, and no topology is built that rounding could make inconsistent.
//!
//! Measured on planar receivers (`analysis/tests/references/exact.rs`, against an independent
//! union of the same shadow polygons by vertical slabs, cut at every vertex and crossing): the
//! worst per-pixel difference is below `1e-14` at 64 x 48 on six built-in scenes and
//! `4.9e-14` on `cage` at 800 x 600, far below the `1e-9` the ground truth must meet. Against
//! analytic areas (rotated squares, spot lights, a grazing perspective view) the agreement is
//! `1e-13` or better. A `surface` pixel adds one such area per tiling triangle.
//!
//! # Choices where the issue is vague
//!
//! - `exact` applies to every scene with opaque casters; it does not apply
//!   (`ReferenceError::NotApplicable`) when the scene has transparency.
//! - A receiver whose plane holds the light (a directional light parallel to it, a spot light
//!   in it) gets light only at grazing incidence and has no projection: its pixels are not
//!   evaluated, and a note says how many.
//! - Caster parts: directional lights keep the part with height `h >= 0` above the plane on
//!   the light's side (triangles with every corner at `h <= 0`, e.g. lying in the plane, are
//!   dropped); spot lights also keep `h <= H`, the light's height (parts beyond the plane
//!   through the light, parallel to the receiver, cast no shadow on it). A point at height
//!   `H` projects to infinity on the plane; in homogeneous coordinates it is the receiver's
//!   horizon, which the camera maps to a finite screen point (perspective) or which the frame
//!   clip removes (orthographic), so no coordinate is ever infinite: no epsilon is needed near
//!   the light plane. The spot's cone is ignored: visibility only asks whether the segment to
//!   the light is blocked (surfaces outside the cone count as lit, as for the shadow maps).
//! - Shadow points must lie at camera depth `>= near` (perspective); orthographic cameras see
//!   every depth.
//! - Degenerate shadow polygons (fewer than three vertices, zero area, a vertex at or behind
//!   the eye) are ignored; they have no area.
//! - A receiver is not asked which side the light is on: a surface facing away from the light
//!   is dark because the rest of its (closed) mesh shadows it, not by a shading rule; an open
//!   sheet lit from behind is lit.
//! - A planar object's shadow polygons are those of every caster over the whole frame, as for
//!   one receiver plane; only its own `planar` pixels are evaluated.
//! - `uncovered` pixels are lit (1) and not evaluated; `edge` pixels without an edge reference
//!   are lit (1) and not evaluated.
//! - A lit fraction within [`SNAP`] (`1e-9`) of 0 or 1 is 0 or 1: the rounding of the cuts
//!   must not make a fully lit or shadowed pixel a shadow-boundary pixel.

mod casters;
pub mod classes;
mod clip;
mod closed;
mod coverage;
mod edges;
mod shadow;
mod surface;

use crate::pixel_class::{self, PixelClass};
use crate::raytrace::RayTrace;
use crate::reference::{Reference, ReferenceError, ReferenceImage};
use instrumentation::Recorder;
use methods::Frame;
use rayon::prelude::*;
use shadow::Setup;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

pub use classes::classify;

/// Polygons in screen space (pixels from the top-left, y down), stored flat: contour `k` is
/// `points[ranges[k].clone()]`, closed implicitly (the last point connects to the first).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ScreenPolygons {
    /// All vertices, contour after contour.
    pub points: Vec<[f64; 2]>,
    /// The vertex range of each contour.
    pub ranges: Vec<Range<usize>>,
}

impl ScreenPolygons {
    /// Appends a contour.
    pub fn push(&mut self, contour: &[[f64; 2]]) {
        let start = self.points.len();
        self.points.extend_from_slice(contour);
        self.ranges.push(start..self.points.len());
    }

    /// Number of contours.
    pub fn len(&self) -> usize {
        self.ranges.len()
    }

    /// Whether there is no contour.
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// Contour `k`'s vertices.
    pub fn contour(&self, k: usize) -> &[[f64; 2]] {
        &self.points[self.ranges[k].clone()]
    }

    /// The contours, each as a slice of vertices.
    pub fn contours(&self) -> impl Iterator<Item = &[[f64; 2]]> + '_ {
        self.ranges.iter().map(|r| &self.points[r.clone()])
    }

    /// The contours of `parts`, part after part: each part is copied into its own range of
    /// the whole in parallel (joined one contour at a time, `bumpy`'s 530,688 screen
    /// triangles cost as much as projecting them).
    pub(crate) fn concat<'a>(parts: impl IntoIterator<Item = &'a ScreenPolygons>) -> Self {
        let parts: Vec<&ScreenPolygons> = parts.into_iter().collect();
        let contours: usize = parts.iter().map(|p| p.len()).sum();
        let points: usize = parts.iter().map(|p| p.points.len()).sum();
        let ranges = (0..contours).into_par_iter().map(|_| 0..0).collect();
        let mut all = Self { points: methods::parallel::filled(points, [0.0; 2]), ranges };
        // Each part's first point in the whole.
        let firsts: Vec<usize> = parts
            .iter()
            .scan(0, |first, p| Some(std::mem::replace(first, *first + p.points.len())))
            .collect();
        let pts = methods::parallel::cut(&mut all.points, parts.iter().map(|p| p.points.len()));
        let ranges = methods::parallel::cut(&mut all.ranges, parts.iter().map(|p| p.len()));
        let places = parts.into_par_iter().zip(firsts).zip(pts).zip(ranges);
        places.for_each(|(((p, first), pts), ranges)| {
            pts.copy_from_slice(&p.points);
            for (r, s) in ranges.iter_mut().zip(&p.ranges) {
                *r = first + s.start..first + s.end;
            }
        });
        all
    }
}

/// The exact reference (name `exact`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExactCoverage {
    /// The reference of `edge` pixels (`raytrace` at some rate); `None` leaves them
    /// unevaluated.
    pub edge: Option<RayTrace>,
}

impl Reference for ExactCoverage {
    fn name(&self) -> &'static str {
        "exact"
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = serde_json::Map::new();
        match &self.edge {
            Some(rt) => {
                m.insert("edge_reference".into(), "raytrace".into());
                m.insert("edge_rate".into(), rt.pattern.rate().into());
                m.insert("edge_pattern".into(), rt.pattern.kind().name().into());
            }
            None => {
                m.insert("edge_reference".into(), "none".into());
            }
        }
        m
    }

    fn evaluate(
        &self,
        frame: &Frame<'_>,
        rec: &mut Recorder,
    ) -> Result<ReferenceImage, ReferenceError> {
        evaluate(frame, self.edge.as_ref(), rec)
    }
}

/// The screen-space shadow polygons on the scene's main planar receiver
/// (`Scene::receiver_plane`): each the shadow of one caster triangle of another object,
/// convex, clipped to the frame, with positive shoelace area in screen coordinates
/// (`sum x_k y_(k+1) - x_(k+1) y_k > 0`). Their union is the receiver's shadow.
pub fn shadow_polygons(frame: &Frame<'_>) -> Result<ScreenPolygons, ReferenceError> {
    let (receiver, setup) = Setup::main_receiver(frame)?;
    let mut closed = closed::ClosedCasters::new(frame);
    Ok(closed::shadow_polygons(frame, &setup, receiver, &mut closed).0)
}

/// Distance from 0 or 1 within which a lit fraction is taken as exactly 0 or 1.
///
/// A pixel's shadowed area is a sum of covered areas (one per tiling triangle on `surface`
/// pixels), each exact up to the rounding of its cuts (see the module documentation), so a
/// fully lit or fully shadowed pixel can come out within about `1e-13` of 1 or 0 rather than
/// on it (on `bumpy` at 800 x 600, 13 000 pixels did when the areas came from unions). Metrics count a pixel whose reference is
/// strictly between 0 and 1 as a shadow-boundary pixel; without the snap those pixels would
/// dilute every boundary statistic. `1e-9` is the precision the ground truth states.
pub const SNAP: f64 = 1e-9;

/// `lit` clamped to `[0, 1]`, and 0 or 1 when within [`SNAP`] of it.
fn snap(lit: f64) -> f64 {
    if lit <= SNAP {
        0.0
    } else if lit >= 1.0 - SNAP {
        1.0
    } else {
        lit
    }
}

fn evaluate(
    frame: &Frame<'_>,
    edge: Option<&RayTrace>,
    rec: &mut Recorder,
) -> Result<ReferenceImage, ReferenceError> {
    Setup::check(frame)?;
    let (width, height) = (frame.width(), frame.height());
    let (w, h) = (width as usize, height as usize);
    let classes = rec.stages.time("pixel classes", || classify(frame));
    rec.counters.pixel_triangle_overlaps += classes.overlaps;
    let class = &classes.class;
    let mut shadowed = methods::parallel::filled(w * h, 0.0f64);
    let mut evaluated = methods::parallel::filled(w * h, false);
    let mut grazing_pixels = 0u64;
    // Which objects are closed casters, each decided in the first stage that asks.
    let mut closed = closed::ClosedCasters::new(frame);

    // Planar objects: the object each `planar` pixel sees (that of its tiles), found once,
    // their planes and their shadow polygons.
    let planar_stages = ["shadow polygons", "pixel unions"];
    let planar = class.contains(&PixelClass::Planar).then(|| {
        rec.stages.time(planar_stages[0], || {
            let planar_object: Vec<Option<u32>> = (0..w * h)
                .into_par_iter()
                .map(|k| {
                    let first = classes.tiles_of(k).first();
                    first
                        .filter(|_| class[k] == PixelClass::Planar)
                        .map(|&t| frame.geometry.object[t as usize])
                })
                .collect();
            // Marked in parallel, then listed: sorting every planar pixel's object cost 5 ms
            // on bunny-plane. A mark is only ever set, and read first, so that the threads
            // share its cache line rather than take it from each other at every pixel.
            let marks: Vec<AtomicBool> =
                frame.scene.objects.iter().map(|_| AtomicBool::new(false)).collect();
            planar_object.par_iter().flatten().for_each(|&o| {
                let mark = &marks[o as usize];
                if !mark.load(Ordering::Relaxed) {
                    mark.store(true, Ordering::Relaxed);
                }
            });
            let seen: Vec<bool> = marks.into_iter().map(AtomicBool::into_inner).collect();
            let (mut planes, mut grazing) = (Vec::new(), 0u64);
            for o in (0..seen.len() as u32).filter(|&o| seen[o as usize]) {
                let setup = frame.scene.objects[o as usize]
                    .mesh
                    .plane()
                    .and_then(|(n, d)| Setup::for_plane(frame, n, d));
                match setup {
                    Some(s) => planes.push((o, s)),
                    None => {
                        grazing += planar_object.iter().filter(|&&p| p == Some(o)).count() as u64;
                    }
                }
            }
            let polys: Vec<(ScreenPolygons, bool)> = planes
                .iter()
                .map(|(o, s)| closed::shadow_polygons(frame, s, *o as usize, &mut closed))
                .collect();
            (planar_object, planes, polys, grazing)
        })
    });
    if planar.is_none() {
        rec.stages.skip(planar_stages[0]);
    }
    let (planar_object, planes, polys, grazing) = planar.unwrap_or_default();
    grazing_pixels += grazing;
    if planes.is_empty() {
        rec.stages.skip(planar_stages[1]);
    } else {
        rec.counters.shadow_polygons += polys.iter().map(|(p, _)| p.len() as u64).sum::<u64>();
        let works: Vec<coverage::Work> = rec.stages.time(planar_stages[1], || {
            planes
                .iter()
                .zip(&polys)
                .map(|((o, _), (p, seams))| {
                    let mine = |k: usize| planar_object[k] == Some(*o);
                    let (area, work) = coverage::union_area(p, w, h, mine, *seams);
                    shadowed.par_iter_mut().zip(&mut evaluated).zip(&area).enumerate().for_each(
                        |(k, ((s, e), &a))| {
                            if mine(k) {
                                (*s, *e) = (a, true);
                            }
                        },
                    );
                    work
                })
                .collect()
        });
        for (((o, _), (p, _)), work) in planes.iter().zip(&polys).zip(&works) {
            rec.counters.covered_pixels += work.covered_pixels;
            rec.counters.pixel_polygon_pairs += work.pixel_polygon_pairs;
            let name = &frame.scene.objects[*o as usize].name;
            rec.notes.push(format!(
                "exact: on `{name}`, {} shadow polygons; {} pixels inside one or inside their \
                 union off its outline, {} pixel-polygon overlaps cut",
                p.len(),
                work.covered_pixels,
                work.pixel_polygon_pairs
            ));
        }
    }

    // Surface triangles.
    let edges: Vec<bool> = class.par_iter().map(|&c| c == PixelClass::Edge).collect();
    let edge_pixels = edges.par_iter().filter(|&&e| e).count();
    // How the edge pixels' rays find the triangles they can meet (see `edges`).
    let edge_trace = edge.filter(|_| edge_pixels > 0).map(|rt| {
        let how = edges::EdgeTrace::choose(
            edge_pixels,
            rt.pattern.rate() as usize,
            classes.edge_overlaps.len(),
            frame.geometry.len(),
        );
        (rt, how)
    });
    let edge_lists = matches!(edge_trace, Some((_, how)) if how != edges::EdgeTrace::All);
    // The grid serves the surface receivers (the triangles tiling the `surface` pixels) and
    // the triangles the edge pixels' rays can meet. Both lists are marked, then listed in
    // ascending order (sorting the pixels' tiles with their repeats cost 30 ms on bumpy).
    let built = (class.contains(&PixelClass::Surface) || edge_lists).then(|| {
        rec.stages.time("caster grid", || {
            // Marked by the pixels in parallel: a mark is only ever set, so the order of the
            // stores does not matter (4 ms serial on bumpy).
            let marked: Vec<AtomicBool> =
                (0..frame.geometry.len()).into_par_iter().map(|_| AtomicBool::new(false)).collect();
            let mark = |t: u32| marked[t as usize].store(true, Ordering::Relaxed);
            (0..w * h)
                .into_par_iter()
                .filter(|&k| class[k] == PixelClass::Surface)
                .for_each(|k| classes.tiles_of(k).iter().for_each(|&t| mark(t)));
            let listed = |marked: &[AtomicBool]| -> Vec<u32> {
                let n = marked.len() as u32;
                (0..n)
                    .into_par_iter()
                    .filter(|&t| marked[t as usize].load(Ordering::Relaxed))
                    .collect()
            };
            let receivers = listed(&marked);
            // The grid's region covers the receivers, and the edge pixels' triangles when the
            // BVHs are built among the casters of their parts, or when there is no receiver.
            // The listed tracer's queries are points, which the grid answers outside its
            // region too: a ground plane's two triangles would stretch the region over the
            // frame and coarsen every receiver's cells.
            let among = matches!(edge_trace, Some((_, edges::EdgeTrace::Among)));
            let all = if among || (edge_lists && receivers.is_empty()) {
                classes.edge_overlaps.iter().for_each(|&(_, t)| mark(t));
                listed(&marked)
            } else {
                receivers.clone()
            };
            (receivers, casters::CasterGrid::new(frame, &all))
        })
    });
    let (receivers, grid) = match built {
        Some((receivers, grid)) => (receivers, Some(grid)),
        None => (Vec::new(), None),
    };
    if grid.is_none() {
        rec.stages.skip("caster grid");
    }
    if receivers.is_empty() {
        rec.stages.skip("surface shadows");
    } else if let Some(grid) = &grid {
        let wanted =
            |r: u32, k: usize| class[k] == PixelClass::Surface && classes.tiles_of(k).contains(&r);
        let s = rec.stages.time("surface shadows", || {
            let polygon = |r: u32| classes.screen_polygon(r);
            let s = surface::shadows(frame, grid, &mut closed, &receivers, polygon, wanted);
            for &(k, a) in &s.areas {
                shadowed[k as usize] += a;
            }
            grazing_pixels += shadowed
                .par_iter_mut()
                .zip(&mut evaluated)
                .enumerate()
                .filter(|(k, _)| class[*k] == PixelClass::Surface)
                .map(|(k, (shadowed, evaluated))| {
                    if classes.tiles_of(k).iter().any(|t| s.grazing.binary_search(t).is_ok()) {
                        *shadowed = 0.0;
                        1
                    } else {
                        *evaluated = true;
                        0
                    }
                })
                .sum::<u64>();
            s
        });
        rec.counters.receiver_triangles += receivers.len() as u64;
        rec.counters.caster_pairs += s.pairs;
        rec.counters.shadow_polygons += s.polygons;
        rec.counters.covered_pixels += s.work.covered_pixels;
        rec.counters.pixel_polygon_pairs += s.work.pixel_polygon_pairs;
        rec.notes.push(format!(
            "exact: {} receiver triangles, {} of them behind their own closed object; {} \
             receiver-caster pairs, {} shadow polygons; {} pixel parts inside one, {} \
             pixel-polygon overlaps cut",
            receivers.len(),
            s.behind,
            s.pairs,
            s.polygons,
            s.work.covered_pixels,
            s.work.pixel_polygon_pairs
        ));
    }
    if grazing_pixels > 0 {
        rec.notes.push(format!(
            "exact: {grazing_pixels} pixels see a surface whose plane holds the light (grazing \
             incidence); not evaluated"
        ));
    }
    // Edge pixels, traced among the triangles they overlap and the casters that can shadow
    // those.
    let traced = match (edge_trace, &grid) {
        (Some((rt, edges::EdgeTrace::Listed)), Some(grid)) => {
            rec.stages.skip("edge casters");
            rec.notes.push(format!(
                "exact: {edge_pixels} edge pixels traced against the triangles each overlaps \
                 and the casters the grid lists for each, without BVHs"
            ));
            let lists = edges::EdgeLists::new(frame, grid, &classes.edge_overlaps);
            Some(rt.evaluate_pixels_listed(frame, &edges, &lists, rec)?)
        }
        (Some((rt, how)), grid) => {
            let among = match grid {
                Some(grid) if how == edges::EdgeTrace::Among => {
                    let among = rec.stages.time("edge casters", || {
                        edges::edge_casters(frame, grid, &classes.edge_overlaps)
                    });
                    rec.notes.push(format!(
                        "exact: edge pixels traced among {} of {} triangles",
                        among.iter().filter(|&&a| a).count(),
                        among.len()
                    ));
                    Some(among)
                }
                _ => {
                    rec.stages.skip("edge casters");
                    None
                }
            };
            Some(rt.evaluate_pixels_among(frame, Some(&edges), among.as_deref(), rec)?)
        }
        (None, _) => {
            rec.stages.skip("edge pixels (raytrace)");
            None
        }
    };
    // Every pixel's lit fraction, from its class's result.
    let lit = rec.stages.time("image assembly", || {
        if let Some(img) = &traced {
            evaluated.par_iter_mut().zip(&edges).zip(&img.evaluated).for_each(
                |((e, &edge), &t)| {
                    if edge {
                        *e = t;
                    }
                },
            );
        }
        (0..w * h)
            .into_par_iter()
            .map(|k| match &traced {
                Some(img) if edges[k] => img.lit[k],
                _ if !evaluated[k] => 1.0,
                _ if shadowed[k].is_nan() => 0.0,
                _ => snap(1.0 - shadowed[k]),
            })
            .collect::<Vec<f64>>()
    });
    let n = pixel_class::counts(class);
    rec.notes.push(format!(
        "exact: pixel classes: {} planar, {} surface, {} edge, {} uncovered",
        n[1], n[2], n[3], n[0]
    ));
    Ok(ReferenceImage {
        width,
        height,
        lit,
        evaluated,
        transmittance: None,
        classes: Some(classes.class),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On the scene's main planar receiver, `exact` takes the values of the covered areas of
    /// every caster's shadow on the receiver's plane over the whole frame, as when it covered
    /// that receiver only: any later change to how pixels are split among receivers must keep
    /// them within 1e-12.
    #[test]
    fn planar_pixels_keep_the_values_of_the_whole_plane() {
        for name in ["plane-square", "cage", "random-1k", "spot-spheres"] {
            let scene = scenes::load(name).expect("built-in");
            let frame = Frame::new(&scene, 200, 150, &mut Recorder::default());
            let (receiver, setup) = Setup::main_receiver(&frame).expect("planar receiver");
            let mut closed = closed::ClosedCasters::new(&frame);
            let (polys, _) = closed::shadow_polygons(&frame, &setup, receiver, &mut closed);
            let (whole, _) = coverage::union_area(&polys, 200, 150, |_| true, false);
            let img = evaluate(&frame, None, &mut Recorder::default()).expect("applies");
            let classes = img.classes.as_deref().expect("classes");
            let mut compared = 0;
            for k in 0..whole.len() {
                let t = frame.gbuffer.triangle[k];
                let on_receiver = img.evaluated[k]
                    && classes[k] == PixelClass::Planar
                    && frame.geometry.object[t as usize] as usize == receiver;
                if on_receiver {
                    let old = (1.0 - whole[k]).clamp(0.0, 1.0);
                    assert!((img.lit[k] - snap(old)).abs() <= 1e-12, "{name}: pixel {k}");
                    compared += 1;
                }
            }
            assert!(compared > 10_000, "{name}: {compared}");
        }
    }
}
