//! The command line as a user meets it: the CLI contract of DESIGN.md (`scenes`, `render`,
//! `compare`), every bad input refused with exit code 2 and one message, and every input the
//! fuzzers saved replayed.

#[path = "../common/mod.rs"]
mod common;

mod animate;
mod bad_input;
mod cli;
mod compare;
mod external;
mod fuzz_regressions;
mod methods_table;
mod scene_messages;
