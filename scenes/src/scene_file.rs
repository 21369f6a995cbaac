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
//! shape.file = { path = "models/bunny00.off" }   # relative to this file
//! transform = { fit_size = 4.0, on_ground = true, rotate_deg = [0.0, 30.0, 0.0] }
//! material = { color = [0.9, 0.6, 0.3], opacity = 1.0 }
//! ```
//!
//! Camera, light and shape are tables named after their kind (serde's external tagging), so
//! that every parse error points at the offending key or value with its line.
//! Unknown keys and bad values are errors naming the file and the key. A transform applies,
//! in order: `scale`, `rotate_deg` (about x, then y, then z), `fit_size` (centre the bounds on
//! the origin and scale uniformly so the largest extent equals it), `on_ground` (lift so the
//! lowest point is at y = 0), `translate`. The fit is exact in scale for any finite mesh with a
//! non-zero extent, from subnormal coordinates to ±1.7e308: the mesh is first scaled by a
//! power of two (exact), so that its bounds, extent and centre neither overflow nor underflow.
//!
//! Resolution refuses, as [`SceneError::OutOfRange`], a scene beyond the range every method
//! supports ([`crate::limits`]): a camera eye or target, a spot light's position or target, or
//! a resolved vertex with a coordinate beyond `MAX_COORDINATE`, or geometry whose bounding box
//! has a diagonal under `MIN_EXTENT`. A resolved scene's directional light has a unit direction.

use crate::{
    camera::Camera,
    generators::{
        CageParams, CityParams, Generator, HairballParams, HeightfieldParams, ParamError,
        PlaneParams, PlantParams, RandomTrianglesParams, SpheresParams,
    },
    io::{load_mesh, LoadError},
    light::Light,
    limits::{MAX_COORDINATE, MIN_EXTENT},
    mesh::Mesh,
    scene::{EffectSwitches, Material, Object, Scene},
};
use glam::{DMat4, DVec3, EulerRot};
use serde::{Deserialize, Serialize};
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
    /// A mesh file (.obj, .off, .ply), relative to the scene file.
    File(FileShape),
}

/// A mesh file reference.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FileShape {
    /// Path of the mesh file, relative to the scene file (or to the models folder for
    /// built-in scenes).
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
    #[error("{path}: `{key}`: {message}")]
    Invalid {
        /// The scene file (or `builtin:NAME`).
        path: PathBuf,
        /// The key, e.g. `object[1].shape.count`.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// The scene lies beyond the supported range of coordinates or sizes ([`crate::limits`]).
    #[error("{path}: `{key}`: {message}")]
    OutOfRange {
        /// The scene file, mesh file or `builtin:NAME`.
        path: PathBuf,
        /// The key, e.g. `camera.eye` or `object[1]`.
        key: String,
        /// What is out of range, with the value and the supported range.
        message: String,
    },
    /// A mesh file referenced by the scene could not be loaded.
    #[error("{path}: `{key}`: {source}")]
    Mesh {
        /// The scene file.
        path: PathBuf,
        /// The key, e.g. `object[1].shape.file.path`.
        key: String,
        /// The loader's error (names the mesh file and line).
        source: LoadError,
    },
    /// A model the scene needs is not present.
    #[error("{path}: `{key}`: scene `{scene}` needs {model}, which is missing{hint}")]
    ModelMissing {
        /// The scene file (or `builtin:NAME`).
        path: PathBuf,
        /// The key, e.g. `object[1].shape.file.path`.
        key: String,
        /// The scene.
        scene: String,
        /// The missing file.
        model: PathBuf,
        /// How to get it, when it is one of the models `scripts/fetch-models` fetches.
        hint: String,
    },
    /// No built-in scene has this name and no file has this path.
    #[error("unknown scene `{name}`: not a built-in scene (known: {known}) nor a .toml, .obj, .off or .ply file")]
    Unknown {
        /// What was asked for.
        name: String,
        /// The built-in names.
        known: String,
    },
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

    /// Reads and resolves a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path)
            .map_err(|source| SceneError::Io { path: path.to_owned(), source })?;
        let desc = Self::from_toml(&text, path)?;
        let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned());
        let base = path.parent().unwrap_or(Path::new("."));
        desc.resolve(stem.as_deref().unwrap_or("scene"), path, base)
    }

    /// Builds the scene: generates or loads every mesh and places it. `origin` names the file
    /// in messages; mesh paths are relative to `base`.
    pub fn resolve(
        &self,
        default_name: &str,
        origin: &Path,
        base: &Path,
    ) -> Result<Scene, SceneError> {
        let invalid = |key: String, message: String| SceneError::Invalid {
            path: origin.to_owned(),
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
        let name = self.name.clone().unwrap_or_else(|| default_name.to_owned());
        let mut objects = Vec::with_capacity(self.objects.len());
        for (i, o) in self.objects.iter().enumerate() {
            let key = |k: &str| format!("object[{i}].{k}");
            let m = &o.material;
            if !m.color.iter().all(|c| (0.0..=1.0).contains(c)) {
                return Err(invalid(key("material.color"), "components must be in [0, 1]".into()));
            }
            if !(0.0..=1.0).contains(&m.opacity) {
                return Err(invalid(
                    key("material.opacity"),
                    format!("must be in [0, 1], got {}", m.opacity),
                ));
            }
            let mut mesh = o.shape.build(base).map_err(|e| match e {
                ShapeError::Param(p) => invalid(key(&format!("shape.{}", p.key)), p.message),
                ShapeError::Missing(model) => {
                    let hint = if model.starts_with(crate::models::models_dir()) {
                        ": run `scripts/fetch-models` to fetch it".to_owned()
                    } else {
                        String::new()
                    };
                    SceneError::ModelMissing {
                        path: origin.to_owned(),
                        key: key("shape.file.path"),
                        scene: name.clone(),
                        model,
                        hint,
                    }
                }
                ShapeError::Load(source) => SceneError::Mesh {
                    path: origin.to_owned(),
                    key: key("shape.file.path"),
                    source,
                },
            })?;
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
                material: *m,
                casts_shadows: o.casts_shadows,
            });
        }
        let scene = Scene {
            name,
            width,
            height,
            camera: self.camera.clone(),
            light: self.light.normalized(),
            objects,
            switches: self.effects,
        };
        let (lo, hi) = scene.bounds();
        let diagonal = (hi - lo).length();
        if diagonal < MIN_EXTENT {
            return Err(out_of_range(
                "object".into(),
                format!(
                    "the geometry's bounding box has a diagonal of {}, below the supported \
                     minimum {MIN_EXTENT:e}",
                    short(diagonal)
                ),
            ));
        }
        Ok(scene)
    }
}

/// `x` in scientific notation with at most 3 significant digits, for messages.
fn short(x: f64) -> String {
    let text = format!("{x:.2e}");
    match text.split_once('e') {
        Some((mantissa, exponent)) => {
            let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
            format!("{mantissa}e{exponent}")
        }
        None => text,
    }
}

/// Why a largest coordinate magnitude `m` is beyond [`MAX_COORDINATE`] (or not finite), if it is.
fn beyond_range(m: f64) -> Option<String> {
    let beyond = format!("beyond the supported range |x| <= {MAX_COORDINATE:e}");
    if m.is_finite() {
        (m > MAX_COORDINATE).then(|| format!("coordinates reach {}, {beyond}", short(m)))
    } else {
        Some(format!("coordinates overflow, {beyond}"))
    }
}

enum ShapeError {
    Param(ParamError),
    Missing(PathBuf),
    Load(LoadError),
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

    fn build(&self, base: &Path) -> Result<Mesh, ShapeError> {
        let generator: &dyn Generator = match self {
            Shape::Plane(p) => p,
            Shape::RandomTriangles(p) => p,
            Shape::Cage(p) => p,
            Shape::Spheres(p) => p,
            Shape::City(p) => p,
            Shape::Plant(p) => p,
            Shape::Heightfield(p) => p,
            Shape::Hairball(p) => p,
            Shape::File(f) => {
                let path = base.join(&f.path);
                if !path.exists() {
                    return Err(ShapeError::Missing(path));
                }
                return load_mesh(&path).map_err(ShapeError::Load);
            }
        };
        generator.validate().map_err(ShapeError::Param)?;
        Ok(generator.generate())
    }
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
