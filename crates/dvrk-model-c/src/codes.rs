//! The return codes of the entry points and their texts (`dvrk_error_string`), and the
//! library's version.

use std::ffi::{c_char, c_int, CStr};

/// Success.
pub const DVRK_OK: c_int = 0;
/// A pointer argument was NULL.
pub const DVRK_ERR_NULL: c_int = -1;
/// An input (`q`, `dq`, `ddq`, `tau`) holds a NaN or an infinity.
pub const DVRK_ERR_NOT_FINITE: c_int = -2;
/// The workspace was created for another model (`dvrk_workspace_new(model)`).
pub const DVRK_ERR_WORKSPACE: c_int = -3;
/// Forward dynamics: the mass matrix is not positive definite at `q` (the parameters are
/// not those of physical bodies).
pub const DVRK_ERR_NOT_POSITIVE_DEFINITE: c_int = -4;
/// A computed output is not finite (the parameters and motion overflow).
pub const DVRK_ERR_OVERFLOW: c_int = -5;
/// A bug in the library (a Rust panic, caught at the boundary). Please report it.
pub const DVRK_ERR_INTERNAL: c_int = -6;
/// An argument is out of its range: the observer's step `dt` is not positive (a
/// non-finite `dt` is `DVRK_ERR_NOT_FINITE`), or the observer was created for another
/// model.
pub const DVRK_ERR_ARGUMENT: c_int = -7;

/// A static, NUL-terminated description of a return code (`DVRK_OK`, `DVRK_ERR_*`);
/// "unknown error code" for any other value. Never NULL.
#[no_mangle]
pub extern "C" fn dvrk_error_string(code: c_int) -> *const c_char {
    let text: &'static CStr = match code {
        DVRK_OK => c"success",
        DVRK_ERR_NULL => c"a pointer argument is NULL",
        DVRK_ERR_NOT_FINITE => c"an input is not finite (NaN or infinity)",
        DVRK_ERR_WORKSPACE => c"the workspace was created for another model",
        DVRK_ERR_NOT_POSITIVE_DEFINITE => {
            c"the mass matrix is not positive definite (the parameters are not physical)"
        }
        DVRK_ERR_OVERFLOW => c"the result is not finite (the parameters and motion overflow)",
        DVRK_ERR_INTERNAL => c"internal error (a bug of dvrk-model-c; please report it)",
        DVRK_ERR_ARGUMENT => {
            c"an argument is out of range (a step dt <= 0, or an observer of another model)"
        }
        _ => c"unknown error code",
    };
    text.as_ptr()
}

/// The library's version (the workspace's, e.g. "0.1.0"), static and NUL-terminated.
#[no_mangle]
pub extern "C" fn dvrk_version() -> *const c_char {
    const VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), "\0");
    VERSION.as_ptr().cast()
}
