//! Each exported routine against a naive reference implementation (or the defining identity:
//! `A = L L^T`, `A V = V diag(w)`, `A = U S V^T`, `A x = b`) on seeded random matrices stored
//! with leading dimensions larger than the row count, with sentinels checking that entries
//! outside the referenced region are untouched.
#![allow(unsafe_code, clippy::too_many_arguments, clippy::needless_range_loop)]

use core::ffi::{c_char, c_int};
use rotavg_lapack::*;

/// xorshift64*; uniform in [-1, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let v = self.0.wrapping_mul(0x2545F4914F6CDD1D);
        (v >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

const SENTINEL: f64 = 12345.678;

/// Column-major matrix with leading dimension `ld`, padding filled with SENTINEL.
#[derive(Clone)]
struct M {
    r: usize,
    c: usize,
    ld: usize,
    d: Vec<f64>,
}
impl M {
    fn rand(rng: &mut Rng, r: usize, c: usize, pad: usize) -> M {
        let ld = r + pad;
        let mut d = vec![SENTINEL; ld * c.max(1)];
        for j in 0..c {
            for i in 0..r {
                d[i + j * ld] = rng.next();
            }
        }
        M { r, c, ld, d }
    }
    fn g(&self, i: usize, j: usize) -> f64 {
        self.d[i + j * self.ld]
    }
    fn s(&mut self, i: usize, j: usize, v: f64) {
        self.d[i + j * self.ld] = v;
    }
    fn ldi(&self) -> c_int {
        self.ld as c_int
    }
    fn padding_intact(&self) -> bool {
        (0..self.c).all(|j| (self.r..self.ld).all(|i| self.g(i, j) == SENTINEL))
    }
    fn spd(rng: &mut Rng, n: usize, pad: usize) -> M {
        let b = M::rand(rng, n, n, 0);
        let mut a = M::rand(rng, n, n, pad);
        for i in 0..n {
            for j in 0..n {
                let mut s = if i == j { n as f64 } else { 0.0 };
                for k in 0..n {
                    s += b.g(i, k) * b.g(j, k);
                }
                a.s(i, j, s);
            }
        }
        a
    }
}

fn ch(c: u8) -> c_char {
    c as c_char
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

/// op(X)(i, j)
fn op(x: &M, t: u8, i: usize, j: usize) -> f64 {
    if t == b'N' { x.g(i, j) } else { x.g(j, i) }
}

#[test]
fn dgemm_matches_naive() {
    let mut rng = Rng(1);
    let (m, n, k) = (5usize, 4usize, 3usize);
    for ta in [b'N', b'T', b'C'] {
        for tb in [b'N', b'T'] {
            for (alpha, beta) in [(1.3, 0.0), (-0.7, 0.5), (0.0, 2.0), (1.0, 1.0)] {
                let a = if ta == b'N' {
                    M::rand(&mut rng, m, k, 2)
                } else {
                    M::rand(&mut rng, k, m, 3)
                };
                let b = if tb == b'N' {
                    M::rand(&mut rng, k, n, 1)
                } else {
                    M::rand(&mut rng, n, k, 4)
                };
                let mut c = M::rand(&mut rng, m, n, 3);
                if beta == 0.0 {
                    c.s(0, 0, f64::NAN); // beta = 0 must not propagate NaN
                }
                let c0 = c.clone();
                let (mi, ni, ki) = (m as c_int, n as c_int, k as c_int);
                unsafe {
                    dgemm_(
                        &ch(ta),
                        &ch(tb),
                        &mi,
                        &ni,
                        &ki,
                        &alpha,
                        a.d.as_ptr(),
                        &a.ldi(),
                        b.d.as_ptr(),
                        &b.ldi(),
                        &beta,
                        c.d.as_mut_ptr(),
                        &c.ldi(),
                    )
                };
                for i in 0..m {
                    for j in 0..n {
                        let mut s = 0.0;
                        for l in 0..k {
                            s += op(&a, ta, i, l) * op(&b, tb, l, j);
                        }
                        let prev = if beta == 0.0 { 0.0 } else { beta * c0.g(i, j) };
                        assert!(
                            close(c.g(i, j), alpha * s + prev, 1e-13),
                            "{ta} {tb} {i} {j}"
                        );
                    }
                }
                assert!(c.padding_intact());
            }
        }
    }
}

fn check_syrk(two: bool) {
    let mut rng = Rng(2);
    let (n, k) = (6usize, 4usize);
    for ul in [b'U', b'L'] {
        for tr in [b'N', b'T'] {
            for (alpha, beta) in [(1.0, 0.0), (0.8, -1.5)] {
                let mk = |rng: &mut Rng| {
                    if tr == b'N' {
                        M::rand(rng, n, k, 2)
                    } else {
                        M::rand(rng, k, n, 3)
                    }
                };
                let a = mk(&mut rng);
                let b = mk(&mut rng);
                let mut c = M::rand(&mut rng, n, n, 1);
                let c0 = c.clone();
                let (ni, ki) = (n as c_int, k as c_int);
                unsafe {
                    if two {
                        dsyr2k_(
                            &ch(ul),
                            &ch(tr),
                            &ni,
                            &ki,
                            &alpha,
                            a.d.as_ptr(),
                            &a.ldi(),
                            b.d.as_ptr(),
                            &b.ldi(),
                            &beta,
                            c.d.as_mut_ptr(),
                            &c.ldi(),
                        )
                    } else {
                        dsyrk_(
                            &ch(ul),
                            &ch(tr),
                            &ni,
                            &ki,
                            &alpha,
                            a.d.as_ptr(),
                            &a.ldi(),
                            &beta,
                            c.d.as_mut_ptr(),
                            &c.ldi(),
                        )
                    }
                };
                // op(X) is n x k: op(X)(i, l) = X(i, l) ('N') or X(l, i) ('T')
                let opx =
                    |x: &M, i: usize, l: usize| if tr == b'N' { x.g(i, l) } else { x.g(l, i) };
                for i in 0..n {
                    for j in 0..n {
                        let in_tri = if ul == b'U' { i <= j } else { i >= j };
                        if !in_tri {
                            assert_eq!(c.g(i, j), c0.g(i, j), "other triangle touched");
                            continue;
                        }
                        let mut s = 0.0;
                        for l in 0..k {
                            s += if two {
                                opx(&a, i, l) * opx(&b, j, l) + opx(&b, i, l) * opx(&a, j, l)
                            } else {
                                opx(&a, i, l) * opx(&a, j, l)
                            };
                        }
                        let want = alpha * s + beta * c0.g(i, j);
                        assert!(close(c.g(i, j), want, 1e-13), "{ul} {tr} {i} {j}");
                    }
                }
                assert!(c.padding_intact());
            }
        }
    }
}

#[test]
fn dsyrk_matches_naive() {
    check_syrk(false);
}

#[test]
fn dsyr2k_matches_naive() {
    check_syrk(true);
}

#[test]
fn dgemv_matches_naive() {
    let mut rng = Rng(3);
    let (m, n) = (5usize, 3usize);
    for tr in [b'N', b'T'] {
        for (incx, incy) in [(1isize, 1isize), (2, -1), (-3, 2)] {
            let a = M::rand(&mut rng, m, n, 2);
            let (lx, ly) = if tr == b'N' { (n, m) } else { (m, n) };
            let x: Vec<f64> = (0..lx * incx.unsigned_abs()).map(|_| rng.next()).collect();
            let mut y: Vec<f64> = (0..ly * incy.unsigned_abs()).map(|_| rng.next()).collect();
            let y0 = y.clone();
            let (alpha, beta) = (1.7, -0.3);
            let idx = |len: usize, inc: isize, i: usize| {
                if inc > 0 {
                    i * inc as usize
                } else {
                    (len - 1 - i) * inc.unsigned_abs()
                }
            };
            let (mi, ni, ix, iy) = (m as c_int, n as c_int, incx as c_int, incy as c_int);
            unsafe {
                dgemv_(
                    &ch(tr),
                    &mi,
                    &ni,
                    &alpha,
                    a.d.as_ptr(),
                    &a.ldi(),
                    x.as_ptr(),
                    &ix,
                    &beta,
                    y.as_mut_ptr(),
                    &iy,
                )
            };
            for i in 0..ly {
                let mut s = 0.0;
                for l in 0..lx {
                    s += op(&a, tr, i, l) * x[idx(lx, incx, l)];
                }
                let want = alpha * s + beta * y0[idx(ly, incy, i)];
                assert!(close(y[idx(ly, incy, i)], want, 1e-13));
            }
        }
    }
}

#[test]
fn dsymv_reads_only_its_triangle() {
    let mut rng = Rng(4);
    let n = 6usize;
    for ul in [b'U', b'L'] {
        let s = M::spd(&mut rng, n, 0);
        let mut a = M::rand(&mut rng, n, n, 3);
        for i in 0..n {
            for j in 0..n {
                let in_tri = if ul == b'U' { i <= j } else { i >= j };
                a.s(i, j, if in_tri { s.g(i, j) } else { f64::NAN });
            }
        }
        let x: Vec<f64> = (0..n).map(|_| rng.next()).collect();
        let mut y: Vec<f64> = (0..n).map(|_| rng.next()).collect();
        let y0 = y.clone();
        let (alpha, beta, ni, one) = (0.9, 1.1, n as c_int, 1);
        unsafe {
            dsymv_(
                &ch(ul),
                &ni,
                &alpha,
                a.d.as_ptr(),
                &a.ldi(),
                x.as_ptr(),
                &one,
                &beta,
                y.as_mut_ptr(),
                &one,
            )
        };
        for i in 0..n {
            let want: f64 = alpha * (0..n).map(|j| s.g(i, j) * x[j]).sum::<f64>() + beta * y0[i];
            assert!(close(y[i], want, 1e-13));
        }
    }
}

#[test]
fn dpotrf_dpotrs_factor_and_solve() {
    let mut rng = Rng(5);
    for n in [1usize, 4, 9, 40] {
        for ul in [b'U', b'L'] {
            let a0 = M::spd(&mut rng, n, 3);
            let mut a = a0.clone();
            let mut info = 99;
            let ni = n as c_int;
            unsafe { dpotrf_(&ch(ul), &ni, a.d.as_mut_ptr(), &a.ldi(), &mut info) };
            assert_eq!(info, 0);
            // factor F (lower: L, upper: U) with A = L L^T = U^T U; other triangle untouched
            let f = |i: usize, j: usize| -> f64 {
                if ul == b'L' {
                    if i >= j { a.g(i, j) } else { 0.0 }
                } else if i <= j {
                    a.g(i, j)
                } else {
                    0.0
                }
            };
            for i in 0..n {
                for j in 0..n {
                    let s: f64 = (0..n)
                        .map(|k| {
                            if ul == b'L' {
                                f(i, k) * f(j, k)
                            } else {
                                f(k, i) * f(k, j)
                            }
                        })
                        .sum();
                    assert!(close(s, a0.g(i, j), 1e-12));
                    let in_tri = if ul == b'U' { i <= j } else { i >= j };
                    if !in_tri {
                        assert_eq!(a.g(i, j), a0.g(i, j), "other triangle touched");
                    }
                }
            }
            assert!(a.padding_intact());
            // solve with 3 right-hand sides
            let x = M::rand(&mut rng, n, 3, 0);
            let mut b = M::rand(&mut rng, n, 3, 2);
            for i in 0..n {
                for c in 0..3 {
                    b.s(i, c, (0..n).map(|k| a0.g(i, k) * x.g(k, c)).sum());
                }
            }
            let nrhs = 3;
            unsafe {
                dpotrs_(
                    &ch(ul),
                    &ni,
                    &nrhs,
                    a.d.as_ptr(),
                    &a.ldi(),
                    b.d.as_mut_ptr(),
                    &b.ldi(),
                    &mut info,
                )
            };
            assert_eq!(info, 0);
            for i in 0..n {
                for c in 0..3 {
                    assert!(close(b.g(i, c), x.g(i, c), 1e-9), "n={n} {ul}");
                }
            }
            assert!(b.padding_intact());
        }
    }
}

#[test]
fn dpotrf_reports_first_non_positive_minor() {
    // diag(1, 2, 3, -1, 5) plus small symmetric coupling that keeps the leading 3x3 PD: the
    // 4th leading minor is negative, so LAPACK returns info = 4.
    let n = 5usize;
    for ul in [b'U', b'L'] {
        let mut a = M {
            r: n,
            c: n,
            ld: n + 1,
            d: vec![0.0; (n + 1) * n],
        };
        for (i, d) in [1.0, 2.0, 3.0, -1.0, 5.0].into_iter().enumerate() {
            a.s(i, i, d);
        }
        a.s(0, 1, 0.1);
        a.s(1, 0, 0.1);
        let mut info = 0;
        let ni = n as c_int;
        unsafe { dpotrf_(&ch(ul), &ni, a.d.as_mut_ptr(), &a.ldi(), &mut info) };
        assert_eq!(info, 4);
        // NaN on the diagonal is not positive definite either
        let mut b = vec![1.0, 0.0, 0.0, f64::NAN];
        let two = 2;
        unsafe { dpotrf_(&ch(ul), &two, b.as_mut_ptr(), &two, &mut info) };
        assert_eq!(info, 2);
    }
    // illegal arguments
    let mut info = 0;
    let mut b = vec![1.0];
    let (one, zero, neg) = (1, 0, -1);
    unsafe { dpotrf_(&ch(b'X'), &one, b.as_mut_ptr(), &one, &mut info) };
    assert_eq!(info, -1);
    unsafe { dpotrf_(&ch(b'L'), &neg, b.as_mut_ptr(), &one, &mut info) };
    assert_eq!(info, -2);
    unsafe { dpotrf_(&ch(b'L'), &one, b.as_mut_ptr(), &zero, &mut info) };
    assert_eq!(info, -4);
}

#[test]
fn dgesv_solves_and_pivots_like_dgetf2() {
    let mut rng = Rng(6);
    for n in [1usize, 3, 8, 30] {
        let a0 = M::rand(&mut rng, n, n, 2);
        let mut a = a0.clone();
        let x = M::rand(&mut rng, n, 2, 0);
        let mut b = M::rand(&mut rng, n, 2, 1);
        for i in 0..n {
            for c in 0..2 {
                b.s(i, c, (0..n).map(|k| a0.g(i, k) * x.g(k, c)).sum());
            }
        }
        let mut ipiv = vec![0 as c_int; n];
        let (ni, nrhs) = (n as c_int, 2);
        let mut info = 99;
        unsafe {
            dgesv_(
                &ni,
                &nrhs,
                a.d.as_mut_ptr(),
                &a.ldi(),
                ipiv.as_mut_ptr(),
                b.d.as_mut_ptr(),
                &b.ldi(),
                &mut info,
            )
        };
        assert_eq!(info, 0);
        for i in 0..n {
            for c in 0..2 {
                assert!(close(b.g(i, c), x.g(i, c), 1e-9));
            }
        }
        // reconstruct: apply the interchanges to A0, compare with L U
        let mut pa = a0.clone();
        for (j, &p) in ipiv.iter().enumerate() {
            let p = p as usize - 1;
            assert!(p >= j && p < n);
            for c in 0..n {
                let t = pa.g(j, c);
                pa.s(j, c, pa.g(p, c));
                pa.s(p, c, t);
            }
        }
        for i in 0..n {
            for j in 0..n {
                let s: f64 = (0..=i.min(j))
                    .map(|k| if k == i { 1.0 } else { a.g(i, k) } * a.g(k, j))
                    .sum();
                assert!(close(s, pa.g(i, j), 1e-12));
                if i > j {
                    assert!(a.g(i, j).abs() <= 1.0, "partial pivoting bounds |L| by 1");
                }
            }
        }
    }
    // exactly singular: second column zero => U(2, 2) = 0 => info = 2
    let mut a = vec![1.0, 2.0, 0.0, 0.0];
    let mut b = vec![1.0, 1.0];
    let mut ipiv = vec![0; 2];
    let (two, one) = (2, 1);
    let mut info = 0;
    unsafe {
        dgesv_(
            &two,
            &one,
            a.as_mut_ptr(),
            &two,
            ipiv.as_mut_ptr(),
            b.as_mut_ptr(),
            &two,
            &mut info,
        )
    };
    assert_eq!(info, 2);
}

fn syevr_call(
    jobz: u8,
    range: u8,
    uplo: u8,
    a: &mut M,
    vl: f64,
    vu: f64,
    il: c_int,
    iu: c_int,
    z: &mut M,
) -> (c_int, Vec<f64>, c_int) {
    let n = a.r as c_int;
    let mut w = vec![0.0; a.r];
    let mut m = -1;
    let mut isuppz = vec![0; 2 * a.r];
    let mut work = vec![0.0];
    let mut iwork = vec![0];
    let mut info = 99;
    let (mut lwork, mut liwork) = (-1, -1);
    for pass in 0..2 {
        unsafe {
            dsyevr_(
                &ch(jobz),
                &ch(range),
                &ch(uplo),
                &n,
                a.d.as_mut_ptr(),
                &a.ldi(),
                &vl,
                &vu,
                &il,
                &iu,
                &-1.0,
                &mut m,
                w.as_mut_ptr(),
                z.d.as_mut_ptr(),
                &z.ldi(),
                isuppz.as_mut_ptr(),
                work.as_mut_ptr(),
                &lwork,
                iwork.as_mut_ptr(),
                &liwork,
                &mut info,
            )
        };
        if pass == 0 {
            assert_eq!(info, 0);
            lwork = work[0] as c_int;
            liwork = iwork[0];
            assert!(lwork >= 26 * a.r as c_int && liwork >= 10 * a.r as c_int);
            work.resize(lwork as usize, 0.0);
            iwork.resize(liwork as usize, 0);
        }
    }
    (info, w, m)
}

#[test]
fn dsyevr_eigenpairs() {
    let mut rng = Rng(7);
    let n = 7usize;
    for ul in [b'U', b'L'] {
        // symmetric, with NaN in the unreferenced triangle
        let s = M::spd(&mut rng, n, 0);
        let mut shifted = s.clone();
        for i in 0..n {
            shifted.s(i, i, s.g(i, i) - 2.0 * n as f64); // make it indefinite
        }
        let mut a = M::rand(&mut rng, n, n, 2);
        for i in 0..n {
            for j in 0..n {
                let in_tri = if ul == b'U' { i <= j } else { i >= j };
                a.s(i, j, if in_tri { shifted.g(i, j) } else { f64::NAN });
            }
        }
        let mut z = M::rand(&mut rng, n, n, 3);
        let (info, w, m) = syevr_call(b'V', b'A', ul, &mut a.clone(), 0.0, 0.0, 0, 0, &mut z);
        assert_eq!((info, m), (0, n as c_int));
        assert!(w.windows(2).all(|p| p[0] <= p[1]), "ascending");
        for c in 0..n {
            for i in 0..n {
                let av: f64 = (0..n).map(|k| shifted.g(i, k) * z.g(k, c)).sum();
                assert!(close(av, w[c] * z.g(i, c), 1e-10));
            }
            for d in 0..n {
                let dot: f64 = (0..n).map(|k| z.g(k, c) * z.g(k, d)).sum();
                assert!(close(dot, if c == d { 1.0 } else { 0.0 }, 1e-12));
            }
        }
        assert!(z.padding_intact());
        // values only
        let mut dummy = M {
            r: 1,
            c: 1,
            ld: 1,
            d: vec![0.0],
        };
        let (info, w2, m) = syevr_call(b'N', b'A', ul, &mut a.clone(), 0.0, 0.0, 0, 0, &mut dummy);
        assert_eq!((info, m), (0, n as c_int));
        for i in 0..n {
            assert!(close(w[i], w2[i], 1e-12));
        }
        // index range 2..=4
        let (info, w3, m) = syevr_call(b'V', b'I', ul, &mut a.clone(), 0.0, 0.0, 2, 4, &mut z);
        assert_eq!((info, m), (0, 3));
        for i in 0..3 {
            assert!(close(w3[i], w[i + 1], 1e-12));
        }
        // value range (w[1], w[4]] contains w[2], w[3], w[4]
        let (info, w4, m) =
            syevr_call(b'N', b'V', ul, &mut a.clone(), w[1], w[4], 0, 0, &mut dummy);
        assert_eq!((info, m), (0, 3));
        assert!(close(w4[0], w[2], 1e-12));
    }
}

fn svd_check(m: usize, n: usize, job: u8, gesdd: bool) {
    let mut rng = Rng(8 + m as u64 * 31 + n as u64);
    let a0 = M::rand(&mut rng, m, n, 2);
    let mut a = a0.clone();
    let mn = m.min(n);
    let (ucols, vrows) = match job {
        b'S' => (mn, mn),
        b'A' => (m, n),
        _ => (1, 1),
    };
    let mut u = M::rand(&mut rng, m, ucols, 1);
    let mut vt = M::rand(&mut rng, vrows, n, 2);
    let mut s = vec![0.0; mn];
    let (mi, ni) = (m as c_int, n as c_int);
    let mut work = vec![0.0];
    let mut iwork = vec![0; 8 * mn];
    let mut info = 99;
    let mut lwork = -1;
    for pass in 0..2 {
        unsafe {
            if gesdd {
                dgesdd_(
                    &ch(job),
                    &mi,
                    &ni,
                    a.d.as_mut_ptr(),
                    &a.ldi(),
                    s.as_mut_ptr(),
                    u.d.as_mut_ptr(),
                    &u.ldi(),
                    vt.d.as_mut_ptr(),
                    &vt.ldi(),
                    work.as_mut_ptr(),
                    &lwork,
                    iwork.as_mut_ptr(),
                    &mut info,
                )
            } else {
                dgesvd_(
                    &ch(job),
                    &ch(job),
                    &mi,
                    &ni,
                    a.d.as_mut_ptr(),
                    &a.ldi(),
                    s.as_mut_ptr(),
                    u.d.as_mut_ptr(),
                    &u.ldi(),
                    vt.d.as_mut_ptr(),
                    &vt.ldi(),
                    work.as_mut_ptr(),
                    &lwork,
                    &mut info,
                )
            }
        };
        assert_eq!(info, 0);
        if pass == 0 {
            lwork = work[0] as c_int;
            assert!(lwork >= 1);
            work.resize(lwork as usize, 0.0);
        }
    }
    assert!(s.windows(2).all(|p| p[0] >= p[1]) && s.iter().all(|&x| x >= 0.0));
    if job == b'N' {
        return;
    }
    for i in 0..m {
        for j in 0..n {
            let r: f64 = (0..mn).map(|k| u.g(i, k) * s[k] * vt.g(k, j)).sum();
            assert!(close(r, a0.g(i, j), 1e-12), "{m}x{n} {}", job as char);
        }
    }
    for c in 0..ucols {
        for d in 0..ucols {
            let dot: f64 = (0..m).map(|k| u.g(k, c) * u.g(k, d)).sum();
            assert!(close(dot, if c == d { 1.0 } else { 0.0 }, 1e-12));
        }
    }
    for c in 0..vrows {
        for d in 0..vrows {
            let dot: f64 = (0..n).map(|k| vt.g(c, k) * vt.g(d, k)).sum();
            assert!(close(dot, if c == d { 1.0 } else { 0.0 }, 1e-12));
        }
    }
    assert!(u.padding_intact() && vt.padding_intact());
}

#[test]
fn dgesdd_dgesvd_reconstruct() {
    for (m, n) in [(6, 4), (4, 6), (5, 5), (1, 3)] {
        for job in [b'S', b'A', b'N'] {
            svd_check(m, n, job, true);
            svd_check(m, n, job, false);
        }
    }
    // overwrite mode is unsupported: info = -1
    let mut a = vec![1.0; 4];
    let (two, mut info) = (2, 0);
    let mut s = vec![0.0; 2];
    let mut work = vec![0.0; 100];
    let mut iwork = vec![0; 16];
    let mut u = vec![0.0; 4];
    let mut vt = vec![0.0; 4];
    unsafe {
        dgesdd_(
            &ch(b'O'),
            &two,
            &two,
            a.as_mut_ptr(),
            &two,
            s.as_mut_ptr(),
            u.as_mut_ptr(),
            &two,
            vt.as_mut_ptr(),
            &two,
            work.as_mut_ptr(),
            &100,
            iwork.as_mut_ptr(),
            &mut info,
        )
    };
    assert_eq!(info, -1);
}
