//! The `gyroscopic` fidelity's reductions of the equations M q̈ = r(q̇) = c + K q̇ (M, K, c
//! from either engine, the precessional rows g and the inertial rows m already classified).
//!
//! **Plain** ([`precession_rates`], then [`inertial_accelerations`]): the precessional
//! coordinates' quadratic kinetic energy T₂ is dropped, their rows become first-order precession
//! equations K_gg q̇_g = −(c_g + K_gm q̇_m), and the inertial rows are solved at those rates. This
//! is Lagrange's for the Lagrangian without that T₂, so its energy balance closes exactly.
//!
//! **Carried** ([`carried_rates`]): the plain reduction keeps the base-rate terms T₀, T₁ of the
//! precessional rows while it drops T₂. A gyro whose frame swings with a rolling ship (the
//! Sperry's gyro-ballistic pendulum, the twin-gyro's spider) is then counted as tilting with its
//! frame where the real one holds its tilt: a spurious torque I·ω² on the precession axes, of the
//! order of the rolling error itself (docs/designs.md). The carried reduction is the slow
//! manifold of the full equations to first order in the precessional inertia: the precession
//! rates q̇_g = φ + δ, φ the precession equations' solution and δ = X q̈_m + y what the full
//! precessional rows add, with q̈_g ≈ G q̈_m + a (G = ∂φ/∂q̇_m = −K_gg⁻¹K_gm, a = φ's rate along
//! the motion); the inertial rows are kept whole. A box's tilt inertia then cancels (I(ν̈ + ω̇) +
//! I α̈ = 0) as it does in the full model. It is no Lagrangian's, so no exact energy balance.

use crate::dual::{Jet, M3, Real, V3};
use crate::linalg;
use crate::model::Base;

/// Solves the precession equations K_gg q̇_g = −(c_g + K_gm q̇_m) into `qd`'s precessional
/// entries (its inertial entries hold q̇_m).
pub(crate) fn precession_rates<T: Real, const N: usize>(
    gi: &[usize],
    mis: &[usize],
    k: &[[T; N]; N],
    c: &[T; N],
    qd: &mut [T; N],
) -> bool {
    let ng = gi.len();
    let mut a = [[T::zero(); N]; N];
    let mut r = [T::zero(); N];
    for (a_r, &i) in gi.iter().enumerate() {
        let mut s = c[i];
        for &j in mis {
            s += k[i][j] * qd[j];
        }
        r[a_r] = -s;
        for (a_c, &j) in gi.iter().enumerate() {
            a[a_r][a_c] = k[i][j];
        }
    }
    if !linalg::solve_nested(&mut a, &mut r, ng) {
        return false;
    }
    for (a_r, &i) in gi.iter().enumerate() {
        qd[i] = r[a_r];
    }
    true
}

/// Solves the inertial rows M_mm q̈_m = c_m + K_m· q̇ at the rates `qd` (all `ni` of them) into
/// `out[..nm]`.
pub(crate) fn inertial_accelerations<T: Real, const N: usize>(
    mis: &[usize],
    ni: usize,
    m: &[[T; N]; N],
    k: &[[T; N]; N],
    c: &[T; N],
    qd: &[T; N],
    out: &mut [T],
) -> bool {
    let nm = mis.len();
    if nm == 0 {
        return true;
    }
    let mut mm = [[T::zero(); N]; N];
    let mut rm = [T::zero(); N];
    for (a_r, &i) in mis.iter().enumerate() {
        let mut s = c[i];
        for j in 0..ni {
            s += k[i][j] * qd[j];
        }
        rm[a_r] = s;
        for (a_c, &j) in mis.iter().enumerate() {
            mm[a_r][a_c] = m[i][j];
        }
    }
    if !linalg::solve_nested(&mut mm, &mut rm, nm) {
        return false;
    }
    out[..nm].copy_from_slice(&rm[..nm]);
    true
}

/// Step of the central difference that gives a = dφ/dt along the motion. The recorded
/// equations are smooth in t and q on the scale of the sea's seconds-long periods, so the
/// truncation, ~(2πH/T)²/6, is below 1e-7 of a. Checked once (2026-12-03, before the base
/// carried ġ, R̈ and ω̈): H = 1e-4 s gave the twin-gyro's, the Sperry's and the three-gyro's
/// rolling errors on compare-rolling-045 to six digits.
pub(crate) const RATE_STEP_S: f64 = 1e-3;

/// ẋ of the carried reduction (module doc) at q and the inertial rates `qd_m`: dx[..ni] the
/// rates of every independent coordinate (q̇_g = φ + δ), dx[ni..ni + nm] q̈_m. Four evaluations
/// of the equations: the precession equations at the state and at ±[`RATE_STEP_S`] along
/// the motion (for a), the full ones at q̇ = (q̇_m, φ). `eval(drop, shift_s, q, qd, m, k, c)`
/// fills M, K and c with the precessional T₂ dropped or not, the base (and motor spins)
/// `shift_s` seconds on to first order ([`shifted_base`]).
#[allow(clippy::type_complexity)]
pub(crate) fn carried_rates<T: Real, const N: usize>(
    gi: &[usize],
    mis: &[usize],
    q: &[T],
    qd_m: &[T],
    mut equations: impl FnMut(bool, f64, &[T], &[T], &mut [[T; N]; N], &mut [[T; N]; N], &mut [T; N]),
    dx: &mut [T],
) -> bool {
    // The engines add into M and K (dampers, pots): each evaluation starts from zero.
    let mut eval = |drop,
                    shift,
                    q: &[T],
                    qd: &[T],
                    m: &mut [[T; N]; N],
                    k: &mut [[T; N]; N],
                    c: &mut [T; N]| {
        *m = [[T::zero(); N]; N];
        *k = [[T::zero(); N]; N];
        *c = [T::zero(); N];
        equations(drop, shift, q, qd, m, k, c);
    };
    let (ng, nm, ni) = (gi.len(), mis.len(), q.len());
    let mut m = [[T::zero(); N]; N];
    let mut k = [[T::zero(); N]; N];
    let mut c = [T::zero(); N];
    let mut qd = [T::zero(); N];
    for (a, &col) in mis.iter().enumerate() {
        qd[col] = qd_m[a];
    }
    // φ, and G = −K_gg⁻¹K_gm (ng × nm) column by column.
    eval(true, 0.0, q, &qd[..ni], &mut m, &mut k, &mut c);
    if !precession_rates(gi, mis, &k, &c, &mut qd) {
        return false;
    }
    let mut kgg = [[T::zero(); N]; N];
    for (a_r, &i) in gi.iter().enumerate() {
        for (a_c, &l) in gi.iter().enumerate() {
            kgg[a_r][a_c] = k[i][l];
        }
    }
    let Some(g) = solve_columns(&kgg, ng, nm, |a_r, b| -k[gi[a_r]][mis[b]]) else {
        return false;
    };
    // a = φ_t + φ_q q̇ at fixed q̇_m (its change is G q̈_m): central difference along (1, q̇).
    let mut phi = [[T::zero(); N]; 2];
    for (side, s) in [RATE_STEP_S, -RATE_STEP_S].into_iter().enumerate() {
        let mut qs = [T::zero(); N];
        for i in 0..ni {
            qs[i] = q[i] + qd[i] * s;
        }
        let mut qds = [T::zero(); N];
        for &col in mis {
            qds[col] = qd[col];
        }
        eval(true, s, &qs[..ni], &qds[..ni], &mut m, &mut k, &mut c);
        if !precession_rates(gi, mis, &k, &c, &mut qds) {
            return false;
        }
        for (a_r, &i) in gi.iter().enumerate() {
            phi[side][a_r] = qds[i];
        }
    }
    let mut acc = [T::zero(); N];
    for a_r in 0..ng {
        acc[a_r] = (phi[0][a_r] - phi[1][a_r]) * (0.5 / RATE_STEP_S);
    }
    // The full equations at q̇ = (q̇_m, φ): r = c + K q̇.
    eval(false, 0.0, q, &qd[..ni], &mut m, &mut k, &mut c);
    let mut r = [T::zero(); N];
    for i in 0..ni {
        let mut s = c[i];
        for j in 0..ni {
            s += k[i][j] * qd[j];
        }
        r[i] = s;
    }
    // Precessional rows, linear in δ: K_gg δ = (M_gm + M_gg G) q̈_m + M_gg a − r_g, so
    // δ = X q̈_m + y.
    for (a_r, &i) in gi.iter().enumerate() {
        for (a_c, &l) in gi.iter().enumerate() {
            kgg[a_r][a_c] = k[i][l];
        }
    }
    let Some(x) = solve_columns(&kgg, ng, nm, |a_r, b| {
        let (i, j) = (gi[a_r], mis[b]);
        let mut s = m[i][j];
        for (l_c, &l) in gi.iter().enumerate() {
            s += m[i][l] * g[l_c][b];
        }
        s
    }) else {
        return false;
    };
    let mut y = [T::zero(); N];
    for (a_r, &i) in gi.iter().enumerate() {
        let mut s = -r[i];
        for (l_c, &l) in gi.iter().enumerate() {
            s += m[i][l] * acc[l_c];
        }
        y[a_r] = s;
    }
    if !linalg::solve_nested(&mut kgg, &mut y, ng) {
        return false;
    }
    // Inertial rows, whole: (M_mm + M_mg G − K_mg X) q̈_m = r_m − M_mg a + K_mg y.
    let mut mm = [[T::zero(); N]; N];
    let mut rm = [T::zero(); N];
    for (a_r, &i) in mis.iter().enumerate() {
        let mut s = r[i];
        for (l_c, &l) in gi.iter().enumerate() {
            s += k[i][l] * y[l_c] - m[i][l] * acc[l_c];
        }
        rm[a_r] = s;
        for (b, &j) in mis.iter().enumerate() {
            let mut e = m[i][j];
            for (l_c, &l) in gi.iter().enumerate() {
                e += m[i][l] * g[l_c][b] - k[i][l] * x[l_c][b];
            }
            mm[a_r][b] = e;
        }
    }
    if !linalg::solve_nested(&mut mm, &mut rm, nm) {
        return false;
    }
    for (a_r, &i) in gi.iter().enumerate() {
        let mut d = y[a_r];
        for b in 0..nm {
            d += x[a_r][b] * rm[b];
        }
        qd[i] += d;
    }
    dx[..ni].copy_from_slice(&qd[..ni]);
    dx[ni..ni + nm].copy_from_slice(&rm[..nm]);
    true
}

/// Y (rows..ng, columns ..nm) solving A Y = B column by column, B's entry (row, column) given
/// by `b`; None if A is singular.
fn solve_columns<T: Real, const N: usize>(
    a: &[[T; N]; N],
    ng: usize,
    nm: usize,
    b: impl Fn(usize, usize) -> T,
) -> Option<[[T; N]; N]> {
    let mut y = [[T::zero(); N]; N];
    for col in 0..nm {
        let mut lu = *a;
        let mut r = [T::zero(); N];
        for (row, r) in r.iter_mut().enumerate().take(ng) {
            *r = b(row, col);
        }
        if !linalg::solve_nested(&mut lu, &mut r, ng) {
            return None;
        }
        for row in 0..ng {
            y[row][col] = r[row];
        }
    }
    Some(y)
}

/// The base `s` seconds on, to first order along its motion (R + sṘ, Ṙ + sR̈, ω + sω̇,
/// ω̇ + sω̈, g + sġ): the central difference of [`carried_rates`] differences along this line,
/// the motion's tangent, which gives the derivative along the motion to O(s²).
pub(crate) fn shifted_base<T: Real>(b: &Base<T>, s: f64) -> Base<T> {
    if s == 0.0 {
        return *b;
    }
    let (r, w, g, g_dot, r_dd, w_dd) = b;
    (
        M3(std::array::from_fn(|i| {
            std::array::from_fn(|j| Jet {
                v: r.0[i][j].v + r.0[i][j].d[0] * s,
                d: [r.0[i][j].d[0] + r_dd[i][j] * s],
            })
        })),
        V3(std::array::from_fn(|i| Jet {
            v: w.0[i].v + w.0[i].d[0] * s,
            d: [w.0[i].d[0] + w_dd[i] * s],
        })),
        std::array::from_fn(|i| g[i] + g_dot[i] * s),
        *g_dot,
        *r_dd,
        *w_dd,
    )
}
