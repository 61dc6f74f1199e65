//! The `dvrk-ident` binary: the command line of [`dvrk_cli::run`].

// No unsafe code: the workspace's only unsafe code is crates/lapack-faer (the Fortran-ABI
// BLAS/LAPACK Clarabel calls).
#![forbid(unsafe_code)]

use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(dvrk_cli::run(std::env::args_os()))
}
