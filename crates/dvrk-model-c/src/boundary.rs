//! What every entry point does at the boundary: pointers to references and slices (the
//! `unsafe` conversions, each with its caller's obligation), the checks of inputs and
//! outputs for non-finite numbers, and panics caught before they cross the ABI.

use std::ffi::c_int;
use std::panic::{catch_unwind, AssertUnwindSafe};

use crate::codes::{
    DVRK_ERR_INTERNAL, DVRK_ERR_NOT_FINITE, DVRK_ERR_NULL, DVRK_ERR_OVERFLOW, DVRK_ERR_WORKSPACE,
    DVRK_OK,
};
use crate::{DvrkModel, DvrkWorkspace};

/// The model `model` points to, or None for NULL.
///
/// # Safety
///
/// `model` is NULL or a live pointer from `dvrk_model_from_result`.
pub(crate) unsafe fn model_ref<'a>(model: *const DvrkModel) -> Option<&'a DvrkModel> {
    // SAFETY: the caller's obligation above; `as_ref` maps NULL to None.
    unsafe { model.as_ref() }
}

/// The model and workspace of a real-time call, after the checks every call shares:
/// neither NULL, and the workspace made for this model.
///
/// # Safety
///
/// `model` and `ws` are NULL or live pointers from their constructors; `ws` is not used
/// by another thread during the call.
pub(crate) unsafe fn pair<'a>(
    model: *const DvrkModel,
    ws: *mut DvrkWorkspace,
) -> Result<(&'a DvrkModel, &'a mut DvrkWorkspace), c_int> {
    // SAFETY: the caller's obligation, passed on.
    let m = unsafe { model_ref(model) }.ok_or(DVRK_ERR_NULL)?;
    // SAFETY: NULL or live, and used by this thread alone (the caller's obligation).
    let w = unsafe { ws.as_mut() }.ok_or(DVRK_ERR_NULL)?;
    if !std::ptr::eq(w.model, model) {
        return Err(DVRK_ERR_WORKSPACE);
    }
    Ok((m, w))
}

/// The arguments of a real-time call on a model and its workspace, after the checks
/// every such call shares, in this order (so the first failing one gives the code):
/// the model and workspace ([`pair`]), then the `N` inputs of `n = dof` doubles and the
/// output of `out_len(n)` doubles ([`slices`]). Each entry point then states only what
/// differs: which inputs must be finite, what it computes and how it delivers.
///
/// # Safety
///
/// As [`pair`]; each input is NULL or valid for `n` doubles as in [`input`], `out` is
/// NULL or valid for `out_len(n)` doubles as in [`output`].
pub(crate) unsafe fn workspace_args<'a, const N: usize>(
    model: *const DvrkModel,
    ws: *mut DvrkWorkspace,
    inputs: [*const f64; N],
    out: *mut f64,
    out_len: impl FnOnce(usize) -> usize,
) -> Result<WorkspaceArgs<'a, N>, c_int> {
    // SAFETY: the caller's obligations, passed on.
    let (m, w) = unsafe { pair(model, ws) }?;
    let n = m.model.dof();
    // SAFETY: the caller's obligations, passed on.
    let (inputs, out) = unsafe { slices(inputs, n, out, out_len(n)) }?;
    Ok((m, w, inputs, out))
}

/// What [`workspace_args`] returns: the model, its workspace, the inputs and the output.
pub(crate) type WorkspaceArgs<'a, const N: usize> = (
    &'a DvrkModel,
    &'a mut DvrkWorkspace,
    [&'a [f64]; N],
    &'a mut [f64],
);

/// `N` inputs of `n` doubles and an output of `out_len` doubles as slices, NULL checked
/// in order (inputs first) as [`input`] and [`output`] do.
///
/// # Safety
///
/// Each input is NULL or valid for `n` doubles as in [`input`], `out` is NULL or valid
/// for `out_len` doubles as in [`output`].
pub(crate) unsafe fn slices<'a, const N: usize>(
    inputs: [*const f64; N],
    n: usize,
    out: *mut f64,
    out_len: usize,
) -> Result<([&'a [f64]; N], &'a mut [f64]), c_int> {
    let mut read: [&[f64]; N] = [&[]; N];
    for (slice, p) in read.iter_mut().zip(inputs) {
        // SAFETY: the caller's obligation, passed on.
        *slice = unsafe { input(p, n) }?;
    }
    // SAFETY: the caller's obligation, passed on.
    Ok((read, unsafe { output(out, out_len) }?))
}

/// `n` doubles at `p` as a slice; NULL is [`DVRK_ERR_NULL`].
///
/// # Safety
///
/// `p` is NULL or valid for reading `n` doubles that nothing writes during the call.
pub(crate) unsafe fn input<'a>(p: *const f64, n: usize) -> Result<&'a [f64], c_int> {
    if p.is_null() {
        return Err(DVRK_ERR_NULL);
    }
    // SAFETY: non-NULL and valid for `n` doubles (the caller's obligation).
    Ok(unsafe { std::slice::from_raw_parts(p, n) })
}

/// `n` doubles at `p` as a mutable slice; NULL is [`DVRK_ERR_NULL`].
///
/// # Safety
///
/// `p` is NULL or valid for writing `n` doubles, overlapping no input of the call.
pub(crate) unsafe fn output<'a>(p: *mut f64, n: usize) -> Result<&'a mut [f64], c_int> {
    if p.is_null() {
        return Err(DVRK_ERR_NULL);
    }
    // SAFETY: non-NULL, valid for `n` doubles and not aliased (the caller's obligation).
    Ok(unsafe { std::slice::from_raw_parts_mut(p, n) })
}

/// Whether every value is finite. Two forms, by length, each the faster one in
/// benches/abi.rs: a vector of a few values (a state, a torque) is checked value by
/// value, with a branch the predictor learns; the mass matrix's n² values by an OR over
/// their exponent bits with no branch per value (a value is NaN or infinite when its
/// exponent field is all ones, and adding one to that field then carries into the sign
/// bit: AND, ADD and OR on 64-bit integers, which baseline x86-64 vectorizes). The
/// branch-free form cost 5-10 ns more on a 7-value torque; the branchy one 15-30 ns more
/// on a 49-value mass matrix.
fn all_finite(x: &[f64]) -> bool {
    const EXPONENT: u64 = 0x7ff0_0000_0000_0000;
    const ONE: u64 = 1 << 52;
    if x.len() <= 16 {
        x.iter().all(|v| v.is_finite())
    } else {
        x.iter().fold(0u64, |any, v| {
            any | (v.to_bits() & EXPONENT).wrapping_add(ONE)
        }) >> 63
            == 0
    }
}

/// [`DVRK_ERR_NOT_FINITE`] unless every input is finite.
pub(crate) fn finite(inputs: &[&[f64]]) -> Result<(), c_int> {
    if inputs.iter().all(|x| all_finite(x)) {
        Ok(())
    } else {
        Err(DVRK_ERR_NOT_FINITE)
    }
}

/// [`DVRK_ERR_NOT_FINITE`] unless the three inputs of a dynamics call (a state of `n`
/// values each) are finite: one pass over the coordinates, `0·x` being ±0 for a finite
/// `x` and NaN otherwise, so one compare and one predicted branch per coordinate instead
/// of per value (benches/abi.rs: the inverse dynamics' overhead went from 4.5-5.8 % to
/// 3.4-3.8 % on the PSM). The three have the model's `n` values (`input`).
pub(crate) fn finite3(a: &[f64], b: &[f64], c: &[f64]) -> Result<(), c_int> {
    debug_assert!(a.len() == b.len() && b.len() == c.len());
    let ok = a
        .iter()
        .zip(b)
        .zip(c)
        .all(|((a, b), c)| a * 0.0 + b * 0.0 + c * 0.0 == 0.0);
    if ok {
        Ok(())
    } else {
        Err(DVRK_ERR_NOT_FINITE)
    }
}

/// Copies a computed result to the caller's output if it is finite (else
/// [`DVRK_ERR_OVERFLOW`], output untouched).
pub(crate) fn deliver(computed: &[f64], out: &mut [f64]) -> Result<(), c_int> {
    if all_finite(computed) {
        out.copy_from_slice(computed);
        Ok(())
    } else {
        Err(DVRK_ERR_OVERFLOW)
    }
}

/// Runs a real-time call's body: a panic (a bug) becomes [`DVRK_ERR_INTERNAL`], an
/// error its code. `catch_unwind` allocates nothing unless something panics.
pub(crate) fn guarded(body: impl FnOnce() -> Result<(), c_int>) -> c_int {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => DVRK_OK,
        Ok(Err(code)) => code,
        Err(_) => DVRK_ERR_INTERNAL,
    }
}

#[cfg(test)]
mod tests {
    use super::{all_finite, finite3, DVRK_ERR_NOT_FINITE};

    /// Both forms of `all_finite` (up to 16 values, and more) against `f64::is_finite`,
    /// with the non-finite value at every position: NaN (quiet, signalling, negative),
    /// ±∞, next to the largest finite values, subnormals and −0.
    #[test]
    fn all_finite_agrees_with_is_finite_in_both_forms() {
        let finite = [
            0.0,
            -0.0,
            f64::MAX,
            f64::MIN,
            f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            1.0,
            -3.5e300,
        ];
        let bad = [
            f64::NAN,
            -f64::NAN,
            f64::from_bits(0x7ff0_0000_0000_0001),
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for len in [1, 2, 7, 15, 16, 17, 49, 64] {
            let base: Vec<f64> = (0..len).map(|i| finite[i % finite.len()]).collect();
            assert!(all_finite(&base), "{len} finite values");
            for at in 0..len {
                for &b in &bad {
                    let mut x = base.clone();
                    x[at] = b;
                    assert!(!all_finite(&x), "{b} at {at} of {len}");
                }
            }
        }
        assert!(all_finite(&[]));
    }

    /// `finite3` refuses a non-finite value in any of its three inputs at any position,
    /// and takes finite extremes (whose `0·x` is exactly ±0).
    #[test]
    fn finite3_refuses_every_non_finite_position() {
        let base = [f64::MAX, -0.0, 5e-324, f64::MIN, 1.0, -2.5, 3e300];
        assert_eq!(finite3(&base, &base, &base), Ok(()));
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for at in 0..base.len() {
                let mut x = base;
                x[at] = bad;
                for which in 0..3 {
                    let mut s = [base, base, base];
                    s[which] = x;
                    assert_eq!(
                        finite3(&s[0], &s[1], &s[2]),
                        Err(DVRK_ERR_NOT_FINITE),
                        "{bad} at {at} of input {which}"
                    );
                }
            }
        }
    }
}
