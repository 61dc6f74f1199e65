//! The `dvrk-ident` binary: the command line of [`dvrk_cli::run`].

use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(dvrk_cli::run(std::env::args_os()))
}
