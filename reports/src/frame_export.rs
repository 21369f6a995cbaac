//! A frame as another renderer needs it to make the same image (`shadowbench frame`):
//! `frame.json` ([`FrameRecord`]: the camera and the light with their matrices, the light
//! frustum of the shadow-map methods, the objects' triangle ids and the conventions in words),
//! `gbuffer.exr` ([`write_gbuffer_exr`]: what the camera sees at each pixel centre) and
//! `samples.json` ([`SamplesRecord`]: the sub-sample offsets of every rate of the shared
//! patterns).
//!
//! Matrices are 4 x 4, row-major (`m[row][column]`), and act on column vectors: `v' = M v`.
//! View space is `x` right, `y` up on screen, `z` forward: `z` is the depth of the workbench
//! (a left-handed frame; negate `z` for a right-handed one looking down `-z`).

use crate::output::OutputError;
use glam::DVec3;
use methods::pattern::{PatternKind, SamplePattern, RATES};
use methods::Frame;
use scenes::projection::{ProjectionKind, Projector};
use scenes::{Camera, Light};
use serde::Serialize;
use std::path::Path;

/// The conventions of the frame, in words (written into `frame.json`).
pub const CONVENTIONS: &[(&str, &str)] = &[
    ("matrices", "4x4, row-major (m[row][column]), acting on column vectors: v' = M v"),
    (
        "view_space",
        "x along `right`, y along `up` (up on screen), z along `forward`; z is the depth (a \
         left-handed frame)",
    ),
    (
        "projection",
        "clip = projection * view; ndc = clip.xyz / clip.w; image x = (1 + ndc.x) / 2 * width, \
         image y = (1 - ndc.y) / 2 * height. Perspective: ndc.z = near / depth (1 at the near \
         plane, 0 at infinity, no far plane). Orthographic: ndc.z = depth, unbounded",
    ),
    (
        "image",
        "image coordinates from the top-left corner, y down; pixel (i, j) covers [i, i+1] x \
         [j, j+1], its centre is (i + 0.5, j + 0.5); the G-buffer is taken at pixel centres",
    ),
    (
        "depth",
        "distance along the forward axis: from the eye (perspective) or from the image plane \
         through `origin` (orthographic); linear in world space",
    ),
    (
        "lit_fraction",
        "per pixel, the fraction of the area of the surface visible in the pixel's square that \
         the light reaches, in [0, 1] (0 in full shadow, 1 fully lit; 1 where no surface is \
         seen), one f32 per pixel, row-major from the top row; an EXR with one channel named \
         `Y`, `L`, `lit` or `visibility` (the workbench's own visibility.exr writes `Y`)",
    ),
    (
        "scored_pixels",
        "the headline metrics are taken over the pixels whose square sees one planar object \
         (`planar`) or is tiled by front-facing triangles of one continuous surface \
         (`surface`) and that the reference evaluated; `edge` pixels (silhouettes, depth \
         discontinuities, several objects, background) are scored apart under classes.edge, \
         `uncovered` pixels (background only) not at all",
    ),
    (
        "light",
        "the light travels along `direction` (directional) or from `position` towards \
         `target` (spot, a cone of full opening `fov_deg`); the shadow-map methods render \
         their depth map through `light.frustum`, an R x R image for map resolution R",
    ),
    (
        "triangle_id",
        "indices into the scene's triangles in the order of `objects` (each object's ids are \
         first_triangle .. first_triangle + triangles; a mesh file's triangles in the order \
         the scene keeps them, as scene.glb has them, which for a large file whose order is \
         not local is the Z order of their centroids, not the file's); 4294967295 (u32::MAX) \
         where no triangle is seen",
    ),
];

/// A projection as matrices and as the workbench's own parameters.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProjectionRecord {
    /// `perspective` or `orthographic`.
    pub kind: &'static str,
    /// World to view, row-major.
    pub world_to_view: [[f64; 4]; 4],
    /// View to clip, row-major.
    pub projection: [[f64; 4]; 4],
    /// Eye (perspective) or centre of the image plane (orthographic).
    pub origin: [f64; 3],
    /// Unit vector along the image's `+x`.
    pub right: [f64; 3],
    /// Unit vector up on screen (the image's `-y`).
    pub up: [f64; 3],
    /// Unit viewing direction.
    pub forward: [f64; 3],
    /// `tan` of half the horizontal field of view (perspective).
    pub tan_half_x: Option<f64>,
    /// `tan` of half the vertical field of view (perspective).
    pub tan_half_y: Option<f64>,
    /// Half the view volume's width in world units (orthographic).
    pub half_width: Option<f64>,
    /// Half the view volume's height in world units (orthographic).
    pub half_height: Option<f64>,
    /// Nearest depth projected (perspective); `None` for orthographic projections.
    pub near: Option<f64>,
}

/// The camera: as the scene gives it, and as the frame projects.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CameraRecord {
    /// `perspective` or `orthographic`.
    pub kind: &'static str,
    /// Eye position.
    pub eye: [f64; 3],
    /// Point looked at.
    pub target: [f64; 3],
    /// Up hint.
    pub up: [f64; 3],
    /// Vertical field of view, degrees (perspective).
    pub fov_y_deg: Option<f64>,
    /// Height of the view volume, world units (orthographic).
    pub height: Option<f64>,
    /// The projection onto the frame.
    pub projection: ProjectionRecord,
}

/// The light: as the scene gives it, and the frustum the shadow-map methods use.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LightRecord {
    /// `directional` or `spot`.
    pub kind: &'static str,
    /// Unit direction the light travels (directional), or the spot's axis (position to
    /// target).
    pub direction: [f64; 3],
    /// The spot's position.
    pub position: Option<[f64; 3]>,
    /// The point the spot is aimed at.
    pub target: Option<[f64; 3]>,
    /// The spot's full opening angle, degrees.
    pub fov_deg: Option<f64>,
    /// The light frustum of the shadow-map methods, fitted to the scene's bounds (its
    /// matrices do not depend on the map's resolution).
    pub frustum: ProjectionRecord,
    /// The nearest and farthest light depth of the scene's bounding box (the unit of the
    /// constant depth bias is their difference).
    pub depth_bounds: [f64; 2],
}

/// An object of the scene and its triangle ids.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ObjectRecord {
    /// The object's name.
    pub name: String,
    /// Its first triangle id.
    pub first_triangle: u32,
    /// Its triangle count.
    pub triangles: u32,
    /// Whether it casts shadows.
    pub casts_shadows: bool,
}

/// What `frame.json` holds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameRecord {
    /// Scene name.
    pub scene: String,
    /// Frame width, pixels.
    pub width: u32,
    /// Frame height, pixels.
    pub height: u32,
    /// The scene's effects.
    pub effects: Vec<String>,
    /// The camera.
    pub camera: CameraRecord,
    /// The light.
    pub light: LightRecord,
    /// The objects, in triangle id order.
    pub objects: Vec<ObjectRecord>,
    /// The conventions, in words ([`CONVENTIONS`]).
    pub conventions: serde_json::Map<String, serde_json::Value>,
}

/// The sub-sample offsets of one rate of one pattern.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PatternRecord {
    /// Samples per pixel.
    pub rate: u32,
    /// Index of the sample at the pixel centre.
    pub centre_index: usize,
    /// Offsets inside the pixel from its top-left corner, `[x, y]` in `[0, 1)`, `y` down.
    pub offsets: Vec<[f64; 2]>,
}

/// What `samples.json` holds: every rate of each shared pattern.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SamplesRecord {
    /// How to read the offsets.
    pub convention: &'static str,
    /// `grid`'s rates.
    pub grid: Vec<PatternRecord>,
    /// `rotated`'s rates.
    pub rotated: Vec<PatternRecord>,
}

fn arr(v: DVec3) -> [f64; 3] {
    v.to_array()
}

/// `p`'s matrices and parameters.
pub fn projection_record(p: &Projector) -> ProjectionRecord {
    let row = |a: DVec3| [a.x, a.y, a.z, -a.dot(p.origin)];
    let world_to_view = [row(p.right), row(p.up), row(p.forward), [0.0, 0.0, 0.0, 1.0]];
    let (kind, projection, tan, half, near) = match p.kind {
        ProjectionKind::Perspective { tan_half_x, tan_half_y } => (
            "perspective",
            [
                [1.0 / tan_half_x, 0.0, 0.0, 0.0],
                [0.0, 1.0 / tan_half_y, 0.0, 0.0],
                [0.0, 0.0, 0.0, p.near],
                [0.0, 0.0, 1.0, 0.0],
            ],
            Some((tan_half_x, tan_half_y)),
            None,
            Some(p.near),
        ),
        ProjectionKind::Orthographic { half_width, half_height } => (
            "orthographic",
            [
                [1.0 / half_width, 0.0, 0.0, 0.0],
                [0.0, 1.0 / half_height, 0.0, 0.0],
                [0.0, 0.0, 1.0, 0.0],
                [0.0, 0.0, 0.0, 1.0],
            ],
            None,
            Some((half_width, half_height)),
            None,
        ),
    };
    ProjectionRecord {
        kind,
        world_to_view,
        projection,
        origin: arr(p.origin),
        right: arr(p.right),
        up: arr(p.up),
        forward: arr(p.forward),
        tan_half_x: tan.map(|t| t.0),
        tan_half_y: tan.map(|t| t.1),
        half_width: half.map(|h| h.0),
        half_height: half.map(|h| h.1),
        near,
    }
}

/// The record of `frame` (see the module documentation).
pub fn frame_record(frame: &Frame<'_>) -> FrameRecord {
    let scene = frame.scene;
    let camera = match &scene.camera {
        Camera::Perspective { eye, target, up, fov_y_deg, .. } => CameraRecord {
            kind: "perspective",
            eye: arr(*eye),
            target: arr(*target),
            up: arr(*up),
            fov_y_deg: Some(*fov_y_deg),
            height: None,
            projection: projection_record(&frame.camera),
        },
        Camera::Orthographic { eye, target, up, height } => CameraRecord {
            kind: "orthographic",
            eye: arr(*eye),
            target: arr(*target),
            up: arr(*up),
            fov_y_deg: None,
            height: Some(*height),
            projection: projection_record(&frame.camera),
        },
    };
    // The frustum's matrices do not depend on the resolution (it only maps NDC to texels).
    let frustum = frame.light_projector(1, methods::LightFit::Scene);
    let (near, far) = frame.light_depth_bounds(&frustum);
    let (kind, position, target, fov_deg) = match &scene.light {
        Light::Directional { .. } => ("directional", None, None, None),
        Light::Spot { position, target, fov_deg } => {
            ("spot", Some(arr(*position)), Some(arr(*target)), Some(*fov_deg))
        }
    };
    let light = LightRecord {
        kind,
        direction: arr(frustum.forward),
        position,
        target,
        fov_deg,
        frustum: projection_record(&frustum),
        depth_bounds: [near, far],
    };
    let mut objects: Vec<ObjectRecord> = Vec::new();
    let mut last_object = None;
    for (t, &o) in frame.geometry.object.iter().enumerate() {
        match objects.last_mut() {
            Some(last) if last_object == Some(o) => last.triangles += 1,
            _ => objects.push(ObjectRecord {
                name: scene.objects[o as usize].name.clone(),
                first_triangle: t as u32,
                triangles: 1,
                casts_shadows: frame.object_casts_shadows(o as usize),
            }),
        }
        last_object = Some(o);
    }
    let conventions = CONVENTIONS.iter().map(|(k, v)| ((*k).to_owned(), (*v).into())).collect();
    FrameRecord {
        scene: scene.name.clone(),
        width: frame.width(),
        height: frame.height(),
        effects: frame.effects.names().into_iter().map(String::from).collect(),
        camera,
        light,
        objects,
        conventions,
    }
}

/// Every rate of both shared patterns.
pub fn samples_record() -> SamplesRecord {
    let kind = |k: PatternKind| {
        RATES
            .iter()
            .filter_map(|&rate| SamplePattern::new(rate, k).ok())
            .map(|p| PatternRecord {
                rate: p.rate(),
                centre_index: p.centre_index(),
                offsets: p.offsets().iter().map(|o| [o.x, o.y]).collect(),
            })
            .collect()
    };
    SamplesRecord {
        convention: "sub-sample s of pixel (i, j) lies at image point (i + x, j + y) for \
                     offsets[s] = [x, y], from the pixel's top-left corner, y down",
        grid: kind(PatternKind::Grid),
        rotated: kind(PatternKind::Rotated),
    }
}

fn write_err(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError::Write { path: path.to_owned(), message: e.to_string() }
}

/// The G-buffer's channels in `gbuffer.exr`: `position.x`, `position.y`, `position.z` (world
/// position at the pixel centre, 0 where no triangle is seen), `normal.x`, `normal.y`,
/// `normal.z` (unit face normal of the triangle as wound, 0 where none), `depth` (along the
/// forward axis, +infinity where none), all f32, and `triangle` (u32, the triangle id,
/// `u32::MAX` where none).
pub const GBUFFER_CHANNELS: &[&str] = &[
    "depth",
    "normal.x",
    "normal.y",
    "normal.z",
    "position.x",
    "position.y",
    "position.z",
    "triangle",
];

/// Writes the frame's G-buffer as `path` (channels: [`GBUFFER_CHANNELS`]).
pub fn write_gbuffer_exr(path: &Path, frame: &Frame<'_>) -> Result<(), OutputError> {
    use exr::prelude::*;
    let g = &frame.gbuffer;
    let (w, h) = (g.width as usize, g.height as usize);
    let f32s = |f: &dyn Fn(usize) -> f64| {
        FlatSamples::F32((0..w * h).map(|k| f(k) as f32).collect::<Vec<f32>>())
    };
    let channels = vec![
        AnyChannel::new("depth", f32s(&|k| g.depth[k])),
        AnyChannel::new("normal.x", f32s(&|k| g.normal[k].x)),
        AnyChannel::new("normal.y", f32s(&|k| g.normal[k].y)),
        AnyChannel::new("normal.z", f32s(&|k| g.normal[k].z)),
        AnyChannel::new("position.x", f32s(&|k| g.position[k].x)),
        AnyChannel::new("position.y", f32s(&|k| g.position[k].y)),
        AnyChannel::new("position.z", f32s(&|k| g.position[k].z)),
        AnyChannel::new("triangle", FlatSamples::U32(g.triangle.clone())),
    ];
    let layer = Layer::new(
        (w, h),
        LayerAttributes::named("gbuffer"),
        Encoding {
            line_order: exr::meta::attribute::LineOrder::Increasing,
            ..Encoding::FAST_LOSSLESS
        },
        AnyChannels::sort(channels.into()),
    );
    Image::from_layer(layer).write().to_file(path).map_err(|e| write_err(path, e))
}

fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), OutputError> {
    let text = serde_json::to_string_pretty(value).map_err(|e| write_err(path, e))?;
    std::fs::write(path, text + "\n").map_err(|e| write_err(path, e))
}

/// Writes `frame.json`, `gbuffer.exr` and `samples.json` of `frame` into `dir`.
pub fn write_frame(dir: &Path, frame: &Frame<'_>) -> Result<(), OutputError> {
    write_json(&dir.join("frame.json"), &frame_record(frame))?;
    write_json(&dir.join("samples.json"), &samples_record())?;
    write_gbuffer_exr(&dir.join("gbuffer.exr"), frame)
}
