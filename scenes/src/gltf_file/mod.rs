//! glTF 2.0 scenes (`.gltf` with external or `data:` buffers, and binary `.glb`), read into the
//! workbench's `f64` objects, camera and light, and written back ([`write_glb`]).
//!
//! The reference is the Khronos glTF 2.0 specification (version 2.0.1,
//! <https://registry.khronos.org/glTF/specs/2.0/glTF-2.0.html>) and the `KHR_lights_punctual`
//! extension (<https://github.com/KhronosGroup/glTF/tree/main/extensions/2.0/Khronos/KHR_lights_punctual>).
//! The JSON is parsed and its references validated by the `gltf` crate; buffers, accessors and
//! the GLB container are read here, with every offset and length checked, so that no file can
//! make the reader panic (the crate's own importer unwraps a URI's percent-decoding and
//! subtracts a GLB's declared length unchecked).
//!
//! What is read, and every choice made:
//! - **Nodes** (spec §3.5): the default scene's node trees (`scene`), else scene 0, else every
//!   root node (a node that is no node's child), in document order, depth first, each node
//!   before its children ("node order" below). A node's transform is its `matrix` or its
//!   `translation`, `rotation`, `scale` (T * R * S, §3.5.2; the rotation quaternion is
//!   normalised), composed from the root down in `f64` from the file's `f32` values. A node
//!   reached twice (the hierarchy must be a set of disjoint trees, §3.5.3), a transform that is
//!   not finite, and a mesh's node whose transform is not invertible (it would flatten the
//!   mesh) are refused naming the node. Skins and morph targets are
//!   ignored (noted): meshes are placed by their nodes' transforms, with their base positions.
//! - **Meshes** (§3.7.2): every primitive of every mesh instanced by a node. `TRIANGLES`,
//!   `TRIANGLE_STRIP` and `TRIANGLE_FAN` are triangulated as §3.7.2.1 says (strip triangle
//!   `i`: `v_i, v_{i+1+i%2}, v_{i+2-i%2}`; fan triangle `i`: `v_{i+1}, v_{i+2}, v_0`), indexed or
//!   not; `POINTS` and the `LINE` modes cast no shadow and are ignored (noted, naming mesh and
//!   primitive). `POSITION` must be a `VEC3` of `FLOAT` (not normalised), indices a `SCALAR` of
//!   unsigned byte, short or int, each in a buffer view (sparse accessors, and accessors without
//!   a buffer view, are refused naming mesh, primitive and accessor). As the OBJ loader does,
//!   vertices no triangle uses are dropped and the others keep their order of first use, so that
//!   an unused vertex never stretches the scene's bounds (and the light's frustum). A primitive
//!   whose vertex count makes no triangle is skipped (noted); a `TRIANGLES` count that is not a
//!   multiple of 3 is refused.
//! - **Objects**: as a whole scene ([`read`]), one object per triangle primitive instance, named
//!   after its node (else its mesh, else `node N`), with `#P` appended when the mesh has several
//!   primitives; every object casts shadows (glTF has no such flag). Used as an object of a
//!   scene file ([`read_mesh`]), every primitive instance is merged into one mesh, in world
//!   space, and the scene file's own transform and material apply; cameras and lights are then
//!   ignored, point lights included.
//! - **Camera** (§3.10): the first node with a camera, in node order; the others are noted. It
//!   looks down its node's -Z with +Y up: `eye` is the node's origin, `target` the origin plus
//!   the node's -Z axis, `up` its +Y axis. Perspective: `fov_y_deg` is `yfov` in degrees,
//!   `near` is `znear`; orthographic: `height` is `2 * ymag`. The aspect ratio (`aspectRatio`,
//!   or `xmag / ymag`) sets the scene's default resolution: 600 pixels high and as wide as the
//!   ratio makes it; without it, 800 x 600. `zfar` is not used (the workbench clips nothing
//!   far). Without a camera: the default camera of a mesh file given as the scene
//!   ([`crate::registry::mesh_scene`]); a glTF scene is not fitted to it.
//! - **Light** (`KHR_lights_punctual`): the first directional or spot light in node order is
//!   the scene's light (the workbench has one); the others are noted by node. Directional: it
//!   shines along its node's -Z. Spot: at the node's origin, aimed along its -Z (`target` is the
//!   origin plus the -Z axis), its frustum's full opening angle twice `outerConeAngle` (which
//!   must give at most 170 degrees; the inner cone, colour, intensity and range are not used).
//!   A point light is refused naming node and light: the workbench has no shadow maps for
//!   omnidirectional lights. Without a light: the mesh file's default directional light.
//! - **Materials** (§3.9): `baseColorFactor`'s RGB is the colour (linear RGB, as the workbench's);
//!   with `alphaMode` `BLEND` its alpha is the opacity; `OPAQUE` ignores the alpha (opacity
//!   1); `MASK`, with a constant alpha, is opacity 1 when the alpha reaches `alphaCutoff`
//!   (default 0.5) and 0 below. Textures are not read: a base-colour texture is ignored (noted,
//!   naming the material), its factor alone used. A primitive without a material has the
//!   spec's default material: white, opaque. Factors outside [0, 1] are refused naming the
//!   material.
//! - **Extensions**: a required extension (`extensionsRequired`) other than
//!   `KHR_lights_punctual` is refused naming it; other used extensions are ignored (noted).
//! - **Buffers**: the GLB's `BIN` chunk, a `data:` URI in base64, or a path relative to the
//!   glTF file (percent-encoded as URIs are); a missing file is named with the buffer's index and
//!   the path looked for. Other URI schemes are refused.
//!
//! Coordinates beyond [`crate::limits`] are refused by the scene's checks like any other
//! geometry; `f32` values overflowing to infinity are refused here, naming the node.
//!
//! The notes ([`GltfScene::notes`]) say, in a sentence each, what was ignored; the scene is
//! otherwise exactly what the file holds.

mod buffers;
mod write;

pub use write::write_glb;

use crate::camera::Camera;
use crate::light::Light;
use crate::mesh::Mesh;
use crate::scene::{Material, Object};
use buffers::{read_accessor, Data};
use glam::{DMat4, DQuat, DVec3};
use gltf::mesh::Mode;
use std::path::{Path, PathBuf};

/// The extensions whose being required does not refuse a file: the ones this reader reads.
const SUPPORTED_REQUIRED: &[&str] = &["KHR_lights_punctual"];

/// Why a glTF file cannot be read or written. Every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum GltfError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The glTF file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The path names a folder.
    #[error("{path}: is a folder, not a glTF file")]
    Folder {
        /// The folder.
        path: PathBuf,
    },
    /// The file is not valid glTF 2.0: its GLB container, its JSON, or its references.
    #[error("{path}: not a valid glTF 2.0 file: {message}")]
    Format {
        /// The glTF file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The file requires an extension this reader does not read.
    #[error(
        "{path}: the file requires the extension {extension}, which is not supported (only \
         KHR_lights_punctual is)"
    )]
    RequiredExtension {
        /// The glTF file.
        path: PathBuf,
        /// The extension.
        extension: String,
    },
    /// A buffer's file is missing.
    #[error("{path}: buffer {buffer} needs the file {}, which is missing", .looked.display())]
    MissingBuffer {
        /// The glTF file.
        path: PathBuf,
        /// The buffer's index.
        buffer: usize,
        /// Where it was looked for.
        looked: PathBuf,
    },
    /// A buffer cannot be read or is shorter than declared.
    #[error("{path}: buffer {buffer}: {message}")]
    Buffer {
        /// The glTF file.
        path: PathBuf,
        /// The buffer's index.
        buffer: usize,
        /// What is wrong.
        message: String,
    },
    /// An accessor of a primitive is not what the primitive needs, or lies outside its buffer.
    #[error("{path}: mesh {mesh}, primitive {primitive}, accessor {accessor}: {message}")]
    Accessor {
        /// The glTF file.
        path: PathBuf,
        /// The mesh, by name and index.
        mesh: String,
        /// The primitive's index in the mesh.
        primitive: usize,
        /// The accessor's index.
        accessor: usize,
        /// What is wrong.
        message: String,
    },
    /// A point light: the workbench casts shadows from directional and spot lights only.
    #[error(
        "{path}: {node}: {light} is a point light; only directional and spot lights cast shadows \
         here"
    )]
    PointLight {
        /// The glTF file.
        path: PathBuf,
        /// The node, by name and index.
        node: String,
        /// The light, by name and index.
        light: String,
    },
    /// A value the workbench cannot use: a node's transform, a camera, a light, a material.
    #[error("{path}: {what}: {message}")]
    Invalid {
        /// The glTF file.
        path: PathBuf,
        /// The node, camera, light or material, by name and index.
        what: String,
        /// What is wrong.
        message: String,
    },
    /// The file holds no triangle.
    #[error("{path}: the scene holds no triangle primitive")]
    NoTriangles {
        /// The glTF file.
        path: PathBuf,
    },
    /// A scene could not be written as glTF.
    #[error("{path}: cannot write the glTF file: {message}")]
    Write {
        /// The file to write.
        path: PathBuf,
        /// What failed.
        message: String,
    },
}

impl GltfError {
    /// The glTF file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            Self::Io { path, .. }
            | Self::Folder { path }
            | Self::Format { path, .. }
            | Self::RequiredExtension { path, .. }
            | Self::MissingBuffer { path, .. }
            | Self::Buffer { path, .. }
            | Self::Accessor { path, .. }
            | Self::PointLight { path, .. }
            | Self::Invalid { path, .. }
            | Self::NoTriangles { path }
            | Self::Write { path, .. } => path,
        }
    }
}

/// A glTF file read as a whole scene: see the module documentation for what each part is.
#[derive(Debug, Clone, PartialEq)]
pub struct GltfScene {
    /// One object per triangle primitive instance, in world space, in node order.
    pub objects: Vec<Object>,
    /// The first camera in node order, if any.
    pub camera: Option<Camera>,
    /// The default resolution its aspect ratio gives, if it has one.
    pub resolution: Option<[u32; 2]>,
    /// The first directional or spot light in node order, if any.
    pub light: Option<Light>,
    /// What the file holds that the scene leaves out, a sentence each.
    pub notes: Vec<String>,
}

/// What a glTF file's JSON says about the scene, before any buffer is read.
#[derive(Debug, Clone, PartialEq)]
pub struct GltfPlan {
    /// The scene's triangles: exact, counted from the accessors.
    pub triangles: u64,
    /// The first camera in node order, if any.
    pub camera: Option<Camera>,
    /// The default resolution its aspect ratio gives, if it has one.
    pub resolution: Option<[u32; 2]>,
    /// The first directional or spot light in node order, if any.
    pub light: Option<Light>,
    /// What the file holds that the scene leaves out, a sentence each.
    pub notes: Vec<String>,
}

/// Whether the file is read as a whole scene (cameras and lights taken, point lights refused)
/// or as one object's mesh (cameras and lights ignored).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Use {
    Scene,
    Mesh,
}

/// One triangle primitive of a mesh, placed by a node.
struct Instance {
    node: usize,
    mesh: usize,
    primitive: usize,
    world: DMat4,
    material: Material,
}

/// The JSON walked: instances, camera, light, notes and the triangle count.
struct Walk {
    instances: Vec<Instance>,
    triangles: u64,
    camera: Option<Camera>,
    resolution: Option<[u32; 2]>,
    light: Option<Light>,
    notes: Vec<String>,
}

/// A glTF file opened: its validated document and the GLB's `BIN` chunk.
struct Opened {
    document: gltf::Document,
    blob: Option<Vec<u8>>,
}

/// Reads a glTF file as a whole scene.
pub fn read(path: &Path) -> Result<GltfScene, GltfError> {
    let opened = open(path, true)?;
    let walk = walk(&opened.document, path, Use::Scene)?;
    let data = Data::load(&opened.document, opened.blob, path)?;
    let mut objects = Vec::with_capacity(walk.instances.len());
    for instance in &walk.instances {
        objects.push(Object {
            name: object_name(&opened.document, instance),
            mesh: build(&opened.document, instance, &data, path)?,
            material: instance.material,
            casts_shadows: true,
        });
    }
    Ok(GltfScene {
        objects,
        camera: walk.camera,
        resolution: walk.resolution,
        light: walk.light,
        notes: walk.notes,
    })
}

/// Reads a glTF file's JSON only (a `.glb`'s `BIN` chunk is not read): its exact triangle
/// count, camera, light and notes, with the errors [`read`] would give about them.
pub fn plan(path: &Path) -> Result<GltfPlan, GltfError> {
    let opened = open(path, false)?;
    let walk = walk(&opened.document, path, Use::Scene)?;
    Ok(GltfPlan {
        triangles: walk.triangles,
        camera: walk.camera,
        resolution: walk.resolution,
        light: walk.light,
        notes: walk.notes,
    })
}

/// Reads every triangle primitive instance of a glTF file into one mesh in world space, for a
/// scene file's object: cameras and lights are ignored.
pub fn read_mesh(path: &Path) -> Result<Mesh, GltfError> {
    let opened = open(path, true)?;
    let walk = walk(&opened.document, path, Use::Mesh)?;
    let data = Data::load(&opened.document, opened.blob, path)?;
    let mut merged = Mesh::default();
    for instance in &walk.instances {
        merged.append(&build(&opened.document, instance, &data, path)?);
    }
    Ok(merged)
}

/// The exact triangle count of [`read_mesh`], from the JSON alone.
pub fn mesh_triangles(path: &Path) -> Result<u64, GltfError> {
    let opened = open(path, false)?;
    Ok(walk(&opened.document, path, Use::Mesh)?.triangles)
}

/// Reads and validates the document; with `blob`, a `.glb`'s `BIN` chunk too.
fn open(path: &Path, blob: bool) -> Result<Opened, GltfError> {
    let io = |source| GltfError::Io { path: path.to_owned(), source };
    if path.is_dir() {
        return Err(GltfError::Folder { path: path.to_owned() });
    }
    let format = |message: String| GltfError::Format { path: path.to_owned(), message };
    let (json, bin) = buffers::read_container(path, blob).map_err(|e| match e {
        buffers::ContainerError::Io(source) => io(source),
        buffers::ContainerError::Format(message) => format(message),
    })?;
    let root: gltf::json::Root =
        gltf::json::deserialize::from_slice(&json).map_err(|e| format(e.to_string()))?;
    if let Some(extension) =
        root.extensions_required.iter().find(|e| !SUPPORTED_REQUIRED.contains(&e.as_str()))
    {
        return Err(GltfError::RequiredExtension {
            path: path.to_owned(),
            extension: extension.clone(),
        });
    }
    // The crate's validation reads each primitive's POSITION accessor without checking its
    // index: checked here first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(a) =
                primitive.attributes.values().find(|a| a.value() >= root.accessors.len())
            {
                return Err(format(format!(
                    "mesh {m}, primitive {p}: an attribute refers to accessor {}, which does not \
                     exist",
                    a.value()
                )));
            }
        }
    }
    // Nor does it check that a camera has the projection its type names, which it unwraps.
    for (i, camera) in root.cameras.iter().enumerate() {
        use gltf::json::{camera::Type, validation::Checked::Valid};
        let lacks = match camera.type_ {
            Valid(Type::Perspective) => camera.perspective.is_none().then_some("perspective"),
            Valid(Type::Orthographic) => camera.orthographic.is_none().then_some("orthographic"),
            _ => None,
        };
        if let Some(kind) = lacks {
            return Err(format(format!("camera {i} is of type {kind} but has no `{kind}` member")));
        }
    }
    let document = gltf::Document::from_json(root).map_err(|e| format(e.to_string()))?;
    Ok(Opened { document, blob: bin })
}

/// Adds `text` to `notes` unless it is there already (a material shared by primitives).
fn note(notes: &mut Vec<String>, text: String) {
    if !notes.contains(&text) {
        notes.push(text);
    }
}

/// `name (index)`, or `index` alone for an unnamed item.
fn label(kind: &str, name: Option<&str>, index: usize) -> String {
    match name {
        Some(name) => format!("{kind} `{name}` ({index})"),
        None => format!("{kind} {index}"),
    }
}

fn node_label(node: &gltf::Node) -> String {
    label("node", node.name(), node.index())
}

fn mesh_label(mesh: &gltf::Mesh) -> String {
    match mesh.name() {
        Some(name) => format!("`{name}` ({})", mesh.index()),
        None => mesh.index().to_string(),
    }
}

fn mesh_of<'a>(document: &'a gltf::Document, index: usize) -> gltf::Mesh<'a> {
    // `walk` took the index from a node of this validated document.
    document.meshes().nth(index).unwrap_or_else(|| unreachable!("mesh {index} was walked"))
}

/// The object's name: its node's, else its mesh's, else `node N`; `#P` when the mesh has
/// several primitives.
fn object_name(document: &gltf::Document, instance: &Instance) -> String {
    let mesh = mesh_of(document, instance.mesh);
    let node = document.nodes().nth(instance.node);
    let base = node
        .as_ref()
        .and_then(|n| n.name())
        .or(mesh.name())
        .map_or_else(|| format!("node {}", instance.node), str::to_owned);
    if mesh.primitives().len() > 1 {
        format!("{base}#{}", instance.primitive)
    } else {
        base
    }
}

/// The node's local transform in `f64`.
fn local(node: &gltf::Node) -> DMat4 {
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from)))
        }
        gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
            let [x, y, z, w] = rotation.map(f64::from);
            let q = DQuat::from_xyzw(x, y, z, w);
            let q = if q.length_squared() > 0.0 { q.normalize() } else { q };
            DMat4::from_scale_rotation_translation(
                DVec3::from(scale.map(f64::from)),
                q,
                DVec3::from(translation.map(f64::from)),
            )
        }
    }
}

/// The root nodes: the default scene's, else scene 0's, else every node that is no node's
/// child.
fn roots(document: &gltf::Document) -> Vec<usize> {
    if let Some(scene) = document.default_scene().or_else(|| document.scenes().next()) {
        return scene.nodes().map(|n| n.index()).collect();
    }
    let mut child = vec![false; document.nodes().len()];
    for node in document.nodes() {
        for c in node.children() {
            child[c.index()] = true;
        }
    }
    (0..child.len()).filter(|&i| !child[i]).collect()
}

/// The number of triangles a primitive of `mode` makes of `count` vertices.
fn triangles_of(mode: Mode, count: usize) -> Option<usize> {
    match mode {
        Mode::Triangles => Some(count / 3),
        Mode::TriangleStrip | Mode::TriangleFan => Some(count.saturating_sub(2)),
        Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip => None,
    }
}

/// Walks the node trees in node order: the triangle primitives' instances and count, the
/// camera and light (as a scene), the notes.
fn walk(document: &gltf::Document, path: &Path, usage: Use) -> Result<Walk, GltfError> {
    let invalid =
        |what: String, message: String| GltfError::Invalid { path: path.to_owned(), what, message };
    let mut w = Walk {
        instances: Vec::new(),
        triangles: 0,
        camera: None,
        resolution: None,
        light: None,
        notes: Vec::new(),
    };
    for extension in document.extensions_used() {
        if !SUPPORTED_REQUIRED.contains(&extension) {
            note(&mut w.notes, format!("the extension {extension} is not read"));
        }
    }
    let nodes: Vec<gltf::Node> = document.nodes().collect();
    let mut seen = vec![false; nodes.len()];
    let mut camera_node: Option<String> = None;
    let mut light_node: Option<String> = None;
    // Depth first, each node before its children, children in order: a stack of nodes to
    // visit with their parents' transform, pushed in reverse.
    let mut stack: Vec<(usize, DMat4)> =
        roots(document).into_iter().rev().map(|i| (i, DMat4::IDENTITY)).collect();
    while let Some((index, parent)) = stack.pop() {
        let node = &nodes[index];
        let name = node_label(node);
        if std::mem::replace(&mut seen[index], true) {
            return Err(invalid(
                name,
                "is reached twice: the node hierarchy must be disjoint trees (glTF 2.0 §3.5.3)"
                    .into(),
            ));
        }
        let world = parent * local(node);
        if !world.is_finite() {
            return Err(invalid(name, "its transform is not finite".into()));
        }
        for child in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child.index(), world));
        }
        if let Some(mesh) = node.mesh() {
            if node.skin().is_some() {
                note(&mut w.notes, format!("{name}: its skin is ignored"));
            }
            if world.determinant() == 0.0 {
                return Err(invalid(name, "its transform is not invertible".into()));
            }
            for primitive in mesh.primitives() {
                let p = primitive.index();
                let where_ = format!("mesh {}, primitive {p}", mesh_label(&mesh));
                if primitive.morph_targets().len() > 0 {
                    note(&mut w.notes, format!("{where_}: morph targets are ignored"));
                }
                let Some(positions) = primitive.get(&gltf::Semantic::Positions) else {
                    note(&mut w.notes, format!("{where_}: no POSITION, ignored"));
                    continue;
                };
                let count = primitive.indices().map_or(positions.count(), |a| a.count());
                let Some(triangles) = triangles_of(primitive.mode(), count) else {
                    note(
                        &mut w.notes,
                        format!("{where_}: mode {:?} casts no shadow, ignored", primitive.mode()),
                    );
                    continue;
                };
                if triangles == 0 {
                    note(&mut w.notes, format!("{where_}: makes no triangle, ignored"));
                    continue;
                }
                let material = material(&primitive.material(), path, &mut w.notes)?;
                w.triangles = w.triangles.saturating_add(triangles as u64);
                w.instances.push(Instance {
                    node: index,
                    mesh: mesh.index(),
                    primitive: p,
                    world,
                    material,
                });
            }
        }
        if usage == Use::Mesh {
            continue;
        }
        if let Some(camera) = node.camera() {
            if let Some(first) = &camera_node {
                note(
                    &mut w.notes,
                    format!("{name}: its camera is ignored; the scene's is {first}'s"),
                );
            } else {
                let (camera, resolution) = camera_at(&camera, &world)
                    .map_err(|m| invalid(format!("{name}, {}", camera_label(&camera)), m))?;
                w.camera = Some(camera);
                w.resolution = resolution;
                camera_node = Some(name.clone());
            }
        }
        if let Some(light) = node.light() {
            let light_name = label("light", light.name(), light.index());
            if let gltf::khr_lights_punctual::Kind::Point = light.kind() {
                return Err(GltfError::PointLight {
                    path: path.to_owned(),
                    node: name,
                    light: light_name,
                });
            }
            if let Some(first) = &light_node {
                note(
                    &mut w.notes,
                    format!("{name}: {light_name} is ignored; the scene's is {first}'s"),
                );
            } else {
                w.light = Some(
                    light_at(&light, &world)
                        .map_err(|m| invalid(format!("{name}, {light_name}"), m))?,
                );
                light_node = Some(name.clone());
            }
        }
    }
    if w.instances.is_empty() {
        return Err(GltfError::NoTriangles { path: path.to_owned() });
    }
    Ok(w)
}

fn camera_label(camera: &gltf::Camera) -> String {
    label("camera", camera.name(), camera.index())
}

/// Resolution for an aspect ratio: 600 pixels high.
fn resolution_for(aspect: f64) -> Option<[u32; 2]> {
    let width = (600.0 * aspect).round();
    (aspect.is_finite() && aspect > 0.0 && (1.0..=16384.0).contains(&width))
        .then_some([width as u32, 600])
}

/// The workbench camera of a glTF camera at a node whose world transform is `world`, and the
/// resolution of its aspect ratio.
fn camera_at(camera: &gltf::Camera, world: &DMat4) -> Result<(Camera, Option<[u32; 2]>), String> {
    let eye = world.w_axis.truncate();
    let target = eye - world.z_axis.truncate();
    let up = world.y_axis.truncate();
    let (camera, aspect) = match camera.projection() {
        gltf::camera::Projection::Perspective(p) => (
            Camera::Perspective {
                eye,
                target,
                up,
                fov_y_deg: f64::from(p.yfov()).to_degrees(),
                near: f64::from(p.znear()),
            },
            p.aspect_ratio().map(f64::from),
        ),
        gltf::camera::Projection::Orthographic(o) => (
            Camera::Orthographic { eye, target, up, height: 2.0 * f64::from(o.ymag()) },
            Some(f64::from(o.xmag()) / f64::from(o.ymag())),
        ),
    };
    camera.validate().map_err(|(key, message)| format!("{} {message}", gltf_name(key)))?;
    let resolution =
        match aspect {
            Some(a) => Some(resolution_for(a).ok_or_else(|| {
                format!("the aspect ratio {a} makes no image of 1 to 16384 pixels")
            })?),
            None => None,
        };
    Ok((camera, resolution))
}

/// What the glTF file calls a camera's or light's value that the workbench's `key` is made of.
fn gltf_name(key: &str) -> &'static str {
    match key {
        "fov_y_deg" => "yfov",
        "near" => "znear",
        "height" => "ymag",
        "eye" | "position" => "the node's origin",
        "target" | "direction" => "the node's -Z axis",
        "up" => "the node's +Y axis",
        "fov_deg" => "twice outerConeAngle",
        _ => "a value",
    }
}

/// The workbench light of a directional or spot light at a node whose world transform is
/// `world`.
fn light_at(light: &gltf::khr_lights_punctual::Light, world: &DMat4) -> Result<Light, String> {
    let axis = -world.z_axis.truncate();
    let light = match light.kind() {
        gltf::khr_lights_punctual::Kind::Spot { outer_cone_angle, .. } => {
            let position = world.w_axis.truncate();
            Light::Spot {
                position,
                target: position + axis,
                fov_deg: (2.0 * f64::from(outer_cone_angle)).to_degrees(),
            }
        }
        // Normalised with the scene (`Light::normalized`), as a scene file's.
        _ => Light::Directional { direction: axis },
    };
    light.validate().map_err(|(key, message)| format!("{} {message}", gltf_name(key)))?;
    Ok(light)
}

/// The workbench material of a glTF material (see the module documentation).
fn material(
    m: &gltf::Material,
    path: &Path,
    notes: &mut Vec<String>,
) -> Result<Material, GltfError> {
    let name = match m.index() {
        Some(i) => label("material", m.name(), i),
        None => return Ok(Material { color: [1.0; 3], opacity: 1.0 }),
    };
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, a] = pbr.base_color_factor().map(f64::from);
    if ![r, g, b, a].iter().all(|c| (0.0..=1.0).contains(c)) {
        return Err(GltfError::Invalid {
            path: path.to_owned(),
            what: name,
            message: format!("baseColorFactor {:?} has a component outside [0, 1]", [r, g, b, a]),
        });
    }
    if pbr.base_color_texture().is_some() {
        note(notes, format!("{name}: its base colour texture is ignored; its factor is used"));
    }
    let opacity = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => 1.0,
        gltf::material::AlphaMode::Blend => a,
        gltf::material::AlphaMode::Mask => {
            if a >= f64::from(m.alpha_cutoff().unwrap_or(0.5)) {
                1.0
            } else {
                0.0
            }
        }
    };
    Ok(Material { color: [r, g, b], opacity })
}

/// The mesh of one instance, in world space.
fn build(
    document: &gltf::Document,
    instance: &Instance,
    data: &Data,
    path: &Path,
) -> Result<Mesh, GltfError> {
    let mesh = mesh_of(document, instance.mesh);
    let primitive = mesh
        .primitives()
        .nth(instance.primitive)
        .unwrap_or_else(|| unreachable!("primitive {} was walked", instance.primitive));
    let p = primitive.index();
    let accessor_error = |accessor: usize, message: String| GltfError::Accessor {
        path: path.to_owned(),
        mesh: mesh_label(&mesh),
        primitive: p,
        accessor,
        message,
    };
    let positions = primitive
        .get(&gltf::Semantic::Positions)
        .unwrap_or_else(|| unreachable!("a walked primitive has POSITION"));
    let points = read_accessor(&positions, data, buffers::Want::Positions)
        .map_err(|m| accessor_error(positions.index(), format!("POSITION {m}")))?;
    let vertices = points.len() / 3;
    if let Some(i) = points.iter().position(|c| !c.is_finite()) {
        return Err(accessor_error(
            positions.index(),
            format!("POSITION of vertex {} is not finite", i / 3),
        ));
    }
    let order: Vec<u32> = match primitive.indices() {
        Some(indices) => {
            let values = read_accessor(&indices, data, buffers::Want::Indices)
                .map_err(|m| accessor_error(indices.index(), format!("indices {m}")))?;
            let mut order = Vec::with_capacity(values.len());
            for v in values {
                // Indices were read from unsigned integers of at most 32 bits.
                let v = v as u32;
                if v as usize >= vertices {
                    return Err(accessor_error(
                        indices.index(),
                        format!("index {v} is out of range: POSITION has {vertices} vertices"),
                    ));
                }
                order.push(v);
            }
            order
        }
        None => (0..vertices as u32).collect(),
    };
    let mode = primitive.mode();
    if mode == Mode::Triangles && !order.len().is_multiple_of(3) {
        let accessor = primitive.indices().map_or(positions.index(), |a| a.index());
        return Err(accessor_error(
            accessor,
            format!("count {} is not a multiple of 3, as TRIANGLES needs", order.len()),
        ));
    }
    let corners: Vec<[u32; 3]> = match mode {
        Mode::Triangles => order.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
        Mode::TriangleStrip => (0..order.len().saturating_sub(2))
            .map(|i| {
                let odd = i % 2;
                [order[i], order[i + 1 + odd], order[i + 2 - odd]]
            })
            .collect(),
        Mode::TriangleFan => (0..order.len().saturating_sub(2))
            .map(|i| [order[i + 1], order[i + 2], order[0]])
            .collect(),
        // `walk` hands over triangle primitives only.
        Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip => Vec::new(),
    };
    // The vertices the triangles use, in order of first use.
    let (triangles, used) = crate::mesh::numbered_by_first_use(corners, vertices);
    let kept = used
        .iter()
        .map(|&v| {
            let i = 3 * v as usize;
            DVec3::new(points[i], points[i + 1], points[i + 2])
        })
        .collect();
    let mut mesh = Mesh { positions: kept, triangles };
    mesh.transform(&instance.world);
    if mesh.positions.iter().any(|p| !p.is_finite()) {
        let node = document.nodes().nth(instance.node);
        return Err(GltfError::Invalid {
            path: path.to_owned(),
            what: node.as_ref().map_or_else(|| "a node".into(), node_label),
            message: "its transform makes the coordinates overflow".into(),
        });
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_counts_follow_the_mode() {
        assert_eq!(triangles_of(Mode::Triangles, 7), Some(2));
        assert_eq!(triangles_of(Mode::TriangleStrip, 5), Some(3));
        assert_eq!(triangles_of(Mode::TriangleFan, 2), Some(0));
        assert_eq!(triangles_of(Mode::Lines, 6), None);
        assert_eq!(triangles_of(Mode::Points, 6), None);
    }

    #[test]
    fn the_aspect_ratio_sets_a_resolution_600_pixels_high() {
        assert_eq!(resolution_for(f64::from(4.0f32 / 3.0)), Some([800, 600]));
        assert_eq!(resolution_for(1.5), Some([900, 600]));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e-4, 1e3] {
            assert_eq!(resolution_for(bad), None, "{bad}");
        }
    }

    #[test]
    fn a_bad_camera_or_light_is_named_in_the_files_terms() {
        let doc = |camera: &str| {
            let json = format!(
                r#"{{"asset": {{"version": "2.0"}}, "extensionsUsed": ["KHR_lights_punctual"],
                "extensions": {{"KHR_lights_punctual": {{"lights": [
                    {{"type": "spot", "spot": {{"outerConeAngle": 1.5}}}}]}}}},
                "cameras": [{camera}]}}"#
            );
            let root = gltf::json::deserialize::from_slice(json.as_bytes()).expect("parses");
            gltf::Document::from_json(root).expect("valid")
        };
        let d = doc(r#"{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0}}"#);
        let camera = d.cameras().next().expect("a camera");
        let err = camera_at(&camera, &DMat4::IDENTITY).expect_err("znear 0");
        assert_eq!(err, "znear must be positive and finite, got 0");
        let light = d.lights().and_then(|mut l| l.next()).expect("a light");
        let err = light_at(&light, &DMat4::IDENTITY).expect_err("a cone of 172 degrees");
        assert!(err.starts_with("twice outerConeAngle must be in (0, 170]"), "{err}");
    }
}
