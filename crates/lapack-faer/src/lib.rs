//! The BLAS and LAPACK routines Clarabel's semidefinite cones call, written in Rust over
//! faer and exported under their Fortran names (`dgemm_`, `dsyevr_`, ...) with the
//! Fortran calling convention (every argument by pointer, column-major arrays).
//!
//! # Why
//!
//! Clarabel reaches dense linear algebra only through the `blas`/`lapack` crates, which
//! declare the Fortran symbols and leave it to a `blas-src`/`lapack-src` provider to
//! link a library that defines them. Every provider is a system or downloaded C/Fortran
//! library (OpenBLAS, Netlib, MKL, ...), so the tool failed to link on a machine without
//! `libopenblas-dev` and the Python wheel needed `libopenblas`. With `blas-src` and
//! `lapack-src` enabled without a provider feature they link nothing, and this crate
//! defines the symbols instead, on top of faer (already `dvrk-ident`'s dense QR): no
//! system library, nothing downloaded. `dvrk-ident` depends on it through its default
//! cargo feature `rust-lapack`; turn that off to link a real BLAS/LAPACK (then enable
//! e.g. `blas-src/openblas`).
//!
//! Only what Clarabel 0.11 calls is provided: `?gemm ?gemv ?symv ?syrk ?syr2k` (BLAS)
//! and `?potrf ?potrs ?syevr ?gesdd ?gesvd ?gesv` (LAPACK), single and double precision,
//! for every argument combination those routines define (all `trans`/`uplo`, strides
//! including negative increments, leading dimensions larger than the rows, every `job`
//! of the SVDs and every `range` of `?syevr`).
//!
//! A crate of its own because it is `unsafe` code (with the C ABI of dvrk-model-c, the
//! workspace's only): a Fortran
//! routine receives raw pointers and must turn them into arrays. Here that is isolated,
//! every unsafe operation carries its justification, and the routines are tested at the
//! ABI (`tests/abi.rs`, through the `blas`/`lapack` wrappers Clarabel calls); every
//! other crate of the workspace declares `#![forbid(unsafe_code)]`.
//!
//! # Linking
//!
//! The routines are reached by symbol name only, so nothing in Rust refers to them and a
//! linker may leave this crate's object files out. A crate that needs them calls
//! [`link`] on the path to Clarabel (`dvrk-ident` does in its semidefinite solve).
//!
//! # Contract
//!
//! - Arguments are checked in the reference order. An illegal LAPACK argument sets
//!   `info = -i` (i-th argument); a BLAS routine, which has no `info`, returns without
//!   touching its outputs. Both print the reference `xerbla` message on stderr but,
//!   unlike the reference, never stop the process. A null or misaligned pointer where
//!   the routine must read or write counts as an illegal value of that argument (the
//!   reference would crash).
//! - Arrays are only viewed with the extent their dimension arguments imply (see
//!   `mat_ref`), after the quick returns for empty problems, so an argument the
//!   routine does not reference (e.g. `z` of `?syevr` with `jobz = 'N'`) may be a dummy.
//!   As in Fortran, an output array must not overlap another argument.
//! - Workspaces: faer's scratch comes from a per-thread buffer (see `with_scratch`),
//!   so `work`/`iwork` are only checked against LAPACK's minimum sizes; a query
//!   (`lwork = -1`) returns that minimum, which is also all this implementation needs.
//! - Results are those of faer's algorithms: the same factorizations and
//!   decompositions, not the same rounding as a reference LAPACK (eigenvector and
//!   singular vector signs may differ, as between any two LAPACK builds). `abstol` of
//!   `?syevr` is ignored (faer always computes to full accuracy).

#![warn(missing_docs)]
// Every unsafe operation in its own block with its justification, also inside an
// `unsafe fn` (the 2024 edition's default).
#![deny(unsafe_op_in_unsafe_fn)]
#![warn(clippy::undocumented_unsafe_blocks)]

/// Exports a routine under its Fortran names, single precision then double: for each, a
/// module `T` is `f32` (`f64`) in, holding the `#[no_mangle] extern "C"` function of the
/// signature given once (every argument by pointer, `T` for the REAL arguments), whose
/// body is `$call`, the generic implementation's result. A `blas` routine reports an
/// illegal argument with the `xerbla` message only; a `lapack` routine also through the
/// trailing `info` argument the macro appends.
macro_rules! export {
    (
        $(#[$doc:meta])*
        $kind:ident $s:ident $s_name:literal, $d:ident $d_name:literal
        ($($arg:ident: $ty:ty),* $(,)?) => $call:expr
    ) => {
        export!(@one $kind f32, $s $s_name [$(#[$doc])*] ($($arg: $ty),*) $call);
        export!(@one $kind f64, $d $d_name [$(#[$doc])*] ($($arg: $ty),*) $call);
    };
    (
        @one $kind:ident $T:ty, $sym:ident $name:literal [$(#[$doc:meta])*]
        ($($arg:ident: $ty:ty),*) $call:expr
    ) => {
        pub use self::$sym::$sym;
        mod $sym {
            #[allow(clippy::wildcard_imports)]
            use super::*;
            type T = $T;
            export!(@fn $kind $sym $name [$(#[$doc])*] ($($arg: $ty),*) $call);
        }
    };
    (@fn blas $sym:ident $name:literal [$(#[$doc:meta])*] ($($arg:ident: $ty:ty),*) $call:expr) => {
        #[doc = concat!("`", $name, "`: ")]
        $(#[$doc])*
        ///
        /// # Safety
        /// Fortran BLAS contract: valid arguments, arrays of the extents the dimensions
        /// and increments imply, the output not overlapping the inputs.
        #[unsafe(no_mangle)]
        #[allow(clippy::too_many_arguments)]
        pub unsafe extern "C" fn $sym($($arg: $ty),*) {
            // SAFETY: forwarded contract.
            let result = unsafe { $call };
            $crate::blas_done($name, result);
        }
    };
    (@fn lapack $sym:ident $name:literal [$(#[$doc:meta])*] ($($arg:ident: $ty:ty),*) $call:expr) => {
        #[doc = concat!("`", $name, "`: ")]
        $(#[$doc])*
        ///
        /// # Safety
        /// Fortran LAPACK contract: valid arguments, arrays of the extents the dimensions
        /// imply, no output overlapping another argument.
        #[unsafe(no_mangle)]
        #[allow(clippy::too_many_arguments)]
        pub unsafe extern "C" fn $sym($($arg: $ty,)* info: *mut std::ffi::c_int) {
            // SAFETY: forwarded contract.
            unsafe { $crate::lapack_done($name, info, $call) };
        }
    };
}

mod blas2;
mod blas3;
mod cholesky;
mod eigen;
mod lu;
mod svd;

use std::cell::RefCell;
use std::ffi::{c_char, c_int};
use std::ptr::NonNull;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::{Accum, ColMut, ColRef, MatMut, MatRef};

/// The scalars of the `s` and `d` routines.
pub(crate) trait Real: faer::traits::RealField + Copy {
    /// A workspace size for `work[0]`, rounded up where the float cannot hold it exactly
    /// (as LAPACK's `?roundup_lwork`), so that reading it back never gives too little.
    fn from_size(n: usize) -> Self;
}

impl Real for f32 {
    fn from_size(n: usize) -> Self {
        let x = n as f32;
        if (x as usize) < n {
            f32::from_bits(x.to_bits() + 1)
        } else {
            x
        }
    }
}

impl Real for f64 {
    fn from_size(n: usize) -> Self {
        let x = n as f64;
        if (x as usize) < n {
            f64::from_bits(x.to_bits() + 1)
        } else {
            x
        }
    }
}

/// The 1-based position of an argument that had an illegal value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Illegal(pub i32);

/// What a BLAS routine does with an illegal argument: the reference `xerbla` message,
/// no output touched, no abort.
pub(crate) fn blas_done(name: &str, result: Result<(), Illegal>) {
    if let Err(Illegal(arg)) = result {
        xerbla(name, arg);
    }
}

/// What a LAPACK routine does on return: `info` set to the routine's result (0, or > 0
/// for a numerical failure), or to `-i` with the `xerbla` message for an illegal i-th
/// argument. A null `info` cannot be reported to and only gets the message.
///
/// # Safety
/// `info` is null or valid for one aligned write.
pub(crate) unsafe fn lapack_done(name: &str, info: *mut c_int, result: Result<i32, Illegal>) {
    let value = match result {
        Ok(v) => v,
        Err(Illegal(arg)) => {
            xerbla(name, arg);
            -arg
        }
    };
    if !info.is_null() && info.is_aligned() {
        // SAFETY: non-null and aligned; the caller passes an INTEGER to write.
        unsafe { *info = value };
    }
}

fn xerbla(name: &str, arg: i32) {
    eprintln!(" ** On entry to {name} parameter number {arg:2} had an illegal value");
}

/// Reads a scalar argument; null or misaligned is an illegal value of argument `arg`.
///
/// # Safety
/// `p` is null or valid for one read.
pub(crate) unsafe fn scalar<T: Copy>(p: *const T, arg: i32) -> Result<T, Illegal> {
    if p.is_null() || !p.is_aligned() {
        return Err(Illegal(arg));
    }
    // SAFETY: non-null and aligned, and valid for reads per the caller.
    Ok(unsafe { *p })
}

/// A CHARACTER option, upper-cased (Fortran's `LSAME` ignores case).
///
/// # Safety
/// As [`scalar`].
pub(crate) unsafe fn option(p: *const c_char, arg: i32) -> Result<u8, Illegal> {
    // SAFETY: forwarded contract.
    Ok((unsafe { scalar(p, arg) }? as u8).to_ascii_uppercase())
}

/// A dimension (`m`, `n`, `k`, `nrhs`): an INTEGER ≥ 0.
///
/// # Safety
/// As [`scalar`].
pub(crate) unsafe fn dim(p: *const c_int, arg: i32) -> Result<usize, Illegal> {
    // SAFETY: forwarded contract.
    usize::try_from(unsafe { scalar(p, arg) }?).map_err(|_| Illegal(arg))
}

/// A leading dimension: an INTEGER ≥ max(1, `rows`).
///
/// # Safety
/// As [`scalar`].
pub(crate) unsafe fn leading(p: *const c_int, arg: i32, rows: usize) -> Result<usize, Illegal> {
    // SAFETY: forwarded contract.
    let ld = unsafe { dim(p, arg) }?;
    if ld < rows.max(1) {
        return Err(Illegal(arg));
    }
    Ok(ld)
}

/// A vector increment: a nonzero INTEGER.
///
/// # Safety
/// As [`scalar`].
pub(crate) unsafe fn increment(p: *const c_int, arg: i32) -> Result<isize, Illegal> {
    // SAFETY: forwarded contract.
    match unsafe { scalar(p, arg) }? {
        0 => Err(Illegal(arg)),
        inc => Ok(inc as isize),
    }
}

/// A `trans` option: `true` for 'T' or 'C' (the same for real matrices), `false` for 'N'.
///
/// # Safety
/// As [`scalar`].
pub(crate) unsafe fn transposed(p: *const c_char, arg: i32) -> Result<bool, Illegal> {
    // SAFETY: forwarded contract.
    match unsafe { option(p, arg) }? {
        b'N' => Ok(false),
        b'T' | b'C' => Ok(true),
        _ => Err(Illegal(arg)),
    }
}

/// An `uplo` option: `true` for 'U', `false` for 'L'.
///
/// # Safety
/// As [`scalar`].
pub(crate) unsafe fn upper(p: *const c_char, arg: i32) -> Result<bool, Illegal> {
    // SAFETY: forwarded contract.
    match unsafe { option(p, arg) }? {
        b'U' => Ok(true),
        b'L' => Ok(false),
        _ => Err(Illegal(arg)),
    }
}

/// The one place a Fortran array becomes a faer view: `rows × cols`, column-major with
/// leading dimension `ld ≥ rows` (elements), at `ptr`. The view spans exactly the
/// elements the dimensions imply, `(cols − 1)·ld + rows`, which must fit in `isize`
/// bytes; `ptr` must be non-null and aligned unless the array is empty (then it is not
/// dereferenced, and a dummy such as a null pointer is fine, as in Fortran). A failed
/// check is an illegal value of argument `arg`.
///
/// # Safety
/// When the checks pass, `ptr` must be valid for reads of that extent for `'a`.
pub(crate) unsafe fn mat_ref<'a, T>(
    ptr: *const T,
    rows: usize,
    cols: usize,
    ld: usize,
    arg: i32,
) -> Result<MatRef<'a, T>, Illegal> {
    let ptr = checked_array(ptr as *mut T, rows, cols, ld, arg)?;
    // SAFETY: `checked_array` verified non-null, alignment and an extent that fits in
    // isize; the caller guarantees the memory.
    Ok(unsafe { MatRef::from_raw_parts(ptr.as_ptr(), rows, cols, 1, ld as isize) })
}

/// [`mat_ref`] for an array the routine writes.
///
/// # Safety
/// When the checks pass, `ptr` must be valid for reads and writes of that extent for
/// `'a` and not aliased by any other view in use.
pub(crate) unsafe fn mat_mut<'a, T>(
    ptr: *mut T,
    rows: usize,
    cols: usize,
    ld: usize,
    arg: i32,
) -> Result<MatMut<'a, T>, Illegal> {
    let ptr = checked_array(ptr, rows, cols, ld, arg)?;
    // SAFETY: as in `mat_ref`, plus exclusive access from the caller.
    Ok(unsafe { MatMut::from_raw_parts_mut(ptr.as_ptr(), rows, cols, 1, ld as isize) })
}

/// A BLAS vector of `len` elements `inc` apart (a negative `inc` walks it backwards from
/// its last element, which is stored first): a `1 × len` [`mat_ref`] with leading
/// dimension `|inc|`, reversed when `inc < 0`.
///
/// # Safety
/// As [`mat_ref`], for the extent `(len − 1)·|inc| + 1`.
pub(crate) unsafe fn vec_ref<'a, T>(
    ptr: *const T,
    len: usize,
    inc: isize,
    arg: i32,
) -> Result<ColRef<'a, T>, Illegal> {
    // SAFETY: forwarded contract.
    let row = unsafe { mat_ref(ptr, 1, len, inc.unsigned_abs(), arg) }?;
    let row = if inc < 0 { row.reverse_cols() } else { row };
    Ok(row.row(0).transpose())
}

/// [`vec_ref`] for a vector the routine writes.
///
/// # Safety
/// As [`mat_mut`], for the extent `(len − 1)·|inc| + 1`.
pub(crate) unsafe fn vec_mut<'a, T>(
    ptr: *mut T,
    len: usize,
    inc: isize,
    arg: i32,
) -> Result<ColMut<'a, T>, Illegal> {
    // SAFETY: forwarded contract.
    let row = unsafe { mat_mut(ptr, 1, len, inc.unsigned_abs(), arg) }?;
    let row = if inc < 0 { row.reverse_cols_mut() } else { row };
    Ok(row.row_mut(0).transpose_mut())
}

/// A contiguous array of `len` elements (`ipiv`, `isuppz`, the singular values), through
/// the same checks as [`mat_mut`].
///
/// # Safety
/// As [`mat_mut`], for `len` elements.
pub(crate) unsafe fn slice_mut<'a, T>(
    ptr: *mut T,
    len: usize,
    arg: i32,
) -> Result<&'a mut [T], Illegal> {
    let ptr = checked_array(ptr, len, 1, len, arg)?;
    // SAFETY: as in `mat_mut`.
    Ok(unsafe { std::slice::from_raw_parts_mut(ptr.as_ptr(), len) })
}

/// The checks of [`mat_ref`]; a dangling (never dereferenced) pointer for an empty array.
fn checked_array<T>(
    ptr: *mut T,
    rows: usize,
    cols: usize,
    ld: usize,
    arg: i32,
) -> Result<NonNull<T>, Illegal> {
    if rows == 0 || cols == 0 {
        return Ok(NonNull::dangling());
    }
    let extent = (cols - 1)
        .checked_mul(ld)
        .and_then(|e| e.checked_add(rows))
        .and_then(|e| e.checked_mul(size_of::<T>().max(1)));
    let fits = extent.is_some_and(|bytes| bytes <= isize::MAX as usize);
    if ld < rows || !fits || !ptr.is_aligned() {
        return Err(Illegal(arg));
    }
    NonNull::new(ptr).ok_or(Illegal(arg))
}

/// Which part of a square matrix a BLAS routine updates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Part {
    All,
    Lower,
    Upper,
}

/// `c ← beta·c` on `part`, where `beta = 0` sets zeros without reading `c` (reference
/// BLAS: a NaN in `c` does not survive `beta = 0`).
pub(crate) fn scale<T: Real>(mut c: MatMut<'_, T>, beta: T, part: Part) {
    if beta == T::one() {
        return;
    }
    for j in 0..c.ncols() {
        let rows = match part {
            Part::All => 0..c.nrows(),
            Part::Lower => j..c.nrows(),
            Part::Upper => 0..(j + 1).min(c.nrows()),
        };
        for i in rows {
            let v = if beta == T::zero() {
                T::zero()
            } else {
                beta * c[(i, j)]
            };
            c[(i, j)] = v;
        }
    }
}

/// Prepares `c` for `c ← product + beta·c` on `part`, returning how faer's matmul must
/// write the product: `beta = 0` overwrites (reference BLAS never reads `c` then),
/// otherwise `c` is scaled here and the product added.
pub(crate) fn accumulate<T: Real>(c: MatMut<'_, T>, beta: T, part: Part) -> Accum {
    if beta == T::zero() {
        Accum::Replace
    } else {
        scale(c, beta, part);
        Accum::Add
    }
}

/// Runs `f` with at least `req` of faer scratch, taken from a per-thread buffer kept
/// between calls (grown to the largest request seen, freed with the thread): Clarabel
/// calls these routines thousands of times per solve on 4×4 blocks, where a fresh
/// aligned allocation per call and temporary cost about 5% of the solve's instructions
/// (callgrind on the PSM/MTM fits). The caller's `work` is not used (see the module
/// documentation). A nested call on the same thread gets a buffer of its own.
pub(crate) fn with_scratch<R>(req: StackReq, f: impl FnOnce(&mut MemStack) -> R) -> R {
    thread_local! {
        static SCRATCH: RefCell<Option<(MemBuffer, StackReq)>> = const { RefCell::new(None) };
    }
    SCRATCH.with(|cell| match cell.try_borrow_mut() {
        Ok(mut slot) => {
            let fits = slot.as_ref().is_some_and(|(_, have)| {
                have.size_bytes() >= req.size_bytes() && have.align_bytes() >= req.align_bytes()
            });
            if !fits {
                let grown = slot.as_ref().map_or(req, |(_, have)| have.or(req));
                *slot = Some((MemBuffer::new(grown), grown));
            }
            match slot.as_mut() {
                Some((buffer, _)) => f(MemStack::new(buffer)),
                None => unreachable!("filled above"),
            }
        }
        Err(_) => f(MemStack::new(&mut MemBuffer::new(req))),
    })
}

/// Makes the linker keep every exported routine: call it (it does nothing else) from the
/// code that leads to Clarabel. The routines are only ever named by symbol; Clarabel's
/// archive references them after this crate's on the link line, which a single-pass
/// linker (GNU ld) would not resolve backwards, and a linker keeps only the object files
/// something refers to. Referencing them all from a function the program calls pulls
/// them in, whatever the linker, into binaries, tests and shared libraries (the Python
/// extension) alike.
pub fn link() {
    let routines: [*const (); 22] = [
        blas3::sgemm_ as *const (),
        blas3::dgemm_ as *const (),
        blas3::ssyrk_ as *const (),
        blas3::dsyrk_ as *const (),
        blas3::ssyr2k_ as *const (),
        blas3::dsyr2k_ as *const (),
        blas2::sgemv_ as *const (),
        blas2::dgemv_ as *const (),
        blas2::ssymv_ as *const (),
        blas2::dsymv_ as *const (),
        cholesky::spotrf_ as *const (),
        cholesky::dpotrf_ as *const (),
        cholesky::spotrs_ as *const (),
        cholesky::dpotrs_ as *const (),
        lu::sgesv_ as *const (),
        lu::dgesv_ as *const (),
        eigen::ssyevr_ as *const (),
        eigen::dsyevr_ as *const (),
        svd::sgesdd_ as *const (),
        svd::dgesdd_ as *const (),
        svd::sgesvd_ as *const (),
        svd::dgesvd_ as *const (),
    ];
    std::hint::black_box(routines);
}
