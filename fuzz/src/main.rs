//! The AFL++ entry point: `shadowbench-fuzz TARGET` runs target `TARGET` of the library
//! (`obj`, `off`, `ply`, `scene`, `suite`) on the inputs AFL++ feeds it. One binary serves
//! every target, so that the instrumented build links once.

use shadowbench_fuzz::TARGETS;
use std::process::ExitCode;

fn main() -> ExitCode {
    let name = std::env::args().nth(1).unwrap_or_default();
    let Some(&(_, target)) = TARGETS.iter().find(|(n, _)| *n == name) else {
        let names: Vec<&str> = TARGETS.iter().map(|(n, _)| *n).collect();
        eprintln!("shadowbench-fuzz: unknown target `{name}` (targets: {})", names.join(", "));
        return ExitCode::from(2);
    };
    afl::fuzz!(|data: &[u8]| {
        target(data);
    });
    ExitCode::SUCCESS
}
