//! Built-in scenes, and loading a scene by name or path.
//!
//! Every built-in is a [`SceneDesc`], so it can be written out as a scene file and edited
//! (`shadowbench scenes --toml NAME`). Models (`bunny-plane`) are read from the models folder
//! ([`crate::models`]).

use crate::{
    camera::Camera,
    generators::{
        CageParams, CityParams, HairballParams, HeightfieldParams, PlaneParams, PlantParams,
        RandomTrianglesParams, SpheresParams,
    },
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
];

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
    }
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
        "plane-square" => {
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
        "random-1k" => random(name, 1_000),
        "random-10k" => random(name, 10_000),
        "random-100k" => random(name, 100_000),
        "random-1m" => random(name, 1_000_000),
        "cage" => desc(
            name,
            [800, 600],
            perspective([0.0, 6.0, 10.0], [0.0, 1.5, 0.0], 45.0),
            directional([-0.6, -1.0, -0.4]),
            vec![ground(16.0), caster("cage", Shape::Cage(CageParams::default()), [0.6, 0.6, 0.7])],
        ),
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
        "bumpy" => {
            let mut receiver = ground(20.0);
            receiver.name = Some("heightfield".into());
            receiver.shape = Shape::Heightfield(HeightfieldParams {
                size: 20.0,
                resolution: 512,
                ..Default::default()
            });
            let spheres = SpheresParams { count: 5, ..Default::default() };
            desc(
                name,
                [800, 600],
                default_view(),
                directional([-0.5, -1.0, -0.4]),
                vec![receiver, caster("spheres", Shape::Spheres(spheres), [0.5, 0.6, 0.8])],
            )
        }
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
        "bunny-plane" => {
            let mut bunny = caster(
                "bunny",
                Shape::File(FileShape { path: "bunny00.off".into() }),
                [0.8, 0.7, 0.6],
            );
            bunny.transform =
                Transform { fit_size: Some(4.0), on_ground: true, ..Default::default() };
            desc(
                name,
                [800, 600],
                perspective([0.0, 5.0, 8.0], [0.0, 1.5, 0.0], 45.0),
                directional([-0.5, -1.0, -0.4]),
                vec![ground(16.0), bunny],
            )
        }
        _ => return None,
    })
}

/// Resolves a built-in scene.
pub fn load_builtin(name: &str) -> Option<Result<Scene, SceneError>> {
    let d = builtin(name)?;
    let origin = PathBuf::from(format!("builtin:{name}"));
    Some(d.resolve(name, &origin, &models_dir()))
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
        [800, 600],
        perspective([0.0, 5.0, 8.0], [0.0, 1.5, 0.0], 45.0),
        directional([-0.5, -1.0, -0.4]),
        vec![ground(16.0), model],
    )
}

/// Loads a scene by built-in name, or from a path: a scene file (`.toml`) or a mesh file
/// (`.obj`, `.off`, `.ply`) placed over a ground plane.
pub fn load(arg: &str) -> Result<Scene, SceneError> {
    if let Some(scene) = load_builtin(arg) {
        return scene;
    }
    let path = Path::new(arg);
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("toml") => SceneDesc::load(path),
        Some("obj" | "off" | "ply") => {
            let d = mesh_scene(path);
            let name = d.name.clone().unwrap_or_default();
            d.resolve(&name, path, Path::new(""))
        }
        _ => Err(SceneError::Unknown {
            name: arg.to_owned(),
            known: BUILTINS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", "),
        }),
    }
}
