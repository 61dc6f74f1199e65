//! The crate's BLAS/LAPACK routines (the Fortran-ABI layer over faer that Clarabel's SDP
//! cones call), called through the same `blas`/`lapack` crate wrappers
//! Clarabel uses, against their mathematical definitions: products against plain loops,
//! `A·X = B` residuals, `L·Lᵀ = A`, `P·A = L·U`, eigenpairs `A·v = λ·v` with orthonormal
//! `V` and a known spectrum, `A = U·Σ·Vᵀ` with orthonormal `U`, `V` and known singular
//! values. Every array has a leading dimension larger than its rows, padded with NaN
//! (which would poison any result that read it) or a sentinel (which must survive
//! where the routine writes around it); triangles LAPACK must not read hold NaN,
//! triangles it must not write hold the sentinel. Edge sizes 0 and 1, non-positive
//! definite and singular inputs, workspace queries and illegal arguments (`info = -i`,
//! BLAS outputs untouched) too. Both precisions.

use dvrk_test_support::Rng;

/// What a routine must leave alone where it writes around it.
const SENTINEL: f64 = 7777.0;

/// The routines under test, one line each: the signature of the `blas`/`lapack` crate
/// wrapper (the Fortran argument list), from which the macro declares `Scalar`'s entry
/// point and forwards it to the `s…` or `d…` function of each precision.
macro_rules! routines {
    ($(fn $name:ident($($arg:ident: $ty:ty),* $(,)?) = $module:ident::[$s:ident, $d:ident];)*) => {
        /// The precision-specific entry points.
        trait Scalar: Copy + PartialOrd + std::fmt::Debug {
            /// Tolerance of a result relative to its scale (a few hundred ulps at these
            /// sizes).
            const TOL: f64;
            fn of(x: f64) -> Self;
            fn f(self) -> f64;
            $(#[allow(clippy::too_many_arguments)] unsafe fn $name($($arg: $ty),*);)*
        }
        routines!(@impl f32, 2e-4, $($name($($arg: $ty),*) = $module::$s;)*);
        routines!(@impl f64, 1e-11, $($name($($arg: $ty),*) = $module::$d;)*);
    };
    (@impl $T:ty, $tol:expr, $($name:ident($($arg:ident: $ty:ty),*) = $module:ident::$f:ident;)*) => {
        impl Scalar for $T {
            const TOL: f64 = $tol;
            fn of(x: f64) -> Self {
                x as $T
            }
            fn f(self) -> f64 {
                self as f64
            }
            $(unsafe fn $name($($arg: $ty),*) {
                // The routines are `#[no_mangle]` symbols of lapack_faer, reached by the
                // wrappers by name only: `link` makes the linker keep them.
                lapack_faer::link();
                unsafe { $module::$f($($arg),*) }
            })*
        }
    };
}

routines! {
    fn gemm(ta: u8, tb: u8, m: i32, n: i32, k: i32, al: Self, a: &[Self], lda: i32, b: &[Self],
        ldb: i32, be: Self, c: &mut [Self], ldc: i32) = blas::[sgemm, dgemm];
    fn gemv(t: u8, m: i32, n: i32, al: Self, a: &[Self], lda: i32, x: &[Self], incx: i32,
        be: Self, y: &mut [Self], incy: i32) = blas::[sgemv, dgemv];
    fn symv(uplo: u8, n: i32, al: Self, a: &[Self], lda: i32, x: &[Self], incx: i32, be: Self,
        y: &mut [Self], incy: i32) = blas::[ssymv, dsymv];
    fn syrk(uplo: u8, t: u8, n: i32, k: i32, al: Self, a: &[Self], lda: i32, be: Self,
        c: &mut [Self], ldc: i32) = blas::[ssyrk, dsyrk];
    fn syr2k(uplo: u8, t: u8, n: i32, k: i32, al: Self, a: &[Self], lda: i32, b: &[Self],
        ldb: i32, be: Self, c: &mut [Self], ldc: i32) = blas::[ssyr2k, dsyr2k];
    fn potrf(uplo: u8, n: i32, a: &mut [Self], lda: i32, info: &mut i32)
        = lapack::[spotrf, dpotrf];
    fn potrs(uplo: u8, n: i32, nrhs: i32, a: &[Self], lda: i32, b: &mut [Self], ldb: i32,
        info: &mut i32) = lapack::[spotrs, dpotrs];
    fn gesv(n: i32, nrhs: i32, a: &mut [Self], lda: i32, ipiv: &mut [i32], b: &mut [Self],
        ldb: i32, info: &mut i32) = lapack::[sgesv, dgesv];
    fn syevr(jobz: u8, range: u8, uplo: u8, n: i32, a: &mut [Self], lda: i32, vl: Self,
        vu: Self, il: i32, iu: i32, abstol: Self, m: &mut i32, w: &mut [Self], z: &mut [Self],
        ldz: i32, isuppz: &mut [i32], work: &mut [Self], lwork: i32, iwork: &mut [i32],
        liwork: i32, info: &mut i32) = lapack::[ssyevr, dsyevr];
    fn gesdd(jobz: u8, m: i32, n: i32, a: &mut [Self], lda: i32, s: &mut [Self], u: &mut [Self],
        ldu: i32, vt: &mut [Self], ldvt: i32, work: &mut [Self], lwork: i32, iwork: &mut [i32],
        info: &mut i32) = lapack::[sgesdd, dgesdd];
    fn gesvd(jobu: u8, jobvt: u8, m: i32, n: i32, a: &mut [Self], lda: i32, s: &mut [Self],
        u: &mut [Self], ldu: i32, vt: &mut [Self], ldvt: i32, work: &mut [Self], lwork: i32,
        info: &mut i32) = lapack::[sgesvd, dgesvd];
}

/// A column-major Fortran array: `rows × cols` with leading dimension `ld`, the
/// `ld − rows` padding rows of each column (and anything a test marks) set apart.
#[derive(Clone, Debug)]
struct Array<T> {
    rows: usize,
    cols: usize,
    ld: usize,
    data: Vec<T>,
}

impl<T: Scalar> Array<T> {
    /// `rows × cols` from `value(i, j)`, with `pad` extra rows filled with `padding`.
    fn new(
        rows: usize,
        cols: usize,
        pad: usize,
        padding: f64,
        value: impl Fn(usize, usize) -> f64,
    ) -> Self {
        let ld = (rows + pad).max(1);
        let mut data = vec![T::of(padding); ld * cols.max(1)];
        for j in 0..cols {
            for i in 0..rows {
                data[i + j * ld] = T::of(value(i, j));
            }
        }
        Array {
            rows,
            cols,
            ld,
            data,
        }
    }

    fn random(rows: usize, cols: usize, pad: usize, padding: f64, g: &mut Rng) -> Self {
        let values: Vec<f64> = (0..rows * cols).map(|_| g.normal()).collect();
        Self::new(rows, cols, pad, padding, |i, j| values[i + j * rows])
    }

    fn from(m: &[Vec<f64>], pad: usize, padding: f64) -> Self {
        let cols = m.first().map_or(0, Vec::len);
        Self::new(m.len(), cols, pad, padding, |i, j| m[i][j])
    }

    fn get(&self, i: usize, j: usize) -> f64 {
        self.data[i + j * self.ld].f()
    }

    /// The matrix in f64, row by row.
    fn dense(&self) -> Vec<Vec<f64>> {
        self.block(self.rows, self.cols)
    }

    /// The leading `rows × cols` block in f64, row by row.
    fn block(&self, rows: usize, cols: usize) -> Vec<Vec<f64>> {
        (0..rows)
            .map(|i| (0..cols).map(|j| self.get(i, j)).collect())
            .collect()
    }

    /// Every element outside the `rows × cols` block is still `padding` (bitwise for NaN).
    fn assert_padding(&self, padding: f64, what: &str) {
        for j in 0..self.cols {
            for i in self.rows..self.ld {
                let v = self.get(i, j);
                assert!(
                    v.to_bits() == T::of(padding).f().to_bits(),
                    "{what}: padding ({i}, {j}) = {v}"
                );
            }
        }
    }
}

fn matmul(a: &[Vec<f64>], b: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let k = b.len();
    let n = b.first().map_or(0, Vec::len);
    a.iter()
        .map(|row| {
            (0..n)
                .map(|j| (0..k).map(|l| row[l] * b[l][j]).sum())
                .collect()
        })
        .collect()
}

fn transpose(a: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let cols = a.first().map_or(0, Vec::len);
    (0..cols)
        .map(|j| a.iter().map(|row| row[j]).collect())
        .collect()
}

fn max_abs(a: &[Vec<f64>]) -> f64 {
    a.iter().flatten().fold(0.0, |m, x| m.max(x.abs()))
}

/// `|x − y| ≤ TOL·scale` elementwise, `scale` at least 1.
fn assert_close<T: Scalar>(x: &[Vec<f64>], y: &[Vec<f64>], scale: f64, what: &str) {
    assert_eq!(x.len(), y.len(), "{what}: rows");
    let tol = T::TOL * scale.max(1.0);
    for (i, (rx, ry)) in x.iter().zip(y).enumerate() {
        assert_eq!(rx.len(), ry.len(), "{what}: columns");
        for (j, (a, b)) in rx.iter().zip(ry).enumerate() {
            assert!(
                (a - b).abs() <= tol,
                "{what}: ({i}, {j}) {a} vs {b} (tol {tol:e})"
            );
        }
    }
}

/// A random orthogonal n×n matrix: a product of Householder reflections, so the test's
/// known spectra do not depend on any routine under test.
fn orthogonal(n: usize, g: &mut Rng) -> Vec<Vec<f64>> {
    let mut q: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| f64::from(u8::from(i == j))).collect())
        .collect();
    for _ in 0..n.min(3) {
        let v: Vec<f64> = (0..n).map(|_| g.normal()).collect();
        let vv: f64 = v.iter().map(|x| x * x).sum();
        let h: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| f64::from(u8::from(i == j)) - 2.0 * v[i] * v[j] / vv)
                    .collect()
            })
            .collect();
        q = matmul(&q, &h);
    }
    q
}

fn diag(values: &[f64], rows: usize, cols: usize) -> Vec<Vec<f64>> {
    (0..rows)
        .map(|i| {
            (0..cols)
                .map(|j| if i == j { values[i] } else { 0.0 })
                .collect()
        })
        .collect()
}

/// `QᵀQ = I` (columns orthonormal).
fn assert_orthonormal_columns<T: Scalar>(q: &[Vec<f64>], what: &str) {
    let cols = q.first().map_or(0, Vec::len);
    let qtq = matmul(&transpose(q), q);
    assert_close::<T>(&qtq, &diag(&vec![1.0; cols], cols, cols), 1.0, what);
}

/// A vector of `len` logical elements stored `inc` apart (backwards for `inc < 0`, the
/// last logical element first, as BLAS does), gaps holding `gap`.
fn strided<T: Scalar>(values: &[f64], inc: i32, gap: f64) -> Vec<T> {
    let step = inc.unsigned_abs() as usize;
    let len = values.len();
    let mut data = vec![T::of(gap); if len == 0 { 1 } else { (len - 1) * step + 1 }];
    for (i, v) in values.iter().enumerate() {
        let at = if inc > 0 {
            i * step
        } else {
            (len - 1 - i) * step
        };
        data[at] = T::of(*v);
    }
    data
}

fn unstrided<T: Scalar>(data: &[T], len: usize, inc: i32) -> Vec<f64> {
    let step = inc.unsigned_abs() as usize;
    (0..len)
        .map(|i| {
            data[if inc > 0 {
                i * step
            } else {
                (len - 1 - i) * step
            }]
            .f()
        })
        .collect()
}

/// The logical elements of `y` (stored `inc` apart) against the column `expected`, each
/// a sum of `terms` products: within `TOL·terms·max|expected|`.
fn assert_strided<T: Scalar>(y: &[T], inc: i32, expected: &[Vec<f64>], terms: usize, what: &str) {
    let got: Vec<Vec<f64>> = unstrided(y, expected.len(), inc)
        .into_iter()
        .map(|v| vec![v])
        .collect();
    assert_close::<T>(&got, expected, max_abs(expected) * terms as f64, what);
}

// ---------------------------------------------------------------------------------
// BLAS

/// `C ← alpha·op(A)·op(B) + beta·C` on the arrays, `op(A)` m×k and `op(B)` k×n.
fn gemm<T: Scalar>(
    (ta, tb): (u8, u8),
    (m, n, k): (usize, usize, usize),
    alpha: f64,
    a: &Array<T>,
    b: &Array<T>,
    beta: f64,
    c: &mut Array<T>,
) {
    let (m, n, k) = (m as i32, n as i32, k as i32);
    let (lda, ldb, ldc) = (a.ld as i32, b.ld as i32, c.ld as i32);
    let (alpha, beta) = (T::of(alpha), T::of(beta));
    unsafe {
        T::gemm(
            ta,
            tb,
            m,
            n,
            k,
            alpha,
            &a.data,
            lda,
            &b.data,
            ldb,
            beta,
            &mut c.data,
            ldc,
        )
    }
}

fn gemm_cases<T: Scalar>() {
    let mut g = Rng::new(1);
    for (m, n, k) in [(4, 3, 5), (1, 1, 1), (6, 2, 1), (3, 7, 4)] {
        for (ta, tb) in [
            (b'N', b'N'),
            (b'T', b'N'),
            (b'N', b'T'),
            (b'C', b'T'),
            (b't', b'n'),
        ] {
            for (alpha, beta) in [(1.0, 0.0), (-0.7, 1.0), (2.5, -0.3)] {
                let plain = |t: u8| t.eq_ignore_ascii_case(&b'N');
                let (ar, ac) = if plain(ta) { (m, k) } else { (k, m) };
                let (br, bc) = if plain(tb) { (k, n) } else { (n, k) };
                let a = Array::<T>::random(ar, ac, 2, f64::NAN, &mut g);
                let b = Array::<T>::random(br, bc, 1, f64::NAN, &mut g);
                let mut c = Array::<T>::random(m, n, 3, SENTINEL, &mut g);
                if beta == 0.0 {
                    // beta = 0: C is not read (reference BLAS), so NaN must not survive.
                    c = Array::new(m, n, 3, SENTINEL, |_, _| f64::NAN);
                }
                let opa = if plain(ta) {
                    a.dense()
                } else {
                    transpose(&a.dense())
                };
                let opb = if plain(tb) {
                    b.dense()
                } else {
                    transpose(&b.dense())
                };
                let ab = matmul(&opa, &opb);
                let c0 = c.dense();
                let expected: Vec<Vec<f64>> = (0..m)
                    .map(|i| {
                        (0..n)
                            .map(|j| {
                                alpha * ab[i][j] + if beta == 0.0 { 0.0 } else { beta * c0[i][j] }
                            })
                            .collect()
                    })
                    .collect();
                gemm((ta, tb), (m, n, k), alpha, &a, &b, beta, &mut c);
                let scale = max_abs(&expected) * k as f64;
                assert_close::<T>(
                    &c.dense(),
                    &expected,
                    scale,
                    &format!("gemm {} {} {m}x{n}x{k}", ta as char, tb as char),
                );
                c.assert_padding(SENTINEL, "gemm C");
            }
        }
    }
    // alpha = 0 or k = 0: C ← beta·C, A and B (all NaN) never read.
    for (k, alpha) in [(3, 0.0), (0, 1.5)] {
        let a = Array::<T>::new(2, k, 1, f64::NAN, |_, _| f64::NAN);
        let b = Array::<T>::new(k, 3, 1, f64::NAN, |_, _| f64::NAN);
        let mut c = Array::<T>::new(2, 3, 1, SENTINEL, |i, j| (i + 2 * j) as f64);
        gemm((b'N', b'N'), (2, 3, k), alpha, &a, &b, -2.0, &mut c);
        let expected: Vec<Vec<f64>> = (0..2)
            .map(|i| (0..3).map(|j| -2.0 * (i + 2 * j) as f64).collect())
            .collect();
        assert_close::<T>(&c.dense(), &expected, 1.0, "gemm without product");
        c.assert_padding(SENTINEL, "gemm C without product");
    }
    // m = 0 / n = 0: nothing happens (not even to a NaN-free C with beta = 0).
    let mut c = vec![T::of(SENTINEL); 4];
    let (a, one, zero) = ([T::of(1.0); 4], T::of(1.0), T::of(0.0));
    for (m, n, ld) in [(0, 2, 1), (2, 0, 2)] {
        unsafe { T::gemm(b'N', b'N', m, n, 2, one, &a, ld, &a, 2, zero, &mut c, ld) };
    }
    assert!(c.iter().all(|x| x.f() == SENTINEL));
}

fn gemv_cases<T: Scalar>() {
    let mut g = Rng::new(2);
    for (m, n) in [(5, 3), (1, 1), (2, 6)] {
        for t in [b'N', b'T', b'C'] {
            for (incx, incy) in [(1, 1), (2, 3), (-1, 1), (-2, -3), (1, -1)] {
                for (alpha, beta) in [(1.0, 0.0), (0.5, -1.5)] {
                    let a = Array::<T>::random(m, n, 2, f64::NAN, &mut g);
                    let (lx, ly) = if t == b'N' { (n, m) } else { (m, n) };
                    let xv: Vec<f64> = (0..lx).map(|_| g.normal()).collect();
                    let yv: Vec<f64> = (0..ly)
                        .map(|_| if beta == 0.0 { f64::NAN } else { g.normal() })
                        .collect();
                    let x = strided::<T>(&xv, incx, f64::NAN);
                    let mut y = strided::<T>(&yv, incy, SENTINEL);
                    let op = if t == b'N' {
                        a.dense()
                    } else {
                        transpose(&a.dense())
                    };
                    let expected: Vec<Vec<f64>> = (0..ly)
                        .map(|i| {
                            let ax: f64 = (0..lx).map(|j| op[i][j] * xv[j]).sum();
                            vec![alpha * ax + if beta == 0.0 { 0.0 } else { beta * yv[i] }]
                        })
                        .collect();
                    let (mi, ni, lda) = (m as i32, n as i32, a.ld as i32);
                    let (al, be) = (T::of(alpha), T::of(beta));
                    unsafe { T::gemv(t, mi, ni, al, &a.data, lda, &x, incx, be, &mut y, incy) };
                    let what = format!("gemv {} {m}x{n} inc {incx} {incy}", t as char);
                    assert_strided(&y, incy, &expected, lx, &what);
                    let logical: Vec<usize> = (0..ly)
                        .map(|i| {
                            (if incy > 0 { i } else { ly - 1 - i }) * incy.unsigned_abs() as usize
                        })
                        .collect();
                    for (p, v) in y.iter().enumerate() {
                        if !logical.contains(&p) {
                            assert_eq!(v.f(), SENTINEL, "gemv y gap {p}");
                        }
                    }
                }
            }
        }
    }
}

fn symv_cases<T: Scalar>() {
    let mut g = Rng::new(3);
    for n in [1, 4, 7] {
        for uplo in [b'U', b'L'] {
            for (incx, incy) in [(1, 1), (-2, 3), (3, -1)] {
                let s = Array::<T>::random(n, n, 0, 0.0, &mut g).dense();
                let sym: Vec<Vec<f64>> = (0..n)
                    .map(|i| (0..n).map(|j| s[i][j] + s[j][i]).collect())
                    .collect();
                // Only the uplo triangle is stored; the other holds NaN (never read).
                let a = Array::<T>::new(n, n, 2, f64::NAN, |i, j| {
                    if (uplo == b'U' && i <= j) || (uplo == b'L' && i >= j) {
                        sym[i][j]
                    } else {
                        f64::NAN
                    }
                });
                let xv: Vec<f64> = (0..n).map(|_| g.normal()).collect();
                let yv: Vec<f64> = (0..n).map(|_| g.normal()).collect();
                let x = strided::<T>(&xv, incx, f64::NAN);
                let mut y = strided::<T>(&yv, incy, SENTINEL);
                let (alpha, beta) = (1.3, 0.4);
                let expected: Vec<Vec<f64>> = (0..n)
                    .map(|i| {
                        vec![alpha * (0..n).map(|j| sym[i][j] * xv[j]).sum::<f64>() + beta * yv[i]]
                    })
                    .collect();
                let (ni, lda, al, be) = (n as i32, a.ld as i32, T::of(alpha), T::of(beta));
                unsafe { T::symv(uplo, ni, al, &a.data, lda, &x, incx, be, &mut y, incy) };
                let what = format!("symv {} n={n}", uplo as char);
                assert_strided(&y, incy, &expected, n, &what);
            }
        }
    }
}

/// `C`'s `uplo` triangle after `routine` (`trans` `t`, `k` terms a sum) against
/// `expected` within `TOL·k·max|expected|`, the other triangle still the sentinel.
fn assert_triangle<T: Scalar>(
    c: &Array<T>,
    expected: &[Vec<f64>],
    (uplo, t, k): (u8, u8, usize),
    routine: &str,
) {
    let upper = uplo == b'U';
    let scale = max_abs(expected) * k as f64;
    let n = expected.len();
    let what = &format!("{routine} {} {} n={n} k={k}", uplo as char, t as char);
    for (i, row) in expected.iter().enumerate() {
        for (j, e) in row.iter().enumerate() {
            let v = c.get(i, j);
            if (upper && i <= j) || (!upper && i >= j) {
                assert!(
                    (v - e).abs() <= T::TOL * scale.max(1.0),
                    "{what}: ({i}, {j}) {v} vs {e}"
                );
            } else {
                assert_eq!(v, SENTINEL, "{what}: other triangle ({i}, {j}) written");
            }
        }
    }
    c.assert_padding(SENTINEL, what);
}

fn syrk_cases<T: Scalar>() {
    let mut g = Rng::new(4);
    for (n, k) in [(4, 3), (1, 1), (3, 6)] {
        for uplo in [b'U', b'L'] {
            for t in [b'N', b'T', b'C'] {
                for (alpha, beta) in [(1.0, 0.0), (-0.5, 2.0)] {
                    let (ar, ac) = if t == b'N' { (n, k) } else { (k, n) };
                    let a = Array::<T>::random(ar, ac, 1, f64::NAN, &mut g);
                    let c0 = Array::<T>::random(n, n, 0, 0.0, &mut g).dense();
                    let up = uplo == b'U';
                    let mut c = Array::<T>::new(n, n, 2, SENTINEL, |i, j| {
                        let inside = (up && i <= j) || (!up && i >= j);
                        match (inside, beta == 0.0) {
                            (true, true) => f64::NAN,
                            (true, false) => c0[i][j],
                            (false, _) => SENTINEL,
                        }
                    });
                    let op = if t == b'N' {
                        a.dense()
                    } else {
                        transpose(&a.dense())
                    };
                    let aat = matmul(&op, &transpose(&op));
                    let expected: Vec<Vec<f64>> = (0..n)
                        .map(|i| {
                            (0..n)
                                .map(|j| {
                                    alpha * aat[i][j]
                                        + if beta == 0.0 { 0.0 } else { beta * c0[i][j] }
                                })
                                .collect()
                        })
                        .collect();
                    let (ni, ki, lda, ldc) = (n as i32, k as i32, a.ld as i32, c.ld as i32);
                    let (al, be) = (T::of(alpha), T::of(beta));
                    unsafe { T::syrk(uplo, t, ni, ki, al, &a.data, lda, be, &mut c.data, ldc) };
                    assert_triangle(&c, &expected, (uplo, t, k), "syrk");
                }
            }
        }
    }
}

fn syr2k_cases<T: Scalar>() {
    let mut g = Rng::new(5);
    for (n, k) in [(4, 3), (1, 2), (3, 5)] {
        for uplo in [b'U', b'L'] {
            for t in [b'N', b'T'] {
                let (ar, ac) = if t == b'N' { (n, k) } else { (k, n) };
                let a = Array::<T>::random(ar, ac, 1, f64::NAN, &mut g);
                let b = Array::<T>::random(ar, ac, 2, f64::NAN, &mut g);
                let c0 = Array::<T>::random(n, n, 0, 0.0, &mut g).dense();
                let up = uplo == b'U';
                let mut c = Array::<T>::new(n, n, 1, SENTINEL, |i, j| {
                    if (up && i <= j) || (!up && i >= j) {
                        c0[i][j]
                    } else {
                        SENTINEL
                    }
                });
                let (oa, ob) = if t == b'N' {
                    (a.dense(), b.dense())
                } else {
                    (transpose(&a.dense()), transpose(&b.dense()))
                };
                let abt = matmul(&oa, &transpose(&ob));
                let (alpha, beta) = (0.8, -1.1);
                let expected: Vec<Vec<f64>> = (0..n)
                    .map(|i| {
                        (0..n)
                            .map(|j| alpha * (abt[i][j] + abt[j][i]) + beta * c0[i][j])
                            .collect()
                    })
                    .collect();
                let (ni, ki, al, be) = (n as i32, k as i32, T::of(alpha), T::of(beta));
                let (lda, ldb, ldc) = (a.ld as i32, b.ld as i32, c.ld as i32);
                let (a, b) = (&a.data, &b.data);
                unsafe { T::syr2k(uplo, t, ni, ki, al, a, lda, b, ldb, be, &mut c.data, ldc) };
                assert_triangle(&c, &expected, (uplo, t, k), "syr2k");
            }
        }
    }
}

// ---------------------------------------------------------------------------------
// LAPACK

/// A random symmetric positive definite n×n matrix, condition number about 10.
fn spd(n: usize, g: &mut Rng) -> Vec<Vec<f64>> {
    let q = orthogonal(n, g);
    let values: Vec<f64> = (0..n)
        .map(|i| 1.0 + 9.0 * i as f64 / n.max(2) as f64)
        .collect();
    matmul(&matmul(&q, &diag(&values, n, n)), &transpose(&q))
}

fn potrf_potrs_cases<T: Scalar>() {
    let mut g = Rng::new(6);
    for n in [1, 2, 5, 9] {
        for uplo in [b'U', b'L'] {
            let up = uplo == b'U';
            let s = spd(n, &mut g);
            // The other triangle holds the sentinel: neither read nor written.
            let mut a = Array::<T>::new(n, n, 3, SENTINEL, |i, j| {
                if (up && i <= j) || (!up && i >= j) {
                    s[i][j]
                } else {
                    SENTINEL
                }
            });
            let mut info = 99;
            unsafe { T::potrf(uplo, n as i32, &mut a.data, a.ld as i32, &mut info) };
            assert_eq!(info, 0, "potrf {} n={n}", uplo as char);
            // L·Lᵀ (L = Uᵀ for 'U') rebuilds A.
            let l: Vec<Vec<f64>> = (0..n)
                .map(|i| {
                    (0..n)
                        .map(|j| {
                            if i >= j {
                                if up {
                                    a.get(j, i)
                                } else {
                                    a.get(i, j)
                                }
                            } else {
                                0.0
                            }
                        })
                        .collect()
                })
                .collect();
            assert!((0..n).all(|i| l[i][i] > 0.0), "positive diagonal");
            assert_close::<T>(
                &matmul(&l, &transpose(&l)),
                &s,
                10.0,
                &format!("potrf {} n={n}: L·Lᵀ", uplo as char),
            );
            for i in 0..n {
                for j in 0..n {
                    if (up && i > j) || (!up && i < j) {
                        assert_eq!(a.get(i, j), SENTINEL, "potrf other triangle ({i}, {j})");
                    }
                }
            }
            a.assert_padding(SENTINEL, "potrf A");
            // potrs: A·X = B from the factor.
            let nrhs = 3;
            let x_true = Array::<T>::random(n, nrhs, 0, 0.0, &mut g).dense();
            let rhs = matmul(&s, &x_true);
            let mut b = Array::<T>::from(&rhs, 2, SENTINEL);
            unsafe {
                T::potrs(
                    uplo,
                    n as i32,
                    nrhs as i32,
                    &a.data,
                    a.ld as i32,
                    &mut b.data,
                    b.ld as i32,
                    &mut info,
                )
            };
            assert_eq!(info, 0);
            assert_close::<T>(
                &matmul(&s, &b.dense()),
                &rhs,
                10.0 * max_abs(&rhs),
                &format!("potrs {} n={n}: A·X = B", uplo as char),
            );
            b.assert_padding(SENTINEL, "potrs B");
        }
    }
    // Not positive definite: info is the order of the first leading minor that is not.
    for (bad, uplo) in [(0, b'L'), (2, b'U'), (4, b'L')] {
        let n = 6;
        let mut s = spd(n, &mut g);
        // Make the leading minor of order bad+1 indefinite: row/column `bad` scaled so
        // that its diagonal is far below what the earlier rows need.
        s[bad][bad] = -1.0;
        let mut a = Array::<T>::from(&s, 1, SENTINEL);
        let mut info = 0;
        unsafe { T::potrf(uplo, n as i32, &mut a.data, a.ld as i32, &mut info) };
        assert_eq!(info, bad as i32 + 1, "potrf non-PD {}", uplo as char);
    }
    // n = 0: quick return with info = 0, nothing touched.
    let mut a = vec![T::of(SENTINEL)];
    let mut info = 5;
    unsafe { T::potrf(b'U', 0, &mut a, 1, &mut info) };
    assert_eq!((info, a[0].f()), (0, SENTINEL));
}

/// `?gesv` on the arrays (`A` n×n, `B` n×nrhs): `X` over `B`, `P·A = L·U` over `A`
/// and `ipiv`; the `info` it returns.
fn gesv<T: Scalar>(a: &mut Array<T>, ipiv: &mut [i32], b: &mut Array<T>) -> i32 {
    let (n, nrhs, lda, ldb) = (a.rows as i32, b.cols as i32, a.ld as i32, b.ld as i32);
    let mut info = -99;
    unsafe { T::gesv(n, nrhs, &mut a.data, lda, ipiv, &mut b.data, ldb, &mut info) };
    info
}

fn gesv_cases<T: Scalar>() {
    let mut g = Rng::new(7);
    for n in [1, 3, 8] {
        for nrhs in [1, 4] {
            let a0 = Array::<T>::random(n, n, 0, 0.0, &mut g).dense();
            let mut a = Array::<T>::from(&a0, 2, SENTINEL);
            let x_true = Array::<T>::random(n, nrhs, 0, 0.0, &mut g).dense();
            let rhs = matmul(&a0, &x_true);
            let mut b = Array::<T>::from(&rhs, 1, SENTINEL);
            let mut ipiv = vec![0; n];
            assert_eq!(gesv(&mut a, &mut ipiv, &mut b), 0);
            assert_close::<T>(
                &matmul(&a0, &b.dense()),
                &rhs,
                100.0 * max_abs(&rhs),
                &format!("gesv n={n}: A·X = B"),
            );
            // P·A = L·U with P from the interchanges in order.
            let mut pa = a0.clone();
            for (i, &p) in ipiv.iter().enumerate() {
                assert!(p as usize > i && p as usize <= n, "ipiv[{i}] = {p}");
                pa.swap(i, p as usize - 1);
            }
            let lu = a.dense();
            let l: Vec<Vec<f64>> = (0..n)
                .map(|i| {
                    (0..n)
                        .map(|j| {
                            if i == j {
                                1.0
                            } else if i > j {
                                lu[i][j]
                            } else {
                                0.0
                            }
                        })
                        .collect()
                })
                .collect();
            let u: Vec<Vec<f64>> = (0..n)
                .map(|i| {
                    (0..n)
                        .map(|j| if i <= j { lu[i][j] } else { 0.0 })
                        .collect()
                })
                .collect();
            assert!(
                l.iter().flatten().all(|x| x.abs() <= 1.0 + 1e-6),
                "partial pivoting bounds L"
            );
            assert_close::<T>(
                &matmul(&l, &u),
                &pa,
                max_abs(&a0) * n as f64,
                &format!("gesv n={n}: P·A = L·U"),
            );
            a.assert_padding(SENTINEL, "gesv A");
            b.assert_padding(SENTINEL, "gesv B");
        }
    }
    // Singular (a zero first column): U(1, 1) = 0 exactly, info = 1, B left alone.
    let mut a = Array::<T>::new(
        3,
        3,
        0,
        0.0,
        |i, j| if j == 0 { 0.0 } else { (i * 3 + j) as f64 },
    );
    let rhs = vec![vec![1.0], vec![2.0], vec![3.0]];
    let mut b = Array::<T>::from(&rhs, 0, 0.0);
    let mut ipiv = vec![0; 3];
    assert_eq!(gesv(&mut a, &mut ipiv, &mut b), 1);
    assert_eq!(b.dense(), rhs);
}

/// `?syevr` on a symmetric matrix of known spectrum (Householder similarity of a
/// diagonal), every `range`, both `uplo` and `jobz`.
fn syevr_cases<T: Scalar>() {
    let mut g = Rng::new(8);
    for n in [1, 2, 4, 7] {
        let q = orthogonal(n, &mut g);
        let spectrum: Vec<f64> = (0..n)
            .map(|i| -2.0 + 1.5 * i as f64 + 0.1 * (i * i) as f64)
            .collect();
        let s = matmul(&matmul(&q, &diag(&spectrum, n, n)), &transpose(&q));
        // (range, vl, vu, il, iu) and the indices of the spectrum it selects.
        let ranges: Vec<(u8, f64, f64, i32, i32, std::ops::Range<usize>)> = vec![
            (b'A', 0.0, 0.0, 0, 0, 0..n),
            (b'I', 0.0, 0.0, 1, n as i32, 0..n),
            (
                b'I',
                0.0,
                0.0,
                n.div_ceil(2) as i32,
                n as i32,
                n.div_ceil(2) - 1..n,
            ),
            (b'V', -2.5, spectrum[n - 1] + 0.5, 0, 0, 0..n),
            (b'V', spectrum[0] + 0.05, spectrum[n - 1] + 0.5, 0, 0, 1..n),
        ];
        for (range, vl, vu, il, iu, selected) in ranges {
            for uplo in [b'U', b'L'] {
                for jobz in [b'N', b'V'] {
                    let up = uplo == b'U';
                    let mut a = Array::<T>::new(n, n, 2, SENTINEL, |i, j| {
                        if (up && i <= j) || (!up && i >= j) {
                            s[i][j]
                        } else {
                            f64::NAN
                        }
                    });
                    // Workspace query first, as Clarabel does.
                    let (mut m, mut info) = (-1, -1);
                    let mut w = vec![T::of(0.0); n];
                    let mut z_dummy = vec![T::of(0.0); 1];
                    let mut isuppz = vec![0; 2 * n];
                    let mut work = vec![T::of(0.0); 1];
                    let mut iwork = vec![0; 1];
                    let (ni, lda, vl, vu, abstol) =
                        (n as i32, a.ld as i32, T::of(vl), T::of(vu), T::of(-1.0));
                    let a_data = &mut a.data;
                    let mut syevr = |z: &mut [T],
                                     ldz: i32,
                                     work: &mut [T],
                                     lwork: i32,
                                     iwork: &mut [i32],
                                     liwork: i32,
                                     info: &mut i32| unsafe {
                        T::syevr(
                            jobz,
                            range,
                            uplo,
                            ni,
                            a_data,
                            lda,
                            vl,
                            vu,
                            il,
                            iu,
                            abstol,
                            &mut m,
                            &mut w,
                            z,
                            ldz,
                            &mut isuppz,
                            work,
                            lwork,
                            iwork,
                            liwork,
                            info,
                        )
                    };
                    syevr(&mut z_dummy, ni, &mut work, -1, &mut iwork, -1, &mut info);
                    assert_eq!(info, 0);
                    let lwork = work[0].f() as usize;
                    let liwork = iwork[0] as usize;
                    assert!(
                        lwork >= 26 * n && liwork >= 10 * n,
                        "syevr query {lwork} {liwork}"
                    );
                    work.resize(lwork, T::of(0.0));
                    iwork.resize(liwork, 0);
                    let mut z = Array::<T>::new(n, n, 1, SENTINEL, |_, _| SENTINEL);
                    // jobz = 'N' with a one-element dummy z (Clarabel's call).
                    let z_data: &mut [T] = if jobz == b'V' {
                        &mut z.data
                    } else {
                        &mut z_dummy
                    };
                    syevr(
                        z_data,
                        ni + 1,
                        &mut work,
                        lwork as i32,
                        &mut iwork,
                        liwork as i32,
                        &mut info,
                    );
                    let what = format!(
                        "syevr {} {} {} n={n}",
                        jobz as char, range as char, uplo as char
                    );
                    assert_eq!(info, 0, "{what}");
                    assert_eq!(m as usize, selected.len(), "{what}: m");
                    let got: Vec<Vec<f64>> = w[..m as usize].iter().map(|x| vec![x.f()]).collect();
                    let expected: Vec<Vec<f64>> = spectrum[selected.clone()]
                        .iter()
                        .map(|x| vec![*x])
                        .collect();
                    assert_close::<T>(&got, &expected, 20.0, &format!("{what}: eigenvalues"));
                    assert!(
                        w[..m as usize].windows(2).all(|p| p[0] <= p[1]),
                        "{what}: ascending"
                    );
                    if jobz == b'V' {
                        let v = z.block(n, m as usize);
                        assert_orthonormal_columns::<T>(&v, &format!("{what}: VᵀV"));
                        let av = matmul(&s, &v);
                        let vl: Vec<Vec<f64>> = (0..n)
                            .map(|i| (0..m as usize).map(|j| v[i][j] * w[j].f()).collect())
                            .collect();
                        assert_close::<T>(&av, &vl, 20.0, &format!("{what}: A·V = V·Λ"));
                        for j in 0..m as usize {
                            let (first, last) = (isuppz[2 * j], isuppz[2 * j + 1]);
                            assert!(
                                1 <= first && first <= last && last as usize <= n,
                                "{what}: isuppz {first} {last}"
                            );
                            assert!(
                                (0..n).all(|i| (i + 1 >= first as usize && i < last as usize)
                                    || v[i][j] == 0.0)
                            );
                        }
                        // Columns beyond m untouched, and the padding row.
                        for j in m as usize..n {
                            assert!(
                                (0..n).all(|i| z.get(i, j) == SENTINEL),
                                "{what}: z column {j}"
                            );
                        }
                        z.assert_padding(SENTINEL, &what);
                    } else {
                        assert_eq!(z_dummy[0].f(), 0.0, "{what}: dummy z written");
                    }
                    a.assert_padding(SENTINEL, &what);
                }
            }
        }
    }
    // n = 0: m = 0, work[0] = 1.
    let (mut m, mut info) = (7, 7);
    let mut work = vec![T::of(0.0); 1];
    let mut iwork = vec![0; 1];
    let zero = T::of(0.0);
    unsafe {
        T::syevr(
            b'V',
            b'A',
            b'U',
            0,
            &mut [],
            1,
            zero,
            zero,
            0,
            0,
            zero,
            &mut m,
            &mut [],
            &mut [],
            1,
            &mut [],
            &mut work,
            1,
            &mut iwork,
            1,
            &mut info,
        );
    }
    assert_eq!((m, info, work[0].f()), (0, 0, 1.0));
}

/// The SVD drivers on a matrix of known singular values, every job, both shapes.
fn svd_cases<T: Scalar>() {
    let mut g = Rng::new(9);
    for (m, n) in [(6, 4), (4, 6), (5, 5), (1, 3), (3, 1), (9, 2)] {
        let k = m.min(n);
        let sigma: Vec<f64> = (0..k).map(|i| 4.0 / (1.0 + i as f64)).collect();
        let a0 = matmul(
            &matmul(&orthogonal(m, &mut g), &diag(&sigma, m, n)),
            &transpose(&orthogonal(n, &mut g)),
        );
        for driver in ["gesdd", "gesvd"] {
            for job in [b'S', b'A', b'O', b'N'] {
                let mut a = Array::<T>::from(&a0, 2, SENTINEL);
                // U is m×(m or k) unless it goes over A, Vᵀ (k or n)×n.
                let u_cols = if job == b'A' { m } else { k };
                let vt_rows = if job == b'A' { n } else { k };
                let mut u = Array::<T>::new(m, u_cols, 1, SENTINEL, |_, _| SENTINEL);
                let mut vt = Array::<T>::new(vt_rows.max(n), n, 1, SENTINEL, |_, _| SENTINEL);
                let mut s = vec![T::of(0.0); k];
                let mut work = vec![T::of(0.0); 1];
                let mut iwork = vec![0; 8 * k];
                let what = format!("{driver} {} {m}x{n}", job as char);
                // gesvd with 'O' on one side only (LAPACK forbids both): U over A.
                let (jobu, jobvt) = if job == b'O' {
                    (b'O', b'S')
                } else {
                    (job, job)
                };
                // The workspace query, then the call: `info` of each.
                let mut call = |work: &mut [T], lwork: i32| {
                    let mut info = -1;
                    let (mi, ni, lda, ldu, ldvt) =
                        (m as i32, n as i32, a.ld as i32, u.ld as i32, vt.ld as i32);
                    let (a, u, vt, s) = (&mut a.data, &mut u.data, &mut vt.data, &mut s);
                    unsafe {
                        if driver == "gesdd" {
                            T::gesdd(
                                job, mi, ni, a, lda, s, u, ldu, vt, ldvt, work, lwork, &mut iwork,
                                &mut info,
                            );
                        } else {
                            T::gesvd(
                                jobu, jobvt, mi, ni, a, lda, s, u, ldu, vt, ldvt, work, lwork,
                                &mut info,
                            );
                        }
                    }
                    info
                };
                assert_eq!(call(&mut work, -1), 0, "{what}: query");
                let lwork = work[0].f() as usize;
                assert!(lwork >= 1, "{what}: lwork {lwork}");
                work.resize(lwork, T::of(0.0));
                assert_eq!(call(&mut work, lwork as i32), 0, "{what}");
                let got: Vec<Vec<f64>> = s.iter().map(|x| vec![x.f()]).collect();
                let expected: Vec<Vec<f64>> = sigma.iter().map(|x| vec![*x]).collect();
                assert_close::<T>(&got, &expected, 10.0, &format!("{what}: singular values"));
                assert!(
                    s.windows(2).all(|p| p[0] >= p[1]) && s.iter().all(|x| x.f() >= 0.0),
                    "{what}: descending"
                );
                if job == b'N' {
                    continue;
                }
                // Where each factor went ('O': gesdd puts the long side's over A; our
                // gesvd call puts U over A).
                let u_over_a = job == b'O' && (driver == "gesvd" || m >= n);
                let vt_over_a = job == b'O' && driver == "gesdd" && m < n;
                let uu = if u_over_a { &a } else { &u }.block(m, k);
                let vv = if vt_over_a { &a } else { &vt }.block(k, n);
                assert_orthonormal_columns::<T>(&uu, &format!("{what}: UᵀU"));
                assert_orthonormal_columns::<T>(&transpose(&vv), &format!("{what}: VᵀV"));
                let usv = matmul(
                    &matmul(
                        &uu,
                        &diag(&s.iter().map(|x| x.f()).collect::<Vec<_>>(), k, k),
                    ),
                    &vv,
                );
                assert_close::<T>(&usv, &a0, 10.0, &format!("{what}: U·Σ·Vᵀ = A"));
                if job == b'A' {
                    let full_v = transpose(&vt.block(n, n));
                    assert_orthonormal_columns::<T>(&u.block(m, m), &format!("{what}: full U"));
                    assert_orthonormal_columns::<T>(&full_v, &format!("{what}: full V"));
                }
                if !u_over_a && !vt_over_a {
                    a.assert_padding(SENTINEL, &what);
                    assert_close::<T>(&a.dense(), &a0, 1.0, &format!("{what}: A kept"));
                }
                u.assert_padding(SENTINEL, &what);
            }
        }
    }
    // A NaN: gesdd refuses it as LAPACK does (info = -4).
    let mut a = vec![T::of(1.0), T::of(f64::NAN), T::of(0.0), T::of(1.0)];
    let (mut s, mut u, mut vt) = (
        vec![T::of(0.0); 2],
        vec![T::of(0.0); 4],
        vec![T::of(0.0); 4],
    );
    let mut work = vec![T::of(0.0); 100];
    let mut iwork = vec![0; 16];
    let mut info = 0;
    unsafe {
        T::gesdd(
            b'S', 2, 2, &mut a, 2, &mut s, &mut u, 2, &mut vt, 2, &mut work, 100, &mut iwork,
            &mut info,
        )
    };
    assert_eq!(info, -4);
}

/// Illegal arguments: LAPACK routines report `info = -i` for the first bad argument;
/// BLAS routines return leaving their output untouched.
fn illegal_argument_cases<T: Scalar>() {
    let one = T::of(1.0);
    let a = vec![one; 16];
    let mut c = vec![T::of(SENTINEL); 16];
    // gemm: (transa, transb, m, k, lda, ldb, ldc), n = 2.
    for (ta, tb, m, k, lda, ldb, ldc) in [
        (b'X', b'N', 2, 2, 2, 2, 2),
        (b'N', b'N', -1, 2, 2, 2, 2),
        (b'N', b'N', 3, 2, 2, 2, 3), // lda < m
        (b'T', b'N', 2, 3, 2, 3, 2), // lda < k
        (b'N', b'N', 2, 2, 2, 2, 1), // ldc < m
    ] {
        unsafe {
            T::gemm(
                ta,
                tb,
                m,
                2,
                k,
                one,
                &a,
                lda,
                &a,
                ldb,
                T::of(0.0),
                &mut c,
                ldc,
            )
        };
    }
    unsafe {
        T::gemv(b'N', 2, 2, one, &a, 2, &a, 0, T::of(0.0), &mut c, 1); // incx = 0
        T::gemv(b'Q', 2, 2, one, &a, 2, &a, 1, T::of(0.0), &mut c, 1);
        T::symv(b'X', 2, one, &a, 2, &a, 1, T::of(0.0), &mut c, 1);
        T::symv(b'U', 2, one, &a, 2, &a, 1, T::of(0.0), &mut c, 0); // incy = 0
        T::syrk(b'U', b'X', 2, 2, one, &a, 2, T::of(0.0), &mut c, 2);
        T::syrk(b'L', b'N', 3, 2, one, &a, 2, T::of(0.0), &mut c, 3); // lda < n
        T::syr2k(b'U', b'N', 2, -2, one, &a, 2, &a, 2, T::of(0.0), &mut c, 2);
        T::syr2k(b'U', b'T', 2, 3, one, &a, 3, &a, 2, T::of(0.0), &mut c, 2); // ldb < k
    }
    assert!(
        c.iter().all(|x| x.f() == SENTINEL),
        "a BLAS routine wrote despite an illegal argument"
    );

    let mut a = vec![one; 16];
    let mut b = vec![one; 16];
    let mut info = 0;
    let check = |expected: i32, what: &str, info: &mut i32| {
        assert_eq!(*info, expected, "{what}");
        *info = 0;
    };
    unsafe {
        T::potrf(b'X', 2, &mut a, 2, &mut info);
        check(-1, "potrf uplo", &mut info);
        T::potrf(b'U', -1, &mut a, 2, &mut info);
        check(-2, "potrf n", &mut info);
        T::potrf(b'U', 3, &mut a, 2, &mut info);
        check(-4, "potrf lda", &mut info);
        T::potrs(b'L', 2, -1, &a, 2, &mut b, 2, &mut info);
        check(-3, "potrs nrhs", &mut info);
        T::potrs(b'L', 2, 1, &a, 2, &mut b, 1, &mut info);
        check(-7, "potrs ldb", &mut info);
        let mut ipiv = vec![0; 4];
        T::gesv(-1, 1, &mut a, 1, &mut ipiv, &mut b, 1, &mut info);
        check(-1, "gesv n", &mut info);
        T::gesv(3, 1, &mut a, 2, &mut ipiv, &mut b, 3, &mut info);
        check(-4, "gesv lda", &mut info);
        T::gesv(3, 1, &mut a, 3, &mut ipiv, &mut b, 2, &mut info);
        check(-7, "gesv ldb", &mut info);
        let (mut m, mut w, mut z) = (0, vec![T::of(0.0); 4], vec![T::of(0.0); 16]);
        let mut isuppz = vec![0; 8];
        let mut work = vec![T::of(0.0); 200];
        let mut iwork = vec![0; 100];
        let z1 = T::of(0.0);
        // syevr: (jobz, range, vl, vu, il, iu, ldz, lwork, liwork), uplo 'U', n = lda = 4.
        for (jobz, range, vl, vu, il, iu, ldz, lwork, liwork, expected, what) in [
            (b'X', b'A', 0.0, 0.0, 0, 0, 4, 200, 100, -1, "syevr jobz"),
            (b'V', b'X', 0.0, 0.0, 0, 0, 4, 200, 100, -2, "syevr range"),
            (
                b'V',
                b'V',
                1.0,
                1.0,
                0,
                0,
                4,
                200,
                100,
                -8,
                "syevr vu <= vl",
            ),
            (b'V', b'I', 0.0, 0.0, 0, 2, 4, 200, 100, -9, "syevr il"),
            (
                b'V',
                b'I',
                0.0,
                0.0,
                3,
                2,
                4,
                200,
                100,
                -10,
                "syevr iu < il",
            ),
            (b'V', b'A', 0.0, 0.0, 0, 0, 3, 200, 100, -15, "syevr ldz"),
            (
                b'V',
                b'A',
                0.0,
                0.0,
                0,
                0,
                4,
                103,
                100,
                -18,
                "syevr lwork < 26n",
            ),
            (
                b'V',
                b'A',
                0.0,
                0.0,
                0,
                0,
                4,
                200,
                39,
                -20,
                "syevr liwork < 10n",
            ),
        ] {
            let (vl, vu) = (T::of(vl), T::of(vu));
            T::syevr(
                jobz,
                range,
                b'U',
                4,
                &mut a,
                4,
                vl,
                vu,
                il,
                iu,
                z1,
                &mut m,
                &mut w,
                &mut z,
                ldz,
                &mut isuppz,
                &mut work,
                lwork,
                &mut iwork,
                liwork,
                &mut info,
            );
            check(expected, what, &mut info);
        }
        let (mut s, mut u, mut vt) = (
            vec![T::of(0.0); 4],
            vec![T::of(0.0); 16],
            vec![T::of(0.0); 16],
        );
        // gesdd: (jobz, m, n, lda, ldu, ldvt, lwork).
        for (jobz, m, n, lda, ldu, ldvt, lwork, expected, what) in [
            (b'X', 4, 4, 4, 4, 4, 200, -1, "gesdd jobz"),
            (b'S', 4, 3, 4, 3, 4, 200, -8, "gesdd ldu"),
            (b'A', 3, 4, 3, 3, 3, 200, -10, "gesdd ldvt"),
            (b'S', 4, 4, 4, 4, 4, 10, -12, "gesdd lwork"),
        ] {
            T::gesdd(
                jobz, m, n, &mut a, lda, &mut s, &mut u, ldu, &mut vt, ldvt, &mut work, lwork,
                &mut iwork, &mut info,
            );
            check(expected, what, &mut info);
        }
        // gesvd: (jobu, jobvt, n, lwork), m = lda = ldu = ldvt = 4.
        for (jobu, jobvt, n, lwork, expected, what) in [
            (b'O', b'O', 4, 200, -2, "gesvd both O"),
            (b'S', b'S', -4, 200, -4, "gesvd n"),
            (b'N', b'N', 4, 19, -13, "gesvd lwork"),
        ] {
            T::gesvd(
                jobu, jobvt, 4, n, &mut a, 4, &mut s, &mut u, 4, &mut vt, 4, &mut work, lwork,
                &mut info,
            );
            check(expected, what, &mut info);
        }
    }
    assert!(
        b.iter().all(|x| x.f() == 1.0),
        "B written despite an illegal argument"
    );
}

/// Empty problems: quick returns with `info = 0`, nothing written (the arrays hold the
/// sentinel), LAPACK's workspace query answering 1.
fn empty_cases<T: Scalar>() {
    let s = T::of(SENTINEL);
    let one = T::of(1.0);
    let mut out = vec![s; 4];
    let a = vec![one; 4];
    let mut info = 9;
    let untouched = |out: &[T], what: &str| assert!(out.iter().all(|x| *x == s), "{what}");
    unsafe {
        T::gemv(b'T', 0, 3, one, &a, 1, &a, 1, T::of(0.0), &mut out, 1);
        untouched(&out, "gemv m = 0");
        T::symv(b'L', 0, one, &a, 1, &a, 1, T::of(0.0), &mut out, 1);
        untouched(&out, "symv n = 0");
        T::syrk(b'U', b'N', 0, 2, one, &a, 1, T::of(0.0), &mut out, 1);
        T::syr2k(b'L', b'T', 0, 2, one, &a, 2, &a, 2, T::of(0.0), &mut out, 1);
        untouched(&out, "syrk/syr2k n = 0");
        T::potrs(b'U', 0, 2, &a, 1, &mut out, 1, &mut info);
        assert_eq!(info, 0);
        T::potrs(b'U', 2, 0, &a, 2, &mut out, 2, &mut info);
        assert_eq!(info, 0);
        let mut ipiv = vec![-5; 2];
        T::gesv(0, 1, &mut out, 1, &mut ipiv, &mut [], 1, &mut info);
        assert_eq!(info, 0);
        untouched(&out, "potrs/gesv empty");
        assert_eq!(ipiv, vec![-5, -5]);
        for (m, n) in [(0, 3), (3, 0)] {
            let (mut u, mut vt) = (vec![s; 9], vec![s; 9]);
            let mut work = vec![T::of(0.0); 1];
            let mut iwork = vec![-5; 1];
            let mut sv: Vec<T> = Vec::new();
            let (ldm, ldn) = (m.max(1), n.max(1));
            T::gesdd(
                b'S', m, n, &mut out, ldm, &mut sv, &mut u, ldm, &mut vt, 1, &mut work, -1,
                &mut iwork, &mut info,
            );
            assert_eq!(
                (info, work[0].f(), iwork[0]),
                (0, 1.0, -5),
                "gesdd {m}x{n} query"
            );
            T::gesdd(
                b'S', m, n, &mut out, ldm, &mut sv, &mut u, ldm, &mut vt, 1, &mut work, 1,
                &mut iwork, &mut info,
            );
            assert_eq!(info, 0);
            T::gesvd(
                b'A', b'A', m, n, &mut out, ldm, &mut sv, &mut u, ldm, &mut vt, ldn, &mut work, 1,
                &mut info,
            );
            assert_eq!(info, 0);
            untouched(&u, "gesdd/gesvd empty U");
            untouched(&vt, "gesdd/gesvd empty Vt");
            untouched(&out, "gesdd/gesvd empty A");
        }
    }
}

macro_rules! both_precisions {
    ($($name:ident),*) => {
        mod f32_routines {
            $(#[test] fn $name() { super::$name::<f32>() })*
        }
        mod f64_routines {
            $(#[test] fn $name() { super::$name::<f64>() })*
        }
    };
}

both_precisions!(
    gemm_cases,
    gemv_cases,
    symv_cases,
    syrk_cases,
    syr2k_cases,
    potrf_potrs_cases,
    gesv_cases,
    syevr_cases,
    svd_cases,
    illegal_argument_cases,
    empty_cases
);
