//! The communicating pots' share of the Lagrangian (Beghin §51), in world axes on the carrier's
//! kinematics.
//!
//! The liquid's kinetic energy is ½∫ρ|v_B + w|², v_B the carrier's velocity field and w the flow
//! relative to it, taken as plug flow at each section's mean velocity (Beghin's hypothesis (2)).
//! With Q = ω₀u̇ the volume flux through every section, the three parts are exact functions of
//! the path the liquid fills (second pot's free surface, down, the tube, up to the first's):
//! - ½∫ρ|v_B|² over the two open columns, point masses ρω₀(c ± u) at their centres
//!   (their own moments at rest level are in the carrier's inertia: `design::pots`);
//! - ∫ρ v_B·w = v_O·P + ω·L, with P = ρQ (top₁ − top₂) and L = ρQ ∫ r × dr along the path
//!   (twice the area it sweeps about the carrier's origin; Beghin's S and 2eh terms);
//! - ½∫ρ|w|² = ½ℰu̇², ℰ = ρω₀(2c + ω₀L/F), constant.
//!
//! The columns' weights give the potential; the flow's viscous loss is a damper on u that the
//! design reader adds. The carriers' other liquid (tube, closed compartments) is rigid and is in
//! the carrier's mass.

use super::{BodyKin, Chain, EvalInput, EvalOutput, body_kinematics, variables};
use crate::design::Pots;
use crate::dual::{Jet, Real, V3};

/// The Lagrangian's accumulators the pots add to (the reference engine's, or fresh ones).
pub(super) struct Terms<'a, T: Real, const N: usize> {
    pub p2: &'a mut [Jet<T, N>; N],
    pub b: &'a mut [Jet<T, N>; N],
    pub t2: &'a mut Jet<T, N>,
    pub t0: &'a mut Jet<T, N>,
    pub v: &'a mut Jet<T, N>,
    /// Mass matrix, n × n row-major.
    pub m: &'a mut [T],
}

impl<T: Real, const N: usize> Terms<'_, T, N> {
    /// The same accumulators, borrowed again for one more contribution.
    pub fn reborrow(&mut self) -> Terms<'_, T, N> {
        Terms {
            p2: &mut *self.p2,
            b: &mut *self.b,
            t2: &mut *self.t2,
            t0: &mut *self.t0,
            v: &mut *self.v,
            m: &mut *self.m,
        }
    }
}

/// Adds every liquid of the chain (communicating pots, tanks), each on its carrier's kinematics
/// `kin[carrier]`, to the Lagrangian's terms.
pub(super) fn add_liquids<T: Real, const N: usize>(
    chain: &Chain,
    kin: &[BodyKin<Jet<T, N>, N>],
    q: &[Jet<T, N>; N],
    inp: &EvalInput<T>,
    w0: &V3<Jet<T, N>>,
    mut out: Terms<T, N>,
) {
    let n = chain.n;
    for pots in &chain.pots {
        add(pots, &kin[pots.body], q, n, inp, w0, out.reborrow());
    }
    for tank in &chain.tanks {
        super::tank::add(tank, &kin[tank.body], q, n, inp, w0, out.reborrow());
    }
}

/// Adds one set of pots, carried by a body with kinematics `k`, to the Lagrangian's terms.
#[allow(clippy::too_many_arguments)]
pub(super) fn add<T: Real, const N: usize>(
    pots: &Pots,
    k: &BodyKin<Jet<T, N>, N>,
    q: &[Jet<T, N>; N],
    n: usize,
    inp: &EvalInput<T>,
    w0: &V3<Jet<T, N>>,
    mut out: Terms<T, N>,
) {
    let dropped = |i: usize| inp.drop_quadratic.get(i).copied().unwrap_or(false);
    let iu = pots.level;
    let lvl = q[iu];
    let rho_w0 = pots.density_kg_per_m3 * pots.section_m2;
    let c = pots.rest_level_m;
    let a = V3::<Jet<T, N>>::from_f64(pots.axis);

    // The open columns: point masses ρω₀(c ± u) at base + (c ± u)/2 â.
    for (j, sign) in [(0usize, 1.0), (1, -1.0)] {
        let len = lvl * sign + c;
        let r_body = V3::from_f64(pots.bases_m[j]).add(&a.scale(len * 0.5));
        carried_mass(k, &r_body, len * rho_w0, n, inp, w0, out.reborrow());
    }

    // The flow relative to the carrier: T = u̇ (Σᵢ Gᵢ q̇ᵢ + G₀) + ½ℰu̇².
    let b0 = V3::<Jet<T, N>>::from_f64(pots.bases_m[0]);
    let b1 = V3::<Jet<T, N>>::from_f64(pots.bases_m[1]);
    // top₁ − top₂ = b₀ − b₁ + 2u â.
    let d_body = b0.sub(&b1).add(&a.scale(lvl * 2.0));
    // ∫ r × dr: down the second pot, along the tube, up the first.
    let mut tube = [0.0; 3];
    for w in pots.tube_path_m.windows(2) {
        let (p, r) = (w[0], w[1]);
        tube[0] += p[1] * r[2] - p[2] * r[1];
        tube[1] += p[2] * r[0] - p[0] * r[2];
        tube[2] += p[0] * r[1] - p[1] * r[0];
    }
    let lam_body = a
        .cross(&b1)
        .scale(-lvl + c)
        .add(&V3::from_f64(tube))
        .add(&b0.cross(&a).scale(lvl + c));
    let d = k.r.mul_v(&d_body);
    let lam = k.r.mul_v(&lam_body);
    let gcol: [Jet<T, N>; N] = std::array::from_fn(|i| {
        if i < n && i != iu {
            (k.jw[i].cross(&k.p).sub(&k.jm[i]).dot(&d) + k.jw[i].dot(&lam)) * rho_w0
        } else {
            Jet::zero()
        }
    });
    let g0 = (w0.cross(&k.p).dot(&d) + w0.dot(&lam)) * rho_w0;
    let e = pots.flow_inertia_kg();
    let uu = Jet::<T, N>::constant(inp.u[iu]);
    let mut gu = Jet::<T, N>::zero();
    for i in 0..n {
        if inp.u[i] != T::zero() {
            gu += gcol[i] * Jet::constant(inp.u[i]);
        }
    }
    if !dropped(iu) {
        out.p2[iu] += gu + uu * e;
    }
    for i in 0..n {
        if !dropped(i) && i != iu {
            out.p2[i] += gcol[i] * uu;
        }
    }
    out.b[iu] += g0;
    *out.t2 += uu * gu + uu * uu * (0.5 * e);
    if !dropped(iu) {
        out.m[iu * n + iu] += T::cst(e);
        for i in (0..n).filter(|&i| !dropped(i) && i != iu) {
            out.m[iu * n + i] += gcol[i].v;
            out.m[i * n + iu] += gcol[i].v;
        }
    }
}

/// A point mass m (a function of the coordinates) at `r_body` in a carrier with kinematics `k`,
/// moving with the carrier: its kinetic energy, momenta, mass-matrix share and weight.
pub(super) fn carried_mass<T: Real, const N: usize>(
    k: &BodyKin<Jet<T, N>, N>,
    r_body: &V3<Jet<T, N>>,
    m: Jet<T, N>,
    n: usize,
    inp: &EvalInput<T>,
    w0: &V3<Jet<T, N>>,
    out: Terms<T, N>,
) {
    let dropped = |i: usize| inp.drop_quadratic.get(i).copied().unwrap_or(false);
    let vz = V3::<Jet<T, N>>::zero();
    let g = V3(inp.gravity.map(Jet::<T, N>::constant));
    let x = k.p.add(&k.r.mul_v(r_body));
    let jv: [V3<Jet<T, N>>; N] = std::array::from_fn(|i| {
        if i < n {
            k.jw[i].cross(&x).sub(&k.jm[i])
        } else {
            vz
        }
    });
    let v0 = w0.cross(&x);
    let mut v_u = vz;
    for i in 0..n {
        if inp.u[i] != T::zero() {
            v_u = v_u.add(&jv[i].scale(Jet::constant(inp.u[i])));
        }
    }
    for i in 0..n {
        if !dropped(i) {
            out.p2[i] += jv[i].dot(&v_u) * m;
        }
        out.b[i] += jv[i].dot(&v0) * m;
    }
    *out.t2 += v_u.dot(&v_u) * m * 0.5;
    *out.t0 += v0.dot(&v0) * m * 0.5;
    *out.v -= g.dot(&x) * m;
    let jvr: [V3<T>; N] = std::array::from_fn(|i| V3(jv[i].0.map(|x| x.v)));
    for i in (0..n).filter(|&i| !dropped(i)) {
        for kk in (0..n).filter(|&kk| !dropped(kk)) {
            out.m[i * n + kk] += jvr[i].dot(&jvr[kk]) * m.v;
        }
    }
}

/// The pots' share of M, K and c alone (added into `out`, whose energies get theirs too), for
/// an engine that walks the chain its own way: the carriers' kinematics walked here in world
/// axes, only down to the carriers.
pub(super) fn evaluate<T: Real, const N: usize>(
    chain: &Chain,
    inp: &EvalInput<T>,
    out: &mut EvalOutput<T>,
) {
    let n = chain.n;
    debug_assert!(N > n);
    let zero = Jet::<T, N>::zero();
    let (q, base_r, w0) = variables::<T, N>(inp, n);
    let mut p2 = [zero; N];
    let mut b = [zero; N];
    let (mut t2, mut t0, mut v) = (zero, zero, zero);
    let mut m = [T::zero(); 256];
    let last = (chain.pots.iter().map(|p| p.body))
        .chain(chain.tanks.iter().map(|t| t.body))
        .max()
        .unwrap_or(0);
    let mut kin: Vec<BodyKin<Jet<T, N>, N>> = Vec::with_capacity(last + 1);
    for body in &chain.bodies[..=last] {
        let k = body_kinematics(&kin, body, &q, n, &base_r);
        kin.push(k);
    }
    let terms = Terms {
        p2: &mut p2,
        b: &mut b,
        t2: &mut t2,
        t0: &mut t0,
        v: &mut v,
        m: &mut m[..n * n],
    };
    add_liquids(chain, &kin, &q, inp, &w0, terms);
    for i in 0..n {
        out.c[i] += t2.d[i] + t0.d[i] - v.d[i] - p2[i].d[n] - b[i].d[n];
        for kk in 0..n {
            out.m[i * n + kk] += m[i * n + kk];
            out.k[i * n + kk] -= p2[i].d[kk] + b[i].d[kk] - b[kk].d[i];
        }
    }
    out.energies[0] += t2.v;
    out.energies[1] += t0.v;
    out.energies[2] += v.v;
}
