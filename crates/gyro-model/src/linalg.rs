//! Small dense linear algebra on any [`Real`] (so exact Jacobians flow through the solves),
//! and the matrix exponential used to propagate `linear` models exactly.
//!
//! `tests/linalg_stiff.rs` holds [`eigenvalues`] and [`expm`] to closed forms (a rotated
//! block-diagonal matrix of eigenvalues 1e-3 … 1e3) and to SciPy on the linearised Anschütz 1906
//! (|λ| from 1.6e-3 to 562 1/s): eigenvalues within 1.2e-12 relative of SciPy's, exp(A h) within
//! 3e-11 of SciPy's for h up to 3600 s (`cargo test --release -p gyro-model --test linalg_stiff`).

use crate::dual::Real;

/// Solves A x = b in place (A row-major n×n, destroyed; b becomes x) by Gaussian elimination
/// with partial pivoting on the real parts. Returns false if A is singular to working precision.
pub fn solve_in_place<T: Real>(a: &mut [T], b: &mut [T], n: usize) -> bool {
    let scale = a.iter().map(|x| x.re().abs()).fold(0.0, f64::max);
    if !(scale > 0.0) || !scale.is_finite() {
        return false;
    }
    for col in 0..n {
        let mut piv = col;
        let mut best = a[col * n + col].re().abs();
        for r in col + 1..n {
            let v = a[r * n + col].re().abs();
            if v > best {
                best = v;
                piv = r;
            }
        }
        if best <= scale * 1e-300 || best == 0.0 {
            return false;
        }
        if piv != col {
            for k in 0..n {
                a.swap(col * n + k, piv * n + k);
            }
            b.swap(col, piv);
        }
        let inv = T::one() / a[col * n + col];
        for r in col + 1..n {
            let f = a[r * n + col] * inv;
            if f.re() == 0.0 && f == T::zero() {
                continue;
            }
            for k in col..n {
                let t = a[col * n + k];
                a[r * n + k] -= f * t;
            }
            let t = b[col];
            b[r] -= f * t;
        }
    }
    for r in (0..n).rev() {
        let mut s = b[r];
        for k in r + 1..n {
            s -= a[r * n + k] * b[k];
        }
        b[r] = s / a[r * n + r];
    }
    true
}

/// [`solve_in_place`] on the leading n×n block of a fixed-size matrix (what the model's
/// stack-allocated equations use): the same elimination, pivots and operations.
pub fn solve_nested<T: Real, const N: usize>(
    a: &mut [[T; N]; N],
    b: &mut [T; N],
    n: usize,
) -> bool {
    if let Some(solved) = T::record_solve(a, b, n, false) {
        return solved;
    }
    eliminate_nested(a, b, n)
}

/// The elimination of [`solve_nested`] without the recording hook: what a recording runs on a
/// constant matrix, whose factor then folds to constants (`tape::Tr::record_solve`).
pub(crate) fn eliminate_nested<T: Real, const N: usize>(
    a: &mut [[T; N]; N],
    b: &mut [T; N],
    n: usize,
) -> bool {
    let scale = a[..n]
        .iter()
        .flat_map(|row| row[..n].iter())
        .map(|x| x.re().abs())
        .fold(0.0, f64::max);
    if !(scale > 0.0) || !scale.is_finite() {
        return false;
    }
    for col in 0..n {
        let mut piv = col;
        let mut best = a[col][col].re().abs();
        for r in col + 1..n {
            let v = a[r][col].re().abs();
            if v > best {
                best = v;
                piv = r;
            }
        }
        if best <= scale * 1e-300 || best == 0.0 {
            return false;
        }
        if piv != col {
            a.swap(col, piv);
            b.swap(col, piv);
        }
        let inv = T::one() / a[col][col];
        for r in col + 1..n {
            let f = a[r][col] * inv;
            if f.re() == 0.0 && f == T::zero() {
                continue;
            }
            for k in col..n {
                let t = a[col][k];
                a[r][k] -= f * t;
            }
            let t = b[col];
            b[r] -= f * t;
        }
    }
    for r in (0..n).rev() {
        let mut s = b[r];
        for k in r + 1..n {
            s -= a[r][k] * b[k];
        }
        b[r] = s / a[r][r];
    }
    true
}

/// Solves A x = b for a symmetric positive definite A (a mass matrix) by LDLᵀ on the leading
/// n×n block, reading only the lower triangle: no pivot search, no row swaps and n divisions
/// instead of 2n, which is most of what a 4×4 solve costs. Stable without pivoting because A is
/// positive definite; returns false (A and b untouched) if a pivot is not positive to working
/// precision, and the caller falls back to [`solve_nested`].
pub fn solve_spd_nested<T: Real, const N: usize>(
    a_in: &[[T; N]; N],
    b: &mut [T; N],
    n: usize,
) -> bool {
    if let Some(solved) = T::record_solve(a_in, b, n, true) {
        return solved;
    }
    ldlt_nested(a_in, b, n)
}

/// The LDLᵀ solve of [`solve_spd_nested`] without the recording hook (see
/// [`eliminate_nested`]).
pub(crate) fn ldlt_nested<T: Real, const N: usize>(
    a_in: &[[T; N]; N],
    b: &mut [T; N],
    n: usize,
) -> bool {
    let scale = (0..n).map(|i| a_in[i][i].re().abs()).fold(0.0, f64::max);
    if !(scale > 0.0) || !scale.is_finite() {
        return false;
    }
    // The strict lower triangle of `a` becomes L, its diagonal D.
    let mut a = *a_in;
    let mut inv_d = [T::zero(); N];
    for j in 0..n {
        let mut d = a[j][j];
        for k in 0..j {
            d -= a[j][k] * a[j][k] * a[k][k];
        }
        if !(d.re() > scale * 1e-14) {
            return false;
        }
        a[j][j] = d;
        inv_d[j] = T::one() / d;
        for i in j + 1..n {
            let mut s = a[i][j];
            for k in 0..j {
                s -= a[i][k] * a[j][k] * a[k][k];
            }
            a[i][j] = s * inv_d[j];
        }
    }
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= a[i][k] * b[k];
        }
        b[i] = s;
    }
    for i in (0..n).rev() {
        let mut s = b[i] * inv_d[i];
        for k in i + 1..n {
            s -= a[k][i] * b[k];
        }
        b[i] = s;
    }
    true
}

/// exp(A·h) for a small dense matrix (row-major), by scaling and squaring of a degree-18 Taylor
/// series: accurate to round-off for the well-scaled matrices of linearised compasses.
pub fn expm(a: &[f64], n: usize, h: f64) -> Vec<f64> {
    let norm = (0..n)
        .map(|i| (0..n).map(|j| (a[i * n + j] * h).abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let s = if norm > 0.5 {
        (norm / 0.5).log2().ceil() as i32
    } else {
        0
    };
    let scale = h / 2f64.powi(s);
    let m: Vec<f64> = a.iter().map(|x| x * scale).collect();
    let mut result = identity(n);
    let mut term = identity(n);
    for k in 1..=18 {
        term = matmul(&term, &m, n);
        for x in term.iter_mut() {
            *x /= k as f64;
        }
        for (r, t) in result.iter_mut().zip(&term) {
            *r += t;
        }
    }
    for _ in 0..s {
        result = matmul(&result, &result, n);
    }
    result
}

pub fn identity(n: usize) -> Vec<f64> {
    let mut m = vec![0.0; n * n];
    for i in 0..n {
        m[i * n + i] = 1.0;
    }
    m
}

pub fn matmul(a: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let mut c = vec![0.0; n * n];
    for i in 0..n {
        for k in 0..n {
            let aik = a[i * n + k];
            if aik == 0.0 {
                continue;
            }
            for j in 0..n {
                c[i * n + j] += aik * b[k * n + j];
            }
        }
    }
    c
}

/// Eigenvalues of a small real matrix (unsymmetric QR iteration on the Hessenberg form),
/// returned as (re, im) pairs. Used to report the modes of a linearised compass.
pub fn eigenvalues(a: &[f64], n: usize) -> Vec<(f64, f64)> {
    // Balance-free Francis double-shift QR (Numerical Recipes `hqr` after `elmhes`).
    let mut h = a.to_vec();
    let at = |h: &Vec<f64>, i: usize, j: usize| h[i * n + j];
    // Reduce to Hessenberg by elimination.
    for m in 1..n.saturating_sub(1) {
        let mut x: f64 = 0.0;
        let mut i = m;
        for j in m..n {
            if at(&h, j, m - 1).abs() > x.abs() {
                x = at(&h, j, m - 1);
                i = j;
            }
        }
        if i != m {
            for j in (m - 1)..n {
                h.swap(i * n + j, m * n + j);
            }
            for j in 0..n {
                h.swap(j * n + i, j * n + m);
            }
        }
        if x != 0.0 {
            for i in (m + 1)..n {
                let mut y = at(&h, i, m - 1);
                if y != 0.0 {
                    y /= x;
                    h[i * n + m - 1] = y;
                    for j in m..n {
                        h[i * n + j] -= y * h[m * n + j];
                    }
                    for j in 0..n {
                        h[j * n + m] += y * h[j * n + i];
                    }
                }
            }
        }
    }
    for i in 2..n {
        for j in 0..i - 1 {
            h[i * n + j] = 0.0;
        }
    }
    hqr(&mut h, n)
}

fn hqr(a: &mut [f64], n: usize) -> Vec<(f64, f64)> {
    let idx = |i: usize, j: usize| i * n + j;
    let mut wr = vec![0.0; n];
    let mut wi = vec![0.0; n];
    let mut anorm: f64 = 0.0;
    for i in 0..n {
        for j in i.saturating_sub(1)..n {
            anorm += a[idx(i, j)].abs();
        }
    }
    let mut nn = n as isize - 1;
    let mut t: f64 = 0.0;
    while nn >= 0 {
        let mut its = 0;
        loop {
            let l = split_point(a, n, nn, anorm);
            let nu = nn as usize;
            let x = a[idx(nu, nu)];
            if l == nn {
                wr[nu] = x + t;
                wi[nu] = 0.0;
                nn -= 1;
                break;
            }
            let y = a[idx(nu - 1, nu - 1)];
            let w = a[idx(nu, nu - 1)] * a[idx(nu - 1, nu)];
            if l == nn - 1 {
                let p = 0.5 * (y - x);
                let q = p * p + w;
                let z = q.abs().sqrt();
                let x = x + t;
                if q >= 0.0 {
                    let z = p + z.copysign(p);
                    wr[nu - 1] = x + z;
                    wr[nu] = if z != 0.0 { x - w / z } else { x + z };
                    wi[nu - 1] = 0.0;
                    wi[nu] = 0.0;
                } else {
                    wr[nu - 1] = x + p;
                    wr[nu] = x + p;
                    wi[nu - 1] = -z;
                    wi[nu] = z;
                }
                nn -= 2;
                break;
            }
            if its == 60 {
                // Give up on this block: report what is there (never loop forever).
                for i in 0..=nu {
                    wr[i] = a[idx(i, i)] + t;
                }
                return wr.into_iter().zip(wi).collect();
            }
            let (mut x, mut y, mut w) = (x, y, w);
            if its == 10 || its == 20 {
                t += x;
                for i in 0..=nu {
                    a[idx(i, i)] -= x;
                }
                let s = a[idx(nu, nu - 1)].abs() + a[idx(nu - 1, nu - 2)].abs();
                x = 0.75 * s;
                y = x;
                w = -0.4375 * s * s;
            }
            its += 1;
            let mut m = nn - 2;
            let (mut p, mut q, mut r);
            loop {
                let mu = m as usize;
                let z = a[idx(mu, mu)];
                let rr = x - z;
                let ss = y - z;
                p = (rr * ss - w) / a[idx(mu + 1, mu)] + a[idx(mu, mu + 1)];
                q = a[idx(mu + 1, mu + 1)] - z - rr - ss;
                r = a[idx(mu + 2, mu + 1)];
                let s = p.abs() + q.abs() + r.abs();
                p /= s;
                q /= s;
                r /= s;
                if m == l {
                    break;
                }
                let u = a[idx(mu, mu - 1)].abs() * (q.abs() + r.abs());
                let v = p.abs()
                    * (a[idx(mu - 1, mu - 1)].abs() + z.abs() + a[idx(mu + 1, mu + 1)].abs());
                if u + v == v {
                    break;
                }
                m -= 1;
            }
            francis_step(a, n, l as usize, m as usize, nu, (p, q, r));
        }
    }
    wr.into_iter().zip(wi).collect()
}

/// The row `l` ≥ 1 below `nn` whose subdiagonal entry is negligible (set to zero), or 0: the
/// active block is rows l…nn.
fn split_point(a: &mut [f64], n: usize, nn: isize, anorm: f64) -> isize {
    let idx = |i: usize, j: usize| i * n + j;
    let mut l = nn;
    while l >= 1 {
        let s = a[idx(l as usize - 1, l as usize - 1)].abs() + a[idx(l as usize, l as usize)].abs();
        let s = if s == 0.0 { anorm } else { s };
        if a[idx(l as usize, l as usize - 1)].abs() + s == s {
            a[idx(l as usize, l as usize - 1)] = 0.0;
            break;
        }
        l -= 1;
    }
    l
}

/// One Francis double-shift QR step on rows `mu`…`nu` of the active block `l`…`nu`, from the
/// first column's Householder vector (p, q, r) (EISPACK `hqr`).
fn francis_step(a: &mut [f64], n: usize, l: usize, mu: usize, nu: usize, pqr: (f64, f64, f64)) {
    let idx = |i: usize, j: usize| i * n + j;
    let (mut p, mut q, mut r) = pqr;
    // x is the column scale of the previous k (set before it is read at k > mu).
    let mut x = 0.0;
    for i in mu + 2..=nu {
        a[idx(i, i - 2)] = 0.0;
        if i != mu + 2 {
            a[idx(i, i - 3)] = 0.0;
        }
    }
    let mut k = mu;
    while k < nu {
        if k != mu {
            p = a[idx(k, k - 1)];
            q = a[idx(k + 1, k - 1)];
            r = if k + 1 != nu {
                a[idx(k + 2, k - 1)]
            } else {
                0.0
            };
            x = p.abs() + q.abs() + r.abs();
            if x != 0.0 {
                p /= x;
                q /= x;
                r /= x;
            }
        }
        let s = (p * p + q * q + r * r).sqrt().copysign(p);
        if s != 0.0 {
            if k == mu {
                if l != mu {
                    a[idx(k, k - 1)] = -a[idx(k, k - 1)];
                }
            } else {
                a[idx(k, k - 1)] = -s * x;
            }
            p += s;
            x = p / s;
            let y = q / s;
            let z = r / s;
            q /= p;
            r /= p;
            for j in k..=nu {
                let mut pp = a[idx(k, j)] + q * a[idx(k + 1, j)];
                if k + 1 != nu {
                    pp += r * a[idx(k + 2, j)];
                    a[idx(k + 2, j)] -= pp * z;
                }
                a[idx(k + 1, j)] -= pp * y;
                a[idx(k, j)] -= pp * x;
            }
            let mmin = if nu < k + 3 { nu } else { k + 3 };
            for i in l..=mmin {
                let mut pp = x * a[idx(i, k)] + y * a[idx(i, k + 1)];
                if k + 1 != nu {
                    pp += z * a[idx(i, k + 2)];
                    a[idx(i, k + 2)] -= pp * r;
                }
                a[idx(i, k + 1)] -= pp * q;
                a[idx(i, k)] -= pp;
            }
        }
        k += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solve_matches_known_solution() {
        let mut a = vec![2.0, 1.0, 0.0, 1.0, 3.0, 1.0, 0.0, 1.0, 4.0];
        let x = [1.0, -2.0, 0.5];
        let mut b: Vec<f64> = (0..3)
            .map(|i| (0..3).map(|j| a[i * 3 + j] * x[j]).sum())
            .collect();
        assert!(solve_in_place(&mut a, &mut b, 3));
        for i in 0..3 {
            assert!((b[i] - x[i]).abs() < 1e-14);
        }
    }

    #[test]
    fn spd_solve_matches_lu_and_refuses_indefinite() {
        // A mass matrix of very unequal inertias (a float and a light vane).
        let a = [
            [4.0e3, 1.0e1, -2.0, 0.5],
            [1.0e1, 3.0e3, 1.0, 0.0],
            [-2.0, 1.0, 2.0e1, 1.0e-3],
            [0.5, 0.0, 1.0e-3, 2.0e-4],
        ];
        let x = [1.0, -2.0, 0.5, 3.0];
        let b: [f64; 4] = std::array::from_fn(|i| (0..4).map(|j| a[i][j] * x[j]).sum());
        let mut xs = b;
        assert!(solve_spd_nested(&a, &mut xs, 4));
        let (mut alu, mut xl) = (a, b);
        assert!(solve_nested(&mut alu, &mut xl, 4));
        for i in 0..4 {
            assert!((xs[i] - x[i]).abs() < 1e-12 * x[i].abs().max(1.0), "{xs:?}");
            assert!((xs[i] - xl[i]).abs() < 1e-12 * x[i].abs().max(1.0));
        }
        // Indefinite: refused, b untouched, so the caller can fall back to LU.
        let s = [
            [1.0, 2.0, 0.0, 0.0],
            [2.0, 1.0, 0.0, 0.0],
            [0.0; 4],
            [0.0; 4],
        ];
        let mut bb = [1.0, 1.0, 0.0, 0.0];
        assert!(!solve_spd_nested(&s, &mut bb, 2));
        assert_eq!(bb, [1.0, 1.0, 0.0, 0.0]);
    }

    #[test]
    fn expm_of_rotation_generator_is_a_rotation() {
        let a = [0.0, -1.0, 1.0, 0.0];
        let e = expm(&a, 2, 2.5);
        assert!((e[0] - 2.5f64.cos()).abs() < 1e-14 && (e[2] - 2.5f64.sin()).abs() < 1e-14);
    }

    #[test]
    fn eigenvalues_of_damped_oscillator() {
        // x'' + 2ζω x' + ω² x = 0, ω = 3, ζ = 0.1
        let a = [0.0, 1.0, -9.0, -0.6];
        let mut ev = eigenvalues(&a, 2);
        ev.sort_by(|x, y| x.1.total_cmp(&y.1));
        assert!((ev[1].0 + 0.3).abs() < 1e-12);
        assert!((ev[1].1 - (9.0f64 - 0.09).sqrt()).abs() < 1e-12);
    }
}
