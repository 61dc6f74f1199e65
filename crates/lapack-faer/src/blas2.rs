//! Level-2 BLAS: `?gemv` and `?symv` (Clarabel's dense matrix-vector products), over
//! faer's matmul with the vectors as one-column matrices (any nonzero increment).

use std::ffi::{c_char, c_int};

use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::reborrow::ReborrowMut;
use faer::{Accum, Par};

use super::{accumulate, dim, increment, leading, mat_ref, scalar, scale};
use super::{transposed, upper, vec_mut, vec_ref, Illegal, Part, Real};

/// The matrix of a matrix-vector product, from the routine's leading arguments.
#[derive(Clone, Copy)]
enum Operand {
    /// `?gemv`'s `op(A)`, `A` m×n (transposed or not).
    General {
        transposed: bool,
        m: usize,
        n: usize,
    },
    /// `?symv`'s `A`, n×n symmetric, of which only the `uplo` triangle is read.
    Symmetric { upper: bool, n: usize },
}

impl Operand {
    /// `?gemv`'s `trans`, `m`, `n` (arguments 1 to 3).
    ///
    /// # Safety
    /// As [`scalar`].
    unsafe fn general(
        trans: *const c_char,
        m: *const c_int,
        n: *const c_int,
    ) -> Result<Self, Illegal> {
        // SAFETY: forwarded contract.
        unsafe {
            Ok(Operand::General {
                transposed: transposed(trans, 1)?,
                m: dim(m, 2)?,
                n: dim(n, 3)?,
            })
        }
    }

    /// `?symv`'s `uplo`, `n` (arguments 1 and 2).
    ///
    /// # Safety
    /// As [`scalar`].
    unsafe fn symmetric(uplo: *const c_char, n: *const c_int) -> Result<Self, Illegal> {
        // SAFETY: forwarded contract.
        unsafe {
            Ok(Operand::Symmetric {
                upper: upper(uplo, 1)?,
                n: dim(n, 2)?,
            })
        }
    }
}

/// `y ← alpha·op(A)·x + beta·y` for `?gemv` and `?symv`, whose arguments from `alpha` on
/// are the same (`alpha` is argument 4 of `?gemv`, 3 of `?symv`). Quick returns as the
/// reference: nothing when `A` is empty or `alpha = 0` with `beta = 1`; `A` and `x` are
/// not read when `alpha = 0`.
#[allow(clippy::too_many_arguments)]
unsafe fn matvec<T: Real>(
    operand: Operand,
    alpha: *const T,
    a: *const T,
    lda: *const c_int,
    x: *const T,
    incx: *const c_int,
    beta: *const T,
    y: *mut T,
    incy: *const c_int,
) -> Result<(), Illegal> {
    let (rows, cols, first) = match operand {
        Operand::General { m, n, .. } => (m, n, 4),
        Operand::Symmetric { n, .. } => (n, n, 3),
    };
    // SAFETY: (whole body) the caller passes valid Fortran arguments; every pointer is
    // read or viewed through the checked helpers with the extent its dimensions imply.
    unsafe {
        let lda = leading(lda, first + 2, rows)?;
        let incx = increment(incx, first + 4)?;
        let incy = increment(incy, first + 7)?;
        if rows == 0 || cols == 0 {
            return Ok(());
        }
        let alpha = scalar(alpha, first)?;
        let beta = scalar(beta, first + 5)?;
        if alpha == T::zero() && beta == T::one() {
            return Ok(());
        }
        let (len_x, len_y) = match operand {
            Operand::General {
                transposed: true, ..
            } => (rows, cols),
            _ => (cols, rows),
        };
        let mut y = vec_mut(y, len_y, incy, first + 6)?.as_mat_mut();
        if alpha == T::zero() {
            scale(y, beta, Part::All);
            return Ok(());
        }
        let a = mat_ref(a, rows, cols, lda, first + 1)?;
        let x = vec_ref(x, len_x, incx, first + 3)?.as_mat();
        let accum = accumulate(y.rb_mut(), beta, Part::All);
        match operand {
            Operand::General { transposed, .. } => {
                let a = if transposed { a.transpose() } else { a };
                matmul(y, accum, a, x, alpha, Par::Seq);
            }
            Operand::Symmetric { upper, .. } => {
                // The stored triangle as a lower one L (the upper one transposed is the
                // same data): A = L + strict(L)ᵀ.
                let lower = if upper { a.transpose() } else { a };
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
            }
        }
        Ok(())
    }
}

export! {
    /// general matrix-vector product (see `matvec`).
    blas sgemv_ "SGEMV", dgemv_ "DGEMV"
    (trans: *const c_char, m: *const c_int, n: *const c_int, alpha: *const T, a: *const T,
     lda: *const c_int, x: *const T, incx: *const c_int, beta: *const T, y: *mut T,
     incy: *const c_int)
    => Operand::general(trans, m, n)
        .and_then(|op| matvec::<T>(op, alpha, a, lda, x, incx, beta, y, incy))
}

export! {
    /// symmetric matrix-vector product (see `matvec`).
    blas ssymv_ "SSYMV", dsymv_ "DSYMV"
    (uplo: *const c_char, n: *const c_int, alpha: *const T, a: *const T, lda: *const c_int,
     x: *const T, incx: *const c_int, beta: *const T, y: *mut T, incy: *const c_int)
    => Operand::symmetric(uplo, n)
        .and_then(|op| matvec::<T>(op, alpha, a, lda, x, incx, beta, y, incy))
}
