//! BLAS/LAPACK for Clarabel's SDP cone, on faer: no system library, no Fortran compiler.
//!
//! Clarabel's SDP cone (feature `sdp`) calls eleven double-precision BLAS/LAPACK routines
//! through the `blas` and `lapack` crates, which declare them as Fortran-ABI externs
//! (`dgemm_`, `dsyevr_`, ...; no hidden string-length arguments, see `blas-sys` 0.7 and
//! `lapack-sys` 0.14). This crate exports exactly those symbols, implemented on
//! [faer](https://docs.rs/faer), so that Clarabel SDPs build and run with cargo alone. See
//! `README.md` next to this file for the rationale.
//!
//! # Using it with Clarabel
//!
//! Enable Clarabel's `sdp` feature *and* its two optional dependencies `blas-src` and
//! `lapack-src` with no backend feature (they then only satisfy Clarabel's
//! `extern crate blas_src;`), and make this crate part of the binary:
//!
//! ```toml
//! [dependencies]
//! clarabel = { version = "0.11.1", features = ["sdp", "blas-src", "lapack-src"] }
//! rotavg-lapack = "0.1"
//! ```
//!
//! ```
//! use rotavg_lapack as _; // link the routines into this binary (any crate of it may say so)
//! ```
//!
//! A crate that is never referenced is not linked at all, hence the `use ... as _;`. Linkers
//! that read archives once, in order (GNU `ld.bfd`), need more: the object files holding the
//! routines must be loaded before or when the first caller is. Code that calls Clarabel can
//! make that hold by construction with [`link_routines`], which takes the address of every
//! routine (this is what `rotavg` does next to its Clarabel calls); with the default linker of
//! Rust 1.90+ on x86_64 Linux (`rust-lld`) the order does not matter.
//!
//! # Semantics
//!
//! Semantics follow the reference BLAS/LAPACK documentation (column-major storage, leading
//! dimensions `ld* >= max(1, rows)`, 1-based `info` codes) with these documented differences:
//! - Invalid arguments: LAPACK routines return `info = -k` for the k-th argument, like LAPACK;
//!   BLAS routines (which have no `info`) print the reference `xerbla` message to stderr and
//!   return without touching their outputs (the reference BLAS would stop the program).
//! - Workspace: no routine needs `work`/`iwork`; a workspace query (`lwork = -1`) returns the
//!   reference LAPACK *minimal* size so callers that allocate what they are told stay valid, and
//!   any `lwork >= 1` is accepted.
//! - `dsyevr_` ignores `abstol` (faer's accuracy is used) and `dgesdd_`/`dgesvd_` do not support
//!   the overwrite modes (`'O'`): they return `info < 0` for them.
//! - An internal panic (which would be a bug) is caught and reported as `info = -1000` (LAPACK)
//!   or a stderr message (BLAS); nothing unwinds across the FFI boundary.
//!
//! # Why this crate contains `unsafe`
//! The routines are `extern "C"` functions taking raw pointers (that is the ABI Clarabel links
//! against), so building slices/views from those pointers is inherently `unsafe`. This is the
//! only `unsafe` code of the rotavg workspace; every pointer is used only within the extent the
//! BLAS/LAPACK contract guarantees (`ld * (cols - 1) + rows` elements for a matrix, and so on).
#![allow(unsafe_code)]
#![deny(missing_docs)]
#![allow(clippy::too_many_arguments, clippy::missing_safety_doc)]

use core::ffi::{c_char, c_int};
use faer::linalg::matmul::matmul;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// `info` value reported when an internal panic was caught (indicates a bug in this crate).
pub const INTERNAL_ERROR: c_int = -1000;

/// The addresses of the eleven exported routines, in the order `dgemm_`, `dsyrk_`, `dsyr2k_`,
/// `dgemv_`, `dsymv_`, `dpotrf_`, `dpotrs_`, `dgesv_`, `dsyevr_`, `dgesdd_`, `dgesvd_`.
///
/// Calling this from the code that calls Clarabel forces every linker to load the routines
/// whenever that code is linked, whatever order the archives are given in (see the crate
/// documentation). The call is cheap and has no other effect.
///
/// ```
/// let addresses = rotavg_lapack::link_routines();
/// assert!(addresses.iter().all(|&a| a != 0));
/// ```
#[inline(never)]
pub fn link_routines() -> [usize; 11] {
    std::hint::black_box([
        dgemm_ as *const () as usize,
        dsyrk_ as *const () as usize,
        dsyr2k_ as *const () as usize,
        dgemv_ as *const () as usize,
        dsymv_ as *const () as usize,
        dpotrf_ as *const () as usize,
        dpotrs_ as *const () as usize,
        dgesv_ as *const () as usize,
        dsyevr_ as *const () as usize,
        dgesdd_ as *const () as usize,
        dgesvd_ as *const () as usize,
    ])
}

// ---------------------------------------------------------------------------------------------
// helpers
// ---------------------------------------------------------------------------------------------

fn par() -> Par {
    faer::get_global_parallelism()
}

/// Upper-cased option letter.
unsafe fn letter(p: *const c_char) -> u8 {
    unsafe { (*p as u8).to_ascii_uppercase() }
}

/// Column-major read-only view of an `m x n` matrix with leading dimension `ld`.
/// Caller guarantees `m > 0 && n > 0` and the BLAS extent.
unsafe fn view<'a>(p: *const f64, m: usize, n: usize, ld: usize) -> MatRef<'a, f64> {
    unsafe { MatRef::from_raw_parts(p, m, n, 1isize, ld as isize) }
}

/// Column-major mutable view (see [`view`]).
unsafe fn view_mut<'a>(p: *mut f64, m: usize, n: usize, ld: usize) -> MatMut<'a, f64> {
    unsafe { MatMut::from_raw_parts_mut(p, m, n, 1isize, ld as isize) }
}

/// Reference-BLAS style error message (the reference implementation would stop here).
fn xerbla(name: &str, arg: i32) {
    eprintln!(" ** On entry to {name} parameter number {arg} had an illegal value");
}

/// Runs `f`, converting a panic into `None`.
fn guarded<R>(f: impl FnOnce() -> R) -> Option<R> {
    catch_unwind(AssertUnwindSafe(f)).ok()
}

/// Scales the triangle (or full matrix when `uplo` is `None`) of `c` by `beta`, with BLAS
/// semantics: `beta == 0` sets entries to zero (even NaN ones).
fn scale(mut c: MatMut<'_, f64>, beta: f64, uplo: Option<u8>) {
    if beta == 1.0 {
        return;
    }
    let n = c.ncols();
    let m = c.nrows();
    for j in 0..n {
        let (lo, hi) = match uplo {
            None => (0, m),
            Some(b'U') => (0, j + 1),
            Some(_) => (j, m),
        };
        for i in lo..hi {
            let v = if beta == 0.0 { 0.0 } else { beta * c[(i, j)] };
            c[(i, j)] = v;
        }
    }
}

/// Start offset of a strided vector of length `len` with increment `inc` (BLAS convention).
fn vstart(len: usize, inc: isize) -> isize {
    if inc < 0 {
        (len as isize - 1) * -inc
    } else {
        0
    }
}

// ---------------------------------------------------------------------------------------------
// BLAS level 3
// ---------------------------------------------------------------------------------------------

/// `C = alpha * op(A) * op(B) + beta * C` with `op(X) = X` (`'N'`) or `X^T` (`'T'`, `'C'`);
/// `C` is `m x n`, `op(A)` is `m x k`, `op(B)` is `k x n`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dgemm_(
    transa: *const c_char,
    transb: *const c_char,
    m: *const c_int,
    n: *const c_int,
    k: *const c_int,
    alpha: *const f64,
    a: *const f64,
    lda: *const c_int,
    b: *const f64,
    ldb: *const c_int,
    beta: *const f64,
    c: *mut f64,
    ldc: *const c_int,
) {
    let (ta, tb) = unsafe { (letter(transa), letter(transb)) };
    let (m, n, k) = unsafe { (*m, *n, *k) };
    let (lda, ldb, ldc) = unsafe { (*lda, *ldb, *ldc) };
    let (alpha, beta) = unsafe { (*alpha, *beta) };
    let valid_t = |t: u8| matches!(t, b'N' | b'T' | b'C');
    let nrowa = if ta == b'N' { m } else { k };
    let nrowb = if tb == b'N' { k } else { n };
    let bad = if !valid_t(ta) {
        1
    } else if !valid_t(tb) {
        2
    } else if m < 0 {
        3
    } else if n < 0 {
        4
    } else if k < 0 {
        5
    } else if lda < nrowa.max(1) {
        8
    } else if ldb < nrowb.max(1) {
        10
    } else if ldc < m.max(1) {
        13
    } else {
        0
    };
    if bad != 0 {
        return xerbla("DGEMM ", bad);
    }
    if m == 0 || n == 0 {
        return;
    }
    let (m, n, k) = (m as usize, n as usize, k as usize);
    let ok = guarded(|| unsafe {
        let mut cm = view_mut(c, m, n, ldc as usize);
        scale(cm.rb_mut(), beta, None);
        if alpha == 0.0 || k == 0 {
            return;
        }
        let am = if ta == b'N' {
            view(a, m, k, lda as usize)
        } else {
            view(a, k, m, lda as usize).transpose()
        };
        let bm = if tb == b'N' {
            view(b, k, n, ldb as usize)
        } else {
            view(b, n, k, ldb as usize).transpose()
        };
        matmul(cm, Accum::Add, am, bm, alpha, par());
    });
    if ok.is_none() {
        eprintln!("rotavg-lapack: internal error in DGEMM");
    }
}

/// Shared implementation of `dsyrk_` (`b = None`) and `dsyr2k_`.
unsafe fn syrk_impl(
    name: &str,
    uplo: *const c_char,
    trans: *const c_char,
    n: *const c_int,
    k: *const c_int,
    alpha: *const f64,
    a: *const f64,
    lda: *const c_int,
    b: Option<(*const f64, *const c_int)>,
    beta: *const f64,
    c: *mut f64,
    ldc: *const c_int,
) {
    let (ul, tr) = unsafe { (letter(uplo), letter(trans)) };
    let (n, k, lda, ldc) = unsafe { (*n, *k, *lda, *ldc) };
    let ldb = b.map(|(_, ldb)| unsafe { *ldb });
    let (alpha, beta) = unsafe { (*alpha, *beta) };
    let nrowa = if tr == b'N' { n } else { k };
    // argument positions: ldc is 10 for syrk, 12 for syr2k
    let ldc_pos = if b.is_some() { 12 } else { 10 };
    let bad = if !matches!(ul, b'U' | b'L') {
        1
    } else if !matches!(tr, b'N' | b'T' | b'C') {
        2
    } else if n < 0 {
        3
    } else if k < 0 {
        4
    } else if lda < nrowa.max(1) {
        7
    } else if ldb.is_some_and(|ldb| ldb < nrowa.max(1)) {
        9
    } else if ldc < n.max(1) {
        ldc_pos
    } else {
        0
    };
    if bad != 0 {
        return xerbla(name, bad);
    }
    if n == 0 {
        return;
    }
    let (n, k) = (n as usize, k as usize);
    let ok = guarded(|| unsafe {
        let mut cm = view_mut(c, n, n, ldc as usize);
        scale(cm.rb_mut(), beta, Some(ul));
        if alpha == 0.0 || k == 0 {
            return;
        }
        // op(X) is n x k
        let op = |p: *const f64, ld: c_int| {
            if tr == b'N' {
                view(p, n, k, ld as usize)
            } else {
                view(p, k, n, ld as usize).transpose()
            }
        };
        let am = op(a, lda);
        let bm = match b {
            Some((bp, _)) => op(bp, ldb.unwrap_or(lda)),
            None => am,
        };
        // full product T = op(A) op(B)^T; the triangle of T (+ T^T for syr2k) is added
        let mut t = Mat::<f64>::zeros(n, n);
        matmul(t.as_mut(), Accum::Replace, am, bm.transpose(), 1.0, par());
        let two = b.is_some();
        for j in 0..n {
            let (lo, hi) = if ul == b'U' { (0, j + 1) } else { (j, n) };
            for i in lo..hi {
                let v = if two {
                    t[(i, j)] + t[(j, i)]
                } else {
                    t[(i, j)]
                };
                cm[(i, j)] += alpha * v;
            }
        }
    });
    if ok.is_none() {
        eprintln!("rotavg-lapack: internal error in {name}");
    }
}

/// Symmetric rank-k update of the `uplo` triangle of `C` (`n x n`):
/// `C = alpha A A^T + beta C` (`trans = 'N'`, `A` is `n x k`) or
/// `C = alpha A^T A + beta C` (`'T'`/`'C'`, `A` is `k x n`). The other triangle is untouched.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dsyrk_(
    uplo: *const c_char,
    trans: *const c_char,
    n: *const c_int,
    k: *const c_int,
    alpha: *const f64,
    a: *const f64,
    lda: *const c_int,
    beta: *const f64,
    c: *mut f64,
    ldc: *const c_int,
) {
    unsafe {
        syrk_impl(
            "DSYRK ", uplo, trans, n, k, alpha, a, lda, None, beta, c, ldc,
        )
    }
}

/// Symmetric rank-2k update of the `uplo` triangle of `C` (`n x n`):
/// `C = alpha (A B^T + B A^T) + beta C` (`'N'`) or `C = alpha (A^T B + B^T A) + beta C`
/// (`'T'`/`'C'`). The other triangle is untouched.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dsyr2k_(
    uplo: *const c_char,
    trans: *const c_char,
    n: *const c_int,
    k: *const c_int,
    alpha: *const f64,
    a: *const f64,
    lda: *const c_int,
    b: *const f64,
    ldb: *const c_int,
    beta: *const f64,
    c: *mut f64,
    ldc: *const c_int,
) {
    unsafe {
        syrk_impl(
            "DSYR2K",
            uplo,
            trans,
            n,
            k,
            alpha,
            a,
            lda,
            Some((b, ldb)),
            beta,
            c,
            ldc,
        )
    }
}

// ---------------------------------------------------------------------------------------------
// BLAS level 2
// ---------------------------------------------------------------------------------------------

/// `y = alpha op(A) x + beta y`, `A` is `m x n`, `op` as in [`dgemm_`]; `incx`, `incy` nonzero
/// (negative increments traverse the vector backwards, as in BLAS).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dgemv_(
    trans: *const c_char,
    m: *const c_int,
    n: *const c_int,
    alpha: *const f64,
    a: *const f64,
    lda: *const c_int,
    x: *const f64,
    incx: *const c_int,
    beta: *const f64,
    y: *mut f64,
    incy: *const c_int,
) {
    let tr = unsafe { letter(trans) };
    let (m, n, lda, incx, incy) = unsafe { (*m, *n, *lda, *incx, *incy) };
    let (alpha, beta) = unsafe { (*alpha, *beta) };
    let bad = if !matches!(tr, b'N' | b'T' | b'C') {
        1
    } else if m < 0 {
        2
    } else if n < 0 {
        3
    } else if lda < m.max(1) {
        6
    } else if incx == 0 {
        8
    } else if incy == 0 {
        11
    } else {
        0
    };
    if bad != 0 {
        return xerbla("DGEMV ", bad);
    }
    if m == 0 || n == 0 {
        return;
    }
    let (m, n) = (m as usize, n as usize);
    let (lenx, leny) = if tr == b'N' { (n, m) } else { (m, n) };
    let (incx, incy) = (incx as isize, incy as isize);
    let ok = guarded(|| unsafe {
        let am = view(a, m, n, lda as usize);
        let (x0, y0) = (vstart(lenx, incx), vstart(leny, incy));
        let xi = |i: usize| *x.offset(x0 + i as isize * incx);
        let yp = |i: usize| y.offset(y0 + i as isize * incy);
        for i in 0..leny {
            let v = if beta == 0.0 { 0.0 } else { beta * *yp(i) };
            *yp(i) = v;
        }
        if alpha == 0.0 {
            return;
        }
        if tr == b'N' {
            for j in 0..n {
                let t = alpha * xi(j);
                for i in 0..m {
                    *yp(i) += t * am[(i, j)];
                }
            }
        } else {
            for j in 0..n {
                let mut s = 0.0;
                for i in 0..m {
                    s += am[(i, j)] * xi(i);
                }
                *yp(j) += alpha * s;
            }
        }
    });
    if ok.is_none() {
        eprintln!("rotavg-lapack: internal error in DGEMV");
    }
}

/// `y = alpha A x + beta y` for symmetric `A` (`n x n`) of which only the `uplo` triangle is read.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dsymv_(
    uplo: *const c_char,
    n: *const c_int,
    alpha: *const f64,
    a: *const f64,
    lda: *const c_int,
    x: *const f64,
    incx: *const c_int,
    beta: *const f64,
    y: *mut f64,
    incy: *const c_int,
) {
    let ul = unsafe { letter(uplo) };
    let (n, lda, incx, incy) = unsafe { (*n, *lda, *incx, *incy) };
    let (alpha, beta) = unsafe { (*alpha, *beta) };
    let bad = if !matches!(ul, b'U' | b'L') {
        1
    } else if n < 0 {
        2
    } else if lda < n.max(1) {
        5
    } else if incx == 0 {
        7
    } else if incy == 0 {
        10
    } else {
        0
    };
    if bad != 0 {
        return xerbla("DSYMV ", bad);
    }
    if n == 0 {
        return;
    }
    let n = n as usize;
    let (incx, incy) = (incx as isize, incy as isize);
    let ok = guarded(|| unsafe {
        let am = view(a, n, n, lda as usize);
        let (x0, y0) = (vstart(n, incx), vstart(n, incy));
        let xi = |i: usize| *x.offset(x0 + i as isize * incx);
        let yp = |i: usize| y.offset(y0 + i as isize * incy);
        for i in 0..n {
            let v = if beta == 0.0 { 0.0 } else { beta * *yp(i) };
            *yp(i) = v;
        }
        if alpha == 0.0 {
            return;
        }
        // entry (i, j) of the symmetric matrix, read from the stored triangle
        let sym = |i: usize, j: usize| {
            let upper = ul == b'U';
            if (i <= j) == upper || i == j {
                am[(i, j)]
            } else {
                am[(j, i)]
            }
        };
        for i in 0..n {
            let mut s = 0.0;
            for j in 0..n {
                s += sym(i, j) * xi(j);
            }
            *yp(i) += alpha * s;
        }
    });
    if ok.is_none() {
        eprintln!("rotavg-lapack: internal error in DSYMV");
    }
}

// ---------------------------------------------------------------------------------------------
// LAPACK: Cholesky
// ---------------------------------------------------------------------------------------------

/// Cholesky factorisation of a symmetric positive definite matrix stored in the `uplo` triangle:
/// `A = U^T U` (`'U'`) or `A = L L^T` (`'L'`), overwriting that triangle; the other triangle is
/// not referenced. `info = 0` success; `info = -k` illegal k-th argument; `info = k > 0` the
/// leading minor of order k is not positive definite (the factorisation could not be completed).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dpotrf_(
    uplo: *const c_char,
    n: *const c_int,
    a: *mut f64,
    lda: *const c_int,
    info: *mut c_int,
) {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::cholesky::llt::factor::{
        LltError, cholesky_in_place, cholesky_in_place_scratch,
    };
    let ul = unsafe { letter(uplo) };
    let (n, lda) = unsafe { (*n, *lda) };
    let code = if !matches!(ul, b'U' | b'L') {
        -1
    } else if n < 0 {
        -2
    } else if lda < n.max(1) {
        -4
    } else if n == 0 {
        0
    } else {
        let n = n as usize;
        guarded(|| unsafe {
            let am = view_mut(a, n, n, lda as usize);
            // faer factors the lower triangle; for 'U' the transposed view's lower triangle is
            // the stored upper triangle and L = U^T.
            let mut am = if ul == b'L' { am } else { am.transpose_mut() };
            // faer may use the strictly upper part as scratch; LAPACK leaves it untouched, and
            // callers may keep data there, so save and restore it.
            let saved: Vec<f64> = (1..n)
                .flat_map(|j| (0..j).map(move |i| (i, j)))
                .map(|(i, j)| am[(i, j)])
                .collect();
            let p = par();
            let mut buf =
                MemBuffer::new(cholesky_in_place_scratch::<f64>(n, p, Default::default()));
            let stack = MemStack::new(&mut buf);
            let res = cholesky_in_place(
                am.rb_mut(),
                Default::default(),
                p,
                stack,
                Default::default(),
            );
            let mut it = saved.into_iter();
            for j in 1..n {
                for i in 0..j {
                    am[(i, j)] = it.next().unwrap_or(0.0);
                }
            }
            match res {
                Ok(_) => 0,
                Err(LltError::NonPositivePivot { index }) => index as c_int + 1,
            }
        })
        .unwrap_or(INTERNAL_ERROR)
    };
    unsafe { *info = code };
}

/// Solves `A X = B` with the Cholesky factor computed by [`dpotrf_`] (same `uplo`); `B` is
/// `n x nrhs` and is overwritten by `X`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dpotrs_(
    uplo: *const c_char,
    n: *const c_int,
    nrhs: *const c_int,
    a: *const f64,
    lda: *const c_int,
    b: *mut f64,
    ldb: *const c_int,
    info: *mut c_int,
) {
    use faer::linalg::triangular_solve::{
        solve_lower_triangular_in_place, solve_upper_triangular_in_place,
    };
    let ul = unsafe { letter(uplo) };
    let (n, nrhs, lda, ldb) = unsafe { (*n, *nrhs, *lda, *ldb) };
    let code = if !matches!(ul, b'U' | b'L') {
        -1
    } else if n < 0 {
        -2
    } else if nrhs < 0 {
        -3
    } else if lda < n.max(1) {
        -5
    } else if ldb < n.max(1) {
        -7
    } else if n == 0 || nrhs == 0 {
        0
    } else {
        let (n, nrhs) = (n as usize, nrhs as usize);
        guarded(|| unsafe {
            let am = view(a, n, n, lda as usize);
            let mut bm = view_mut(b, n, nrhs, ldb as usize);
            // lower factor L with A = L L^T (for 'U', L = U^T is the transposed view)
            let l = if ul == b'L' { am } else { am.transpose() };
            solve_lower_triangular_in_place(l, bm.rb_mut(), par());
            solve_upper_triangular_in_place(l.transpose(), bm.rb_mut(), par());
            0
        })
        .unwrap_or(INTERNAL_ERROR)
    };
    unsafe { *info = code };
}

// ---------------------------------------------------------------------------------------------
// LAPACK: LU solve
// ---------------------------------------------------------------------------------------------

/// Solves `A X = B` by LU factorisation with partial pivoting (`A = P L U`, the unblocked
/// algorithm of LAPACK's `dgetf2`, so pivots match the reference). On exit `A` holds `L`
/// (unit diagonal not stored) and `U`, `ipiv` the 1-based row interchanges, `B` the solution.
/// `info = k > 0`: `U(k, k)` is exactly zero, no solution computed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dgesv_(
    n: *const c_int,
    nrhs: *const c_int,
    a: *mut f64,
    lda: *const c_int,
    ipiv: *mut c_int,
    b: *mut f64,
    ldb: *const c_int,
    info: *mut c_int,
) {
    let (n, nrhs, lda, ldb) = unsafe { (*n, *nrhs, *lda, *ldb) };
    let code = if n < 0 {
        -1
    } else if nrhs < 0 {
        -2
    } else if lda < n.max(1) {
        -4
    } else if ldb < n.max(1) {
        -7
    } else if n == 0 {
        0
    } else {
        let (n, nrhs) = (n as usize, nrhs as usize);
        guarded(|| unsafe {
            let mut am = view_mut(a, n, n, lda as usize);
            let mut first_zero = 0;
            for j in 0..n {
                // pivot: first index of max |a(i, j)|, i >= j (idamax)
                let mut p = j;
                for i in j + 1..n {
                    if am[(i, j)].abs() > am[(p, j)].abs() {
                        p = i;
                    }
                }
                *ipiv.add(j) = p as c_int + 1;
                if am[(p, j)] != 0.0 {
                    if p != j {
                        for c in 0..n {
                            let t = am[(j, c)];
                            am[(j, c)] = am[(p, c)];
                            am[(p, c)] = t;
                        }
                    }
                    let d = am[(j, j)];
                    for i in j + 1..n {
                        am[(i, j)] /= d;
                    }
                } else if first_zero == 0 {
                    first_zero = j as c_int + 1;
                }
                for c in j + 1..n {
                    let t = am[(j, c)];
                    if t != 0.0 {
                        for i in j + 1..n {
                            let l = am[(i, j)];
                            am[(i, c)] -= l * t;
                        }
                    }
                }
            }
            if first_zero != 0 || nrhs == 0 {
                return first_zero;
            }
            let mut bm = view_mut(b, n, nrhs, ldb as usize);
            for j in 0..n {
                let p = *ipiv.add(j) as usize - 1;
                if p != j {
                    for c in 0..nrhs {
                        let t = bm[(j, c)];
                        bm[(j, c)] = bm[(p, c)];
                        bm[(p, c)] = t;
                    }
                }
            }
            let lu = am.rb();
            faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place(
                lu,
                bm.rb_mut(),
                par(),
            );
            faer::linalg::triangular_solve::solve_upper_triangular_in_place(lu, bm.rb_mut(), par());
            0
        })
        .unwrap_or(INTERNAL_ERROR)
    };
    unsafe { *info = code };
}

// ---------------------------------------------------------------------------------------------
// LAPACK: symmetric eigendecomposition
// ---------------------------------------------------------------------------------------------

/// Eigenvalues (ascending) and optionally eigenvectors of a symmetric matrix given by its
/// `uplo` triangle. `jobz`: `'N'` values only, `'V'` values and vectors; `range`: `'A'` all,
/// `'V'` those in `(vl, vu]`, `'I'` the `il`-th through `iu`-th (1-based). `m` receives the count,
/// `w[0..m]` the values, the first `m` columns of `Z` (`ldz`) the orthonormal vectors, `isuppz`
/// their support (1-based first/last nonzero row). `A` is destroyed (here: left unchanged).
/// `abstol` is ignored. Workspace query: `lwork = -1` or `liwork = -1` sets `work[0] = 26 n`,
/// `iwork[0] = 10 n` (LAPACK minima). `info = k > 0`: the eigensolver did not converge.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dsyevr_(
    jobz: *const c_char,
    range: *const c_char,
    uplo: *const c_char,
    n: *const c_int,
    a: *mut f64,
    lda: *const c_int,
    vl: *const f64,
    vu: *const f64,
    il: *const c_int,
    iu: *const c_int,
    _abstol: *const f64,
    m: *mut c_int,
    w: *mut f64,
    z: *mut f64,
    ldz: *const c_int,
    isuppz: *mut c_int,
    work: *mut f64,
    lwork: *const c_int,
    iwork: *mut c_int,
    liwork: *const c_int,
    info: *mut c_int,
) {
    let (jz, rg, ul) = unsafe { (letter(jobz), letter(range), letter(uplo)) };
    let (n, lda, ldz, lwork, liwork) = unsafe { (*n, *lda, *ldz, *lwork, *liwork) };
    let wantz = jz == b'V';
    let (vl, vu, il, iu) = unsafe {
        (
            if rg == b'V' { *vl } else { 0.0 },
            if rg == b'V' { *vu } else { 0.0 },
            if rg == b'I' { *il } else { 0 },
            if rg == b'I' { *iu } else { 0 },
        )
    };
    let query = lwork == -1 || liwork == -1;
    let code = if !matches!(jz, b'N' | b'V') {
        -1
    } else if !matches!(rg, b'A' | b'V' | b'I') {
        -2
    } else if !matches!(ul, b'U' | b'L') {
        -3
    } else if n < 0 {
        -4
    } else if lda < n.max(1) {
        -6
    } else if rg == b'V' && n > 0 && vu <= vl {
        -8
    } else if rg == b'I' && (il < 1.min(n) || il > n.max(1)) {
        -9
    } else if rg == b'I' && (iu < il.min(n) || iu > n) {
        -10
    } else if ldz < 1 || (wantz && ldz < n) {
        -15
    } else if !query && lwork < 1 {
        -18
    } else if !query && liwork < 1 {
        -20
    } else {
        0
    };
    if code != 0 {
        unsafe { *info = code };
        return;
    }
    if query {
        unsafe {
            *work = (26 * n.max(1)) as f64;
            *iwork = 10 * n.max(1);
            *info = 0;
        }
        return;
    }
    unsafe { *m = 0 };
    if n == 0 {
        unsafe { *info = 0 };
        return;
    }
    let n = n as usize;
    let code = guarded(|| unsafe {
        let am = view(a, n, n, lda as usize);
        let side = if ul == b'L' { Side::Lower } else { Side::Upper };
        let (vals, vecs): (Vec<f64>, Option<Mat<f64>>) = if wantz {
            match am.self_adjoint_eigen(side) {
                Ok(e) => ((0..n).map(|i| e.S()[i]).collect(), Some(e.U().to_owned())),
                Err(_) => return 1,
            }
        } else {
            match am.self_adjoint_eigenvalues(side) {
                Ok(v) => (v, None),
                Err(_) => return 1,
            }
        };
        // selected indices (values are ascending)
        let sel: Vec<usize> = match rg {
            b'A' => (0..n).collect(),
            b'I' => (il as usize - 1..iu as usize).collect(),
            _ => (0..n).filter(|&i| vals[i] > vl && vals[i] <= vu).collect(),
        };
        *m = sel.len() as c_int;
        for (c, &i) in sel.iter().enumerate() {
            *w.add(c) = vals[i];
        }
        if let Some(u) = vecs {
            let mut zm = view_mut(z, n, sel.len().max(1), ldz as usize);
            for (c, &i) in sel.iter().enumerate() {
                let mut first = n;
                let mut last = 0;
                for r in 0..n {
                    let v = u[(r, i)];
                    zm[(r, c)] = v;
                    if v != 0.0 {
                        first = first.min(r);
                        last = r;
                    }
                }
                if first == n {
                    first = 0;
                }
                *isuppz.add(2 * c) = first as c_int + 1;
                *isuppz.add(2 * c + 1) = last as c_int + 1;
            }
        }
        0
    })
    .unwrap_or(INTERNAL_ERROR);
    unsafe { *info = code };
}

// ---------------------------------------------------------------------------------------------
// LAPACK: SVD
// ---------------------------------------------------------------------------------------------

/// What to compute for one factor of the SVD.
#[derive(Clone, Copy, PartialEq)]
enum Job {
    None,
    Thin,
    Full,
}

fn parse_job(c: u8) -> Option<Job> {
    match c {
        b'N' => Some(Job::None),
        b'S' => Some(Job::Thin),
        b'A' => Some(Job::Full),
        _ => None, // 'O' (overwrite A) is not supported
    }
}

/// Computes the SVD of `A` (`m x n`) and writes `s`, `U` (`ldu`) and `V^T` (`ldvt`) as
/// requested. Returns the LAPACK `info`.
unsafe fn svd_impl(
    ju: Job,
    jvt: Job,
    m: usize,
    n: usize,
    a: *const f64,
    lda: usize,
    s: *mut f64,
    u: *mut f64,
    ldu: usize,
    vt: *mut f64,
    ldvt: usize,
) -> c_int {
    let mn = m.min(n);
    let am = unsafe { view(a, m, n, lda) };
    let full = ju == Job::Full || jvt == Job::Full;
    let res = if full { am.svd() } else { am.thin_svd() };
    let Ok(svd) = res else {
        return 1;
    };
    for i in 0..mn {
        unsafe { *s.add(i) = svd.S()[i] };
    }
    let uf = svd.U();
    let vf = svd.V();
    let ucols = match ju {
        Job::None => 0,
        Job::Thin => mn,
        Job::Full => m,
    };
    let vrows = match jvt {
        Job::None => 0,
        Job::Thin => mn,
        Job::Full => n,
    };
    if ucols > 0 {
        let mut um = unsafe { view_mut(u, m, ucols, ldu) };
        for j in 0..ucols {
            for i in 0..m {
                um[(i, j)] = uf[(i, j)];
            }
        }
    }
    if vrows > 0 {
        let mut vm = unsafe { view_mut(vt, vrows, n, ldvt) };
        for j in 0..n {
            for i in 0..vrows {
                vm[(i, j)] = vf[(j, i)];
            }
        }
    }
    0
}

/// Singular value decomposition `A = U diag(s) V^T` (divide-and-conquer interface; here computed
/// by faer). `jobz`: `'N'` values only, `'S'` thin `U` (`m x min`) and `V^T` (`min x n`),
/// `'A'` full `U` (`m x m`) and `V^T` (`n x n`); `'O'` is not supported (`info = -1`).
/// Singular values descending. `A` is left unchanged. Workspace query `lwork = -1` writes the
/// LAPACK minimal size to `work[0]`; `iwork` is not used. `info = 1`: no convergence.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dgesdd_(
    jobz: *const c_char,
    m: *const c_int,
    n: *const c_int,
    a: *mut f64,
    lda: *const c_int,
    s: *mut f64,
    u: *mut f64,
    ldu: *const c_int,
    vt: *mut f64,
    ldvt: *const c_int,
    work: *mut f64,
    lwork: *const c_int,
    _iwork: *mut c_int,
    info: *mut c_int,
) {
    let jz = unsafe { letter(jobz) };
    let (m, n, lda, ldu, ldvt, lwork) = unsafe { (*m, *n, *lda, *ldu, *ldvt, *lwork) };
    let job = parse_job(jz);
    let mn = m.min(n);
    let code = if job.is_none() {
        -1
    } else if m < 0 {
        -2
    } else if n < 0 {
        -3
    } else if lda < m.max(1) {
        -5
    } else if ldu < 1 || (job != Some(Job::None) && ldu < m) {
        -8
    } else if ldvt < 1
        || (job == Some(Job::Thin) && ldvt < mn)
        || (job == Some(Job::Full) && ldvt < n)
    {
        -10
    } else if lwork < 1 && lwork != -1 {
        -12
    } else {
        0
    };
    if code != 0 {
        unsafe { *info = code };
        return;
    }
    if lwork == -1 {
        // reference dgesdd minimal workspace for jobz = 'S'/'A' (upper bound for 'N')
        let (mn, mx) = (mn.max(0) as i64, m.max(n) as i64);
        let need = 3 * mn + (5 * mn * mn + 4 * mn).max(mx);
        unsafe {
            *work = need.max(1) as f64;
            *info = 0;
        }
        return;
    }
    if mn == 0 {
        unsafe { *info = 0 };
        return;
    }
    let job = job.unwrap_or(Job::None);
    let code = guarded(|| unsafe {
        svd_impl(
            job,
            job,
            m as usize,
            n as usize,
            a,
            lda as usize,
            s,
            u,
            ldu as usize,
            vt,
            ldvt as usize,
        )
    })
    .unwrap_or(INTERNAL_ERROR);
    unsafe { *info = code };
}

/// Singular value decomposition `A = U diag(s) V^T` (QR-iteration interface; here computed by
/// faer). `jobu`/`jobvt`: `'N'`, `'S'` (thin) or `'A'` (full) for `U` and `V^T` separately;
/// `'O'` is not supported (`info = -1` / `-2`). Singular values descending; `A` unchanged.
/// Workspace query `lwork = -1` writes the LAPACK minimal size to `work[0]`.
/// `info = 1`: no convergence.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn dgesvd_(
    jobu: *const c_char,
    jobvt: *const c_char,
    m: *const c_int,
    n: *const c_int,
    a: *mut f64,
    lda: *const c_int,
    s: *mut f64,
    u: *mut f64,
    ldu: *const c_int,
    vt: *mut f64,
    ldvt: *const c_int,
    work: *mut f64,
    lwork: *const c_int,
    info: *mut c_int,
) {
    let (cu, cvt) = unsafe { (letter(jobu), letter(jobvt)) };
    let (m, n, lda, ldu, ldvt, lwork) = unsafe { (*m, *n, *lda, *ldu, *ldvt, *lwork) };
    let (ju, jvt) = (parse_job(cu), parse_job(cvt));
    let mn = m.min(n);
    let code = if ju.is_none() {
        -1
    } else if jvt.is_none() {
        -2
    } else if m < 0 {
        -3
    } else if n < 0 {
        -4
    } else if lda < m.max(1) {
        -6
    } else if ldu < 1 || (ju != Some(Job::None) && ldu < m) {
        -9
    } else if ldvt < 1
        || (jvt == Some(Job::Thin) && ldvt < mn)
        || (jvt == Some(Job::Full) && ldvt < n)
    {
        -11
    } else if lwork < 1 && lwork != -1 {
        -13
    } else {
        0
    };
    if code != 0 {
        unsafe { *info = code };
        return;
    }
    if lwork == -1 {
        // reference dgesvd minimal workspace: max(1, 3 min + max, 5 min)
        let (mn, mx) = (mn as i64, m.max(n) as i64);
        let need = (3 * mn + mx).max(5 * mn).max(1);
        unsafe {
            *work = need as f64;
            *info = 0;
        }
        return;
    }
    if mn == 0 {
        unsafe { *info = 0 };
        return;
    }
    let (ju, jvt) = (ju.unwrap_or(Job::None), jvt.unwrap_or(Job::None));
    let code = guarded(|| unsafe {
        svd_impl(
            ju,
            jvt,
            m as usize,
            n as usize,
            a,
            lda as usize,
            s,
            u,
            ldu as usize,
            vt,
            ldvt as usize,
        )
    })
    .unwrap_or(INTERNAL_ERROR);
    unsafe { *info = code };
}
