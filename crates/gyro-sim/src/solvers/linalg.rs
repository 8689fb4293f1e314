//! Dense LU factorisation with partial pivoting for the small (2–16 state) iteration matrices
//! of the implicit solver. Row-major storage, in place, no allocation.

/// Factor the row-major n×n matrix `a` in place into L (unit lower, below the diagonal) and U,
/// with row interchanges recorded in `piv` (row k was swapped with row `piv[k]`).
/// Returns false if a zero pivot makes the matrix singular.
pub(crate) fn lu_decompose(a: &mut [f64], n: usize, piv: &mut [usize]) -> bool {
    for k in 0..n {
        let mut p = k;
        let mut best = a[k * n + k].abs();
        for i in k + 1..n {
            let v = a[i * n + k].abs();
            if v > best {
                best = v;
                p = i;
            }
        }
        piv[k] = p;
        if best.is_nan() || best == 0.0 {
            return false;
        }
        if p != k {
            for j in 0..n {
                a.swap(k * n + j, p * n + j);
            }
        }
        let inv_pivot = 1.0 / a[k * n + k];
        for i in k + 1..n {
            let l = a[i * n + k] * inv_pivot;
            a[i * n + k] = l;
            if l != 0.0 {
                for j in k + 1..n {
                    a[i * n + j] -= l * a[k * n + j];
                }
            }
        }
    }
    true
}

/// Solve A y = b in place (`b` becomes y) from the factors of [`lu_decompose`].
pub(crate) fn lu_solve(a: &[f64], n: usize, piv: &[usize], b: &mut [f64]) {
    for k in 0..n {
        b.swap(k, piv[k]);
    }
    for i in 1..n {
        let mut s = b[i];
        for j in 0..i {
            s -= a[i * n + j] * b[j];
        }
        b[i] = s;
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for j in i + 1..n {
            s -= a[i * n + j] * b[j];
        }
        b[i] = s / a[i * n + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_system_that_needs_pivoting() {
        // Zero in the (0,0) position: fails without row interchange.
        let a0 = [0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 3.0, 0.0, 1.0];
        let y = [1.0, -2.0, 0.5];
        let mut b = [0.0; 3];
        for i in 0..3 {
            b[i] = (0..3).map(|j| a0[i * 3 + j] * y[j]).sum();
        }
        let mut a = a0;
        let mut piv = [0; 3];
        assert!(lu_decompose(&mut a, 3, &mut piv));
        lu_solve(&a, 3, &piv, &mut b);
        for i in 0..3 {
            assert!((b[i] - y[i]).abs() < 1e-14, "{b:?}");
        }
    }

    #[test]
    fn reports_singular() {
        let mut a = [1.0, 2.0, 2.0, 4.0];
        let mut piv = [0; 2];
        assert!(!lu_decompose(&mut a, 2, &mut piv));
    }
}
