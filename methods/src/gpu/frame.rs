//! What the kernels read: the frame's triangles, its camera G-buffer and the light depth map,
//! in storage buffers (`f64` where the CPU holds `f64`).
//!
//! Layouts (WGSL side in `common.wgsl`): a projector is one [`ProjectorData`] (its WGSL struct
//! of the same name, checked against the shader by `gpu::layout`), its vectors
//! [`Xyz`](super::common::Xyz), three `f64` each; triangles are 9 `f64` each (three corners),
//! casters one `u32` each (1 casts); the G-buffer holds per pixel the triangle id
//! (`NO_TRIANGLE` for background), the depth (the camera ray's parameter, `f64`), position and
//! unit normal (3 `f64` each); the depth map per texel the depth (`f64`, infinity where no
//! caster) and the triangle id.

use super::{
    common::ProjectorData,
    raster::{rasterize, RasterJob},
    GpuContext, GpuError,
};
use crate::{
    depth_map::LightDepthMap,
    frame::{Frame, STAGE_GPU_GBUFFER},
    gbuffer::GBuffer,
};
use scenes::projection::Projector;

/// The frame's geometry and camera G-buffer on the GPU.
#[derive(Debug)]
pub struct GpuFrame {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Number of triangles.
    pub triangles: u32,
    /// Corners, 9 `f64` per triangle.
    pub corners: wgpu::Buffer,
    /// 1 where the triangle casts shadows, one `u32` per triangle.
    pub casters: wgpu::Buffer,
    /// Camera projector, one [`ProjectorData`].
    pub camera: wgpu::Buffer,
    /// G-buffer: triangle id per pixel.
    pub triangle: wgpu::Buffer,
    /// G-buffer: depth per pixel, the parameter of the camera ray through the pixel centre
    /// (infinity where no surface), `f64`.
    pub depth: wgpu::Buffer,
    /// G-buffer: world position per pixel, 3 `f64`.
    pub position: wgpu::Buffer,
    /// G-buffer: unit face normal per pixel, 3 `f64`.
    pub normal: wgpu::Buffer,
}

/// Corners of every triangle, 9 `f64` each.
pub fn corner_data(frame: &Frame<'_>) -> Vec<f64> {
    let g = &frame.geometry;
    let mut out = Vec::with_capacity(g.triangles.len() * 9);
    for t in 0..g.triangles.len() {
        for c in g.corners(t) {
            out.extend_from_slice(&[c.x, c.y, c.z]);
        }
    }
    out
}

impl GpuFrame {
    /// Uploads the frame's geometry and `gbuffer` (the CPU's, for parity; or one read back).
    pub fn upload(ctx: &GpuContext, frame: &Frame<'_>, gbuffer: &GBuffer) -> Self {
        let n = frame.geometry.triangles.len();
        let casters: Vec<u32> = (0..n).map(|t| u32::from(frame.is_caster(t))).collect();
        let flat =
            |v: &[glam::DVec3]| -> Vec<f64> { v.iter().flat_map(|p| p.to_array()).collect() };
        Self {
            width: gbuffer.width,
            height: gbuffer.height,
            triangles: n as u32,
            corners: ctx.upload("corners", &corner_data(frame)),
            casters: ctx.upload("casters", &casters),
            camera: ctx.upload("camera", &[ProjectorData::new(&frame.camera)]),
            triangle: ctx.upload("gbuffer triangle", &gbuffer.triangle),
            depth: ctx.upload("gbuffer depth", &gbuffer.depth),
            position: ctx.upload("gbuffer position", &flat(&gbuffer.position)),
            normal: ctx.upload("gbuffer normal", &flat(&gbuffer.normal)),
        }
    }

    /// The frame's G-buffer for a GPU run, made on the GPU as the stage [`STAGE_GPU_GBUFFER`].
    pub fn for_run(
        ctx: &GpuContext,
        frame: &Frame<'_>,
        rec: &mut instrumentation::Recorder,
    ) -> Result<Self, GpuError> {
        let n = frame.geometry.triangles.len();
        let casters: Vec<u32> = (0..n).map(|t| u32::from(frame.is_caster(t))).collect();
        let corners = ctx.upload("corners", &corner_data(frame));
        let casters = ctx.upload("casters", &casters);
        let job = RasterJob {
            projector: &frame.camera,
            casters_only: false,
            shift: glam::DVec2::ZERO,
            gbuffer: true,
        };
        let r = rasterize(ctx, frame, &corners, &casters, job, STAGE_GPU_GBUFFER, rec)?;
        Ok(Self {
            width: frame.width(),
            height: frame.height(),
            triangles: n as u32,
            corners,
            casters,
            camera: ctx.upload("camera", &[ProjectorData::new(&frame.camera)]),
            triangle: r.triangle,
            depth: r.depth,
            position: r.position,
            normal: r.normal,
        })
    }

    /// Reads the G-buffer back.
    pub fn read_gbuffer(&self, ctx: &GpuContext) -> Result<GBuffer, GpuError> {
        let triangle: Vec<u32> = ctx.read(&self.triangle)?;
        let vec3 = |v: Vec<f64>| -> Vec<glam::DVec3> {
            v.chunks_exact(3).map(|c| glam::DVec3::new(c[0], c[1], c[2])).collect()
        };
        let mut depth: Vec<f64> = ctx.read(&self.depth)?;
        depth.truncate(triangle.len());
        let position = vec3(ctx.read(&self.position)?);
        let normal = vec3(ctx.read(&self.normal)?);
        Ok(GBuffer { width: self.width, height: self.height, triangle, depth, position, normal })
    }

    /// Number of pixels.
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

/// A light depth map on the GPU.
#[derive(Debug)]
pub struct GpuDepthMap {
    /// The light's projector onto the map (CPU side).
    pub projector: Projector,
    /// Map resolution.
    pub res: u32,
    /// Where the samples lie: texel `(i, j)` holds the depth at `(i + 0.5, j + 0.5) + shift`.
    pub shift: glam::DVec2,
    /// Light projector, one [`ProjectorData`].
    pub light: wgpu::Buffer,
    /// Depth per texel (`f64`, infinity where no caster).
    pub depth: wgpu::Buffer,
    /// Caster triangle per texel.
    pub triangle: wgpu::Buffer,
}

impl GpuDepthMap {
    /// Uploads a map made on the CPU (for parity tests and for maps the GPU does not render).
    pub fn upload(ctx: &GpuContext, map: &LightDepthMap) -> Self {
        Self {
            projector: map.projector,
            res: map.res,
            shift: map.shift,
            light: ctx.upload("light", &[ProjectorData::new(&map.projector)]),
            depth: ctx.upload("map depth", &map.depth),
            triangle: ctx.upload("map triangle", &map.triangle),
        }
    }

    /// The light depth map for a GPU run through the frustum `fit` gives (texel centres moved
    /// by `shift` texels, zero for the plain map), made on the GPU as the stage `stage`.
    pub fn for_run(
        ctx: &GpuContext,
        frame: &Frame<'_>,
        res: u32,
        fit: crate::light_fit::LightFit,
        shift: glam::DVec2,
        stage: &str,
        rec: &mut instrumentation::Recorder,
    ) -> Result<Self, GpuError> {
        let n = frame.geometry.triangles.len();
        let casters: Vec<u32> = (0..n).map(|t| u32::from(frame.is_caster(t))).collect();
        let corners = ctx.upload("corners", &corner_data(frame));
        let casters = ctx.upload("casters", &casters);
        let projector = frame.light_projector(res, fit);
        let job = RasterJob { projector: &projector, casters_only: true, shift, gbuffer: false };
        let r = rasterize(ctx, frame, &corners, &casters, job, stage, rec)?;
        Ok(Self {
            projector,
            res,
            shift,
            light: ctx.upload("light", &[ProjectorData::new(&projector)]),
            depth: r.depth,
            triangle: r.triangle,
        })
    }

    /// Reads the map back.
    pub fn read(&self, ctx: &GpuContext) -> Result<LightDepthMap, GpuError> {
        Ok(LightDepthMap {
            projector: self.projector,
            res: self.res,
            shift: self.shift,
            depth: ctx.read(&self.depth)?,
            triangle: ctx.read(&self.triangle)?,
        })
    }
}
