//! The models folder, where the mesh files of built-in scenes (`bunny-plane`) are read from:
//! `$SHADOWBENCH_MODELS` if set, else `scenes/models/` in the source tree, filled by
//! `scripts/fetch-models`. The built-in scenes (`registry`) resolve their files against it,
//! scene files (`scene_file`) look there for a mesh path not found beside them, and a model
//! missing from it is named with a hint to fetch the models: a module of its own, so that
//! both can name it.

use std::path::{Path, PathBuf};

/// The folder models are read from.
pub fn models_dir() -> PathBuf {
    std::env::var_os("SHADOWBENCH_MODELS")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("models"))
}
