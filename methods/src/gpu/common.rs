//! The WGSL every kernel starts from, `common.wgsl` (the projector in `f64`, rays, near
//! clipping, robust helpers), and the Rust mirrors of its structs, [`Xyz`] and
//! [`ProjectorData`]: how the frame's buffers, the rasterizer and every technique's parameters
//! hold a projector. The frame's buffers and the rasterizer both need it, and the frame uses
//! the rasterizer, so it is a module of its own below both.

use super::shader::Part;
use bytemuck::{Pod, Zeroable};
use glam::DVec3;
use scenes::projection::{ProjectionKind, Projector};

/// WGSL shared by the kernels: the projector in `f64`, rays, near clipping, robust helpers.
pub(crate) const COMMON: Part = Part::file("common.wgsl", include_str!("common.wgsl"));

/// Three `f64` as the kernels' buffers hold them, the WGSL struct `Xyz` of `common.wgsl`: a
/// 3-vector without `vec3<f64>`'s 32-byte alignment, so that a struct holding it is packed as
/// in Rust.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct Xyz {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

impl From<DVec3> for Xyz {
    fn from(v: DVec3) -> Self {
        Self { x: v.x, y: v.y, z: v.z }
    }
}

/// A projector as the kernels read it: the WGSL struct `ProjectorData` of `common.wgsl`,
/// field for field, which `proj_load` turns into the `Proj` the kernels compute with.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct ProjectorData {
    /// [`Projector::origin`].
    pub origin: Xyz,
    /// [`Projector::right`].
    pub right: Xyz,
    /// [`Projector::up`].
    pub up: Xyz,
    /// [`Projector::forward`].
    pub forward: Xyz,
    /// The projection: 0 orthographic (`a`, `b` are the half width and height), 1 perspective
    /// (`a`, `b` are the tangents of the half angles along x and y).
    pub kind: u32,
    /// Zero; puts `a` at a multiple of 8 bytes, as WGSL does.
    pub pad: u32,
    /// Half width, or the tangent of the half angle along x.
    pub a: f64,
    /// Half height, or the tangent of the half angle along y.
    pub b: f64,
    /// [`Projector::near`].
    pub near: f64,
    /// [`Projector::width`].
    pub width: f64,
    /// [`Projector::height`].
    pub height: f64,
}

impl ProjectorData {
    /// The layout of `p`.
    pub fn new(p: &Projector) -> Self {
        let (kind, a, b) = match p.kind {
            ProjectionKind::Orthographic { half_width, half_height } => {
                (0, half_width, half_height)
            }
            ProjectionKind::Perspective { tan_half_x, tan_half_y } => (1, tan_half_x, tan_half_y),
        };
        Self {
            origin: p.origin.into(),
            right: p.right.into(),
            up: p.up.into(),
            forward: p.forward.into(),
            kind,
            pad: 0,
            a,
            b,
            near: p.near,
            width: p.width,
            height: p.height,
        }
    }
}

super::layout::wgsl_mirror!(
    Xyz, "Xyz", crate::gpu::shader::compose(&[&COMMON]), [x, y, z];
    ProjectorData,
    "ProjectorData",
    crate::gpu::shader::compose(&[&COMMON]),
    [origin, right, up, forward, kind, pad, a, b, near, width, height];
);
