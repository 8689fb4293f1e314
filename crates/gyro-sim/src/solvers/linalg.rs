//! Dense LU factorisation with partial pivoting for the small (2–16 state) iteration matrices
//! of the implicit solvers, real and complex (RADAU5's (α + iβ)/h · I − J). Row-major storage,
//! in place, no allocation in the step loop. [`IterationMatrix`] and [`ComplexIterationMatrix`]
//! factor c·I − J with a model's kinematic rows q̇ = v eliminated first.

/// `match $n` over the sizes this module monomorphises (1 to 16, what models have): `$body` with
/// the constant `$k` bound to the size (so arrays and loops have it at compile time), `$other`
/// for any other size.
macro_rules! by_size {
    ($n:expr, $k:ident => $body:expr, _ => $other:expr) => {
        by_size!(@arms $n, $k, $body, $other, [1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16])
    };
    (@arms $n:expr, $k:ident, $body:expr, $other:expr, [$($size:literal)*]) => {
        match $n {
            $($size => {
                const $k: usize = $size;
                $body
            })*
            _ => $other,
        }
    };
}

/// Factor the row-major n×n matrix `a` in place into L (unit lower, below the diagonal) and U
/// (above it, with the reciprocals of its pivots on the diagonal). `piv` holds 2n entries: the
/// row interchanges (row k was swapped with row `piv[k]`), then the permutation they make (row
/// i of the permuted matrix is row `piv[n + i]` of `a`), which the solves gather by.
/// Returns false if a zero pivot makes the matrix singular.
pub(crate) fn lu_decompose(a: &mut [f64], n: usize, piv: &mut [usize]) -> bool {
    by_size!(n, K => real_factorisation(&mut a[..K * K], K, &mut piv[..2 * K]),
        _ => real_factorisation(a, n, piv))
}

#[inline(always)]
fn real_factorisation(a: &mut [f64], n: usize, piv: &mut [usize]) -> bool {
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
/// 33.2–33.3 → 30.7–31.4 µs; the same steps and RHS calls. Whole runs (whole-process timing, old and new
/// `gyrolab run` paired, medians of 9 pairs): 6 h of `rolling-intercardinal` at `full` under
/// RODAS4 0.932× wall; `speed-change-20kn` at `full` under RADAU5 rtol 1e-8 (16 states, its time
/// mostly the right-hand side) 1.012× (1.003–1.027), a cost not traced.
pub(crate) fn lu_solve(a: &[f64], n: usize, piv: &[usize], b: &mut [f64]) {
    by_size!(n, K => lu_solve_sized::<K>(a, piv, b), _ => {
        interchange(&piv[..n], &mut b[..n]);
        real_substitution(a, n, &mut b[..n]);
    })
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
    by_size!(n, K => {
        let perm = &piv[K..2 * K];
        let mut yr: [f64; K] = std::array::from_fn(|i| br[perm[i]]);
        let mut yi: [f64; K] = std::array::from_fn(|i| bi[perm[i]]);
        complex_substitution(&re[..K * K], &im[..K * K], K, &mut yr, &mut yi);
        br[..K].copy_from_slice(&yr);
        bi[..K].copy_from_slice(&yi);
    }, _ => {
        interchange(&piv[..n], &mut br[..n]);
        interchange(&piv[..n], &mut bi[..n]);
        complex_substitution(re, im, n, &mut br[..n], &mut bi[..n]);
    })
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

/// Σⱼ xⱼ·(row j of `cols`), `cols` row-major with R columns: the product of the matrix whose
/// columns are `cols`' rows with x, column by column (the columns' terms independent).
#[inline(always)]
fn column_sum<const R: usize>(cols: &[f64], x: &[f64]) -> [f64; R] {
    let mut acc = [0.0; R];
    for (&u, col) in x.iter().zip(cols.chunks_exact(R)) {
        for (a, &b) in acc.iter_mut().zip(col) {
            *a += b * u;
        }
    }
    acc
}

/// A real iteration matrix c·I − J, factored for repeated solves.
///
/// The engine's `full` and `linear` models start their state with the coordinates q and their
/// rates v, and q̇ = v: J's first m rows are unit rows (row i is 1 at column m + i and 0
/// elsewhere). Write the unknowns (u, z), u the first m, z = (v, w) the rest, the right-hand
/// side (r₁, r₂), and B, R for J's lower rows left and right of column m. The top rows say
/// c u − v = r₁, so u leaves the system and what is left is the (n − m)-square Schur complement
/// S = c I − R − (1/c) B [I 0]: an 8-state model factors a 4 × 4 matrix instead of an 8 × 8 one
/// (an eighth of the work) and solves a 4-square system plus two short products.
///
/// Each kinematic pair j is recovered in the form that does not cancel. Where c is large
/// against B's column (short steps) u_j ≈ r₁ⱼ/c and v_j is small: S is solved for v_j and
/// u_j = (r₁ⱼ + v_j)/c. Where B's column is large against c·|(c I − R)'s column| (long steps over
/// a stiff mode) v_j ≈ −r₁ⱼ and u_j is small, so (r₁ⱼ + v_j)/c would lose u_j's digits: the same S
/// is then solved for c·u_j (its column j scaled by c, which partial pivoting does not see),
/// u_j = (c u_j)/c and v_j = c u_j − r₁ⱼ. The right-hand side of S is r₂ plus one product G r₁
/// whose column j is B's over c in the first form and (c I − R)'s in the second. Results differ
/// from the whole pivoted factorisation by rounding only: the unit tests below hold the two to
/// each other and the residual to a few ulps, with the stiffness up to 4e5 and c from 1e-3 to
/// 1e3. A Jacobian without these rows (a `gyroscopic` model, a hand-written system in another
/// order, a difference Jacobian) is factored whole.
pub(crate) struct IterationMatrix {
    n: usize,
    /// Kinematic rows eliminated (0: the whole matrix is factored).
    m: usize,
    /// 1/c.
    g: f64,
    /// LU factors of S ((n − m)², row-major), as [`lu_decompose`] leaves them.
    /// With the product form: only for a whole matrix above `REDUCED_MAX` states.
    lu: Vec<f64>,
    piv: Vec<usize>,
    /// Gᵀ (m × (n − m), row-major), its columns in S's row permutation (not kept with the
    /// product form: K holds S⁻¹G).
    gt: Vec<f64>,
    /// Pair j solved for c·u_j (true) or for v_j.
    stiff: Vec<bool>,
    /// Solves are one product with K = (S⁻¹G | S⁻¹) ([`Self::with_inverse`]).
    inverse: bool,
    /// Kᵀ (n × (n − m), row-major): column j of K is row j here.
    kt: Vec<f64>,
}

/// The most states a reduced (or product-form) factorisation leaves: its arrays are sized at
/// compile time, by `by_size!`, up to here.
const REDUCED_MAX: usize = 16;

/// Whether kinematic pair j is solved for c·u_j: B's column j (`b_col`, 1-norm) against |c|
/// times the 1-norm of (c I − R)'s column j (`s_col`).
fn solve_for_position(b_col: f64, c_abs: f64, s_col: f64) -> bool {
    b_col > c_abs * s_col
}

impl IterationMatrix {
    pub(crate) fn new(n: usize) -> Self {
        Self::with_form(n, false)
    }

    /// The same, but each factorisation also forms S⁻¹ (the (n − m)-square inverse, from the
    /// factors, one column per unit vector) and K = (S⁻¹G | S⁻¹), and a solve is then the
    /// product K (r₁, r₂) and the pairs' recovery: a sum whose terms are all known at once, not
    /// the substitutions' chain of dependent steps (a forward level and a backward level per
    /// unknown, each waiting on the last). For up to 16 states left (sizes monomorphised; the
    /// whole matrix, m = 0, included), larger ones keep the substitutions. Forming K costs
    /// (n − m) solves for S⁻¹ and m·(n − m)² products for S⁻¹G, several factorisations' work,
    /// so this is for a matrix that many solves follow (a Rosenbrock step's 6–8 stages), not
    /// one or two (RADAU5's real matrix per Newton iteration). The
    /// results differ from the substitutions' by rounding (the unit tests below hold both to the
    /// whole factorisation and to the residual).
    ///
    /// Measured (2026-12-07, a throwaway example: the peer benchmark's engine-linear case,
    /// Rodas5P at rtol 1e-3, 12 steps, best of 10⁵ runs, one binary switching between the two
    /// forms, alternated three times): 13.32–13.96 µs with the substitutions, 12.41–12.89 µs
    /// with K (0.93×), the same steps, RHS calls and error (8.4555e-5), the samples' checksum
    /// moved in the 15th digit.
    pub(crate) fn with_inverse(n: usize) -> Self {
        Self::with_form(n, true)
    }

    /// Storage for the form chosen: the product form keeps K, the substitutions Gᵀ, and S's
    /// factors are kept wherever a whole factorisation can happen ([`Self::factored_whole`]
    /// with m = 0: always for the substitutions, above `REDUCED_MAX` states for the product).
    fn with_form(n: usize, inverse: bool) -> Self {
        let (gt, kt) = if inverse { (0, n * n) } else { (n * n, 0) };
        let mut matrix = IterationMatrix {
            n,
            m: 0,
            g: 0.0,
            lu: Vec::new(),
            piv: vec![0; 2 * n],
            gt: vec![0.0; gt],
            stiff: vec![false; n],
            inverse,
            kt: vec![0.0; kt],
        };
        if matrix.factored_whole(0) {
            matrix.lu = vec![0.0; n * n];
        }
        matrix
    }

    /// How many leading rows of the row-major n × n `jac` are kinematic (row i exactly the unit
    /// vector at column m + i); 0 if they are not.
    pub(crate) fn kinematic_rows(jac: &[f64], n: usize) -> usize {
        let Some(m) = jac[..n].iter().position(|&v| v != 0.0) else {
            return 0;
        };
        if m == 0 || 2 * m > n || n - m > REDUCED_MAX {
            return 0;
        }
        for i in 0..m {
            let row = &jac[i * n..(i + 1) * n];
            if row[m + i] != 1.0 || row.iter().filter(|&&v| v != 0.0).count() != 1 {
                return 0;
            }
        }
        m
    }

    /// Whether a factorisation with `m` rows eliminated is the whole matrix's pivoted LU and
    /// its substitutions: m = 0, unless the product form takes it (up to `REDUCED_MAX` states).
    fn factored_whole(&self, m: usize) -> bool {
        m == 0 && !(self.inverse && self.n <= REDUCED_MAX)
    }

    /// Factors c·I − `jac`, eliminating the first `m` rows (see [`Self::kinematic_rows`]).
    /// Returns false if the matrix is singular.
    pub(crate) fn factor(&mut self, jac: &[f64], m: usize, c: f64) -> bool {
        let r = self.n - m;
        self.m = m;
        self.g = 1.0 / c;
        if self.factored_whole(m) {
            let n = self.n;
            for (e, &v) in self.lu.iter_mut().zip(jac) {
                *e = -v;
            }
            for i in 0..n {
                self.lu[i * n + i] += c;
            }
            return lu_decompose(&mut self.lu, n, &mut self.piv);
        }
        by_size!(r, R => self.reduced_factor::<R>(jac, c), _ => unreachable!(
            "kinematic rows are eliminated up to 16 remaining states"
        ))
    }

    /// The factorisation with m = `self.m` > 0 rows eliminated and R = n − m left: S and G
    /// formed in arrays of the size they have (their loops unrolled, no bounds checks), S
    /// factored there, then stored with Gᵀ in S's row permutation.
    fn reduced_factor<const R: usize>(&mut self, jac: &[f64], c: f64) -> bool {
        let (n, m, g) = (self.n, self.m, self.g);
        let mut s = [[0.0; R]; R];
        // G's columns (m ≤ R of them): (c I − R)'s column j, or B's over c.
        let mut gcol = [[0.0; R]; R];
        for (i, si) in s.iter_mut().enumerate() {
            let row = &jac[(m + i) * n..(m + i + 1) * n];
            let (left, right) = row.split_at(m);
            for (e, &v) in si.iter_mut().zip(right) {
                *e = -v;
            }
            si[i] += c;
            for (col, &v) in gcol.iter_mut().zip(left) {
                col[i] = g * v;
            }
            for (e, &v) in si.iter_mut().zip(left) {
                *e -= g * v;
            }
        }
        for (j, col) in gcol.iter_mut().enumerate().take(m) {
            let b_col: f64 = (0..R).map(|i| jac[(m + i) * n + j].abs()).sum();
            let s_col: f64 = (0..R)
                .map(|i| (jac[(m + i) * n + m + j] - if i == j { c } else { 0.0 }).abs())
                .sum();
            self.stiff[j] = solve_for_position(b_col, c.abs(), s_col);
            if self.stiff[j] {
                for (i, e) in col.iter_mut().enumerate() {
                    let cs = if i == j { c } else { 0.0 };
                    *e = cs - jac[(m + i) * n + m + j];
                }
            }
        }
        let flat = s.as_flattened_mut();
        if !real_factorisation(flat, R, &mut self.piv[..2 * R]) {
            return false;
        }
        if self.inverse {
            // S⁻¹ column by column (the unit vectors, gathered by the permutation, solved),
            // then Kᵀ: S⁻¹G's columns, S⁻¹'s.
            let perm = &self.piv[R..2 * R];
            let mut inv = [[0.0; R]; R];
            for (k, col) in inv.iter_mut().enumerate() {
                for (e, &p) in col.iter_mut().zip(perm) {
                    *e = if p == k { 1.0 } else { 0.0 };
                }
                real_substitution(flat, R, col);
            }
            let (k1, k2) = self.kt[..(m + R) * R].split_at_mut(m * R);
            for (out, gc) in k1.chunks_exact_mut(R).zip(&gcol) {
                out.copy_from_slice(&column_sum::<R>(inv.as_flattened(), gc));
            }
            k2.copy_from_slice(inv.as_flattened());
            return true;
        }
        self.lu[..R * R].copy_from_slice(flat);
        let perm = &self.piv[R..2 * R];
        for (out, col) in self.gt[..m * R].chunks_exact_mut(R).zip(&gcol) {
            for (e, &p) in out.iter_mut().zip(perm) {
                *e = col[p];
            }
        }
        true
    }

    /// Solves (c·I − J) y = `b` in place.
    pub(crate) fn solve(&self, rhs: &mut [f64]) {
        let (m, r) = (self.m, self.n - self.m);
        if self.factored_whole(m) {
            return lu_solve(&self.lu[..r * r], r, &self.piv[..2 * r], &mut rhs[..r]);
        }
        by_size!(r, R => self.reduced_solve::<R>(rhs), _ => unreachable!(
            "kinematic rows are eliminated up to 16 remaining states"
        ))
    }

    /// The solve with m rows eliminated and R = n − m left, R in registers: K (r₁, r₂) (with
    /// the inverse), or r₂ gathered by S's permutation, plus G r₁ column by column, S's
    /// substitutions; then u (and v).
    fn reduced_solve<const R: usize>(&self, rhs: &mut [f64]) {
        let (r1, r2) = rhs[..self.n].split_at_mut(self.m);
        if self.inverse {
            // K (r₁, r₂) as two sums, each its own short chain, added last.
            let (k1, k2) = self.kt[..self.n * R].split_at(self.m * R);
            let y1 = column_sum::<R>(k1, r1);
            let y2 = column_sum::<R>(k2, &r2[..R]);
            for ((o, a), b) in r2[..R].iter_mut().zip(y1).zip(y2) {
                *o = a + b;
            }
        } else {
            let perm = &self.piv[R..2 * R];
            let mut y: [f64; R] = std::array::from_fn(|i| r2[perm[i]]);
            for (&u, col) in r1.iter().zip(self.gt.chunks_exact(R)) {
                for (z, &b) in y.iter_mut().zip(col) {
                    *z += b * u;
                }
            }
            real_substitution(&self.lu[..R * R], R, &mut y);
            r2[..R].copy_from_slice(&y);
        }
        for ((u, v), &stiff) in r1.iter_mut().zip(r2.iter_mut()).zip(&self.stiff) {
            if stiff {
                // y_j = c u_j.
                let cu = *v;
                *v = cu - *u;
                *u = self.g * cu;
            } else {
                *u = self.g * (*u + *v);
            }
        }
    }
}

/// The complex counterpart of [`IterationMatrix`], for RADAU5's c·I − J with c = (α + iβ)/h:
/// the same elimination of the kinematic rows and the same choice of form per pair; J (so B
/// and R) is real, c, G and S complex.
pub(crate) struct ComplexIterationMatrix {
    n: usize,
    m: usize,
    /// 1/c, real and imaginary parts.
    g: (f64, f64),
    /// LU factors of S, real and imaginary parts, as [`lu_decompose_complex`] leaves them.
    re: Vec<f64>,
    im: Vec<f64>,
    piv: Vec<usize>,
    /// Gᵀ (m × (n − m), row-major), real and imaginary parts, in S's row permutation.
    gt_re: Vec<f64>,
    gt_im: Vec<f64>,
    stiff: Vec<bool>,
    scratch_re: Vec<f64>,
    scratch_im: Vec<f64>,
}

impl ComplexIterationMatrix {
    pub(crate) fn new(n: usize) -> Self {
        ComplexIterationMatrix {
            n,
            m: 0,
            g: (0.0, 0.0),
            re: vec![0.0; n * n],
            im: vec![0.0; n * n],
            piv: vec![0; 2 * n],
            gt_re: vec![0.0; n * n],
            gt_im: vec![0.0; n * n],
            stiff: vec![false; n],
            scratch_re: vec![0.0; n * n],
            scratch_im: vec![0.0; n * n],
        }
    }

    /// Factors (cr + i ci)·I − `jac`, eliminating the first `m` rows
    /// ([`IterationMatrix::kinematic_rows`]). Returns false if the matrix is singular.
    pub(crate) fn factor(&mut self, jac: &[f64], m: usize, cr: f64, ci: f64) -> bool {
        let n = self.n;
        let r = n - m;
        let d = cr * cr + ci * ci;
        let (gr, gi) = (cr / d, -ci / d);
        self.m = m;
        self.g = (gr, gi);
        for i in 0..r {
            let row = &jac[(m + i) * n..(m + i + 1) * n];
            let (left, right) = row.split_at(m);
            let sr = &mut self.re[i * r..(i + 1) * r];
            let si = &mut self.im[i * r..(i + 1) * r];
            for ((er, ei), &v) in sr.iter_mut().zip(si.iter_mut()).zip(right) {
                *er = -v;
                *ei = 0.0;
            }
            sr[i] += cr;
            si[i] += ci;
            for (j, &v) in left.iter().enumerate() {
                self.scratch_re[j * r + i] = gr * v;
                self.scratch_im[j * r + i] = gi * v;
            }
            for ((er, ei), &v) in sr.iter_mut().zip(si.iter_mut()).zip(left) {
                *er -= gr * v;
                *ei -= gi * v;
            }
        }
        let c_abs = cr.hypot(ci);
        for j in 0..m {
            let b_col: f64 = (0..r).map(|i| jac[(m + i) * n + j].abs()).sum();
            let s_col: f64 = (0..r)
                .map(|i| {
                    let (sr, si) = if i == j { (cr, ci) } else { (0.0, 0.0) };
                    (sr - jac[(m + i) * n + m + j]).hypot(si)
                })
                .sum();
            self.stiff[j] = solve_for_position(b_col, c_abs, s_col);
            if self.stiff[j] {
                for i in 0..r {
                    let (sr, si) = if i == j { (cr, ci) } else { (0.0, 0.0) };
                    self.scratch_re[j * r + i] = sr - jac[(m + i) * n + m + j];
                    self.scratch_im[j * r + i] = si;
                }
            }
        }
        if !lu_decompose_complex(
            &mut self.re[..r * r],
            &mut self.im[..r * r],
            r,
            &mut self.piv[..2 * r],
        ) {
            return false;
        }
        let perm = &self.piv[r..2 * r];
        for (gt, raw) in [
            (&mut self.gt_re, &self.scratch_re),
            (&mut self.gt_im, &self.scratch_im),
        ] {
            for (col, raw) in gt[..m * r].chunks_exact_mut(r).zip(raw.chunks_exact(r)) {
                for (e, &p) in col.iter_mut().zip(perm) {
                    *e = raw[p];
                }
            }
        }
        true
    }

    /// Solves (c·I − J) y = `br` + i `bi` in place.
    pub(crate) fn solve(&self, br: &mut [f64], bi: &mut [f64]) {
        let (m, r) = (self.m, self.n - self.m);
        if m == 0 {
            let (re, im) = (&self.re[..r * r], &self.im[..r * r]);
            return lu_solve_complex(re, im, r, &self.piv[..2 * r], br, bi);
        }
        by_size!(r, R => self.reduced_solve::<R>(br, bi), _ => unreachable!(
            "kinematic rows are eliminated up to 16 remaining states"
        ))
    }

    fn reduced_solve<const R: usize>(&self, br: &mut [f64], bi: &mut [f64]) {
        let (gr, gi) = self.g;
        let (r1r, r2r) = br[..self.n].split_at_mut(self.m);
        let (r1i, r2i) = bi[..self.n].split_at_mut(self.m);
        let perm = &self.piv[R..2 * R];
        let mut yr: [f64; R] = std::array::from_fn(|i| r2r[perm[i]]);
        let mut yi: [f64; R] = std::array::from_fn(|i| r2i[perm[i]]);
        let cols = self.gt_re.chunks_exact(R).zip(self.gt_im.chunks_exact(R));
        for ((&ur, &ui), (cre, cim)) in r1r.iter().zip(r1i.iter()).zip(cols) {
            for (((a, b), &er), &ei) in yr.iter_mut().zip(yi.iter_mut()).zip(cre).zip(cim) {
                *a += er * ur - ei * ui;
                *b += er * ui + ei * ur;
            }
        }
        complex_substitution(&self.re[..R * R], &self.im[..R * R], R, &mut yr, &mut yi);
        r2r[..R].copy_from_slice(&yr);
        r2i[..R].copy_from_slice(&yi);
        let pairs = r1r.iter_mut().zip(r1i.iter_mut());
        let rates = r2r.iter_mut().zip(r2i.iter_mut());
        for (((ur, ui), (vr, vi)), &stiff) in pairs.zip(rates).zip(&self.stiff) {
            let (ar, ai) = if stiff {
                // y_j = c u_j.
                let (cur, cui) = (*vr, *vi);
                *vr = cur - *ur;
                *vi = cui - *ui;
                (cur, cui)
            } else {
                (*ur + *vr, *ui + *vi)
            };
            *ur = gr * ar - gi * ai;
            *ui = gr * ai + gi * ar;
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

    /// J with kinematic first m rows and random lower rows (the stiffness block scaled by
    /// `stiff`), n = 2m + extra.
    fn kinematic_jacobian(m: usize, extra: usize, stiff: f64, seed: u64) -> Vec<f64> {
        let n = 2 * m + extra;
        let mut jac = entries(seed, n * n);
        for i in 0..m {
            for j in 0..n {
                jac[i * n + j] = if j == m + i { 1.0 } else { 0.0 };
            }
        }
        for i in m..n {
            for j in 0..m {
                jac[i * n + j] *= stiff;
            }
        }
        jac
    }

    #[test]
    fn kinematic_rows_are_found_only_where_they_are() {
        let jac = kinematic_jacobian(4, 0, 1.0, 3);
        assert_eq!(IterationMatrix::kinematic_rows(&jac, 8), 4);
        let jac = kinematic_jacobian(3, 2, 1.0, 4);
        assert_eq!(IterationMatrix::kinematic_rows(&jac, 8), 3);
        // A stray entry in a kinematic row, a rate of 2, an empty first row: factored whole.
        // (Entries of the row-major 8 × 8: row 1 column 0, row 2 column 6, row 0 column 4.)
        for (at, v) in [(8, 1e-300), (22, 2.0), (4, 0.0)] {
            let mut bad = kinematic_jacobian(4, 0, 1.0, 3);
            bad[at] = v;
            assert_eq!(
                IterationMatrix::kinematic_rows(&bad, 8),
                0,
                "entry {at} = {v}"
            );
        }
        // More kinematic columns than rows can hold.
        let mut wide = vec![0.0; 9];
        wide[2] = 1.0;
        assert_eq!(IterationMatrix::kinematic_rows(&wide, 3), 0);
    }

    /// The reduced solve against the whole pivoted factorisation of the same c·I − J, from
    /// mild to very stiff (the stiffness block up to 4e5, a 100-Hz mode, with c down to 1e-3:
    /// steps of 10³ s on it).
    #[test]
    fn reduced_solve_agrees_with_the_whole_factorisation() {
        let mut worst = [0.0f64; 2];
        for (m, extra) in [(1, 0), (2, 0), (4, 0), (3, 2), (8, 0), (5, 3)] {
            let n = 2 * m + extra;
            for (k, (stiff, c)) in [
                (1.0, 1.0),
                (1.0, 1e3),
                (4e5, 1e-3),
                (4e5, 10.0),
                (1e-3, 1e-2),
            ]
            .into_iter()
            .enumerate()
            {
                let jac = kinematic_jacobian(m, extra, stiff, 11 + k as u64);
                assert_eq!(IterationMatrix::kinematic_rows(&jac, n), m);
                let mut whole: Vec<f64> = jac.iter().map(|v| -v).collect();
                for i in 0..n {
                    whole[i * n + i] += c;
                }
                let b0 = entries(99 + k as u64, n);
                let mut piv = vec![0; 2 * n];
                let mut y_whole = b0.clone();
                assert!(lu_decompose(&mut whole, n, &mut piv));
                lu_solve(&whole, n, &piv, &mut y_whole);
                for (f, (form, mut im)) in [
                    ("substitution", IterationMatrix::new(n)),
                    ("inverse", IterationMatrix::with_inverse(n)),
                ]
                .into_iter()
                .enumerate()
                {
                    assert!(im.factor(&jac, m, c));
                    let mut y = b0.clone();
                    im.solve(&mut y);
                    // Residual of the reduced solution in the original matrix, relative.
                    let scale = y.iter().map(|v| v.abs()).fold(0.0, f64::max);
                    let mut w: f64 = 0.0;
                    for i in 0..n {
                        let mut r = c * y[i] - b0[i];
                        for j in 0..n {
                            r -= jac[i * n + j] * y[j];
                        }
                        let row = c + jac[i * n..(i + 1) * n].iter().map(|v| v.abs()).sum::<f64>();
                        w = w.max(r.abs() / (row * scale));
                    }
                    let diff = y
                        .iter()
                        .zip(&y_whole)
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max);
                    worst[f] = worst[f].max(w);
                    assert!(
                        diff <= 1e-9 * scale,
                        "{form}: m {m} n {n} stiff {stiff} c {c}: {diff:e}"
                    );
                }
            }
        }
        assert!(worst[0] < 1e-14, "backward error {:e}", worst[0]);
        assert!(worst[1] < 1e-14, "backward error (inverse) {:e}", worst[1]);
        // m = 0 is the whole factorisation itself: with the inverse, the whole matrix's up to
        // `REDUCED_MAX` states, and above that pivoted LU, whose factors the product form then
        // keeps (its storage is sized by the form).
        for (n, c) in [(6, 2.0), (REDUCED_MAX + 4, 8.0)] {
            let jac = entries(5, n * n);
            for mut im in [IterationMatrix::new(n), IterationMatrix::with_inverse(n)] {
                assert!(im.factor(&jac, 0, c));
                let mut y = entries(6, n);
                let b0 = y.clone();
                im.solve(&mut y);
                for i in 0..n {
                    let r: f64 =
                        c * y[i] - b0[i] - (0..n).map(|j| jac[i * n + j] * y[j]).sum::<f64>();
                    assert!(r.abs() < 1e-13, "n {n}: {r:e}");
                }
            }
        }
    }

    /// The complex reduced solve against the whole complex factorisation of (cr + i ci) I − J.
    #[test]
    fn complex_reduced_solve_agrees_with_the_whole_factorisation() {
        for (m, extra) in [(1, 0), (4, 0), (3, 2), (8, 0)] {
            let n = 2 * m + extra;
            for (k, (stiff, cr, ci)) in [(1.0, 1.0, 0.5), (4e5, 2e-3, 1.5e-3), (1.0, 1e3, 800.0)]
                .into_iter()
                .enumerate()
            {
                let jac = kinematic_jacobian(m, extra, stiff, 31 + k as u64);
                let (mut re, mut im): (Vec<f64>, Vec<f64>) =
                    (jac.iter().map(|v| -v).collect(), vec![0.0; n * n]);
                for i in 0..n {
                    re[i * n + i] += cr;
                    im[i * n + i] = ci;
                }
                let (br0, bi0) = (entries(7 + k as u64, n), entries(8 + k as u64, n));
                let mut piv = vec![0; 2 * n];
                assert!(lu_decompose_complex(&mut re, &mut im, n, &mut piv));
                let (mut wr, mut wi) = (br0.clone(), bi0.clone());
                lu_solve_complex(&re, &im, n, &piv, &mut wr, &mut wi);
                let mut cm = ComplexIterationMatrix::new(n);
                assert!(cm.factor(&jac, m, cr, ci));
                let (mut yr, mut yi) = (br0.clone(), bi0.clone());
                cm.solve(&mut yr, &mut yi);
                let scale = yr.iter().chain(&yi).map(|v| v.abs()).fold(0.0, f64::max);
                for i in 0..n {
                    // Residual of (c I − J) y − b, relative to the row's size.
                    let (mut rr, mut ri) = (
                        cr * yr[i] - ci * yi[i] - br0[i],
                        cr * yi[i] + ci * yr[i] - bi0[i],
                    );
                    for j in 0..n {
                        rr -= jac[i * n + j] * yr[j];
                        ri -= jac[i * n + j] * yi[j];
                    }
                    let row =
                        cr.hypot(ci) + jac[i * n..(i + 1) * n].iter().map(|v| v.abs()).sum::<f64>();
                    assert!(
                        rr.hypot(ri) < 1e-14 * row * scale,
                        "m {m} n {n} k {k}: residual {:e}",
                        rr.hypot(ri) / (row * scale)
                    );
                    let d = (yr[i] - wr[i]).hypot(yi[i] - wi[i]);
                    assert!(d <= 1e-9 * scale, "m {m} n {n} k {k}: {d:e}");
                }
            }
        }
    }
}
