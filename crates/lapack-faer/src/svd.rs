//! `?gesdd` and `?gesvd`: Clarabel's singular value decompositions (its PSD completion
//! and rank-deficient solves), both over faer's SVD: the two LAPACK drivers differ in
//! algorithm, not in what they return.

use std::ffi::{c_char, c_int};

use faer::dyn_stack::StackReq;
use faer::linalg::svd::{self, ComputeSvdVectors};
use faer::linalg::{temp_mat_scratch, temp_mat_zeroed};
use faer::mat::AsMatMut;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::traits::ext::ComplexFieldExt;
use faer::{MatMut, MatRef, Par};

use super::{dim, leading, mat_mut, option, scalar, slice_mut};
use super::{with_scratch, Illegal, Real};

/// Where a driver puts one side's singular vectors (`jobu`/`jobvt` of `?gesvd`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Job {
    /// All m (or n) vectors, in `u` (or `vt`).
    All,
    /// The first min(m, n), in `u` (or `vt`).
    Thin,
    /// The first min(m, n), over the first columns (rows for `vt`) of `a`.
    Overwrite,
    /// Not computed.
    None,
}

impl Job {
    fn parse(c: u8) -> Option<Job> {
        match c {
            b'A' => Some(Job::All),
            b'S' => Some(Job::Thin),
            b'O' => Some(Job::Overwrite),
            b'N' => Some(Job::None),
            _ => None,
        }
    }
}

/// `A = U·Σ·Vᵀ` of the m×n `A` (lda): singular values descending in `s`, `U` and `Vᵀ`
/// placed per `ju`/`jv` (`ldu`, `ldvt` already checked against LAPACK's rules by the
/// driver; `args` are the argument positions of `s`, `u`, `vt`). Returns false when faer's iteration did not converge. `A` is left as it was
/// unless a side is [`Job::Overwrite`].
///
/// # Safety
/// The arrays are valid for the extents the dimensions imply.
#[allow(clippy::too_many_arguments)]
unsafe fn decompose<T: Real>(
    (ju, jv): (Job, Job),
    (m, n): (usize, usize),
    args: [i32; 3],
    a: MatMut<'_, T>,
    s: *mut T,
    (u, ldu): (*mut T, usize),
    (vt, ldvt): (*mut T, usize),
) -> Result<bool, Illegal> {
    let [arg_s, arg_u, arg_vt] = args;
    let k = m.min(n);
    // SAFETY: forwarded contract; every view goes through the checked helpers.
    unsafe {
        let s = slice_mut(s, k, arg_s)?;
        let u_cols = if ju == Job::All { m } else { k };
        let vt_rows = if jv == Job::All { n } else { k };
        let mut u = match ju {
            Job::All | Job::Thin => Some(mat_mut(u, m, u_cols, ldu, arg_u)?),
            _ => None,
        };
        let mut vt = match jv {
            Job::All | Job::Thin => Some(mat_mut(vt, vt_rows, n, ldvt, arg_vt)?),
            _ => None,
        };
        let compute = |job: Job| match job {
            Job::All => ComputeSvdVectors::Full,
            Job::Thin | Job::Overwrite => ComputeSvdVectors::Thin,
            Job::None => ComputeSvdVectors::No,
        };
        // Vectors that go over A are computed aside first: faer reads A throughout.
        let u_aside_cols = if ju == Job::Overwrite { k } else { 0 };
        let v_aside_cols = if jv == Job::Overwrite { k } else { 0 };
        let req = StackReq::all_of(&[
            temp_mat_scratch::<T>(k, 1),
            temp_mat_scratch::<T>(m, u_aside_cols),
            temp_mat_scratch::<T>(n, v_aside_cols),
            svd::svd_scratch::<T>(m, n, compute(ju), compute(jv), Par::Seq, Default::default()),
        ]);
        Ok(with_scratch(req, |stack| {
            let (mut values, stack) = temp_mat_zeroed::<T, _, _>(k, 1, stack);
            let mut values = values.as_mat_mut();
            let (mut u_aside, stack) = temp_mat_zeroed::<T, _, _>(m, u_aside_cols, stack);
            let mut u_aside = u_aside.as_mat_mut();
            let (mut v_aside, stack) = temp_mat_zeroed::<T, _, _>(n, v_aside_cols, stack);
            let mut v_aside = v_aside.as_mat_mut();
            let u_view = match (&mut u, ju) {
                (Some(u), _) => Some(u.rb_mut()),
                (None, Job::Overwrite) => Some(u_aside.rb_mut()),
                (None, _) => None,
            };
            // faer returns V; Vᵀ's array seen transposed is V's.
            let v_view = match (&mut vt, jv) {
                (Some(vt), _) => Some(vt.rb_mut().transpose_mut()),
                (None, Job::Overwrite) => Some(v_aside.rb_mut()),
                (None, _) => None,
            };
            let solved = svd::svd(
                a.rb(),
                values.rb_mut().col_mut(0).as_diagonal_mut(),
                zeroed(u_view),
                zeroed(v_view),
                Par::Seq,
                stack,
                Default::default(),
            );
            if solved.is_err() {
                return false;
            }
            for (i, si) in s.iter_mut().enumerate() {
                *si = values[(i, 0)];
            }
            let mut a = a;
            if ju == Job::Overwrite {
                a.rb_mut().get_mut(.., ..k).copy_from(u_aside.rb());
            }
            if jv == Job::Overwrite {
                a.rb_mut()
                    .get_mut(..k, ..)
                    .copy_from(v_aside.rb().transpose());
            }
            true
        }))
    }
}

/// `view` filled with zeros: faer's QR path leaves the block of a full U right of its
/// first min(m, n) columns unwritten (it expects zeroed outputs, which its own wrappers
/// allocate).
fn zeroed<T: Real>(view: Option<MatMut<'_, T>>) -> Option<MatMut<'_, T>> {
    view.map(|mut v| {
        v.fill(T::zero());
        v
    })
}

/// Whether every entry is finite (faer's iteration is not meant for NaN or infinity).
fn finite<T: Real>(a: MatRef<'_, T>) -> bool {
    (0..a.ncols()).all(|j| (0..a.nrows()).all(|i| a[(i, j)].is_finite()))
}

/// LAPACK's minimum `lwork` of `?gesdd` for `jobz` (its path choice included, so that
/// any size LAPACK accepts is accepted).
fn gesdd_min_work(jobz: u8, m: usize, n: usize) -> usize {
    let (small, large) = (m.min(n), m.max(n));
    if small == 0 {
        return 1;
    }
    let bdspac = if jobz == b'N' {
        7 * small
    } else {
        3 * small * small + 4 * small
    };
    let much_larger = large >= small * 11 / 6;
    match (much_larger, jobz) {
        (true, b'N') => bdspac + small,
        (true, b'O') => bdspac + 2 * small * small + 3 * small,
        (true, b'S') => bdspac + small * small + 3 * small,
        (true, _) => small * small + (3 * small + bdspac).max(small + large),
        (false, b'O') => 3 * small + large.max(small * small + bdspac),
        (false, _) => 3 * small + large.max(bdspac),
    }
}

/// LAPACK's minimum `lwork` of `?gesvd` (its path choice included): `5·min(m, n)` when
/// the long side's vectors are not wanted and it is much longer, else
/// `max(3·min + max, 5·min)`.
fn gesvd_min_work(ju: Job, jv: Job, m: usize, n: usize) -> usize {
    let (small, large) = (m.min(n), m.max(n));
    if small == 0 {
        return 1;
    }
    let long_side_unwanted = if m >= n {
        ju == Job::None
    } else {
        jv == Job::None
    };
    let much_larger = large >= (small as f32 * 1.6) as usize;
    if much_larger && long_side_unwanted {
        5 * small
    } else {
        (3 * small + large).max(5 * small)
    }
}

/// Which driver, with its job arguments parsed.
#[derive(Clone, Copy)]
enum Driver {
    /// `?gesdd`: `jobz` 'A' (all of U and Vᵀ), 'S' (the first min(m, n)), 'O' (those
    /// over `A`: U's when m ≥ n, with all of Vᵀ in `vt`; else Vᵀ's, with all of U in
    /// `u`), 'N' (values only); and its `iwork`. `info = -4` for a non-finite `A` (as
    /// LAPACK).
    Gesdd { job: u8, iwork: *mut c_int },
    /// `?gesvd`: `jobu`/`jobvt` each 'A', 'S', 'O', 'N' as [`Job`] (not both 'O').
    /// `info = 1` for a non-finite `A` (LAPACK: the number of superdiagonals that did
    /// not converge).
    Gesvd(Job, Job),
}

impl Driver {
    /// `?gesdd`'s `jobz` (argument 1).
    ///
    /// # Safety
    /// As [`scalar`].
    unsafe fn gesdd(jobz: *const c_char, iwork: *mut c_int) -> Result<Self, Illegal> {
        // SAFETY: forwarded contract.
        let job = unsafe { option(jobz, 1) }?;
        if !matches!(job, b'A' | b'S' | b'O' | b'N') {
            return Err(Illegal(1));
        }
        Ok(Driver::Gesdd { job, iwork })
    }

    /// `?gesvd`'s `jobu` and `jobvt` (arguments 1 and 2).
    ///
    /// # Safety
    /// As [`scalar`].
    unsafe fn gesvd(jobu: *const c_char, jobvt: *const c_char) -> Result<Self, Illegal> {
        // SAFETY: forwarded contract.
        unsafe {
            let ju = Job::parse(option(jobu, 1)?).ok_or(Illegal(1))?;
            let jv = Job::parse(option(jobvt, 2)?).ok_or(Illegal(2))?;
            if ju == Job::Overwrite && jv == Job::Overwrite {
                return Err(Illegal(2));
            }
            Ok(Driver::Gesvd(ju, jv))
        }
    }

    /// Where U and Vᵀ go for an m×n `A` (`?gesdd`'s 'O' overwrites the long side's).
    fn jobs(self, m: usize, n: usize) -> (Job, Job) {
        match self {
            Driver::Gesdd { job, .. } => match (job, m >= n) {
                (b'A', _) => (Job::All, Job::All),
                (b'S', _) => (Job::Thin, Job::Thin),
                (b'O', true) => (Job::Overwrite, Job::Thin),
                (b'O', false) => (Job::Thin, Job::Overwrite),
                _ => (Job::None, Job::None),
            },
            Driver::Gesvd(ju, jv) => (ju, jv),
        }
    }
}

/// `?gesdd` and `?gesvd` after their job arguments: the same arguments from `m` on
/// (argument 2 of `?gesdd`, 3 of `?gesvd`), the same checks (LAPACK's `ldu`/`ldvt`
/// rules are those of the jobs [`Driver::jobs`] gives), `info = 1` when the iteration
/// did not converge.
#[allow(clippy::too_many_arguments)]
unsafe fn svd<T: Real>(
    driver: Driver,
    m: *const c_int,
    n: *const c_int,
    a: *mut T,
    lda: *const c_int,
    s: *mut T,
    u: *mut T,
    ldu: *const c_int,
    vt: *mut T,
    ldvt: *const c_int,
    work: *mut T,
    lwork: *const c_int,
) -> Result<i32, Illegal> {
    let first = match driver {
        Driver::Gesdd { .. } => 2,
        Driver::Gesvd(..) => 3,
    };
    // SAFETY: (whole body) the caller passes valid Fortran arguments; every pointer is
    // read or viewed through the checked helpers with the extent its dimensions imply.
    unsafe {
        let m = dim(m, first)?;
        let n = dim(n, first + 1)?;
        let k = m.min(n);
        let lda = leading(lda, first + 3, m)?;
        let (ju, jv) = driver.jobs(m, n);
        let ldu = dim(ldu, first + 6)?;
        if ldu < 1 || (matches!(ju, Job::All | Job::Thin) && ldu < m) {
            return Err(Illegal(first + 6));
        }
        let ldvt = dim(ldvt, first + 8)?;
        if ldvt < 1 || (jv == Job::All && ldvt < n) || (jv == Job::Thin && ldvt < k) {
            return Err(Illegal(first + 8));
        }
        let lwork = scalar(lwork, first + 10)?;
        let min_work = match driver {
            Driver::Gesdd { job, .. } => gesdd_min_work(job, m, n),
            Driver::Gesvd(ju, jv) => gesvd_min_work(ju, jv, m, n),
        };
        slice_mut(work, 1, first + 9)?[0] = T::from_size(min_work);
        if lwork == -1 {
            // `?gesdd`'s `iwork` holds 8·min(m, n) integers; LAPACK has no query for it,
            // Clarabel reads it back anyway.
            if let (Driver::Gesdd { iwork, .. }, true) = (driver, k > 0) {
                slice_mut(iwork, 1, first + 11)?[0] = (8 * k) as c_int;
            }
            return Ok(0);
        }
        if lwork < 0 || (lwork as usize) < min_work {
            return Err(Illegal(first + 10));
        }
        if k == 0 {
            return Ok(0);
        }
        let a = mat_mut(a, m, n, lda, first + 2)?;
        if !finite(a.rb()) {
            return match driver {
                Driver::Gesdd { .. } => Err(Illegal(first + 2)),
                Driver::Gesvd(..) => Ok(1),
            };
        }
        let args = [first + 4, first + 5, first + 7];
        let solved = decompose((ju, jv), (m, n), args, a, s, (u, ldu), (vt, ldvt))?;
        Ok(if solved { 0 } else { 1 })
    }
}

export! {
    /// SVD, divide and conquer in LAPACK (see `Driver::Gesdd`).
    lapack sgesdd_ "SGESDD", dgesdd_ "DGESDD"
    (jobz: *const c_char, m: *const c_int, n: *const c_int, a: *mut T, lda: *const c_int,
     s: *mut T, u: *mut T, ldu: *const c_int, vt: *mut T, ldvt: *const c_int, work: *mut T,
     lwork: *const c_int, iwork: *mut c_int)
    => Driver::gesdd(jobz, iwork)
        .and_then(|d| svd::<T>(d, m, n, a, lda, s, u, ldu, vt, ldvt, work, lwork))
}

export! {
    /// SVD, QR iteration in LAPACK (see `Driver::Gesvd`).
    lapack sgesvd_ "SGESVD", dgesvd_ "DGESVD"
    (jobu: *const c_char, jobvt: *const c_char, m: *const c_int, n: *const c_int, a: *mut T,
     lda: *const c_int, s: *mut T, u: *mut T, ldu: *const c_int, vt: *mut T,
     ldvt: *const c_int, work: *mut T, lwork: *const c_int)
    => Driver::gesvd(jobu, jobvt)
        .and_then(|d| svd::<T>(d, m, n, a, lda, s, u, ldu, vt, ldvt, work, lwork))
}
