//! Built-in scenes, and loading a scene by name or path.
//!
//! Every built-in is a [`SceneDesc`], so it can be written out as a scene file and edited
//! (`shadowbench scenes --toml NAME`). Models (`bunny-plane`, `bunny-dolly`) are read from the
//! models folder ([`crate::models`]). Five built-ins move ([`crate::animation`]), each a still
//! built-in with an `[animation]` of 24 frames, small enough to be measured frame by frame at
//! 64 x 48: `bumpy-orbit` (the light orbiting the vertical 55 degrees above the horizon, a full
//! turn in keys 30 degrees apart, over `bumpy`'s spheres and a 128-quad heightfield: a curved
//! receiver and self-shadowing, cheap for the exact reference), `cage-sweep` (`cage`, its
//! light swept through 30 degrees along one great circle), `bunny-dolly` (`bunny-plane`, the
//! eye moved a quarter of the way towards its target), `square-slide` (`plane-square`, the
//! square moved 5 units across the ground, light and camera fixed) and `cage-ramp` (`cage`,
//! still, the shadow map's resolution factor ramping from 0.25 to 1).
//!
//! Loading is two steps, so that a scene can be measured before it is built: [`describe`]
//! finds the built-in, reads and parses the scene file, or makes the scene around a mesh file,
//! and builds nothing; [`Described::triangles`] bounds its triangles from generator parameters
//! and mesh file headers; [`Described::resolve`] builds it (refusing first a scene beyond
//! [`crate::limits::MAX_SCENE_TRIANGLES`]). [`load`] is the two in one. A mesh file given as
//! the scene is the user's file: its errors name that file and line only, not the key of the
//! object the scene made of it.

use crate::{
    animation::{AnimationDesc, CameraKey, LightKey, ObjectKey, ObjectTrack, ScaleKey},
    camera::Camera,
    generators::{
        CageParams, CityParams, HairballParams, HeightfieldParams, PlaneParams, PlantParams,
        RandomTrianglesParams, SpheresParams,
    },
    gltf_file::GltfPlan,
    io::LoadError,
    light::Light,
    models::models_dir,
    scene::{Material, Scene},
    scene_file::{FileShape, ObjectDesc, SceneDesc, SceneError, Shape, Transform},
};
use glam::DVec3;
use std::path::{Path, PathBuf};

/// Name and one-line description of every built-in scene.
pub const BUILTINS: &[(&str, &str)] = &[
    ("plane-square", "one square occluder over a plane (exact reference test bed)"),
    ("random-1k", "1k random triangles of constant total area over a plane (Aila & Laine Table 1)"),
    (
        "random-10k",
        "10k random triangles of constant total area over a plane (Aila & Laine Table 1)",
    ),
    (
        "random-100k",
        "100k random triangles of constant total area over a plane (Aila & Laine Table 1)",
    ),
    ("random-1m", "1M random triangles of constant total area over a plane (Aila & Laine Table 1)"),
    ("cage", "a cage of thin bars over a plane (Pan et al. Fig. 11)"),
    ("plant", "many thin leaves over a plane (Pan et al. Fig. 12c)"),
    ("spheres", "floating spheres over a plane (Lecocq et al.)"),
    ("city", "a city of boxes on a plane"),
    ("bumpy", "spheres over a densely tessellated heightfield receiver (Pan et al. Fig. 9)"),
    ("hairball", "a ball of thin strands of opacity 0.1 over a plane (Aila & Laine Fig. 1)"),
    ("grazing", "boxes on a plane under a light 84 degrees from the vertical"),
    ("spot-spheres", "floating spheres over a plane under a spot light"),
    (
        "bunny-plane",
        "the Stanford bunny (CGAL's bunny00.off, 75k triangles) over a plane (Pan et al. Fig. 8)",
    ),
    (
        "bumpy-orbit",
        "animated: a light 55 degrees high orbiting the vertical once over spheres and a bumpy \
         heightfield",
    ),
    ("cage-sweep", "animated: the cage under a light swept through 30 degrees"),
    ("bunny-dolly", "animated: bunny-plane's camera dollying slowly towards the bunny"),
    ("square-slide", "animated: plane-square's square sliding across the ground"),
    ("cage-ramp", "animated: the cage, its shadow map's resolution ramping from 0.25 to 1"),
];

/// The frames of the animated built-ins.
const FRAMES: u32 = 24;

fn ground(size: f64) -> ObjectDesc {
    ObjectDesc {
        name: Some("ground".into()),
        shape: Shape::Plane(PlaneParams { size, ..Default::default() }),
        transform: Transform::default(),
        material: Material { color: [0.85, 0.85, 0.8], opacity: 1.0 },
        casts_shadows: true,
    }
}

fn caster(name: &str, shape: Shape, color: [f64; 3]) -> ObjectDesc {
    ObjectDesc {
        name: Some(name.into()),
        shape,
        transform: Transform::default(),
        material: Material { color, opacity: 1.0 },
        casts_shadows: true,
    }
}

fn perspective(eye: [f64; 3], target: [f64; 3], fov_y_deg: f64) -> Camera {
    Camera::Perspective {
        eye: DVec3::from(eye),
        target: DVec3::from(target),
        up: DVec3::Y,
        fov_y_deg,
        near: 0.01,
    }
}

fn directional(d: [f64; 3]) -> Light {
    Light::Directional { direction: DVec3::from(d) }
}

fn desc(
    name: &str,
    resolution: [u32; 2],
    camera: Camera,
    light: Light,
    objects: Vec<ObjectDesc>,
) -> SceneDesc {
    SceneDesc {
        name: Some(name.into()),
        resolution,
        camera,
        light,
        effects: Default::default(),
        objects,
        animation: Default::default(),
    }
}

/// One square occluder over a plane.
fn plane_square(name: &str) -> SceneDesc {
    let mut square = caster(
        "square",
        Shape::Plane(PlaneParams { size: 2.0, ..Default::default() }),
        [0.7, 0.3, 0.3],
    );
    square.transform = Transform {
        rotate_deg: DVec3::new(0.0, 20.0, 0.0),
        translate: DVec3::new(0.0, 1.5, 0.0),
        ..Default::default()
    };
    desc(
        name,
        [800, 600],
        perspective([0.0, 7.0, 9.0], [0.0, 0.0, 0.0], 40.0),
        directional([-0.4, -1.0, -0.25]),
        vec![ground(12.0), square],
    )
}

/// A cage of thin bars over a plane.
fn cage(name: &str) -> SceneDesc {
    desc(
        name,
        [800, 600],
        perspective([0.0, 6.0, 10.0], [0.0, 1.5, 0.0], 45.0),
        directional([-0.6, -1.0, -0.4]),
        vec![ground(16.0), caster("cage", Shape::Cage(CageParams::default()), [0.6, 0.6, 0.7])],
    )
}

/// Spheres over a heightfield of `resolution` quads a side.
fn bumpy(name: &str, resolution: u32) -> SceneDesc {
    let mut receiver = ground(20.0);
    receiver.name = Some("heightfield".into());
    receiver.shape =
        Shape::Heightfield(HeightfieldParams { size: 20.0, resolution, ..Default::default() });
    let spheres = SpheresParams { count: 5, ..Default::default() };
    desc(
        name,
        [800, 600],
        perspective([0.0, 7.0, 10.0], [0.0, 1.0, 0.0], 45.0),
        directional([-0.5, -1.0, -0.4]),
        vec![receiver, caster("spheres", Shape::Spheres(spheres), [0.5, 0.6, 0.8])],
    )
}

/// The Stanford bunny over a plane.
fn bunny_plane(name: &str) -> SceneDesc {
    let mut bunny =
        caster("bunny", Shape::File(FileShape { path: "bunny00.off".into() }), [0.8, 0.7, 0.6]);
    bunny.transform = Transform { fit_size: Some(4.0), on_ground: true, ..Default::default() };
    desc(
        name,
        [800, 600],
        perspective([0.0, 5.0, 8.0], [0.0, 1.5, 0.0], 45.0),
        directional([-0.5, -1.0, -0.4]),
        vec![ground(16.0), bunny],
    )
}

/// `scene` moving as `animation`, sampled at [`FRAMES`] frames.
fn animated(scene: SceneDesc, animation: AnimationDesc) -> SceneDesc {
    SceneDesc { animation: AnimationDesc { frames: FRAMES, ..animation }, ..scene }
}

/// A key of a directional light, its direction rounded to 12 decimals so that the printed
/// scene file reads plainly (`0` rather than `1.0536428202654814e-16`); the direction is made
/// unit when the scene is resolved.
fn light_key(time: f64, direction: DVec3) -> LightKey {
    let direction = (direction * 1e12).round() / 1e12;
    LightKey { time, direction: Some(direction), position: None, target: None, fov_deg: None }
}

fn random(name: &str, count: u32) -> SceneDesc {
    let tris = RandomTrianglesParams { count, ..Default::default() };
    desc(
        name,
        [1024, 768],
        perspective([0.0, 9.0, 11.0], [0.0, 1.0, 0.0], 45.0),
        directional([-0.5, -1.0, -0.3]),
        vec![ground(16.0), caster("triangles", Shape::RandomTriangles(tris), [0.7, 0.5, 0.4])],
    )
}

/// The description of the built-in scene `name`.
pub fn builtin(name: &str) -> Option<SceneDesc> {
    let default_view = || perspective([0.0, 7.0, 10.0], [0.0, 1.0, 0.0], 45.0);
    Some(match name {
        "plane-square" => plane_square(name),
        "random-1k" => random(name, 1_000),
        "random-10k" => random(name, 10_000),
        "random-100k" => random(name, 100_000),
        "random-1m" => random(name, 1_000_000),
        "cage" => cage(name),
        "plant" => desc(
            name,
            [800, 600],
            default_view(),
            directional([-0.5, -1.0, -0.6]),
            vec![
                ground(16.0),
                caster("plant", Shape::Plant(PlantParams::default()), [0.3, 0.6, 0.3]),
            ],
        ),
        "spheres" => desc(
            name,
            [800, 600],
            default_view(),
            directional([-0.5, -1.0, -0.4]),
            vec![
                ground(16.0),
                caster("spheres", Shape::Spheres(SpheresParams::default()), [0.5, 0.6, 0.8]),
            ],
        ),
        "city" => desc(
            name,
            [800, 600],
            perspective([0.0, 9.0, 12.0], [0.0, 0.0, 0.0], 45.0),
            directional([-0.6, -1.0, -0.3]),
            vec![ground(16.0), caster("city", Shape::City(CityParams::default()), [0.7, 0.7, 0.7])],
        ),
        "bumpy" => bumpy(name, 512),
        "hairball" => {
            let mut ball =
                caster("hairball", Shape::Hairball(HairballParams::default()), [0.4, 0.3, 0.2]);
            ball.material.opacity = 0.1;
            desc(
                name,
                [800, 600],
                perspective([0.0, 6.0, 11.0], [0.0, 2.5, 0.0], 45.0),
                directional([-0.4, -1.0, -0.3]),
                vec![ground(16.0), ball],
            )
        }
        "grazing" => {
            let blocks = CityParams { blocks: 3, ..Default::default() };
            desc(
                name,
                [800, 600],
                perspective([0.0, 8.0, 12.0], [0.0, 0.0, 0.0], 45.0),
                // 84 degrees from the vertical: tan(84°) ≈ 9.5.
                directional([0.95, -0.1, 0.3]),
                vec![ground(20.0), caster("blocks", Shape::City(blocks), [0.7, 0.7, 0.7])],
            )
        }
        "spot-spheres" => desc(
            name,
            [800, 600],
            default_view(),
            Light::Spot { position: DVec3::new(3.0, 9.0, 2.0), target: DVec3::ZERO, fov_deg: 75.0 },
            vec![
                ground(16.0),
                caster("spheres", Shape::Spheres(SpheresParams::default()), [0.5, 0.6, 0.8]),
            ],
        ),
        "bunny-plane" => bunny_plane(name),
        "bumpy-orbit" => {
            // 55 degrees above the horizon, a full turn about the vertical in steps of 30
            // degrees (each step slerped along its great circle).
            let (elevation, steps) = (55f64.to_radians(), 12);
            let light = (0..=steps)
                .map(|k| {
                    let azimuth = (f64::from(k) * 30.0).to_radians();
                    let direction = -DVec3::new(
                        elevation.cos() * azimuth.cos(),
                        elevation.sin(),
                        elevation.cos() * azimuth.sin(),
                    );
                    light_key(f64::from(k), direction)
                })
                .collect();
            animated(bumpy(name, 128), AnimationDesc { light, ..Default::default() })
        }
        "cage-sweep" => {
            // The cage's light's azimuth, from 20 to 50 degrees off the vertical: a sweep
            // through 30 degrees along one great circle.
            let horizontal = DVec3::new(-0.6, 0.0, -0.4).normalize();
            let light = [(0.0, 20f64), (1.0, 50.0)]
                .map(|(time, off)| {
                    let off = off.to_radians();
                    light_key(time, horizontal * off.sin() - DVec3::Y * off.cos())
                })
                .into();
            animated(cage(name), AnimationDesc { light, ..Default::default() })
        }
        "bunny-dolly" => {
            // A quarter of the way from bunny-plane's eye to its target.
            let camera = [(0.0, [0.0, 5.0, 8.0]), (1.0, [0.0, 4.125, 6.0])]
                .map(|(time, eye)| CameraKey {
                    time,
                    eye: Some(DVec3::from(eye)),
                    target: None,
                    up: None,
                    fov_y_deg: None,
                    height: None,
                })
                .into();
            animated(bunny_plane(name), AnimationDesc { camera, ..Default::default() })
        }
        "square-slide" => {
            let keys = [(0.0, -2.5), (1.0, 2.5)]
                .map(|(time, x)| ObjectKey {
                    time,
                    translate: DVec3::new(x, 0.0, 0.0),
                    rotate_deg: DVec3::ZERO,
                })
                .into();
            let object = vec![ObjectTrack { name: "square".into(), keys }];
            animated(plane_square(name), AnimationDesc { object, ..Default::default() })
        }
        "cage-ramp" => {
            let map_scale =
                [(0.0, 0.25), (1.0, 1.0)].map(|(time, value)| ScaleKey { time, value }).into();
            animated(cage(name), AnimationDesc { map_scale, ..Default::default() })
        }
        _ => return None,
    })
}

/// A scene found and read, but not built: see [`describe`].
#[derive(Debug, Clone)]
pub struct Described {
    /// What the scene is made from.
    source: Source,
    /// The name when the description has none: the built-in's name or the file stem.
    default_name: String,
    /// What messages name: `builtin:NAME`, the scene file, the mesh file or the glTF file.
    origin: PathBuf,
}

/// What a described scene is made from.
#[derive(Debug, Clone)]
enum Source {
    /// A built-in, a scene file, or a mesh file given as the scene.
    Desc {
        desc: SceneDesc,
        /// Where mesh paths are looked for, in order.
        folders: Vec<PathBuf>,
        /// Whether the scene is made around a mesh file given as the scene.
        mesh_file: bool,
        /// The scene file's text, for errors to name the line of a key.
        text: Option<String>,
    },
    /// A glTF file given as the scene: what its JSON says.
    Gltf(GltfPlan),
}

impl Described {
    /// The scene's name.
    pub fn name(&self) -> &str {
        match &self.source {
            Source::Desc { desc, .. } => desc.name.as_deref().unwrap_or(&self.default_name),
            Source::Gltf(_) => &self.default_name,
        }
    }

    /// The scene's default image size `[width, height]`.
    pub fn resolution(&self) -> [u32; 2] {
        match &self.source {
            Source::Desc { desc, .. } => desc.resolution,
            Source::Gltf(plan) => plan.resolution.unwrap_or(DEFAULT_RESOLUTION),
        }
    }

    /// The frames the scene's animation is sampled at by default (`[animation] frames`; 1
    /// for a still scene and for a glTF scene, whose animations are not read).
    pub fn frames(&self) -> u32 {
        match &self.source {
            Source::Desc { desc, .. } => desc.animation.frames,
            Source::Gltf(_) => 1,
        }
    }

    /// What a glTF scene holds that the workbench leaves out (ignored primitives, lights,
    /// cameras, textures, extensions), a sentence each, for the user to be told; empty for
    /// other scenes.
    pub fn notes(&self) -> &[String] {
        match &self.source {
            Source::Desc { .. } => &[],
            Source::Gltf(plan) => &plan.notes,
        }
    }

    /// An upper bound of the scene's triangle count, computed without generating or loading
    /// any mesh: generators count theirs from their parameters (exactly), mesh files are
    /// bounded from their headers and sizes ([`crate::io::triangle_bound`]: exact for binary
    /// PLY of triangles and glTF, loose for text files), a glTF scene from its accessors'
    /// counts (exactly). Generator parameters are checked and mesh files found, with the
    /// errors [`Self::resolve`] would give.
    pub fn triangles(&self) -> Result<u64, SceneError> {
        match &self.source {
            Source::Desc { desc, folders, .. } => {
                desc.triangles(&self.default_name, &self.origin, folders).map_err(|e| self.own(e))
            }
            Source::Gltf(plan) => Ok(plan.triangles),
        }
    }

    /// Whether [`Self::triangles`] is the exact count: no object is a mesh file other than
    /// glTF, whose bound from a text file's size can be loose.
    pub fn triangles_exact(&self) -> bool {
        match &self.source {
            Source::Desc { desc, .. } => !desc.objects.iter().any(|o| match &o.shape {
                Shape::File(f) => !crate::io::is_gltf(&f.path),
                _ => false,
            }),
            Source::Gltf(_) => true,
        }
    }

    /// Builds the scene; one whose [`Self::triangles`] exceed
    /// [`crate::limits::MAX_SCENE_TRIANGLES`] is refused before any mesh is built.
    pub fn resolve(&self) -> Result<Scene, SceneError> {
        match &self.source {
            Source::Desc { desc, folders, .. } => {
                desc.resolve_in(&self.default_name, &self.origin, folders).map_err(|e| self.own(e))
            }
            Source::Gltf(_) => gltf_scene(&self.origin, &self.default_name),
        }
    }

    /// `e` as the user should read it: a scene file's errors name the key as written and its
    /// line; a mesh-file scene's name the file (and line) alone, not the object the scene made
    /// of it.
    fn own(&self, e: SceneError) -> SceneError {
        let Source::Desc { desc, mesh_file, text, .. } = &self.source else { return e };
        if let Some(text) = text {
            return e.located(text, desc);
        }
        if !mesh_file {
            return e;
        }
        match e {
            SceneError::Mesh { source, .. } => SceneError::MeshFile { source: *source },
            SceneError::TooManyTriangles { path, triangles, limit, largest_triangles, .. } => {
                SceneError::TooManyTriangles {
                    largest: path.display().to_string(),
                    path,
                    triangles,
                    limit,
                    largest_triangles,
                    from_file: true,
                }
            }
            e => e,
        }
    }
}

/// The default resolution of a scene that names none.
const DEFAULT_RESOLUTION: [u32; 2] = [800, 600];

/// The default camera of a mesh file given as the scene, and of a glTF scene without one.
fn default_camera() -> Camera {
    perspective([0.0, 5.0, 8.0], [0.0, 1.5, 0.0], 45.0)
}

/// The default light of a mesh file given as the scene, and of a glTF scene without one.
fn default_light() -> Light {
    directional([-0.5, -1.0, -0.4])
}

/// Builds the glTF scene in `path` ([`crate::gltf_file::read`]), with the mesh file's default
/// camera and light where it has none, and without a ground plane (a glTF scene is a whole
/// scene), then checks it as a scene file is checked: the triangle limit, the coordinate
/// range and the smallest extent ([`crate::limits`]).
fn gltf_scene(path: &Path, name: &str) -> Result<Scene, SceneError> {
    let gltf = crate::gltf_file::read(path)?;
    let [width, height] = gltf.resolution.unwrap_or(DEFAULT_RESOLUTION);
    let scene = Scene {
        name: name.to_owned(),
        width,
        height,
        camera: gltf.camera.unwrap_or_else(default_camera),
        light: gltf.light.unwrap_or_else(default_light).normalized(),
        // Each mesh's triangles in a spatial order, as a mesh file's (see `spatial_order`).
        objects: gltf
            .objects
            .into_iter()
            .map(|o| crate::Object { mesh: crate::spatial_order::spatially_ordered(o.mesh), ..o })
            .collect(),
        switches: Default::default(),
        animation: Default::default(),
    };
    crate::scene_file::check_resolved(&scene, path)?;
    Ok(scene)
}

/// The built-in scene `name`, described.
fn describe_builtin(name: &str) -> Option<Described> {
    Some(Described {
        source: Source::Desc {
            desc: builtin(name)?,
            folders: vec![models_dir()],
            mesh_file: false,
            text: None,
        },
        default_name: name.to_owned(),
        origin: PathBuf::from(format!("builtin:{name}")),
    })
}

/// Resolves a built-in scene.
pub fn load_builtin(name: &str) -> Option<Result<Scene, SceneError>> {
    describe_builtin(name).map(|d| d.resolve())
}

/// A scene around one mesh file: the model fitted to 4 units, standing on a ground plane,
/// with a default camera and light.
pub fn mesh_scene(path: &Path) -> SceneDesc {
    let mut model =
        caster("model", Shape::File(FileShape { path: path.to_owned() }), [0.8, 0.7, 0.6]);
    model.transform = Transform { fit_size: Some(4.0), on_ground: true, ..Default::default() };
    desc(
        &path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "model".into()),
        DEFAULT_RESOLUTION,
        default_camera(),
        default_light(),
        vec![ground(16.0), model],
    )
}

/// Finds a scene by built-in name, or from a path: a scene file (`.toml`, read and parsed; its
/// mesh paths looked for beside it, then in the models folder), a glTF scene (`.gltf`, `.glb`:
/// its JSON read and walked, its buffers not read; [`crate::gltf_file`]) or a mesh file
/// (`.obj`, `.off`, `.ply`, which must exist and not be a folder) placed over a ground plane.
/// Builds nothing.
pub fn describe(arg: &str) -> Result<Described, SceneError> {
    if let Some(described) = describe_builtin(arg) {
        return Ok(described);
    }
    let path = Path::new(arg);
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned());
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("toml") => Ok(Described {
            source: {
                let (desc, text) = SceneDesc::read_with_text(path)?;
                Source::Desc {
                    desc,
                    folders: SceneDesc::mesh_folders(path),
                    mesh_file: false,
                    text: Some(text),
                }
            },
            default_name: stem.unwrap_or_else(|| "scene".into()),
            origin: path.to_owned(),
        }),
        Some("gltf" | "glb") => Ok(Described {
            source: Source::Gltf(crate::gltf_file::plan(path)?),
            default_name: stem.unwrap_or_else(|| "scene".into()),
            origin: path.to_owned(),
        }),
        Some("obj" | "off" | "ply") => {
            let metadata = std::fs::metadata(path)
                .map_err(|source| SceneError::Io { path: path.to_owned(), source })?;
            if metadata.is_dir() {
                let source = LoadError::Folder { path: path.to_owned() };
                return Err(SceneError::MeshFile { source });
            }
            let desc = mesh_scene(path);
            Ok(Described {
                default_name: desc.name.clone().unwrap_or_default(),
                // The path as given, relative to the working folder.
                source: Source::Desc {
                    desc,
                    folders: vec![PathBuf::new()],
                    mesh_file: true,
                    text: None,
                },
                origin: path.to_owned(),
            })
        }
        _ => Err(SceneError::Unknown {
            name: arg.to_owned(),
            known: BUILTINS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", "),
        }),
    }
}

/// Loads a scene by built-in name, or from a path: [`describe`], then [`Described::resolve`].
pub fn load(arg: &str) -> Result<Scene, SceneError> {
    describe(arg)?.resolve()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_is_described_with_a_bound_of_its_triangles() {
        for (name, _) in BUILTINS {
            let described = describe(name).expect("a built-in");
            assert_eq!(described.name(), *name);
            let triangles = described.triangles();
            match described.resolve() {
                Ok(scene) => {
                    assert_eq!(described.resolution(), [scene.width, scene.height], "{name}");
                    assert_eq!(described.frames(), scene.animation.frames(), "{name}");
                    let triangles = triangles.unwrap_or_else(|e| panic!("{name}: {e}"));
                    let real = scene.triangle_count() as u64;
                    // Exact for generated scenes; a bound for one with a mesh file (the
                    // bunny's text OFF: 967,196 for 75,410).
                    if described.triangles_exact() {
                        assert_eq!(triangles, real, "{name}");
                    } else {
                        assert!(triangles >= real, "{name}: {triangles} below {real}");
                    }
                }
                // The models folder may not be fetched: then both say so.
                Err(e @ SceneError::ModelMissing { .. }) => {
                    assert!(matches!(triangles, Err(SceneError::ModelMissing { .. })), "{e}");
                }
                Err(e) => panic!("{name}: {e}"),
            }
        }
    }

    /// The animated built-ins.
    const ANIMATED: [&str; 5] =
        ["bumpy-orbit", "cage-sweep", "bunny-dolly", "square-slide", "cage-ramp"];

    #[test]
    fn animated_builtins_round_trip_and_keep_their_triangles_in_every_pose() {
        for name in ANIMATED {
            assert!(BUILTINS.iter().any(|(n, _)| *n == name), "{name} is listed");
            let desc = builtin(name).expect("a built-in");
            assert_eq!(desc.animation.frames, FRAMES, "{name}");
            let text = desc.to_toml();
            assert!(text.contains("[animation]"), "{name}:\n{text}");
            let back = SceneDesc::from_toml(&text, Path::new("round-trip.toml"))
                .unwrap_or_else(|e| panic!("{name}: {e}\n{text}"));
            assert_eq!(back, desc, "{name}");
            let scene = match load_builtin(name).expect("a built-in") {
                Ok(scene) => scene,
                // The models folder may not be fetched.
                Err(SceneError::ModelMissing { .. }) => continue,
                Err(e) => panic!("{name}: {e}"),
            };
            let animation = &scene.animation;
            assert!(!animation.is_still(), "{name}");
            let rest = scene.geometry();
            let mut poses = (0..animation.frames()).map(|i| animation.pose(&scene, i));
            let first = poses.next().expect("a frame");
            let mut moved = false;
            for posed in std::iter::once(first.clone()).chain(poses) {
                let g = posed.geometry();
                assert_eq!((&g.triangles, &g.object), (&rest.triangles, &rest.object), "{name}");
                assert!(posed.animation.is_still(), "{name}");
                moved |= posed != first;
            }
            // Every animated built-in changes from frame to frame, but the one whose map
            // resolution alone changes.
            assert_eq!(moved, name != "cage-ramp", "{name}");
            let scales = (animation.map_scale(0), animation.map_scale(FRAMES - 1));
            let want = if name == "cage-ramp" { (0.25, 1.0) } else { (1.0, 1.0) };
            assert_eq!(scales, want, "{name}");
        }
    }

    #[test]
    fn animated_builtins_move_as_described() {
        let angle = |a: DVec3, b: DVec3| a.angle_between(b).to_degrees();
        let light = |scene: &Scene| match scene.light {
            Light::Directional { direction } => direction,
            Light::Spot { .. } => panic!("a directional light"),
        };
        let sweep = load_builtin("cage-sweep").expect("built-in").expect("builds");
        let (a, b) = (sweep.animation.pose(&sweep, 0), sweep.animation.pose(&sweep, FRAMES - 1));
        assert!((angle(light(&a), light(&b)) - 30.0).abs() < 1e-9);
        let orbit = load_builtin("bumpy-orbit").expect("built-in").expect("builds");
        let mut turned = 0.0;
        for i in 0..FRAMES {
            let d = light(&orbit.animation.pose(&orbit, i));
            // 55 degrees high, give or take the great circles between the keys 30 degrees
            // apart (each rises above the circle of latitude by at most 2 degrees).
            let elevation = (-d.y).asin().to_degrees();
            assert!((55.0..57.0).contains(&elevation), "frame {i}: {elevation}");
            if i > 0 {
                let p = light(&orbit.animation.pose(&orbit, i - 1));
                turned += angle(DVec3::new(p.x, 0.0, p.z), DVec3::new(d.x, 0.0, d.z));
            }
        }
        assert!((turned - 360.0).abs() < 1e-6, "{turned}");
        let slide = load_builtin("square-slide").expect("built-in").expect("builds");
        let x = |i: u32| {
            let posed = slide.animation.pose(&slide, i);
            posed.objects[1].mesh.bounds().map(|(lo, hi)| 0.5 * (lo.x + hi.x))
        };
        for (i, want) in [(0, -2.5), (FRAMES - 1, 2.5)] {
            let got = x(i).expect("vertices");
            assert!((got - want).abs() < 1e-14, "frame {i}: {got}");
        }
        assert!(!slide.animation.moves_camera());
        let dolly = builtin("bunny-dolly").expect("built-in");
        let keys: Vec<_> = dolly.animation.camera.iter().filter_map(|k| k.eye).collect();
        let target = dolly.camera.target();
        let toward = (keys[1] - target).length() / (keys[0] - target).length();
        assert!((toward - 0.75).abs() < 1e-15, "{toward}");
        assert_eq!((keys[0] - target).cross(keys[1] - target), DVec3::ZERO);
    }

    #[test]
    fn a_mesh_file_scene_names_the_users_file_and_line_only() {
        let dir = tempfile::tempdir().expect("tempdir");
        let bad = dir.path().join("bad.obj");
        std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").expect("writes");
        let described = describe(bad.to_str().expect("utf-8")).expect("described");
        assert_eq!(described.name(), "bad");
        assert!(described.triangles().is_ok_and(|t| t >= 3));
        let err = described.resolve().expect_err("bad index");
        assert!(matches!(err, SceneError::MeshFile { .. }), "{err}");
        assert_eq!(
            err.to_string(),
            format!(
                "{}: line 4: vertex index 4 out of range: the file has 3 vertices",
                bad.display()
            )
        );
        let folder = dir.path().join("folder.obj");
        std::fs::create_dir(&folder).expect("mkdir");
        let err = describe(folder.to_str().expect("utf-8")).expect_err("a folder");
        assert_eq!(err.to_string(), format!("{}: is a folder, not a mesh file", folder.display()));
        // A mesh file's loose bound from its size (sparse: 50 M by size) refuses nothing: the
        // file is read, and what fails is its content, named by the file alone.
        let huge = dir.path().join("huge.obj");
        let file = std::fs::File::create(&huge).expect("creates");
        file.set_len(100_000_000).expect("a sparse file");
        let described = describe(huge.to_str().expect("utf-8")).expect("described");
        assert_eq!(described.triangles().ok(), Some(50_000_002));
        let err = described.resolve().expect_err("no faces");
        assert!(matches!(err, SceneError::MeshFile { .. }), "{err}");
        let missing = dir.path().join("missing.ply");
        let err = describe(missing.to_str().expect("utf-8")).expect_err("missing");
        assert!(matches!(err, SceneError::Io { .. }), "{err}");
    }
}
