//! Helpers shared by the workspace tests.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

/// Runs the `shadowbench` binary with `args`.
pub fn shadowbench(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_shadowbench"))
        .args(args)
        .output()
        .expect("the shadowbench binary runs")
}

/// Standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Writes `text` to `dir/name` and returns the path as a string.
pub fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("writes the test file");
    p.to_string_lossy().into_owned()
}
