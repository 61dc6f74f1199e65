//! Level-3 BLAS: `?gemm` (Clarabel's dense products), `?syrk` and `?syr2k` (its
//! symmetric updates in the PSD cone's scaling), over faer's (triangular) matmul.

use std::ffi::{c_char, c_int};

use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::reborrow::ReborrowMut;
use faer::{Accum, MatRef, Par};

use super::{accumulate, dim, leading, mat_mut, mat_ref, scalar, scale, transposed};
use super::{upper, Illegal, Part, Real};

/// `C ← alpha·op(A)·op(B) + beta·C`, `C` m×n. Quick returns as the reference: nothing
/// when `m = 0`, `n = 0` or (`alpha = 0` or `k = 0`) with `beta = 1`; `A` and `B` are
/// not read when `alpha = 0` or `k = 0`.
#[allow(clippy::too_many_arguments)]
unsafe fn gemm<T: Real>(
    transa: *const c_char,
    transb: *const c_char,
    m: *const c_int,
    n: *const c_int,
    k: *const c_int,
    alpha: *const T,
    a: *const T,
    lda: *const c_int,
    b: *const T,
    ldb: *const c_int,
    beta: *const T,
    c: *mut T,
    ldc: *const c_int,
) -> Result<(), Illegal> {
    // SAFETY: (whole body) the caller passes valid Fortran arguments; every pointer is
    // read or viewed through the checked helpers with the extent its dimensions imply.
    unsafe {
        let ta = transposed(transa, 1)?;
        let tb = transposed(transb, 2)?;
        let m = dim(m, 3)?;
        let n = dim(n, 4)?;
        let k = dim(k, 5)?;
        let (a_rows, a_cols) = if ta { (k, m) } else { (m, k) };
        let (b_rows, b_cols) = if tb { (n, k) } else { (k, n) };
        let lda = leading(lda, 8, a_rows)?;
        let ldb = leading(ldb, 10, b_rows)?;
        let ldc = leading(ldc, 13, m)?;
        if m == 0 || n == 0 {
            return Ok(());
        }
        let alpha = scalar(alpha, 6)?;
        let beta = scalar(beta, 11)?;
        let no_product = alpha == T::zero() || k == 0;
        if no_product && beta == T::one() {
            return Ok(());
        }
        let mut c = mat_mut(c, m, n, ldc, 12)?;
        if no_product {
            scale(c, beta, Part::All);
            return Ok(());
        }
        let a = op(mat_ref(a, a_rows, a_cols, lda, 7)?, ta);
        let b = op(mat_ref(b, b_rows, b_cols, ldb, 9)?, tb);
        let accum = accumulate(c.rb_mut(), beta, Part::All);
        matmul(c, accum, a, b, alpha, Par::Seq);
        Ok(())
    }
}

/// The symmetric rank updates on the `uplo` triangle of `C` (n×n), the other triangle
/// neither read nor written: `?syrk` (`b = None`), `C ← alpha·op(A)·op(A)ᵀ + beta·C`, and
/// `?syr2k`, `C ← alpha·(op(A)·op(B)ᵀ + op(B)·op(A)ᵀ) + beta·C`, where `op(X)` is `X`
/// (n×k) for `trans = 'N'` and `Xᵀ` (X k×n) otherwise. Argument positions are
/// `?syr2k`'s; `?syrk`'s after `lda` are two less (no `b`, `ldb`). Quick returns as
/// `gemm`.
#[allow(clippy::too_many_arguments)]
unsafe fn rank_update<T: Real>(
    uplo: *const c_char,
    trans: *const c_char,
    n: *const c_int,
    k: *const c_int,
    alpha: *const T,
    a: *const T,
    lda: *const c_int,
    b: Option<(*const T, *const c_int)>,
    beta: *const T,
    c: *mut T,
    ldc: *const c_int,
) -> Result<(), Illegal> {
    let shift = if b.is_some() { 0 } else { -2 };
    // SAFETY: as in `gemm`.
    unsafe {
        let up = upper(uplo, 1)?;
        let t = transposed(trans, 2)?;
        let n = dim(n, 3)?;
        let k = dim(k, 4)?;
        let (rows, cols) = if t { (k, n) } else { (n, k) };
        let lda = leading(lda, 7, rows)?;
        let ldb = match b {
            Some((_, ldb)) => leading(ldb, 9, rows)?,
            None => lda,
        };
        let ldc = leading(ldc, 12 + shift, n)?;
        if n == 0 {
            return Ok(());
        }
        let alpha = scalar(alpha, 5)?;
        let beta = scalar(beta, 10 + shift)?;
        let no_product = alpha == T::zero() || k == 0;
        if no_product && beta == T::one() {
            return Ok(());
        }
        let mut c = mat_mut(c, n, n, ldc, 11 + shift)?;
        let (part, structure) = if up {
            (Part::Upper, BlockStructure::TriangularUpper)
        } else {
            (Part::Lower, BlockStructure::TriangularLower)
        };
        if no_product {
            scale(c, beta, part);
            return Ok(());
        }
        let a = op(mat_ref(a, rows, cols, lda, 6)?, t);
        let terms = match b {
            Some((b, _)) => {
                let b = op(mat_ref(b, rows, cols, ldb, 8)?, t);
                vec![(a, b), (b, a)]
            }
            None => vec![(a, a)],
        };
        let mut accum = accumulate(c.rb_mut(), beta, part);
        for (x, y) in terms {
            triangular::matmul(
                c.rb_mut(),
                structure,
                accum,
                x,
                BlockStructure::Rectangular,
                y.transpose(),
                BlockStructure::Rectangular,
                alpha,
                Par::Seq,
            );
            accum = Accum::Add;
        }
        Ok(())
    }
}

/// `A` or `Aᵀ`.
fn op<T>(a: MatRef<'_, T>, transposed: bool) -> MatRef<'_, T> {
    if transposed {
        a.transpose()
    } else {
        a
    }
}

export! {
    /// general matrix product (see `gemm`).
    blas sgemm_ "SGEMM", dgemm_ "DGEMM"
    (transa: *const c_char, transb: *const c_char, m: *const c_int, n: *const c_int,
     k: *const c_int, alpha: *const T, a: *const T, lda: *const c_int, b: *const T,
     ldb: *const c_int, beta: *const T, c: *mut T, ldc: *const c_int)
    => gemm::<T>(transa, transb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc)
}

export! {
    /// symmetric rank-k update (see `rank_update`).
    blas ssyrk_ "SSYRK", dsyrk_ "DSYRK"
    (uplo: *const c_char, trans: *const c_char, n: *const c_int, k: *const c_int,
     alpha: *const T, a: *const T, lda: *const c_int, beta: *const T, c: *mut T,
     ldc: *const c_int)
    => rank_update::<T>(uplo, trans, n, k, alpha, a, lda, None, beta, c, ldc)
}

export! {
    /// symmetric rank-2k update (see `rank_update`).
    blas ssyr2k_ "SSYR2K", dsyr2k_ "DSYR2K"
    (uplo: *const c_char, trans: *const c_char, n: *const c_int, k: *const c_int,
     alpha: *const T, a: *const T, lda: *const c_int, b: *const T, ldb: *const c_int,
     beta: *const T, c: *mut T, ldc: *const c_int)
    => rank_update::<T>(uplo, trans, n, k, alpha, a, lda, Some((b, ldb)), beta, c, ldc)
}
