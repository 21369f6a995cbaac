//! Scenes for the shadow workbench: meshes, materials, lights, cameras, scene files,
//! procedural generators, mesh loaders, the effects a scene calls for, and how a scene moves.

pub mod animation;
mod arrays;
pub mod camera;
pub mod direction;
pub mod generators;
pub mod gltf_file;
pub mod io;
pub mod light;
pub mod limits;
pub mod mesh;
pub mod models;
pub mod morton;
pub mod projection;
pub mod scene;
pub mod spatial_order;
mod toml_lines;

pub use animation::{Animation, AnimationDesc, AnimationError, MAX_FRAMES};
pub use camera::Camera;
pub use light::Light;
pub use mesh::{Mesh, MeshError};
pub use projection::{Projector, Ray};
pub use scene::{Effects, Geometry, Material, Object, Scene};
pub mod registry;
pub mod scene_file;

pub use gltf_file::{write_glb, GltfError};
pub use registry::{describe, load, Described, BUILTINS};
pub use scene_file::{SceneDesc, SceneError};
