//! Replays every input saved in `tests/data/fuzz/TARGET/` (the seeds `scripts/fuzz` starts from,
//! `seed-*`, and every crash it found, `crash-*`) through the fuzz target's own function, so that
//! a crash once found stays fixed; the seeds must also be accepted, so that fuzzing starts from
//! valid files. The target functions are `fuzz/src/lib.rs`, included here by path: the fuzz
//! crate is a workspace of its own (it needs the fuzzing engine), and this way both run the
//! same code.

#[path = "../../fuzz/src/lib.rs"]
mod targets;

use anyhow::{ensure, Context};
use std::any::Any;
use std::path::{Path, PathBuf};

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz")
}

/// The text of a panic's payload.
fn message(payload: &(dyn Any + Send)) -> &str {
    payload
        .downcast_ref::<String>()
        .map(String::as_str)
        .or_else(|| payload.downcast_ref::<&str>().copied())
        .unwrap_or("(a panic without a message)")
}

/// Runs target `name` on every file in its folder; fails naming every input that panics and
/// every seed that is rejected.
fn replay(name: &str) -> anyhow::Result<()> {
    let &(_, target) = targets::TARGETS
        .iter()
        .find(|(n, _)| *n == name)
        .with_context(|| format!("no fuzz target `{name}`"))?;
    let dir = data().join(name);
    let mut inputs = std::fs::read_dir(&dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .map(|entry| Ok(entry?.path()))
        .collect::<std::io::Result<Vec<_>>>()?;
    inputs.sort();
    ensure!(!inputs.is_empty(), "{} holds no input for target `{name}`", dir.display());
    let mut failures = Vec::new();
    for path in &inputs {
        let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
        let seed = path.file_name().is_some_and(|n| n.to_string_lossy().starts_with("seed-"));
        match std::panic::catch_unwind(|| target(&bytes)) {
            Err(payload) => {
                failures.push(format!("{}: panics: {}", path.display(), message(payload.as_ref())))
            }
            Ok(false) if seed => {
                failures.push(format!("{}: a seed that is rejected", path.display()))
            }
            Ok(_) => {}
        }
    }
    ensure!(
        failures.is_empty(),
        "{} of {} inputs of target `{name}` fail:\n{}",
        failures.len(),
        inputs.len(),
        failures.join("\n")
    );
    Ok(())
}

#[test]
fn every_folder_is_a_target() -> anyhow::Result<()> {
    for entry in std::fs::read_dir(data())? {
        let name = entry?.file_name();
        let name = name.to_string_lossy();
        ensure!(
            targets::TARGETS.iter().any(|(n, _)| *n == name),
            "tests/data/fuzz/{name} is not a fuzz target, so its inputs would never be replayed"
        );
    }
    Ok(())
}

#[test]
fn obj_inputs_pass() -> anyhow::Result<()> {
    replay("obj")
}

#[test]
fn off_inputs_pass() -> anyhow::Result<()> {
    replay("off")
}

#[test]
fn ply_inputs_pass() -> anyhow::Result<()> {
    replay("ply")
}

#[test]
fn scene_inputs_pass() -> anyhow::Result<()> {
    replay("scene")
}

#[test]
fn suite_inputs_pass() -> anyhow::Result<()> {
    replay("suite")
}
