//! `?gesv`: Clarabel's general dense solve, over faer's LU with partial pivoting.

use std::ffi::c_int;

use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Par, Spec};

use super::{dim, leading, mat_mut, slice_mut, with_scratch, Illegal, Real};

/// Solves `A·X = B` (A n×n, B n×nrhs): `A` is overwritten by `L` (unit, below the
/// diagonal) and `U` of `P·A = L·U`, `ipiv` receives LAPACK's row interchanges (row i
/// was swapped with row `ipiv[i]`, 1-based, in order) and `B` the solution. `info = i > 0`
/// when `U(i, i)` is exactly zero: `A` is singular and `B` is left as it was. Unlike
/// LAPACK's, faer's elimination divides by a zero pivot, so `L` then holds non-finite
/// values below it.
#[allow(clippy::too_many_arguments)]
unsafe fn gesv<T: Real>(
    n: *const c_int,
    nrhs: *const c_int,
    a: *mut T,
    lda: *const c_int,
    ipiv: *mut c_int,
    b: *mut T,
    ldb: *const c_int,
) -> Result<i32, Illegal> {
    // SAFETY: (whole body) the caller passes valid Fortran arguments; every pointer is
    // read or viewed through the checked helpers with the extent its dimensions imply.
    unsafe {
        let n = dim(n, 1)?;
        let nrhs = dim(nrhs, 2)?;
        let lda = leading(lda, 4, n)?;
        let ldb = leading(ldb, 7, n)?;
        if n == 0 {
            return Ok(0);
        }
        let mut a = mat_mut(a, n, n, lda, 3)?;
        let ipiv = slice_mut(ipiv, n, 5)?;
        let b = mat_mut(b, n, nrhs, ldb, 6)?;
        let mut perm = vec![0usize; n];
        let mut perm_inv = vec![0usize; n];
        let req = factor::lu_in_place_scratch::<usize, T>(n, n, Par::Seq, Spec::default())
            .or(solve::solve_in_place_scratch::<usize, T>(n, nrhs, Par::Seq));
        let singular = with_scratch(req, |stack| {
            let (_, p) = factor::lu_in_place(
                a.rb_mut(),
                &mut perm,
                &mut perm_inv,
                Par::Seq,
                stack,
                Spec::default(),
            );
            interchanges(p.arrays().0, ipiv);
            let singular = (0..n).find(|&i| a[(i, i)] == T::zero());
            if singular.is_none() && nrhs > 0 {
                let a = a.rb();
                solve::solve_in_place(a, a, p, b, Par::Seq, stack);
            }
            singular
        });
        Ok(singular.map_or(0, |i| i as i32 + 1))
    }
}

/// LAPACK's `ipiv` (1-based row interchanges applied in order) of the row permutation
/// `perm` (row i of `P·A` is row `perm[i]` of `A`): replays the swaps that bring each
/// wanted row to position i, which is how the permutation was built.
fn interchanges(perm: &[usize], ipiv: &mut [c_int]) {
    let n = perm.len();
    let mut row_at: Vec<usize> = (0..n).collect();
    let mut position: Vec<usize> = (0..n).collect();
    for i in 0..n {
        let j = position[perm[i]];
        ipiv[i] = (j + 1) as c_int;
        let displaced = row_at[i];
        row_at.swap(i, j);
        position[displaced] = j;
        position[perm[i]] = i;
    }
}

export! {
    /// general linear solve (see `gesv`).
    lapack sgesv_ "SGESV", dgesv_ "DGESV"
    (n: *const c_int, nrhs: *const c_int, a: *mut T, lda: *const c_int, ipiv: *mut c_int,
     b: *mut T, ldb: *const c_int)
    => gesv::<T>(n, nrhs, a, lda, ipiv, b, ldb)
}

#[cfg(test)]
mod tests {
    use super::interchanges;

    /// The interchanges replayed on the identity give the permutation back.
    #[test]
    fn interchanges_rebuild_the_permutation() {
        for perm in [
            vec![0, 1, 2, 3],
            vec![3, 2, 1, 0],
            vec![2, 0, 3, 1],
            vec![1, 3, 0, 2],
        ] {
            let mut ipiv = vec![0; perm.len()];
            interchanges(&perm, &mut ipiv);
            let mut rows: Vec<usize> = (0..perm.len()).collect();
            for (i, &p) in ipiv.iter().enumerate() {
                assert!(p as usize > i, "LAPACK swaps only with a later row");
                rows.swap(i, p as usize - 1);
            }
            assert_eq!(rows, perm);
        }
    }
}
