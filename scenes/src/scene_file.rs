//! Scene files (TOML, serde) and their resolution into [`Scene`]s.
//!
//! ```toml
//! name = "my-scene"                 # optional; defaults to the file stem
//! resolution = [800, 600]           # default image size
//! [camera.perspective]              # or [camera.orthographic] with `height`
//! eye = [0.0, 8.0, 12.0]
//! target = [0.0, 0.0, 0.0]
//! fov_y_deg = 45.0
//! [light.directional]               # or [light.spot] with position, target, fov_deg
//! direction = [-1.0, -2.0, -0.5]
//! [effects]                         # optional: force derived effects off
//! curved_receivers = false
//! [[object]]
//! name = "ground"
//! shape.plane = { size = 20.0 }     # a generator and its parameters
//! [[object]]
//! shape.file = { path = "bunny00.off" }   # beside this file, else in the models folder
//! transform = { fit_size = 4.0, on_ground = true, rotate_deg = [0.0, 30.0, 0.0] }
//! material = { color = [0.9, 0.6, 0.3], opacity = 1.0 }
//! [animation]                       # optional: how the scene moves (see `crate::animation`)
//! frames = 24
//! [[animation.light]]
//! time = 0.0
//! direction = [-1.0, -2.0, 0.5]
//! ```
//!
//! Camera, light and shape are tables named after their kind (serde's external tagging), so
//! that every parse error points at the offending key or value with its line.
//! Unknown keys and bad values are errors naming the file and the key. An error found after
//! parsing (a value out of range, a mesh file missing or malformed) names, when the file's text
//! is at hand ([`SceneDesc::load`], [`crate::registry::describe`]), the line the key is written
//! on and the key as written (`camera.perspective.eye`, not the resolution's `camera.eye`). A transform applies,
//! in order: `scale`, `rotate_deg` (about x, then y, then z), `fit_size` (centre the bounds on
//! the origin and scale uniformly so the largest extent equals it), `on_ground` (lift so the
//! lowest point is at y = 0), `translate`. The fit is exact in scale for any finite mesh with a
//! non-zero extent, from subnormal coordinates to ±1.7e308: the mesh is first scaled by a
//! power of two (exact), so that its bounds, extent and centre neither overflow nor underflow.
//!
//! Resolution refuses, as [`SceneError::OutOfRange`], a scene beyond the range every method
//! supports ([`crate::limits`]): a camera eye or target, a spot light's position or target, or
//! a resolved vertex with a coordinate beyond `MAX_COORDINATE`, or geometry whose bounding box
//! has a diagonal under `MIN_EXTENT`; the message gives the value with as many digits as it
//! takes to differ from the bound. A resolved scene's directional light has a unit direction.
//! The `[animation]` table is resolved last, against the built scene
//! ([`crate::animation::Animation::resolve`]); its errors name the key as written
//! (`animation.light[2].time`) and its line, as the others do.
//!
//! Before any mesh is built, resolution checks every object's parameters and mesh file and
//! bounds the scene's triangles ([`SceneDesc::triangles`]: generators count theirs from their
//! parameters, mesh files are bounded from their headers and sizes by
//! [`crate::io::triangle_bound`]). A scene whose generated objects exceed
//! [`MAX_SCENE_TRIANGLES`] is refused as [`SceneError::TooManyTriangles`] before anything is
//! built, naming the count, the limit and its largest object; mesh files, whose bounds from
//! text files are loose (up to 17 times the count), are held to the limit by their real counts
//! once loaded, so that no mesh that fits is refused.
//!
//! Mesh paths are looked for in a list of folders, in order; the first that holds the path is
//! used (a folder there is refused as a folder, not skipped). A scene file's list is its own
//! folder, then the models folder ([`crate::models`]; [`SceneDesc::mesh_folders`]), so that a
//! scene file naming `bunny00.off` works wherever it is copied; a missing file is named with
//! every place looked in. An empty path is refused as such.

use crate::{
    animation::{Animation, AnimationDesc, AnimationError},
    camera::Camera,
    generators::{
        CageParams, CityParams, Generator, HairballParams, HeightfieldParams, ParamError,
        PlaneParams, PlantParams, RandomTrianglesParams, SpheresParams,
    },
    io::{load_mesh, triangle_bound, LoadError},
    light::Light,
    limits::{below_extent, beyond_range, MAX_SCENE_TRIANGLES},
    mesh::Mesh,
    models::models_dir,
    scene::{EffectSwitches, Material, Object, Scene},
};
use glam::{DMat4, DVec3, EulerRot};
use serde::{Deserialize, Serialize};
use std::num::NonZeroU32;
use std::path::{Path, PathBuf};

/// Where an object's mesh comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Shape {
    /// A square ground plane.
    Plane(PlaneParams),
    /// Random triangles of constant total area.
    RandomTriangles(RandomTrianglesParams),
    /// A cage of thin bars.
    Cage(CageParams),
    /// Spheres.
    Spheres(SpheresParams),
    /// A city of boxes.
    City(CityParams),
    /// A plant of thin leaves.
    Plant(PlantParams),
    /// A bumpy heightfield receiver.
    Heightfield(HeightfieldParams),
    /// A hair ball of thin strands.
    Hairball(HairballParams),
    /// A mesh file (.obj, .off, .ply), or a glTF file (.gltf, .glb) whose triangle primitives,
    /// in world space, make one mesh (its cameras and lights are ignored), relative to the
    /// scene file.
    File(FileShape),
}

/// A mesh file reference.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FileShape {
    /// Path of the mesh file, relative to the scene file, else to the models folder (only the
    /// models folder for built-in scenes).
    pub path: PathBuf,
}

/// How an object is placed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Transform {
    /// Per-axis scale (default `[1, 1, 1]`).
    #[serde(deserialize_with = "crate::arrays::dvec3")]
    pub scale: DVec3,
    /// Rotation in degrees about x, then y, then z (default zero).
    #[serde(deserialize_with = "crate::arrays::dvec3")]
    pub rotate_deg: DVec3,
    /// If set, centre the bounds on the origin and scale so the largest extent equals this.
    pub fit_size: Option<f64>,
    /// Lift the object so its lowest point is at y = 0 (default false).
    pub on_ground: bool,
    /// Translation (default zero).
    #[serde(deserialize_with = "crate::arrays::dvec3")]
    pub translate: DVec3,
}

impl Default for Transform {
    fn default() -> Self {
        Self {
            scale: DVec3::ONE,
            rotate_deg: DVec3::ZERO,
            fit_size: None,
            on_ground: false,
            translate: DVec3::ZERO,
        }
    }
}

fn default_true() -> bool {
    true
}

fn is_default<T: Default + PartialEq>(v: &T) -> bool {
    *v == T::default()
}

/// One object of a scene file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    /// Name (default: the shape's kind and index).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Where the mesh comes from.
    pub shape: Shape,
    /// Placement.
    #[serde(default, skip_serializing_if = "is_default")]
    pub transform: Transform,
    /// Material.
    #[serde(default)]
    pub material: Material,
    /// Whether the object blocks light (default true).
    #[serde(default = "default_true")]
    pub casts_shadows: bool,
}

fn default_resolution() -> [u32; 2] {
    [800, 600]
}

/// A scene as written in a scene file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    /// Scene name (default: the file stem).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Default image size `[width, height]` (default `[800, 600]`).
    #[serde(default = "default_resolution", deserialize_with = "crate::arrays::exact")]
    pub resolution: [u32; 2],
    /// Camera.
    pub camera: Camera,
    /// Light.
    pub light: Light,
    /// Effects forced off.
    #[serde(default, skip_serializing_if = "is_default")]
    pub effects: EffectSwitches,
    /// Objects, in order (`[[object]]`).
    #[serde(rename = "object")]
    pub objects: Vec<ObjectDesc>,
    /// How the scene moves (`[animation]`, [`crate::animation`]; default: still).
    #[serde(default, skip_serializing_if = "is_default")]
    pub animation: AnimationDesc,
}

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The scene file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The scene file is not valid TOML or does not match the format (names line and key).
    #[error("{path}: {message}")]
    Parse {
        /// The scene file.
        path: PathBuf,
        /// The parser's message, with line and column.
        message: String,
    },
    /// A value is out of range.
    #[error("{path}: {}`{key}`: {message}", Line(*.line))]
    Invalid {
        /// The scene file (or `builtin:NAME`).
        path: PathBuf,
        /// The 1-based line of the scene file where the key is written (or, when the value is a
        /// default, the line of the table that lacks it), when the file's text is at hand.
        line: Option<NonZeroU32>,
        /// The key, e.g. `object[1].shape.count`.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// The scene lies beyond the supported range of coordinates or sizes ([`crate::limits`]).
    #[error("{path}: {}`{key}`: {message}", Line(*.line))]
    OutOfRange {
        /// The scene file, mesh file or `builtin:NAME`.
        path: PathBuf,
        /// The line of the scene file where the key is written, as for `Invalid`.
        line: Option<NonZeroU32>,
        /// The key, e.g. `camera.eye` or `object[1]`.
        key: String,
        /// What is out of range, with the value and the supported range.
        message: String,
    },
    /// A mesh file referenced by the scene could not be loaded.
    #[error("{path}: {}`{key}`: {source}", Line(*.line))]
    Mesh {
        /// The scene file.
        path: PathBuf,
        /// The line of the scene file where the key is written, as for `Invalid`.
        line: Option<NonZeroU32>,
        /// The key, e.g. `object[1].shape.file.path`.
        key: String,
        /// The loader's error (names the mesh file and line).
        source: Box<LoadError>,
    },
    /// The mesh file given as the scene could not be loaded: the loader's error alone, which
    /// names the file and line (the scene made around it is no concern of the user's).
    #[error("{source}")]
    MeshFile {
        /// The loader's error.
        source: LoadError,
    },
    /// The scene file named is a folder.
    #[error("{path}: is a folder, not a scene file")]
    Folder {
        /// The folder.
        path: PathBuf,
    },
    /// A model the scene needs is not present.
    #[error(
        "{path}: {}`{key}`: scene `{scene}` needs {model}, which is missing (looked for {}){}",
        Line(*.line),
        Places(.looked),
        if *.fetch { FETCH_HINT } else { "" }
    )]
    ModelMissing {
        /// The scene file (or `builtin:NAME`).
        path: PathBuf,
        /// The line of the scene file where the key is written, as for `Invalid`.
        line: Option<NonZeroU32>,
        /// The key, e.g. `object[1].shape.file.path`.
        key: String,
        /// The scene.
        scene: String,
        /// The missing file, as the scene names it.
        model: PathBuf,
        /// Every path it was looked for at, in order.
        looked: Box<[PathBuf]>,
        /// Whether it was looked for in the models folder, which `scripts/fetch-models` fills:
        /// the message then says so.
        fetch: bool,
    },
    /// The scene may have more triangles than [`MAX_SCENE_TRIANGLES`]: refused before any mesh
    /// is built.
    #[error(
        "{path}: the scene has {triangles} triangles, more than the limit of {limit} (the \
         largest object, {largest}, has {largest_triangles}); {}",
        if *.from_file { "use a smaller mesh" } else { "lower the generators' counts" }
    )]
    TooManyTriangles {
        /// The scene file, mesh file or `builtin:NAME`.
        path: PathBuf,
        /// The scene's triangles (its generated objects' before anything is built, all of
        /// them once its mesh files are loaded).
        triangles: u64,
        /// The limit.
        limit: u64,
        /// The object with the most triangles: its key, and its mesh file if it has one, e.g.
        /// `` `object[3]` (bunny.obj) ``; for a mesh file given as the scene, the file.
        largest: String,
        /// Its triangles.
        largest_triangles: u64,
        /// Whether that object is a mesh file.
        from_file: bool,
    },
    /// The glTF file given as the scene cannot be read, or a scene cannot be written as glTF:
    /// the glTF error alone, which names the file and the node, mesh, accessor, buffer or
    /// extension at fault.
    #[error(transparent)]
    Gltf(Box<crate::gltf_file::GltfError>),
    /// No built-in scene has this name and no file has this path.
    #[error("unknown scene `{name}`: not a built-in scene (known: {known}) nor a .toml, .gltf, .glb, .obj, .off or .ply file")]
    Unknown {
        /// What was asked for.
        name: String,
        /// The built-in names.
        known: String,
    },
}

impl From<crate::gltf_file::GltfError> for SceneError {
    fn from(e: crate::gltf_file::GltfError) -> Self {
        Self::Gltf(Box::new(e))
    }
}

impl SceneDesc {
    /// Parses a scene file's text; `path` is used in messages.
    pub fn from_toml(text: &str, path: &Path) -> Result<Self, SceneError> {
        toml::from_str(text)
            .map_err(|e| SceneError::Parse { path: path.to_owned(), message: e.to_string() })
    }

    /// The scene file text of this description.
    pub fn to_toml(&self) -> String {
        // Every field serializes; a failure would be an internal error of the format.
        toml::to_string_pretty(self).unwrap_or_else(|e| format!("# cannot serialize: {e}\n"))
    }

    /// Reads and parses a scene file; a folder is refused as such.
    pub fn read(path: &Path) -> Result<Self, SceneError> {
        Self::read_with_text(path).map(|(desc, _)| desc)
    }

    /// [`Self::read`], with the file's text, which [`SceneError::located`] needs.
    pub(crate) fn read_with_text(path: &Path) -> Result<(Self, String), SceneError> {
        if path.is_dir() {
            return Err(SceneError::Folder { path: path.to_owned() });
        }
        let text = std::fs::read_to_string(path)
            .map_err(|source| SceneError::Io { path: path.to_owned(), source })?;
        Ok((Self::from_toml(&text, path)?, text))
    }

    /// Where the mesh paths of the scene file `path` are looked for: its folder, made absolute
    /// (so that a missing mesh's message names the very place looked in, whatever the working
    /// folder), then the models folder.
    pub fn mesh_folders(path: &Path) -> Vec<PathBuf> {
        let folder = path.parent().unwrap_or(Path::new("."));
        vec![std::path::absolute(folder).unwrap_or_else(|_| folder.to_owned()), models_dir()]
    }

    /// Reads and resolves a scene file, its mesh paths looked for in [`Self::mesh_folders`].
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let (desc, text) = Self::read_with_text(path)?;
        let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned());
        desc.resolve_in(stem.as_deref().unwrap_or("scene"), path, &Self::mesh_folders(path))
            .map_err(|e| e.located(&text, &desc))
    }

    /// Builds the scene: generates or loads every mesh and places it. `origin` names the file
    /// in messages; mesh paths are relative to `base`.
    pub fn resolve(
        &self,
        default_name: &str,
        origin: &Path,
        base: &Path,
    ) -> Result<Scene, SceneError> {
        self.resolve_in(default_name, origin, &[base.to_owned()])
    }

    /// An upper bound of the scene's triangles, with nothing built: each generator's count
    /// from its parameters (which are checked), each mesh file's bound from its header and
    /// size ([`crate::io::triangle_bound`]), mesh paths looked for in `folders`.
    /// `default_name` and `origin` are as for [`Self::resolve_in`].
    pub fn triangles(
        &self,
        default_name: &str,
        origin: &Path,
        folders: &[PathBuf],
    ) -> Result<u64, SceneError> {
        let counts = self.object_triangles(default_name, origin, folders)?;
        Ok(counts.iter().fold(0, |n, &t| n.saturating_add(t)))
    }

    /// [`Self::triangles`] of each object.
    fn object_triangles(
        &self,
        default_name: &str,
        origin: &Path,
        folders: &[PathBuf],
    ) -> Result<Vec<u64>, SceneError> {
        let scene = self.name.as_deref().unwrap_or(default_name);
        self.objects
            .iter()
            .enumerate()
            .map(|(i, o)| o.shape.triangles(folders).map_err(|e| e.at(i, origin, scene)))
            .collect()
    }

    /// Refuses the scene when `counts` (its objects' triangles) add up to more than
    /// [`MAX_SCENE_TRIANGLES`], naming the largest object.
    fn check_triangles(&self, origin: &Path, counts: &[u64]) -> Result<(), SceneError> {
        let total = counts.iter().fold(0u64, |n, &t| n.saturating_add(t));
        if total <= MAX_SCENE_TRIANGLES {
            return Ok(());
        }
        // The first of the largest (`max_by_key` keeps the last).
        let (largest, &largest_triangles) =
            counts.iter().enumerate().rev().max_by_key(|&(_, t)| *t).unwrap_or((0, &0));
        Err(SceneError::TooManyTriangles {
            path: origin.to_owned(),
            triangles: total,
            limit: MAX_SCENE_TRIANGLES,
            largest: match &self.objects[largest].shape {
                Shape::File(f) => format!("`object[{largest}]` ({})", f.path.display()),
                _ => format!("`object[{largest}]`"),
            },
            largest_triangles,
            from_file: matches!(self.objects[largest].shape, Shape::File(_)),
        })
    }

    /// Builds the scene: checks it, bounds its generated objects' triangles against
    /// [`MAX_SCENE_TRIANGLES`] before anything is built (mesh files' real counts after they
    /// are loaded), then generates or loads every mesh and places it. `origin` names the file in messages; mesh
    /// paths are looked for in `folders`, in order.
    pub fn resolve_in(
        &self,
        default_name: &str,
        origin: &Path,
        folders: &[PathBuf],
    ) -> Result<Scene, SceneError> {
        let invalid = |key: String, message: String| SceneError::Invalid {
            path: origin.to_owned(),
            line: None,
            key,
            message,
        };
        let [width, height] = self.resolution;
        if !(1..=16384).contains(&width) || !(1..=16384).contains(&height) {
            return Err(invalid("resolution".into(), "each side must be in 1..=16384".into()));
        }
        self.camera.validate().map_err(|(k, m)| invalid(format!("camera.{k}"), m))?;
        self.light.validate().map_err(|(k, m)| invalid(format!("light.{k}"), m))?;
        let out_of_range = |key: String, message: String| SceneError::OutOfRange {
            path: origin.to_owned(),
            line: None,
            key,
            message,
        };
        let mut points =
            vec![("camera.eye", self.camera.eye()), ("camera.target", self.camera.target())];
        if let Light::Spot { position, target, .. } = self.light {
            points.extend([("light.position", position), ("light.target", target)]);
        }
        for (key, p) in points {
            if let Some(message) = beyond_range(p.abs().max_element()) {
                return Err(out_of_range(key.into(), message));
            }
        }
        if self.objects.is_empty() {
            return Err(invalid("object".into(), "a scene needs at least one [[object]]".into()));
        }
        for (i, o) in self.objects.iter().enumerate() {
            let m = &o.material;
            if !m.color.iter().all(|c| (0.0..=1.0).contains(c)) {
                return Err(invalid(
                    format!("object[{i}].material.color"),
                    "components must be in [0, 1]".into(),
                ));
            }
            if !(0.0..=1.0).contains(&m.opacity) {
                return Err(invalid(
                    format!("object[{i}].material.opacity"),
                    format!("must be in [0, 1], got {}", m.opacity),
                ));
            }
        }
        let name = self.name.clone().unwrap_or_else(|| default_name.to_owned());
        let counts = self.object_triangles(&name, origin, folders)?;
        // Generators' counts are exact and refuse the scene before anything is built; mesh
        // files' bounds can be loose (text files: up to 17 times the count), so their real
        // counts are checked once they are loaded, and no mesh that fits is refused.
        let generated: Vec<u64> = counts
            .iter()
            .zip(&self.objects)
            .map(|(&t, o)| if matches!(o.shape, Shape::File(_)) { 0 } else { t })
            .collect();
        self.check_triangles(origin, &generated)?;
        let mut objects = Vec::with_capacity(self.objects.len());
        for (i, o) in self.objects.iter().enumerate() {
            let key = |k: &str| format!("object[{i}].{k}");
            let mut mesh = o.shape.build(folders).map_err(|e| e.at(i, origin, &name))?;
            o.transform
                .apply(&mut mesh)
                .map_err(|(k, msg)| invalid(key(&format!("transform.{k}")), msg))?;
            let object_name = o.name.clone().unwrap_or_else(|| format!("{}{i}", o.shape.kind()));
            let largest = mesh
                .positions
                .iter()
                .map(|p| if p.is_finite() { p.abs().max_element() } else { f64::INFINITY })
                .fold(0.0, f64::max);
            if let Some(message) = beyond_range(largest) {
                let from = match &o.shape {
                    Shape::File(f) => format!(" ({})", f.path.display()),
                    _ => String::new(),
                };
                return Err(out_of_range(
                    format!("object[{i}]"),
                    format!("object `{object_name}`{from}: {message}"),
                ));
            }
            objects.push(Object {
                name: object_name,
                mesh,
                material: o.material,
                casts_shadows: o.casts_shadows,
            });
        }
        let built: Vec<u64> = objects.iter().map(|o| o.mesh.triangle_count() as u64).collect();
        self.check_triangles(origin, &built)?;
        let mut scene = Scene {
            name,
            width,
            height,
            camera: self.camera.clone(),
            light: self.light.normalized(),
            objects,
            switches: self.effects,
            animation: Animation::still(),
        };
        if let Some(message) = too_small(&scene) {
            return Err(out_of_range("object".into(), message));
        }
        scene.animation = Animation::resolve(&self.animation, &scene).map_err(|e| match e {
            AnimationError::Invalid { key, message } => invalid(key, message),
            AnimationError::OutOfRange { key, message } => out_of_range(key, message),
            e @ AnimationError::Frames { .. } => invalid("animation.frames".into(), e.to_string()),
        })?;
        Ok(scene)
    }
}

/// Why the scene's geometry is below the smallest supported extent, if it is.
fn too_small(scene: &Scene) -> Option<String> {
    let (lo, hi) = scene.bounds();
    below_extent((hi - lo).length())
}

/// Checks a scene built from elsewhere than a scene file (a glTF scene) as [`SceneDesc::resolve_in`]
/// checks its own: the whole-scene triangle limit, the coordinate range of the camera, the
/// spot light and every object, and the smallest extent ([`crate::limits`]). Keys name the
/// camera, the light or the object by its name.
pub(crate) fn check_resolved(scene: &Scene, origin: &Path) -> Result<(), SceneError> {
    let out_of_range = |key: String, message: String| SceneError::OutOfRange {
        path: origin.to_owned(),
        line: None,
        key,
        message,
    };
    let triangles = scene.triangle_count() as u64;
    if triangles > MAX_SCENE_TRIANGLES {
        let largest = scene.objects.iter().rev().max_by_key(|o| o.mesh.triangle_count());
        return Err(SceneError::TooManyTriangles {
            path: origin.to_owned(),
            triangles,
            limit: MAX_SCENE_TRIANGLES,
            largest: largest.map_or_else(String::new, |o| format!("`{}`", o.name)),
            largest_triangles: largest.map_or(0, |o| o.mesh.triangle_count() as u64),
            from_file: true,
        });
    }
    let mut points = vec![("camera", scene.camera.eye()), ("camera", scene.camera.target())];
    if let Light::Spot { position, target, .. } = scene.light {
        points.extend([("light", position), ("light", target)]);
    }
    for (key, p) in points {
        if let Some(message) = beyond_range(p.abs().max_element()) {
            return Err(out_of_range(key.into(), message));
        }
    }
    for o in &scene.objects {
        let largest = o.mesh.positions.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
        if let Some(message) = beyond_range(largest) {
            return Err(out_of_range(o.name.clone(), message));
        }
    }
    match too_small(scene) {
        Some(message) => Err(out_of_range("object".into(), message)),
        None => Ok(()),
    }
}

/// What [`SceneError::ModelMissing`] adds when the model was looked for in the models folder.
const FETCH_HINT: &str = "; if it is one of CGAL's sample meshes, run `scripts/fetch-models` to \
                          fetch them into the models folder";

/// Formats `line N: ` when a line is known.
struct Line(Option<NonZeroU32>);

impl std::fmt::Display for Line {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0 {
            Some(line) => write!(f, "line {line}: "),
            None => Ok(()),
        }
    }
}

impl SceneError {
    /// The error as the user of the scene file `text` (which `desc` was parsed from) should
    /// read it: a key as written in the file (`camera.eye` is written
    /// `camera.perspective.eye`, a generator's `shape.count` `shape.random_triangles.count`),
    /// with the line it is written on ([`crate::toml_lines`]).
    pub(crate) fn located(self, text: &str, desc: &SceneDesc) -> Self {
        let place = |key: String| {
            let written = desc.written_key(&key);
            (
                crate::toml_lines::line_of(text, &written)
                    .and_then(|l| u32::try_from(l).ok())
                    .and_then(NonZeroU32::new),
                written,
            )
        };
        match self {
            Self::Invalid { path, key, message, .. } => {
                let (line, key) = place(key);
                Self::Invalid { path, line, key, message }
            }
            Self::OutOfRange { path, key, message, .. } => {
                let (line, key) = place(key);
                Self::OutOfRange { path, line, key, message }
            }
            Self::Mesh { path, key, source, .. } => {
                let (line, key) = place(key);
                Self::Mesh { path, line, key, source }
            }
            Self::ModelMissing { path, key, scene, model, looked, fetch, .. } => {
                let (line, key) = place(key);
                Self::ModelMissing { path, line, key, scene, model, looked, fetch }
            }
            e => e,
        }
    }
}

impl SceneDesc {
    /// `key`, as the resolution names it, as written in the scene file: the camera's, the
    /// light's and a generator's tables are named after their kind.
    fn written_key(&self, key: &str) -> String {
        let camera = match self.camera {
            Camera::Perspective { .. } => "perspective",
            Camera::Orthographic { .. } => "orthographic",
        };
        let light = match self.light {
            Light::Directional { .. } => "directional",
            Light::Spot { .. } => "spot",
        };
        if let Some(rest) = key.strip_prefix("camera.") {
            return format!("camera.{camera}.{rest}");
        }
        if let Some(rest) = key.strip_prefix("light.") {
            return format!("light.{light}.{rest}");
        }
        if let Some((object, rest)) = key.split_once(".shape.") {
            let kind = object
                .strip_prefix("object[")
                .and_then(|i| i.strip_suffix(']'))
                .and_then(|i| i.parse::<usize>().ok())
                .and_then(|i| self.objects.get(i))
                .map(|o| o.shape.kind());
            if let Some(kind) = kind {
                if !rest.starts_with(&format!("{kind}.")) {
                    return format!("{object}.shape.{kind}.{rest}");
                }
            }
        }
        key.to_owned()
    }
}

/// Paths joined by commas and a final `and`, for messages.
struct Places<'a>(&'a [PathBuf]);

impl std::fmt::Display for Places<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (i, path) in self.0.iter().enumerate() {
            let sep = match i {
                0 => "",
                _ if i + 1 == self.0.len() => " and ",
                _ => ", ",
            };
            write!(f, "{sep}{}", path.display())?;
        }
        Ok(())
    }
}

/// Why an object's shape cannot be counted or built.
enum ShapeError {
    Param(ParamError),
    EmptyPath,
    Missing { model: PathBuf, looked: Vec<PathBuf> },
    Load(LoadError),
}

impl ShapeError {
    /// The scene's error for object `i` of scene `scene` in `origin`.
    fn at(self, i: usize, origin: &Path, scene: &str) -> SceneError {
        let path = origin.to_owned();
        let key = |k: &str| format!("object[{i}].{k}");
        match self {
            ShapeError::Param(p) => SceneError::Invalid {
                path,
                line: None,
                key: key(&format!("shape.{}", p.key)),
                message: p.message,
            },
            ShapeError::EmptyPath => SceneError::Invalid {
                path,
                line: None,
                key: key("shape.file.path"),
                message: "the path is empty: name a .obj, .off, .ply, .gltf or .glb file".into(),
            },
            ShapeError::Missing { model, looked } => {
                let models = models_dir();
                let fetch = looked.iter().any(|p| p.starts_with(&models));
                SceneError::ModelMissing {
                    path,
                    line: None,
                    key: key("shape.file.path"),
                    scene: scene.to_owned(),
                    model,
                    looked: looked.into(),
                    fetch,
                }
            }
            ShapeError::Load(source) => SceneError::Mesh {
                path,
                line: None,
                key: key("shape.file.path"),
                source: Box::new(source),
            },
        }
    }
}

impl Shape {
    /// The shape's kind as written in scene files.
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Plane(_) => "plane",
            Shape::RandomTriangles(_) => "random_triangles",
            Shape::Cage(_) => "cage",
            Shape::Spheres(_) => "spheres",
            Shape::City(_) => "city",
            Shape::Plant(_) => "plant",
            Shape::Heightfield(_) => "heightfield",
            Shape::Hairball(_) => "hairball",
            Shape::File(_) => "file",
        }
    }

    /// The generator, or the mesh file's path as written.
    fn source(&self) -> Result<&dyn Generator, &Path> {
        Ok(match self {
            Shape::Plane(p) => p,
            Shape::RandomTriangles(p) => p,
            Shape::Cage(p) => p,
            Shape::Spheres(p) => p,
            Shape::City(p) => p,
            Shape::Plant(p) => p,
            Shape::Heightfield(p) => p,
            Shape::Hairball(p) => p,
            Shape::File(f) => return Err(&f.path),
        })
    }

    /// An upper bound of the triangles [`Self::build`] makes, with the generator's parameters
    /// checked and the mesh file found, but nothing built.
    fn triangles(&self, folders: &[PathBuf]) -> Result<u64, ShapeError> {
        match self.source() {
            Ok(generator) => {
                generator.validate().map_err(ShapeError::Param)?;
                Ok(generator.triangle_count())
            }
            Err(path) => triangle_bound(&find(path, folders)?).map_err(ShapeError::Load),
        }
    }

    fn build(&self, folders: &[PathBuf]) -> Result<Mesh, ShapeError> {
        match self.source() {
            Ok(generator) => {
                generator.validate().map_err(ShapeError::Param)?;
                Ok(generator.generate())
            }
            // A file's triangles are kept in a spatial order (see `spatial_order`).
            Err(path) => load_mesh(&find(path, folders)?)
                .map(crate::spatial_order::spatially_ordered)
                .map_err(ShapeError::Load),
        }
    }
}

/// The mesh file `path` (as a scene names it): the first of `folders` that holds it (a folder
/// found there is the loader's to refuse), or every place it was looked for.
fn find(path: &Path, folders: &[PathBuf]) -> Result<PathBuf, ShapeError> {
    if path.as_os_str().is_empty() {
        return Err(ShapeError::EmptyPath);
    }
    let mut looked: Vec<PathBuf> = Vec::with_capacity(folders.len());
    for folder in folders {
        let candidate = folder.join(path);
        if candidate.exists() {
            return Ok(candidate);
        }
        if !looked.contains(&candidate) {
            looked.push(candidate);
        }
    }
    Err(ShapeError::Missing { model: path.to_owned(), looked })
}

impl Transform {
    /// Applies the transform to `mesh`; errors name the bad key.
    pub fn apply(&self, mesh: &mut Mesh) -> Result<(), (&'static str, String)> {
        for (key, v) in
            [("scale", self.scale), ("rotate_deg", self.rotate_deg), ("translate", self.translate)]
        {
            if !v.is_finite() {
                return Err((key, "must be finite".into()));
            }
        }
        if self.scale.cmpeq(DVec3::ZERO).any() {
            return Err(("scale", "must not be zero on any axis".into()));
        }
        if let Some(size) = self.fit_size {
            if !(size > 0.0 && size.is_finite()) {
                return Err(("fit_size", format!("must be positive and finite, got {size}")));
            }
        }
        let r = self.rotate_deg;
        let rotate =
            DMat4::from_euler(EulerRot::ZYX, r.z.to_radians(), r.y.to_radians(), r.x.to_radians());
        if self.fit_size.is_some() {
            // The fit undoes any uniform scale: bring the coordinates near 1 first, so that
            // scaling and rotating a mesh near ±1e308 does not overflow.
            scale_by_power_of_two(mesh, -exponent(largest_magnitude(mesh)));
        }
        mesh.transform(&(rotate * DMat4::from_scale(self.scale)));
        if mesh.positions.iter().any(|p| !p.is_finite()) {
            return Err(("scale", "scaling and rotating make the coordinates overflow".into()));
        }
        if let Some(size) = self.fit_size {
            fit(mesh, size).map_err(|message| ("fit_size", message))?;
        }
        if self.on_ground {
            if let Some((lo, _)) = mesh.bounds() {
                mesh.transform(&DMat4::from_translation(DVec3::new(0.0, -lo.y, 0.0)));
            }
        }
        mesh.transform(&DMat4::from_translation(self.translate));
        Ok(())
    }
}

/// Centres `mesh`'s bounds on the origin and scales it uniformly so that its largest extent is
/// `size` (finite and positive); a mesh whose vertices are all one point has no extent to fit
/// and is refused. Exact in scale for any finite mesh: powers of two bring first its
/// coordinates and then its extent near 1, so that neither the extent nor the centre overflows
/// and the scale factor neither overflows nor underflows, whether the coordinates are near
/// ±1e308 or subnormal.
fn fit(mesh: &mut Mesh, size: f64) -> Result<(), String> {
    scale_by_power_of_two(mesh, -exponent(largest_magnitude(mesh)));
    let Some((lo, hi)) = mesh.bounds() else { return Ok(()) };
    // Coordinates below 2 in magnitude: the extent is below 4, the centre exact.
    let extent = (hi - lo).max_element();
    if extent == 0.0 {
        return Err("the mesh has no extent to fit: its vertices are all one point".into());
    }
    let centre = 0.5 * (lo + hi);
    for p in &mut mesh.positions {
        *p -= centre;
    }
    let k = exponent(extent);
    scale_by_power_of_two(mesh, -k);
    // The extent is now in [1, 2): the factor is finite, and no coordinate overflows.
    let s = size / times_power_of_two(DVec3::splat(extent), -k).x;
    for p in &mut mesh.positions {
        *p *= s;
    }
    Ok(())
}

/// The largest magnitude of any coordinate of `mesh` (0 without vertices).
fn largest_magnitude(mesh: &Mesh) -> f64 {
    mesh.positions.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max)
}

/// The exponent `k` with `2^k <= m < 2^(k+1)` of a finite positive `m` (subnormal included),
/// read from its bits; 0 for 0.
fn exponent(m: f64) -> i32 {
    let bits = m.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let mantissa = bits & ((1 << 52) - 1);
    match (biased, mantissa) {
        (0, 0) => 0,
        (0, _) => -1074 + 63 - mantissa.leading_zeros() as i32,
        _ => biased - 1023,
    }
}

/// Multiplies every coordinate of `mesh` by `2^k` ([`times_power_of_two`]).
fn scale_by_power_of_two(mesh: &mut Mesh, k: i32) {
    for p in &mut mesh.positions {
        *p = times_power_of_two(*p, k);
    }
}

/// `v * 2^k`, in steps of at most `2^±1000` (each exact unless it underflows), so that `2^k`
/// itself need not be an `f64`.
fn times_power_of_two(mut v: DVec3, mut k: i32) -> DVec3 {
    while k != 0 {
        let step = k.clamp(-1000, 1000);
        v *= 2f64.powi(step);
        k -= step;
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scene file's text: a camera, a light and `objects` (`[[object]]` tables).
    fn scene(objects: &str) -> SceneDesc {
        let text = format!(
            "[camera.perspective]\neye = [0.0, 6.0, 8.0]\ntarget = [0.0, 0.0, 0.0]\n\
             fov_y_deg = 45.0\n[light.directional]\ndirection = [-0.3, -1.0, -0.2]\n{objects}"
        );
        SceneDesc::from_toml(&text, Path::new("test.toml")).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn ten_objects_of_19m_triangles_are_refused_before_anything_is_built() {
        // The first object's mesh file has a sound header and a broken body: building anything
        // would fail on it before the limit is checked.
        let dir = tempfile::tempdir().expect("tempdir");
        let broken = "OFF\n3 1 0\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n";
        std::fs::write(dir.path().join("broken.off"), broken).expect("writes");
        let big = "[[object]]\nshape.random_triangles = { count = 19000000 }\n";
        let desc = scene(&format!(
            "[[object]]\nshape.file = {{ path = \"broken.off\" }}\n{}",
            big.repeat(10)
        ));
        let folders = [dir.path().to_owned()];
        let bound = triangle_bound(&dir.path().join("broken.off")).expect("a sound header");
        let triangles = desc.triangles("ten", Path::new("ten.toml"), &folders).expect("counts");
        assert_eq!(triangles, 190_000_000 + bound);
        let err = desc.resolve_in("ten", Path::new("ten.toml"), &folders).expect_err("too many");
        assert!(
            matches!(
                &err,
                SceneError::TooManyTriangles { triangles: t, limit: MAX_SCENE_TRIANGLES, largest, .. }
                    if *t == 190_000_000 && largest == "`object[1]`"
            ),
            "{err}"
        );
        assert!(
            err.to_string().starts_with(
                "ten.toml: the scene has 190000000 triangles, more than the limit of \
                 40000000 (the largest object, `object[1]`, has 19000000); lower the \
                 generators' counts"
            ),
            "{err}"
        );
        // A mesh file's bound from its size is loose (a sparse 100 MB OBJ may hold 50 M by
        // size alone): it refuses nothing; the file is read, and its content is what fails.
        let huge = std::fs::File::create(dir.path().join("huge.obj")).expect("creates");
        huge.set_len(100_000_000).expect("a sparse file");
        let desc = scene("[[object]]\nshape.file = { path = \"huge.obj\" }\n");
        assert_eq!(desc.triangles("huge", Path::new("huge.toml"), &folders).ok(), Some(50_000_000));
        let err = desc.resolve_in("huge", Path::new("huge.toml"), &folders).expect_err("no faces");
        assert!(!matches!(&err, SceneError::TooManyTriangles { .. }), "{err}");
        // Within the limit, the broken body is what stops it.
        let err = scene(&format!("[[object]]\nshape.file = {{ path = \"broken.off\" }}\n{big}"))
            .resolve_in("one", Path::new("one.toml"), &folders)
            .expect_err("broken");
        assert!(matches!(err, SceneError::Mesh { .. }), "{err}");
    }

    #[test]
    fn an_empty_mesh_path_is_named_as_such() {
        let desc = scene("[[object]]\nshape.file = { path = \"\" }\n");
        let folders = [PathBuf::from(".")];
        for err in [
            desc.triangles("e", Path::new("e.toml"), &folders).expect_err("empty"),
            desc.resolve_in("e", Path::new("e.toml"), &folders).expect_err("empty"),
        ] {
            assert_eq!(
                err.to_string(),
                "e.toml: `object[0].shape.file.path`: the path is empty: name a .obj, .off, .ply, \
                 .gltf or .glb file"
            );
        }
    }

    #[test]
    fn mesh_paths_are_looked_for_in_each_folder_in_turn() {
        let dir = tempfile::tempdir().expect("tempdir");
        let (near, far) = (dir.path().join("near"), dir.path().join("far"));
        for folder in [&near, &far] {
            std::fs::create_dir(folder).expect("mkdir");
        }
        let off = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        std::fs::write(far.join("m.off"), off).expect("writes");
        std::fs::create_dir(near.join("dir.off")).expect("mkdir");
        std::fs::write(far.join("dir.off"), off).expect("writes");
        let folders = [near.clone(), far.clone()];
        let with =
            |path: &str| scene(&format!("[[object]]\nshape.file = {{ path = \"{path}\" }}\n"));
        let found = with("m.off").resolve_in("s", Path::new("s.toml"), &folders).expect("in far");
        assert_eq!(found.triangle_count(), 1);
        let err = with("n.off").resolve_in("s", Path::new("s.toml"), &folders).expect_err("none");
        let looked = vec![near.join("n.off"), far.join("n.off")];
        assert!(
            matches!(&err, SceneError::ModelMissing { looked: l, .. } if **l == *looked),
            "{err}"
        );
        assert!(
            err.to_string().contains(&format!(
                "needs n.off, which is missing (looked for {} and {})",
                looked[0].display(),
                looked[1].display()
            )),
            "{err}"
        );
        // The first place that holds the path is used: a folder there is refused as such.
        let err = with("dir.off").resolve_in("s", Path::new("s.toml"), &folders).expect_err("dir");
        assert!(err.to_string().ends_with("dir.off: is a folder, not a mesh file"), "{err}");
    }

    #[test]
    fn a_folder_named_as_a_scene_file_is_named_as_such() {
        let dir = tempfile::tempdir().expect("tempdir");
        let folder = dir.path().join("scene.toml");
        std::fs::create_dir(&folder).expect("mkdir");
        let err = SceneDesc::read(&folder).expect_err("a folder");
        assert!(matches!(err, SceneError::Folder { .. }), "{err}");
        assert!(err.to_string().ends_with("scene.toml: is a folder, not a scene file"), "{err}");
    }
}
