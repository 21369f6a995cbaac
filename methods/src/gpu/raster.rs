//! The rasterizer of the GPU path: the camera G-buffer and the light depth map as hardware
//! render passes, resolved in `f64` so that what the kernels read is what the CPU rasterizer
//! ([`crate::raster`]) would give for the same triangle.
//!
//! Stages, all on the GPU: `setup` (a compute kernel: each triangle's unit normal, plane offset
//! and the depth range of its near-clipped corners, as the CPU's setup computes them), `project`
//! (each corner to clip coordinates in `f64`, rounded to `f32` for the hardware), the render
//! pass (every triangle drawn into an `R32Uint` id image with a `Depth32Float` depth test, ties
//! to the first drawn, the lower id, as on the CPU), and `resolve` (per sample, the depth where
//! the sample's ray meets the kept triangle's plane, clamped to its corners' range: the CPU's
//! formula, in `f64`; for the G-buffer also the position on the ray and the face normal).
//!
//! Invariant (tested): where the hardware keeps the same triangle as the CPU's exact
//! rasterizer, depth, position and normal are bit-identical to the CPU's. Where it keeps
//! another, the cause is coverage (the hardware snaps corners to its sub-pixel grid and decides
//! edges in fixed point, the CPU decides them exactly in `f64`) or a nearest-surface decision
//! within `f32` depth precision; `tests/gpu/raster.rs` measures how many samples that touches.

use super::{
    common::{ProjectorData, COMMON},
    shader::{compose, Part},
    GpuContext, GpuError,
};
use crate::frame::Frame;
use bytemuck::{Pod, Zeroable};
use glam::DVec2;
use instrumentation::Recorder;
use scenes::Projector;

/// The kernels of `raster.wgsl`.
const RASTER: Part =
    Part { name: "raster.wgsl", source: include_str!("raster.wgsl"), needs: &[&COMMON] };
/// The render pass of `raster_draw.wgsl`.
const DRAW_WGSL: &str = include_str!("raster_draw.wgsl");

/// Uniforms of `raster.wgsl`: its WGSL `Params`, field for field ([`super::layout`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(super) struct Params {
    width: u32,
    height: u32,
    triangles: u32,
    casters_only: u32,
    row_words: u32,
    gbuffer: u32,
    pad0: u32,
    pad1: u32,
    shift_x: f64,
    shift_y: f64,
    znear: f64,
    zfar: f64,
}

super::layout::wgsl_mirror!(
    Params,
    "Params",
    compose(&[&RASTER]),
    [
        width,
        height,
        triangles,
        casters_only,
        row_words,
        gbuffer,
        pad0,
        pad1,
        shift_x,
        shift_y,
        znear,
        zfar
    ]
);

/// What one rasterization gives: the kept triangle and the `f64` depth per sample, and for a
/// G-buffer the position and normal.
#[derive(Debug)]
pub struct Rasterized {
    /// Triangle id per sample (`NO_TRIANGLE` where none).
    pub triangle: wgpu::Buffer,
    /// Depth per sample, `f64` (infinity where none).
    pub depth: wgpu::Buffer,
    /// Position per sample, 3 `f64` (zero where none); G-buffer only.
    pub position: wgpu::Buffer,
    /// Unit face normal per sample, 3 `f64` (zero where none); G-buffer only.
    pub normal: wgpu::Buffer,
}

/// What to rasterize and how.
#[derive(Debug, Clone, Copy)]
pub struct RasterJob<'a> {
    /// Through this projector (its width and height are the image's).
    pub projector: &'a Projector,
    /// Only the frame's shadow casters (a light depth map) or every triangle (a G-buffer).
    pub casters_only: bool,
    /// Samples at `i + 0.5 + shift`.
    pub shift: DVec2,
    /// Also resolve position and normal.
    pub gbuffer: bool,
}

/// Rasterizes the frame's triangles (already in `corners` and `casters`, see
/// [`super::GpuFrame`]) as one stage named `stage`.
pub fn rasterize(
    ctx: &GpuContext,
    frame: &Frame<'_>,
    corners: &wgpu::Buffer,
    casters: &wgpu::Buffer,
    job: RasterJob<'_>,
    stage: &str,
    rec: &mut Recorder,
) -> Result<Rasterized, GpuError> {
    let p = job.projector;
    let (width, height) = (p.width as u32, p.height as u32);
    let triangles = frame.geometry.triangles.len() as u32;
    let max_dim = ctx.device.limits().max_texture_dimension_2d;
    if width > max_dim || height > max_dim {
        return Err(GpuError::Limit(format!(
            "{width}x{height} exceeds the adapter's largest image, {max_dim}"
        )));
    }
    let (lo, hi) = frame.light_depth_bounds(p);
    let (znear, zfar) = if p.is_perspective() {
        (p.near, 2.0 * hi.max(p.near) + 1.0)
    } else {
        let margin = 0.01 * (hi - lo) + 1e-9 * hi.abs().max(lo.abs()).max(1.0);
        (lo - margin, hi + margin)
    };
    let row_words = (width * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) / 4;
    let params = Params {
        width,
        height,
        triangles,
        casters_only: u32::from(job.casters_only),
        row_words,
        gbuffer: u32::from(job.gbuffer),
        pad0: 0,
        pad1: 0,
        shift_x: job.shift.x,
        shift_y: job.shift.y,
        znear,
        zfar,
    };
    let samples = width as usize * height as usize;
    let g = |n: usize| if job.gbuffer { n } else { 1 };
    let uniform = ctx.uniform("raster params", &params);
    let proj = ctx.upload("raster projector", &[ProjectorData::new(p)]);
    let planes = ctx.zeroed::<f64>("planes", 6 * triangles as usize);
    let clip = ctx.zeroed::<[f32; 4]>("clip", 3 * triangles as usize);
    let ids = ctx.zeroed::<u32>("ids", row_words as usize * height as usize);
    let out = Rasterized {
        triangle: ctx.zeroed::<u32>("triangle", samples),
        depth: ctx.upload("depth", &vec![f64::INFINITY; samples]),
        position: ctx.zeroed::<f64>("position", g(3 * samples)),
        normal: ctx.zeroed::<f64>("normal", g(3 * samples)),
    };
    let source = compose(&[&RASTER]);
    let kernels = ["setup", "project", "resolve"].map(|e| ctx.pipeline(e, &source, e));
    // Each entry point binds only what it uses; auto layouts drop the rest.
    let bind = |k: &wgpu::ComputePipeline, used: &[(u32, &wgpu::Buffer)]| {
        let entries: Vec<wgpu::BindGroupEntry<'_>> = used
            .iter()
            .map(|(i, b)| wgpu::BindGroupEntry { binding: *i, resource: b.as_entire_binding() })
            .collect();
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &k.get_bind_group_layout(0),
            entries: &entries,
        })
    };
    let setup_bind = bind(&kernels[0], &[(0, &uniform), (1, &proj), (2, corners), (4, &planes)]);
    let project_bind =
        bind(&kernels[1], &[(0, &uniform), (1, &proj), (2, corners), (3, casters), (5, &clip)]);
    let resolve_bind = bind(
        &kernels[2],
        &[
            (0, &uniform),
            (1, &proj),
            (4, &planes),
            (6, &ids),
            (7, &out.triangle),
            (8, &out.depth),
            (9, &out.position),
            (10, &out.normal),
        ],
    );

    let draw = ctx.device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("raster draw"),
        source: wgpu::ShaderSource::Wgsl(DRAW_WGSL.into()),
    });
    let pipeline = ctx.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("raster draw"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &draw,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &draw,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: wgpu::TextureFormat::R32Uint,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    });
    let draw_bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry { binding: 0, resource: clip.as_entire_binding() }],
    });
    let size = wgpu::Extent3d { width, height, depth_or_array_layers: 1 };
    let texture = |label, format, usage| {
        ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let id_image = texture(
        "id image",
        wgpu::TextureFormat::R32Uint,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let depth_image = texture(
        "depth image",
        wgpu::TextureFormat::Depth32Float,
        wgpu::TextureUsages::RENDER_ATTACHMENT,
    );
    let id_view = id_image.create_view(&Default::default());
    let depth_view = depth_image.create_view(&Default::default());

    ctx.stage(rec, stage, |encoder| {
        GpuContext::dispatch(
            encoder,
            &kernels[0],
            &setup_bind,
            GpuContext::groups_1d(triangles as usize, 64),
        );
        GpuContext::dispatch(
            encoder,
            &kernels[1],
            &project_bind,
            GpuContext::groups_1d(3 * triangles as usize, 64),
        );
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("raster draw"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &id_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: f64::from(crate::raster::NO_TRIANGLE),
                            g: 0.0,
                            b: 0.0,
                            a: 0.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &draw_bind, &[]);
            pass.draw(0..3 * triangles, 0..1);
        }
        encoder.copy_texture_to_buffer(
            id_image.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &ids,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row_words * 4),
                    rows_per_image: Some(height),
                },
            },
            size,
        );
        GpuContext::dispatch(
            encoder,
            &kernels[2],
            &resolve_bind,
            GpuContext::groups_1d(samples, 64),
        );
    })?;
    Ok(out)
}
