//! Scenes for the shadow workbench: meshes, materials, lights, cameras, scene files,
//! procedural generators, mesh loaders, and the effects a scene calls for.

pub mod generators;
pub mod io;
pub mod mesh;

pub use mesh::{Mesh, MeshError};
