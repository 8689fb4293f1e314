//! Dense LU factorisation with partial pivoting for the small (2–16 state) iteration matrices
//! of the implicit solvers, real and complex (RADAU5's (α + iβ)/h · I − J). Row-major storage,
//! in place, no allocation.

/// Factor the row-major n×n matrix `a` in place into L (unit lower, below the diagonal) and U
/// (above it, with the reciprocals of its pivots on the diagonal). `piv` holds 2n entries: the
/// row interchanges (row k was swapped with row `piv[k]`), then the permutation they make (row
/// i of the permuted matrix is row `piv[n + i]` of `a`), which the solves gather by.
/// Returns false if a zero pivot makes the matrix singular.
pub(crate) fn lu_decompose(a: &mut [f64], n: usize, piv: &mut [usize]) -> bool {
    let (piv, perm) = piv.split_at_mut(n);
    for (i, p) in perm[..n].iter_mut().enumerate() {
        *p = i;
    }
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
            perm.swap(k, p);
            for j in 0..n {
                a.swap(k * n + j, p * n + j);
            }
        }
        let inv_pivot = 1.0 / a[k * n + k];
        // U's diagonal is kept as its reciprocal: the substitution then multiplies, and no
        // division lies on its chain.
        a[k * n + k] = inv_pivot;
        // Row k and the rows below it as slices: the update of a row is one bounds check and
        // a loop the compiler vectorises (same operations, same order, as element indexing).
        let (upper, lower) = a.split_at_mut((k + 1) * n);
        let pivot_row = &upper[k * n + k + 1..(k + 1) * n];
        for row in lower.chunks_exact_mut(n) {
            let l = row[k] * inv_pivot;
            row[k] = l;
            if l != 0.0 {
                for (e, &u) in row[k + 1..].iter_mut().zip(pivot_row) {
                    *e -= l * u;
                }
            }
        }
    }
    true
}

/// Solve A y = b in place (`b` becomes y) from the factors of [`lu_decompose`].
///
/// An 8-state solve with a runtime n was latency-bound (≈ 80 ns, 48 % of a linear harbour run
/// under RODAS4): every step of the substitution's chain waited on a store and a load of `b`.
/// The sizes models have (up to 16) are monomorphised so that the right-hand side lives in
/// registers, and both substitutions are column-oriented (once y_j is known it leaves every
/// remaining row at once: independent updates, not one chain). The back substitution multiplies
/// by the reciprocal pivots the factorisation stores, so no division sits on its chain. Against
/// the textbook row-oriented form with divisions the results differ by rounding only (the unit
/// test below holds both to it); the solver harness's steps and RHS calls moved by under 0.5 %,
/// the regression baseline's by one step in 59 (`run-north-30kn`) and under 0.7 % elsewhere.
/// Measured (2026-12-06, in-process best of repeated runs over ≥ 0.3 s, old and new alternated
/// twice, `accuracy::peer_report` at rtol 1e-4/1e-6/1e-8): RODAS4 on the 4-state Anschütz
/// 0.84–0.86×, on the engine's 8-state linear one 0.80–0.82×; RADAU5 0.94–0.97× and 0.86–0.91×.
///
/// The sized solves then still spent half their time on the row interchanges (`perf record`,
/// RODAS4 at 5e-4 on the 4-state case: solves 31 % of the run, ≈ 22 ns for a 4 × 4 one):
/// swapping entries of an array at indices known only at run time keeps it in memory, each swap
/// waiting on the last one's store. They now gather the right-hand side by the permutation the
/// factorisation records beside the interchanges, n loads with no chain between them. The
/// values land where the swaps put them, so the results are the same to the bit. Old and new
/// throwaway binaries alternated three times (2026-12-06, best of 10⁵ runs each): RODAS4 at 5e-4
/// on the 4-state case 7.36–7.40 → 6.04–6.25 µs, RADAU5 at 1e-6 14.73–14.76 → 13.76–13.98 µs;
/// the engine's 8-state linear case under RODAS4 at 2e-4 13.76–13.92 → 12.88–13.06 µs, at 2e-6
/// 33.2–33.3 → 30.7–31.4 µs; the same steps and RHS calls. Whole runs (`farm-bench`, old and new
/// `gyrolab run` paired, medians of 9 pairs): 6 h of `rolling-intercardinal` at `full` under
/// RODAS4 0.932× wall; `speed-change-20kn` at `full` under RADAU5 rtol 1e-8 (16 states, its time
/// mostly the right-hand side) 1.012× (1.003–1.027), a cost not traced.
pub(crate) fn lu_solve(a: &[f64], n: usize, piv: &[usize], b: &mut [f64]) {
    macro_rules! sized {
        ($($k:literal)*) => {
            match n {
                $($k => lu_solve_sized::<$k>(a, piv, b),)*
                _ => {
                    interchange(&piv[..n], &mut b[..n]);
                    real_substitution(a, n, &mut b[..n]);
                }
            }
        };
    }
    sized!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
}

/// One size's solve, on a copy of `b` in an array (a function of its own per size: inlining all
/// sixteen into `lu_solve` measured 2–4 % slower on RADAU5). The copy gathers `b` by the
/// permutation: n independent loads, where the interchanges, one after another on an array
/// indexed at run time, kept it in memory and made a chain of stores and loads (the same
/// values in the same places either way).
fn lu_solve_sized<const N: usize>(a: &[f64], piv: &[usize], b: &mut [f64]) {
    let perm = &piv[N..2 * N];
    let mut y: [f64; N] = std::array::from_fn(|i| b[perm[i]]);
    real_substitution(&a[..N * N], N, &mut y);
    b[..N].copy_from_slice(&y);
}

/// The interchanges of `piv` applied to `b` in place, one after another (sizes above 16).
fn interchange(piv: &[usize], b: &mut [f64]) {
    for (k, &p) in piv.iter().enumerate() {
        b.swap(k, p);
    }
}

/// Both substitutions column-oriented, the backward one multiplying by reciprocal pivots, on
/// the permuted right-hand side; inlined so that a fixed `n` unrolls and `b` stays in registers.
#[inline(always)]
fn real_substitution(a: &[f64], n: usize, b: &mut [f64]) {
    for j in 0..n {
        let bj = b[j];
        for i in j + 1..n {
            b[i] -= a[i * n + j] * bj;
        }
    }
    for i in (0..n).rev() {
        let yi = b[i] * a[i * n + i];
        b[i] = yi;
        for r in 0..i {
            b[r] -= a[r * n + i] * yi;
        }
    }
}

/// Complex counterpart of [`lu_decompose`] for the row-major n×n matrix `re + i·im`, pivoting
/// on |re| + |im| as Hairer's `DECC` does; the diagonal holds the pivots' reciprocals, `piv` the
/// interchanges and the permutation as there. Returns false on a zero pivot.
pub(crate) fn lu_decompose_complex(
    re: &mut [f64],
    im: &mut [f64],
    n: usize,
    piv: &mut [usize],
) -> bool {
    let (piv, perm) = piv.split_at_mut(n);
    for (i, p) in perm[..n].iter_mut().enumerate() {
        *p = i;
    }
    for k in 0..n {
        let mut p = k;
        let mut best = re[k * n + k].abs() + im[k * n + k].abs();
        for i in k + 1..n {
            let v = re[i * n + k].abs() + im[i * n + k].abs();
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
            perm.swap(k, p);
            for j in 0..n {
                re.swap(k * n + j, p * n + j);
                im.swap(k * n + j, p * n + j);
            }
        }
        let (pr, pi) = (re[k * n + k], im[k * n + k]);
        let d = pr * pr + pi * pi;
        let (inv_r, inv_i) = (pr / d, -pi / d);
        // The reciprocal pivot in place of the pivot, as in the real factorisation.
        re[k * n + k] = inv_r;
        im[k * n + k] = inv_i;
        for i in k + 1..n {
            let (ar, ai) = (re[i * n + k], im[i * n + k]);
            let lr = ar * inv_r - ai * inv_i;
            let li = ar * inv_i + ai * inv_r;
            re[i * n + k] = lr;
            im[i * n + k] = li;
            if lr != 0.0 || li != 0.0 {
                for j in k + 1..n {
                    let (ur, ui) = (re[k * n + j], im[k * n + j]);
                    re[i * n + j] -= lr * ur - li * ui;
                    im[i * n + j] -= lr * ui + li * ur;
                }
            }
        }
    }
    true
}

/// Solve (re + i·im) y = b in place (`br + i·bi` becomes y) from [`lu_decompose_complex`].
pub(crate) fn lu_solve_complex(
    re: &[f64],
    im: &[f64],
    n: usize,
    piv: &[usize],
    br: &mut [f64],
    bi: &mut [f64],
) {
    // Monomorphised for the sizes the models have, as [`lu_solve`].
    macro_rules! sized {
        ($($k:literal)*) => {
            match n {
                $($k => {
                    let perm = &piv[$k..2 * $k];
                    let mut yr: [f64; $k] = std::array::from_fn(|i| br[perm[i]]);
                    let mut yi: [f64; $k] = std::array::from_fn(|i| bi[perm[i]]);
                    complex_substitution(&re[..$k * $k], &im[..$k * $k], $k, &mut yr, &mut yi);
                    br[..$k].copy_from_slice(&yr);
                    bi[..$k].copy_from_slice(&yi);
                })*
                _ => {
                    interchange(&piv[..n], &mut br[..n]);
                    interchange(&piv[..n], &mut bi[..n]);
                    complex_substitution(re, im, n, &mut br[..n], &mut bi[..n]);
                }
            }
        };
    }
    sized!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
}

/// The complex [`real_substitution`]: column-oriented, reciprocal pivots.
#[inline(always)]
fn complex_substitution(re: &[f64], im: &[f64], n: usize, br: &mut [f64], bi: &mut [f64]) {
    for j in 0..n {
        let (yr, yi) = (br[j], bi[j]);
        for i in j + 1..n {
            let (ar, ai) = (re[i * n + j], im[i * n + j]);
            br[i] -= ar * yr - ai * yi;
            bi[i] -= ar * yi + ai * yr;
        }
    }
    for i in (0..n).rev() {
        let (sr, si) = (br[i], bi[i]);
        let (ir, ii) = (re[i * n + i], im[i * n + i]);
        let (yr, yi) = (sr * ir - si * ii, sr * ii + si * ir);
        br[i] = yr;
        bi[i] = yi;
        for r in 0..i {
            let (ar, ai) = (re[r * n + i], im[r * n + i]);
            br[r] -= ar * yr - ai * yi;
            bi[r] -= ar * yi + ai * yr;
        }
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
        let mut piv = [0; 6];
        assert!(lu_decompose(&mut a, 3, &mut piv));
        lu_solve(&a, 3, &piv, &mut b);
        for i in 0..3 {
            assert!((b[i] - y[i]).abs() < 1e-14, "{b:?}");
        }
    }

    /// Deterministic pseudo-random entries in [-1, 1) (no RNG dependency for a unit test).
    fn entries(seed: u64, count: usize) -> Vec<f64> {
        let mut s = seed;
        (0..count)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
            })
            .collect()
    }

    /// The textbook row-oriented substitution, dividing by the pivots, on factors whose
    /// diagonal holds U's pivots (the reciprocals [`lu_decompose`] stores, inverted back).
    fn textbook_solve(a: &[f64], n: usize, piv: &[usize], b: &mut [f64]) {
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
            b[i] = s / (1.0 / a[i * n + i]);
        }
    }

    fn textbook_solve_complex(
        re: &[f64],
        im: &[f64],
        n: usize,
        piv: &[usize],
        br: &mut [f64],
        bi: &mut [f64],
    ) {
        for k in 0..n {
            br.swap(k, piv[k]);
            bi.swap(k, piv[k]);
        }
        for i in 1..n {
            let (mut sr, mut si) = (br[i], bi[i]);
            for j in 0..i {
                let (ar, ai) = (re[i * n + j], im[i * n + j]);
                sr -= ar * br[j] - ai * bi[j];
                si -= ar * bi[j] + ai * br[j];
            }
            br[i] = sr;
            bi[i] = si;
        }
        for i in (0..n).rev() {
            let (mut sr, mut si) = (br[i], bi[i]);
            for j in i + 1..n {
                let (ar, ai) = (re[i * n + j], im[i * n + j]);
                sr -= ar * br[j] - ai * bi[j];
                si -= ar * bi[j] + ai * br[j];
            }
            // The pivot p = 1/(stored reciprocal), then y = s/p.
            let (ir, ii) = (re[i * n + i], im[i * n + i]);
            let m = ir * ir + ii * ii;
            let (pr, pi) = (ir / m, -ii / m);
            let d = pr * pr + pi * pi;
            br[i] = (sr * pr + si * pi) / d;
            bi[i] = (si * pr - sr * pi) / d;
        }
    }

    /// The solves multiply by stored reciprocal pivots and substitute backwards by columns,
    /// for speed (see [`lu_solve`]): they must agree with the textbook substitution to
    /// rounding, and leave a backward error of a few ulps, at every size (1–16 monomorphised,
    /// 17–20 runtime n).
    #[test]
    fn solves_agree_with_the_textbook_substitution_to_rounding_at_every_size() {
        let close = |fast: &[f64], slow: &[f64], what: &str| {
            let scale = slow.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (f, s) in fast.iter().zip(slow) {
                assert!(
                    (f - s).abs() <= 1e-11 * scale,
                    "{what}: {fast:?} vs {slow:?}"
                );
            }
            // Not the same bits everywhere: the test would pass on the textbook form itself.
            fast != slow
        };
        let mut differed = 0;
        for n in 1..=20 {
            let a0 = entries(n as u64, n * n);
            let (re0, im0) = (
                entries(100 + n as u64, n * n),
                entries(200 + n as u64, n * n),
            );
            let (mut a, mut re, mut im) = (a0.clone(), re0.clone(), im0.clone());
            let (mut piv, mut pivc) = (vec![0; 2 * n], vec![0; 2 * n]);
            assert!(lu_decompose(&mut a, n, &mut piv), "n = {n}");
            assert!(
                lu_decompose_complex(&mut re, &mut im, n, &mut pivc),
                "n = {n}"
            );
            let b = entries(300 + n as u64, n);
            let (mut fast, mut slow) = (b.clone(), b.clone());
            lu_solve(&a, n, &piv, &mut fast);
            textbook_solve(&a, n, &piv, &mut slow);
            differed += usize::from(close(&fast, &slow, &format!("real, n = {n}")));
            // Backward error: |A y − b| within 64 n ulps of |A| |y|, row by row.
            for i in 0..n {
                let row = &a0[i * n..(i + 1) * n];
                let r: f64 = row.iter().zip(&fast).map(|(a, y)| a * y).sum::<f64>() - b[i];
                let s: f64 = row.iter().zip(&fast).map(|(a, y)| (a * y).abs()).sum();
                assert!(
                    r.abs() <= 64.0 * n as f64 * f64::EPSILON * s,
                    "n = {n}, row {i}"
                );
            }
            // The sizes' gather by the permutation against the interchanges one by one (the
            // path above 16): the same values, so the same bits.
            let mut swapped = b.clone();
            interchange(&piv[..n], &mut swapped);
            real_substitution(&a, n, &mut swapped);
            assert_eq!(fast, swapped, "real, n = {n}: gather against interchanges");
            let bi = entries(400 + n as u64, n);
            let (mut fr, mut fi, mut sr, mut si) = (b.clone(), bi.clone(), b.clone(), bi.clone());
            lu_solve_complex(&re, &im, n, &pivc, &mut fr, &mut fi);
            let (mut gr, mut gi) = (b.clone(), bi.clone());
            interchange(&pivc[..n], &mut gr);
            interchange(&pivc[..n], &mut gi);
            complex_substitution(&re, &im, n, &mut gr, &mut gi);
            assert_eq!(
                (&fr, &fi),
                (&gr, &gi),
                "complex, n = {n}: gather against interchanges"
            );
            textbook_solve_complex(&re, &im, n, &pivc, &mut sr, &mut si);
            differed += usize::from(close(&fr, &sr, &format!("complex re, n = {n}")));
            differed += usize::from(close(&fi, &si, &format!("complex im, n = {n}")));
            for i in 0..n {
                let (mut rr, mut ri, mut s) = (-b[i], -bi[i], 0.0);
                for j in 0..n {
                    let (ar, ai) = (re0[i * n + j], im0[i * n + j]);
                    rr += ar * fr[j] - ai * fi[j];
                    ri += ar * fi[j] + ai * fr[j];
                    s += ar.hypot(ai) * fr[j].hypot(fi[j]);
                }
                assert!(
                    rr.hypot(ri) <= 128.0 * n as f64 * f64::EPSILON * s,
                    "complex, n = {n}, row {i}"
                );
            }
        }
        assert!(differed > 0, "the fast and textbook forms never differed");
    }

    #[test]
    fn reports_singular() {
        let mut a = [1.0, 2.0, 2.0, 4.0];
        let mut piv = [0; 4];
        assert!(!lu_decompose(&mut a, 2, &mut piv));
    }

    #[test]
    fn complex_solve_needs_pivoting_and_recovers_the_solution() {
        // A (re + i im) with a zero (0,0) entry; y known, b = A y formed in complex arithmetic.
        let ar0 = [0.0, 2.0, 1.0, 1.0, -1.0, 0.5, 3.0, 0.0, 1.0];
        let ai0 = [0.0, 1.0, -1.0, 2.0, 0.5, 0.0, 0.0, -3.0, 1.0];
        let (yr, yi) = ([1.0, -2.0, 0.5], [0.25, 1.0, -1.5]);
        let (mut br, mut bi) = ([0.0; 3], [0.0; 3]);
        for i in 0..3 {
            for j in 0..3 {
                let (a, b) = (ar0[i * 3 + j], ai0[i * 3 + j]);
                br[i] += a * yr[j] - b * yi[j];
                bi[i] += a * yi[j] + b * yr[j];
            }
        }
        let (mut ar, mut ai) = (ar0, ai0);
        let mut piv = [0; 6];
        assert!(lu_decompose_complex(&mut ar, &mut ai, 3, &mut piv));
        assert_ne!(piv[0], 0, "the zero pivot must be swapped away");
        lu_solve_complex(&ar, &ai, 3, &piv, &mut br, &mut bi);
        for i in 0..3 {
            assert!((br[i] - yr[i]).abs() < 1e-14 && (bi[i] - yi[i]).abs() < 1e-14);
        }
        let (mut sr, mut si) = ([1.0, 2.0, 2.0, 4.0], [1.0, 0.0, 2.0, 0.0]);
        assert!(!lu_decompose_complex(&mut sr, &mut si, 2, &mut piv));
    }
}
