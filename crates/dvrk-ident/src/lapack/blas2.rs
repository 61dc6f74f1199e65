//! Level-2 BLAS: `?gemv` and `?symv` (Clarabel's dense matrix-vector products), over
//! faer's matmul with the vectors as one-column matrices (any nonzero increment).

use std::ffi::{c_char, c_int};

use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::reborrow::ReborrowMut;
use faer::{Accum, Par};

use super::{accumulate, dim, increment, leading, mat_ref, scalar, scale};
use super::{transposed, upper, vec_mut, vec_ref, Illegal, Part, Real};

/// `y ← alpha·op(A)·x + beta·y`, `A` m×n. Quick returns as the reference: nothing when
/// `m = 0`, `n = 0` or `alpha = 0` with `beta = 1`; `A` and `x` are not read when
/// `alpha = 0`.
#[allow(clippy::too_many_arguments)]
unsafe fn gemv<T: Real>(
    trans: *const c_char,
    m: *const c_int,
    n: *const c_int,
    alpha: *const T,
    a: *const T,
    lda: *const c_int,
    x: *const T,
    incx: *const c_int,
    beta: *const T,
    y: *mut T,
    incy: *const c_int,
) -> Result<(), Illegal> {
    // SAFETY (whole body): the caller passes valid Fortran arguments; every pointer is
    // read or viewed through the checked helpers with the extent its dimensions imply.
    unsafe {
        let t = transposed(trans, 1)?;
        let m = dim(m, 2)?;
        let n = dim(n, 3)?;
        let lda = leading(lda, 6, m)?;
        let incx = increment(incx, 8)?;
        let incy = increment(incy, 11)?;
        if m == 0 || n == 0 {
            return Ok(());
        }
        let alpha = scalar(alpha, 4)?;
        let beta = scalar(beta, 9)?;
        if alpha == T::zero() && beta == T::one() {
            return Ok(());
        }
        let (len_x, len_y) = if t { (m, n) } else { (n, m) };
        let mut y = vec_mut(y, len_y, incy, 10)?.as_mat_mut();
        if alpha == T::zero() {
            scale(y, beta, Part::All);
            return Ok(());
        }
        let a = mat_ref(a, m, n, lda, 5)?;
        let a = if t { a.transpose() } else { a };
        let x = vec_ref(x, len_x, incx, 7)?.as_mat();
        let accum = accumulate(y.rb_mut(), beta, Part::All);
        matmul(y, accum, a, x, alpha, Par::Seq);
        Ok(())
    }
}

/// `y ← alpha·A·x + beta·y`, `A` n×n symmetric of which only the `uplo` triangle is
/// read. Quick returns as `gemv`.
#[allow(clippy::too_many_arguments)]
unsafe fn symv<T: Real>(
    uplo: *const c_char,
    n: *const c_int,
    alpha: *const T,
    a: *const T,
    lda: *const c_int,
    x: *const T,
    incx: *const c_int,
    beta: *const T,
    y: *mut T,
    incy: *const c_int,
) -> Result<(), Illegal> {
    // SAFETY: as in `gemv`.
    unsafe {
        let up = upper(uplo, 1)?;
        let n = dim(n, 2)?;
        let lda = leading(lda, 5, n)?;
        let incx = increment(incx, 7)?;
        let incy = increment(incy, 10)?;
        if n == 0 {
            return Ok(());
        }
        let alpha = scalar(alpha, 3)?;
        let beta = scalar(beta, 8)?;
        if alpha == T::zero() && beta == T::one() {
            return Ok(());
        }
        let mut y = vec_mut(y, n, incy, 9)?.as_mat_mut();
        if alpha == T::zero() {
            scale(y, beta, Part::All);
            return Ok(());
        }
        // The stored triangle as a lower one L (the upper one transposed is the same
        // data): A = L + strict(L)ᵀ.
        let a = mat_ref(a, n, n, lda, 4)?;
        let lower = if up { a.transpose() } else { a };
        let x = vec_ref(x, n, incx, 6)?.as_mat();
        let accum = accumulate(y.rb_mut(), beta, Part::All);
        for (l, structure, accum) in [
            (lower, BlockStructure::TriangularLower, accum),
            (
                lower.transpose(),
                BlockStructure::StrictTriangularUpper,
                Accum::Add,
            ),
        ] {
            triangular::matmul(
                y.rb_mut(),
                BlockStructure::Rectangular,
                accum,
                l,
                structure,
                x,
                BlockStructure::Rectangular,
                alpha,
                Par::Seq,
            );
        }
        Ok(())
    }
}

export! {
    /// general matrix-vector product (see `gemv`).
    blas sgemv_ "SGEMV", dgemv_ "DGEMV"
    (trans: *const c_char, m: *const c_int, n: *const c_int, alpha: *const T, a: *const T,
     lda: *const c_int, x: *const T, incx: *const c_int, beta: *const T, y: *mut T,
     incy: *const c_int)
    => gemv::<T>(trans, m, n, alpha, a, lda, x, incx, beta, y, incy)
}

export! {
    /// symmetric matrix-vector product (see `symv`).
    blas ssymv_ "SSYMV", dsymv_ "DSYMV"
    (uplo: *const c_char, n: *const c_int, alpha: *const T, a: *const T, lda: *const c_int,
     x: *const T, incx: *const c_int, beta: *const T, y: *mut T, incy: *const c_int)
    => symv::<T>(uplo, n, alpha, a, lda, x, incx, beta, y, incy)
}
