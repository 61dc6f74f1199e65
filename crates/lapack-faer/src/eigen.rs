//! `?syevr`: Clarabel's symmetric eigendecomposition (the PSD cone projections and
//! step lengths), over faer's self-adjoint EVD.

use std::ffi::{c_char, c_int};

use faer::dyn_stack::StackReq;
use faer::linalg::evd::{self, ComputeEigenvectors};
use faer::linalg::{temp_mat_scratch, temp_mat_zeroed};
use faer::mat::AsMatMut;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::Par;

use super::{dim, leading, mat_mut, mat_ref, option, scalar, slice_mut};
use super::{upper, with_scratch, Illegal, Real};

/// Eigenvalues (ascending in `w[..m]`) and optionally eigenvectors (columns of `z`,
/// orthonormal) of the symmetric `A` (n×n, the `uplo` triangle read; `A` is not
/// modified, which LAPACK allows). `range`: 'A' all, 'I' the `il`-th to `iu`-th
/// (1-based, ascending), 'V' those in `(vl, vu]`; `m` receives their number. With
/// `jobz = 'V'`, `isuppz[2i..2i+2]` receives the first and last row (1-based) where
/// eigenvector i is nonzero. `abstol` is ignored (full accuracy always). `info = 1`
/// when faer's iteration did not converge (LAPACK: "internal error").
#[allow(clippy::too_many_arguments)]
unsafe fn syevr<T: Real>(
    jobz: *const c_char,
    range: *const c_char,
    uplo: *const c_char,
    n: *const c_int,
    a: *mut T,
    lda: *const c_int,
    vl: *const T,
    vu: *const T,
    il: *const c_int,
    iu: *const c_int,
    m: *mut c_int,
    w: *mut T,
    z: *mut T,
    ldz: *const c_int,
    isuppz: *mut c_int,
    work: *mut T,
    lwork: *const c_int,
    iwork: *mut c_int,
    liwork: *const c_int,
) -> Result<i32, Illegal> {
    // SAFETY: (whole body) the caller passes valid Fortran arguments; every pointer is
    // read or viewed through the checked helpers with the extent its dimensions imply.
    unsafe {
        let wantz = match option(jobz, 1)? {
            b'V' => true,
            b'N' => false,
            _ => return Err(Illegal(1)),
        };
        let range = option(range, 2)?;
        if !matches!(range, b'A' | b'V' | b'I') {
            return Err(Illegal(2));
        }
        let up = upper(uplo, 3)?;
        let n = dim(n, 4)?;
        let lda = leading(lda, 6, n)?;
        let mut bounds = (T::zero(), T::zero());
        let mut indices = (0, 0);
        if range == b'V' {
            bounds = (scalar(vl, 7)?, scalar(vu, 8)?);
            if n > 0 && bounds.1 <= bounds.0 {
                return Err(Illegal(8));
            }
        } else if range == b'I' {
            let (il, iu) = (scalar(il, 9)?, scalar(iu, 10)?);
            if il < 1 || il as usize > n.max(1) {
                return Err(Illegal(9));
            }
            if (iu as i64) < n.min(il as usize) as i64 || iu as usize > n {
                return Err(Illegal(10));
            }
            indices = (il as usize, iu as usize);
        }
        let ldz = dim(ldz, 15).and_then(|ldz| {
            if ldz < 1 || (wantz && ldz < n) {
                Err(Illegal(15))
            } else {
                Ok(ldz)
            }
        })?;
        let (lwork, liwork) = (scalar(lwork, 18)?, scalar(liwork, 20)?);
        let query = lwork == -1 || liwork == -1;
        let (lwmin, liwmin) = ((26 * n).max(1), (10 * n).max(1));
        if !query && (lwork < 0 || (lwork as usize) < lwmin) {
            return Err(Illegal(18));
        }
        if !query && (liwork < 0 || (liwork as usize) < liwmin) {
            return Err(Illegal(20));
        }
        // LAPACK reports the sizes on every successful return, not only to a query.
        slice_mut(work, 1, 17)?[0] = T::from_size(lwmin);
        slice_mut(iwork, 1, 19)?[0] = liwmin as c_int;
        if query {
            return Ok(0);
        }
        let m_out = slice_mut(m, 1, 12)?;
        if n == 0 {
            m_out[0] = 0;
            return Ok(0);
        }
        let a = mat_ref(a, n, n, lda, 5)?;
        let lower = if up { a.transpose() } else { a };
        let w = slice_mut(w, n, 13)?;
        let compute = if wantz {
            ComputeEigenvectors::Yes
        } else {
            ComputeEigenvectors::No
        };
        let vectors_cols = if wantz { n } else { 0 };
        let req = StackReq::all_of(&[
            temp_mat_scratch::<T>(n, 1),
            temp_mat_scratch::<T>(n, vectors_cols),
            evd::self_adjoint_evd_scratch::<T>(n, compute, Par::Seq, Default::default()),
        ]);
        with_scratch(req, |stack| -> Result<i32, Illegal> {
            let (mut values, stack) = temp_mat_zeroed::<T, _, _>(n, 1, stack);
            let mut values = values.as_mat_mut();
            let (mut vectors, stack) = temp_mat_zeroed::<T, _, _>(n, vectors_cols, stack);
            let mut vectors = vectors.as_mat_mut();
            let solved = evd::self_adjoint_evd(
                lower,
                values.rb_mut().col_mut(0).as_diagonal_mut(),
                wantz.then_some(vectors.rb_mut()),
                Par::Seq,
                stack,
                Default::default(),
            );
            if solved.is_err() {
                m_out[0] = 0;
                return Ok(1);
            }
            let values = values.rb().col(0);
            let selected = match range {
                b'A' => 0..n,
                b'I' => indices.0 - 1..indices.1,
                _ => {
                    let inside = |i: &usize| values[*i] > bounds.0 && values[*i] <= bounds.1;
                    let first = (0..n).find(inside).unwrap_or(n);
                    first..(first..n).find(|i| !inside(i)).unwrap_or(n)
                }
            };
            let count = selected.len();
            if wantz {
                let mut z = mat_mut(z, n, count, ldz, 14)?;
                let support = slice_mut(isuppz, 2 * count.max(1), 16)?;
                for (col, i) in selected.clone().enumerate() {
                    let v = vectors.rb().col(i);
                    z.rb_mut().col_mut(col).copy_from(v);
                    let nonzero = |r: &usize| v[*r] != T::zero();
                    let first = (0..n).find(nonzero).unwrap_or(0);
                    let last = (0..n).rev().find(nonzero).unwrap_or(0);
                    support[2 * col] = first as c_int + 1;
                    support[2 * col + 1] = last as c_int + 1;
                }
            }
            for (k, i) in selected.enumerate() {
                w[k] = values[i];
            }
            m_out[0] = count as c_int;
            Ok(0)
        })
    }
}

export! {
    /// symmetric eigendecomposition (see `syevr`); `abstol` is not read.
    lapack ssyevr_ "SSYEVR", dsyevr_ "DSYEVR"
    (jobz: *const c_char, range: *const c_char, uplo: *const c_char, n: *const c_int,
     a: *mut T, lda: *const c_int, vl: *const T, vu: *const T, il: *const c_int,
     iu: *const c_int, abstol: *const T, m: *mut c_int, w: *mut T, z: *mut T,
     ldz: *const c_int, isuppz: *mut c_int, work: *mut T, lwork: *const c_int,
     iwork: *mut c_int, liwork: *const c_int)
    => {
        let _ = abstol;
        syevr::<T>(
            jobz, range, uplo, n, a, lda, vl, vu, il, iu, m, w, z, ldz, isuppz, work, lwork,
            iwork, liwork,
        )
    }
}
