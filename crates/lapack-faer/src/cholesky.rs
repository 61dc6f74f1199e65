//! `?potrf` and `?potrs`: Clarabel's Cholesky factorization of the PSD cone blocks and
//! its solves, over faer's LLᵀ.

use std::ffi::{c_char, c_int};

use faer::linalg::cholesky::llt;
use faer::linalg::cholesky::llt::factor::LltError;
use faer::linalg::{temp_mat_scratch, temp_mat_zeroed};
use faer::mat::AsMatMut;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{MatMut, MatRef, Par};

use super::{dim, leading, mat_mut, mat_ref, upper, with_scratch, Illegal, Real};

/// Factors the symmetric `A` (n×n, the `uplo` triangle) in place: `A = Uᵀ·U` ('U') or
/// `L·Lᵀ` ('L') in that triangle, the other triangle untouched. `info = i > 0` when the
/// leading minor of order i is not positive definite (NaN included), as LAPACK: the
/// factorization stopped there.
unsafe fn potrf<T: Real>(
    uplo: *const c_char,
    n: *const c_int,
    a: *mut T,
    lda: *const c_int,
) -> Result<i32, Illegal> {
    // SAFETY: (whole body) the caller passes valid Fortran arguments; every pointer is
    // read or viewed through the checked helpers with the extent its dimensions imply.
    unsafe {
        let up = upper(uplo, 1)?;
        let n = dim(n, 2)?;
        let lda = leading(lda, 4, n)?;
        if n == 0 {
            return Ok(0);
        }
        let a = mat_mut(a, n, n, lda, 3)?;
        // Uᵀ is the lower factor of the upper triangle read as a lower one.
        let mut lower = if up { a.transpose_mut() } else { a };
        // faer works on a copy: its in-place factorization also writes above the
        // diagonal, where LAPACK promises to leave the caller's other triangle alone.
        let req = temp_mat_scratch::<T>(n, n).and(llt::factor::cholesky_in_place_scratch::<T>(
            n,
            Par::Seq,
            Default::default(),
        ));
        let factored = with_scratch(req, |stack| {
            let (mut factor, stack) = temp_mat_zeroed::<T, _, _>(n, n, stack);
            let mut factor = factor.as_mat_mut();
            copy_lower(factor.rb_mut(), lower.rb());
            let factored = llt::factor::cholesky_in_place(
                factor.rb_mut(),
                Default::default(),
                Par::Seq,
                stack,
                Default::default(),
            );
            // Also after a failure, as LAPACK leaves the part it factored.
            copy_lower(lower.rb_mut(), factor.rb());
            factored
        });
        Ok(match factored {
            Ok(_) => 0,
            Err(LltError::NonPositivePivot { index }) => index as i32 + 1,
        })
    }
}

/// Copies the lower triangle (diagonal included) of `src` into `dst`.
fn copy_lower<T: Real>(mut dst: MatMut<'_, T>, src: MatRef<'_, T>) {
    for j in 0..src.ncols() {
        for i in j..src.nrows() {
            dst[(i, j)] = src[(i, j)];
        }
    }
}

/// Solves `A·X = B` in place of `B` (n×nrhs) from the factor `?potrf` left in the
/// `uplo` triangle of `A`.
#[allow(clippy::too_many_arguments)]
unsafe fn potrs<T: Real>(
    uplo: *const c_char,
    n: *const c_int,
    nrhs: *const c_int,
    a: *const T,
    lda: *const c_int,
    b: *mut T,
    ldb: *const c_int,
) -> Result<i32, Illegal> {
    // SAFETY: as in `potrf`.
    unsafe {
        let up = upper(uplo, 1)?;
        let n = dim(n, 2)?;
        let nrhs = dim(nrhs, 3)?;
        let lda = leading(lda, 5, n)?;
        let ldb = leading(ldb, 7, n)?;
        if n == 0 || nrhs == 0 {
            return Ok(0);
        }
        let a = mat_ref(a, n, n, lda, 4)?;
        let b = mat_mut(b, n, nrhs, ldb, 6)?;
        let lower = if up { a.transpose() } else { a };
        with_scratch(
            llt::solve::solve_in_place_scratch::<T>(n, nrhs, Par::Seq),
            |stack| llt::solve::solve_in_place(lower, b, Par::Seq, stack),
        );
        Ok(0)
    }
}

export! {
    /// Cholesky factorization (see `potrf`).
    lapack spotrf_ "SPOTRF", dpotrf_ "DPOTRF"
    (uplo: *const c_char, n: *const c_int, a: *mut T, lda: *const c_int)
    => potrf::<T>(uplo, n, a, lda)
}

export! {
    /// solve from a Cholesky factor (see `potrs`).
    lapack spotrs_ "SPOTRS", dpotrs_ "DPOTRS"
    (uplo: *const c_char, n: *const c_int, nrhs: *const c_int, a: *const T,
     lda: *const c_int, b: *mut T, ldb: *const c_int)
    => potrs::<T>(uplo, n, nrhs, a, lda, b, ldb)
}
