//! Stage "antialiasing" of `spsm` on the GPU (`antialias.wgsl`), equal to
//! [`spsm::antialias::antialias_pixels`] pixel for pixel.
//!
//! The silhouettes recovered in stage 5 (centre texel, kept pattern) are resolved on the CPU
//! by the twin's code and uploaded per pixel as a [`Record`]: the occluding triangles
//! (decoded once, with their orientation's sign, which the CPU decides exactly), the tangent
//! normals and the origin, the surface's normal and plane offset, and the light's projection
//! of the point. The GPU evaluates every sub-sample: its camera ray meets the
//! surface's plane, the point is projected into the light's map, and the recovered
//! silhouette function says lit or shadowed. Only pixels whose pattern has tangents are
//! evaluated, as on the CPU.

use crate::{
    frame::Frame,
    gpu::{
        common::{ProjectorData, Xyz, COMMON},
        shader::{compose, Part},
        GpuContext, GpuError,
    },
    pattern::SamplePattern,
    spsm::{
        classify::{Lookup, UncertainPixel},
        recover::{Pattern, Resolved, Silhouette},
    },
};
use bytemuck::{Pod, Zeroable};
use instrumentation::{Counters, Recorder};

/// WGSL of a resolved silhouette's occluders and its function along a tangent.
pub(super) const SILHOUETTE: Part =
    Part::file("spsm/silhouette.wgsl", include_str!("silhouette.wgsl"));
const ANTIALIAS: Part = Part {
    name: "spsm/antialias.wgsl",
    source: include_str!("antialias.wgsl"),
    needs: &[&COMMON, &SILHOUETTE],
};

/// One uncertain pixel's silhouette as the kernel reads it (the WGSL `Record` of
/// `antialias.wgsl`): the origin of its tangent frames, the normal and plane offset of the
/// surface seen at the pixel, the light's projection of the point, the tangents' normals (`x, y`,
/// up to four) and the occluding triangles (per triangle its vertices' `x, y` and its
/// orientation's sign, up to nine). Entries past the pixel's counts are zero.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct Record {
    origin: [f64; 2],
    normal: Xyz,
    offset: f64,
    centre: [f64; 2],
    normals: [f64; 8],
    tris: [f64; 63],
}

/// The kernel's sizes, the WGSL `Dims` of `antialias.wgsl`: the pixels to shade, the image
/// width, the rate.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct Dims {
    pixels: u32,
    width: u32,
    rate: u32,
}

crate::gpu::layout::wgsl_mirror!(
    Record,
    "Record",
    compose(&[&ANTIALIAS]),
    [origin, normal, offset, centre, normals, tris];
    Dims,
    "Dims",
    compose(&[&ANTIALIAS]),
    [pixels, width, rate];
);

/// Antialiases the `uncertain` pixels with their recovered `silhouettes` (same order),
/// writing their lit fraction into `lit`; the GPU pass is recorded as the stage `stage`.
#[allow(clippy::too_many_arguments)]
pub fn antialias_pixels(
    ctx: &GpuContext,
    frame: &Frame<'_>,
    lookup: &Lookup<'_>,
    pattern: &SamplePattern,
    uncertain: &[UncertainPixel],
    silhouettes: &[Option<Silhouette>],
    lit: &mut [f32],
    stage: &str,
    rec: &mut Recorder,
) -> Result<Counters, GpuError> {
    let g = &frame.gbuffer;
    let rate = pattern.offsets().len();
    // The CPU's part of the stage (the records) is timed into it beside the GPU pass.
    let start = std::time::Instant::now();
    let mut records: Vec<Record> = Vec::new();
    let mut rec_u: Vec<u32> = Vec::new();
    for (u, s) in uncertain.iter().zip(silhouettes) {
        let Some(s) = s else { continue };
        let Pattern::Tangents { count, normals } = s.pattern() else { continue };
        let k = u.pixel as usize;
        let (position, normal) = (g.position[k], g.normal[k]);
        let Some((centre, _)) = lookup.tester.projector.project(position) else { continue };
        let resolved = Resolved::new(lookup.map, s);
        let (tris, _, origin) = resolved.parts();
        let mut r = Record::zeroed();
        r.origin = origin.to_array();
        r.normal = normal.into();
        r.offset = normal.dot(position);
        r.centre = centre.to_array();
        for (slot, n) in r.normals.chunks_exact_mut(2).zip(&normals) {
            slot.copy_from_slice(&n.to_array());
        }
        for (slot, t) in r.tris.chunks_exact_mut(7).zip(tris) {
            for (k, v) in t.v.iter().enumerate() {
                slot[2 * k..2 * k + 2].copy_from_slice(&v.to_array());
            }
            slot[6] = t.orientation().signum();
        }
        records.push(r);
        rec_u.extend_from_slice(&[u.pixel, u32::from(count), tris.len() as u32]);
    }
    let n = rec_u.len() / 3;
    let cpu_ms = start.elapsed().as_secs_f64() * 1e3;
    let offsets: Vec<f64> = pattern.offsets().iter().flat_map(|o| [o.x, o.y]).collect();
    let pipeline = ctx.pipeline("spsm antialiasing", &compose(&[&ANTIALIAS]), "main");
    let out = ctx.zeroed::<f32>("spsm antialiased", n);
    let bind = ctx.bind(
        &pipeline,
        &[
            &ctx.upload(
                "spsm aa dims",
                &[Dims { pixels: n as u32, width: frame.width(), rate: rate as u32 }],
            ),
            &ctx.upload("spsm aa camera", &[ProjectorData::new(&frame.camera)]),
            &ctx.upload("spsm aa light", &[ProjectorData::new(&lookup.tester.projector)]),
            &ctx.upload("spsm aa offsets", &offsets),
            &ctx.upload("spsm aa records", &records),
            &ctx.upload("spsm aa pixels", &rec_u),
            &out,
        ],
    );
    ctx.stage(rec, stage, |e| {
        GpuContext::dispatch(e, &pipeline, &bind, GpuContext::groups_1d(n, 64));
    })?;
    rec.stages.add(stage, cpu_ms);
    let values: Vec<f32> = ctx.read(&out)?;
    for (p, v) in rec_u.chunks_exact(3).zip(values) {
        lit[p[0] as usize] = v;
    }
    Ok(Counters { antialiased_samples: (n * rate) as u64, ..Counters::default() })
}
