//! The GPU kernels against their CPU twins, one module per technique, on Mesa's llvmpipe
//! where no GPU is present. Built only with the `gpu` feature (on by default).
#![cfg(feature = "gpu")]

#[path = "../common/mod.rs"]
mod common;

mod afsm;
mod afsm_ss;
mod filtered;
mod ftizb;
mod pan09;
mod raster;
mod sm_pcf;
mod spsm;
