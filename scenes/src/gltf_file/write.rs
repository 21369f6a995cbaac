//! A scene written as one binary glTF (`.glb`), for renderers outside the workbench.
//!
//! One node per object, in the scene's order and named after it, its mesh in world space (the
//! node's transform is the identity): positions as `FLOAT` `VEC3` (the `f64` coordinates
//! rounded to the nearest `f32`, which is what a renderer reads), triangles as `UNSIGNED_INT`
//! indices, one primitive of mode `TRIANGLES` a mesh. Each object has a material: its colour
//! and opacity as `baseColorFactor`, `alphaMode` `BLEND` when the opacity is below 1, else
//! `OPAQUE`; metallic 0, roughness 1 (a diffuse surface, as the Lambert image the workbench
//! draws), double-sided. The camera is a camera node at the eye looking down its -Z towards
//! the target, +Y the up hint made orthogonal: perspective with `yfov`, `znear` and the scene's
//! aspect ratio, or orthographic with `ymag` half the height, `xmag` by the aspect ratio,
//! `znear` 0 and `zfar` beyond the farthest corner of the scene's bounds. The light is a
//! `KHR_lights_punctual` node (the extension is used, not required): directional along its
//! -Z, or spot at the position aimed at the target with `outerConeAngle` half the frustum's
//! opening. Read back by [`super::read`], the file gives the same objects (their
//! triangles to the rounding to `f32`, their vertices in order of first use), camera (its
//! target one unit along the view), light and materials. Not written: whether an object casts shadows (glTF has
//! no such property: every exported object casts), the effect switches and the resolution
//! beyond its aspect ratio.

use super::GltfError;
use crate::camera::Camera;
use crate::light::Light;
use crate::projection::look_basis;
use crate::scene::Scene;
use crate::scene_file::SceneError;
use glam::{DMat4, DVec3, DVec4};
use gltf::json::{
    self,
    validation::{Checked::Valid, USize64},
    Index,
};
use std::collections::BTreeMap;
use std::path::Path;

/// Writes `scene` to `path` as one `.glb` (see the module documentation for the layout). A
/// failure is [`SceneError::Gltf`] holding [`GltfError::Write`], naming the file.
pub fn write_glb(scene: &Scene, path: &Path) -> Result<(), SceneError> {
    let write = |message: String| GltfError::Write { path: path.to_owned(), message };
    let bytes = glb_bytes(scene).map_err(write)?;
    std::fs::write(path, bytes).map_err(|e| write(e.to_string()))?;
    Ok(())
}

/// A node's matrix (column-major `f32`) from its axes and origin.
fn node_matrix(x: DVec3, y: DVec3, z: DVec3, origin: DVec3) -> [f32; 16] {
    let m =
        DMat4::from_cols(x.extend(0.0), y.extend(0.0), z.extend(0.0), DVec4::from((origin, 1.0)));
    m.to_cols_array().map(|v| v as f32)
}

/// The `.glb` bytes of `scene`.
fn glb_bytes(scene: &Scene) -> Result<Vec<u8>, String> {
    let mut root = json::Root {
        asset: json::Asset { generator: Some("shadowbench".into()), ..Default::default() },
        ..Default::default()
    };
    let mut bin: Vec<u8> = Vec::new();
    let buffer = Index::new(0);
    let mut view = |root: &mut json::Root, bytes: &[u8], target: json::buffer::Target| {
        let offset = bin.len();
        bin.extend_from_slice(bytes);
        root.push(json::buffer::View {
            buffer,
            byte_length: USize64::from(bytes.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: Some(Valid(target)),
            extensions: None,
            extras: Default::default(),
        })
    };
    let mut nodes = Vec::with_capacity(scene.objects.len() + 2);
    for object in &scene.objects {
        let mesh = &object.mesh;
        let positions: Vec<[f32; 3]> =
            mesh.positions.iter().map(|p| p.to_array().map(|c| c as f32)).collect();
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for p in &positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let position_bytes: Vec<u8> =
            positions.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
        let index_bytes: Vec<u8> =
            mesh.triangles.iter().flatten().flat_map(|i| i.to_le_bytes()).collect();
        let position_view = view(&mut root, &position_bytes, json::buffer::Target::ArrayBuffer);
        let index_view = view(&mut root, &index_bytes, json::buffer::Target::ElementArrayBuffer);
        let accessor =
            |view, count: usize, component, type_, bounds: Option<([f32; 3], [f32; 3])>| {
                json::Accessor {
                    buffer_view: Some(view),
                    byte_offset: None,
                    count: USize64::from(count),
                    component_type: Valid(json::accessor::GenericComponentType(component)),
                    extensions: None,
                    extras: Default::default(),
                    type_: Valid(type_),
                    min: bounds.map(|(lo, _)| json::Value::from(lo.to_vec())),
                    max: bounds.map(|(_, hi)| json::Value::from(hi.to_vec())),
                    name: None,
                    normalized: false,
                    sparse: None,
                }
            };
        let position_accessor = root.push(accessor(
            position_view,
            positions.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Vec3,
            Some((lo, hi)),
        ));
        let index_accessor = root.push(accessor(
            index_view,
            3 * mesh.triangles.len(),
            json::accessor::ComponentType::U32,
            json::accessor::Type::Scalar,
            None,
        ));
        let m = object.material;
        let material = root.push(json::Material {
            name: Some(object.name.clone()),
            alpha_mode: Valid(if m.opacity < 1.0 {
                json::material::AlphaMode::Blend
            } else {
                json::material::AlphaMode::Opaque
            }),
            double_sided: true,
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor(
                    [m.color[0], m.color[1], m.color[2], m.opacity].map(|c| c as f32),
                ),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(1.0),
                ..Default::default()
            },
            ..Default::default()
        });
        let gltf_mesh = root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: Some(object.name.clone()),
            primitives: vec![json::mesh::Primitive {
                attributes: BTreeMap::from([(
                    Valid(json::mesh::Semantic::Positions),
                    position_accessor,
                )]),
                extensions: None,
                extras: Default::default(),
                indices: Some(index_accessor),
                material: Some(material),
                mode: Valid(json::mesh::Mode::Triangles),
                targets: None,
            }],
            weights: None,
        });
        nodes.push(root.push(json::Node {
            mesh: Some(gltf_mesh),
            name: Some(object.name.clone()),
            ..Default::default()
        }));
    }
    let aspect = f64::from(scene.width) / f64::from(scene.height);
    let (mut eye, target) = (scene.camera.eye(), scene.camera.target());
    let (right, up, forward) = look_basis(target - eye, camera_up(&scene.camera));
    let camera = match scene.camera {
        Camera::Perspective { fov_y_deg, near, .. } => json::Camera {
            name: Some("camera".into()),
            type_: Valid(json::camera::Type::Perspective),
            perspective: Some(json::camera::Perspective {
                aspect_ratio: Some(aspect as f32),
                yfov: fov_y_deg.to_radians() as f32,
                zfar: None,
                znear: near as f32,
                extensions: None,
                extras: Default::default(),
            }),
            orthographic: None,
            extensions: None,
            extras: Default::default(),
        },
        Camera::Orthographic { height, .. } => {
            // The workbench's orthographic camera clips nothing; glTF's needs every object
            // within `znear..zfar`: the eye moves back along the view until none is behind it
            // (which changes no image of a parallel projection).
            let (lo, hi) = scene.bounds();
            let depths = crate::mesh::box_corners(lo, hi).map(|c| (c - eye).dot(forward));
            let nearest = depths.iter().copied().fold(0.0, f64::min);
            let far = depths.iter().copied().fold(0.0, f64::max) - nearest;
            eye += nearest * forward;
            json::Camera {
                name: Some("camera".into()),
                type_: Valid(json::camera::Type::Orthographic),
                orthographic: Some(json::camera::Orthographic {
                    xmag: (0.5 * height * aspect) as f32,
                    ymag: (0.5 * height) as f32,
                    zfar: (far * (1.0 + crate::light::FIT_MARGIN)).max(f64::MIN_POSITIVE) as f32,
                    znear: 0.0,
                    extensions: None,
                    extras: Default::default(),
                }),
                perspective: None,
                extensions: None,
                extras: Default::default(),
            }
        }
    };
    let camera = root.push(camera);
    nodes.push(root.push(json::Node {
        camera: Some(camera),
        name: Some("camera".into()),
        matrix: Some(node_matrix(right, up, -forward, eye)),
        ..Default::default()
    }));
    use json::extensions::scene::khr_lights_punctual as punctual;
    let (type_, spot, origin, axis) = match scene.light {
        Light::Directional { direction } => {
            (punctual::Type::Directional, None, DVec3::ZERO, direction)
        }
        Light::Spot { position, target, fov_deg } => {
            let cone = punctual::Spot {
                inner_cone_angle: 0.0,
                outer_cone_angle: (0.5 * fov_deg).to_radians() as f32,
            };
            (punctual::Type::Spot, Some(cone), position, target - position)
        }
    };
    let light = punctual::Light {
        color: [1.0; 3],
        extensions: None,
        extras: Default::default(),
        intensity: 1.0,
        name: Some("light".into()),
        range: None,
        spot,
        type_: Valid(type_),
    };
    let (x, y, forward) = look_basis(axis, DVec3::Y);
    root.extensions = Some(json::extensions::Root {
        khr_lights_punctual: Some(json::extensions::root::KhrLightsPunctual {
            lights: vec![light],
        }),
    });
    root.extensions_used = vec!["KHR_lights_punctual".into()];
    nodes.push(root.push(json::Node {
        name: Some("light".into()),
        matrix: Some(node_matrix(x, y, -forward, origin)),
        extensions: Some(json::extensions::scene::Node {
            khr_lights_punctual: Some(punctual::KhrLightsPunctual { light: Index::new(0) }),
        }),
        ..Default::default()
    }));
    root.scenes = vec![json::Scene {
        extensions: None,
        extras: Default::default(),
        name: Some(scene.name.clone()),
        nodes,
    }];
    root.scene = Some(Index::new(0));
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    if u32::try_from(bin.len()).is_err() {
        return Err(format!("{} bytes of geometry do not fit in one GLB (4 GiB)", bin.len()));
    }
    root.buffers = vec![json::Buffer {
        byte_length: USize64::from(bin.len()),
        name: None,
        uri: None,
        extensions: None,
        extras: Default::default(),
    }];
    let json_bytes = json::serialize::to_vec(&root).map_err(|e| e.to_string())?;
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header { magic: *b"glTF", version: 2, length: 0 },
        json: json_bytes.into(),
        bin: Some(bin.into()),
    };
    glb.to_vec().map_err(|e| e.to_string())
}

fn camera_up(camera: &Camera) -> DVec3 {
    match camera {
        Camera::Perspective { up, .. } | Camera::Orthographic { up, .. } => *up,
    }
}
