//! The `full` equations as the integrator needs them: M and the right-hand side r = c + K q̇,
//! without forming K. Same chain walk and same Lagrangian as [`super::evaluate`], less work.
//!
//! Why K need not be formed: with u = q̇ and p = ∂L/∂q̇,
//!   rᵢ = Qᵢ − ∂ₜpᵢ + ∂L/∂qᵢ − Σₖ (∂pᵢ/∂qₖ) q̇ₖ,
//! and the last sum is the derivative of pᵢ along q̇ at fixed velocities: one direction, not n.
//! So instead of carrying n Jacobian columns with n derivative lanes each (n² lanes, which is
//! what K costs), this walk carries
//! - the absolute angular velocity ω, gravity, the frame's position and the lever velocity
//!   Σ jmᵢ q̇ᵢ with n lanes (for ∂L/∂q: one scalar L per chain), and
//! - the Jacobian columns jwᵢ, jmᵢ with a single lane, their derivative along q̇ (for pᵢ).
//!
//! Derivatives along q̇ of anything with n lanes are the dot product of its lanes with q̇, so
//! the two kinds of numbers meet without a second pass. The Jacobian of the right-hand side
//! (duals over duals) goes through this walk too.

use super::{Kinetics, cross_const, inertia_mul, re, scale, turn, turn_const};
use crate::design::Force;
use crate::engine::EvalInput;
use crate::real::{Jet, M3, Real, V3};

/// What is carried down the chain, in the current frame's axes.
#[derive(Clone, Copy)]
struct Carried<T: Real, const N: usize> {
    /// Absolute angular velocity of the frame: base rate plus the chain's rates.
    w: V3<Jet<T, N>>,
    /// dω₀/dt at fixed coordinates (only for a moving base).
    w0_dot: V3<T>,
    /// Apparent gravity.
    g: V3<Jet<T, N>>,
    /// Frame origin relative to the pivot.
    p: V3<Jet<T, N>>,
    /// Σ jmᵢ q̇ᵢ: the hinges' lever contribution to the origin's velocity.
    jm_u: V3<Jet<T, N>>,
    /// Jacobian columns with their derivative along q̇.
    jw: [V3<Jet<T, 1>>; N],
    jm: [V3<Jet<T, 1>>; N],
    jw_on: u32,
    jm_on: u32,
}

/// A jet's value with its derivative along `u`.
#[inline(always)]
fn along<T: Real, const N: usize>(x: Jet<T, N>, u: &[T]) -> Jet<T, 1> {
    let mut d = T::zero();
    for (dk, uk) in x.d.iter().zip(u) {
        d += *dk * *uk;
    }
    Jet { v: x.v, d: [d] }
}

#[inline(always)]
fn valong<T: Real, const N: usize>(x: &V3<Jet<T, N>>, u: &[T]) -> V3<Jet<T, 1>> {
    V3([along(x.0[0], u), along(x.0[1], u), along(x.0[2], u)])
}

/// M (first n rows and columns of `m_out`) and r = c + K q̇ (first n of `r_out`) of the
/// chain's own equations at fidelity `full` (no quadratic energy dropped, `inp.u` = `inp.qd`).
pub fn evaluate_rates<T: Real, const N: usize>(
    kin: &Kinetics,
    inp: &EvalInput<T>,
    spins: &[(usize, T, T)],
    m_out: &mut [[T; N]; N],
    r_out: &mut [T; N],
) {
    let n = kin.n;
    debug_assert!(N >= n);
    type J<T, const N: usize> = Jet<T, N>;
    let zero = J::<T, N>::zero();
    let vz = V3::<J<T, N>>::zero();
    let vz1 = V3::<Jet<T, 1>>::zero();
    let q: [J<T, N>; N] = std::array::from_fn(|i| {
        if i < n {
            Jet::variable(inp.q[i], i)
        } else {
            zero
        }
    });
    let u = &inp.qd[..n];

    let r = inp.world_from_base;
    let w_base = r.tmul_v(inp.base_rate);
    let moving = w_base.0.iter().any(|x| x.d[0] != T::zero());
    let g_world = V3([
        T::cst(inp.gravity[0]),
        T::cst(inp.gravity[1]),
        T::cst(inp.gravity[2]),
    ]);
    let g_base = M3(r.0.map(|row| row.map(|x| x.v))).tmul_v(&g_world);
    let mut st = Carried::<T, N> {
        w: V3(w_base.0.map(|x| J::<T, N>::constant(x.v))),
        w0_dot: V3(w_base.0.map(|x| x.d[0])),
        g: V3(g_base.0.map(J::<T, N>::constant)),
        p: vz,
        jm_u: vz,
        jw: [vz1; N],
        jm: [vz1; N],
        jw_on: 0,
        jm_on: 0,
    };
    let mut saved: Vec<(usize, Carried<T, N>)> = Vec::new();
    if kin.frames[0].save {
        saved.push((0, st));
    }

    // L = T − V with n lanes; p along q̇ (one lane); ∂ₜp; generalised forces.
    let mut lagrangian = zero;
    let mut p = [Jet::<T, 1>::zero(); N];
    let mut pt = [T::zero(); N];
    let mut qf = [T::zero(); N];
    for row in m_out.iter_mut().take(n) {
        for x in row.iter_mut().take(n) {
            *x = T::zero();
        }
    }

    for (fi, fr) in kin.frames.iter().enumerate().skip(1) {
        if fr.parent + 1 != fi {
            st = match saved.iter().rev().find(|(i, _)| *i == fr.parent) {
                Some((_, s)) => *s,
                None => unreachable!("the parent frame's state is saved at compile time"),
            };
        }
        if fr.origin_nonzero {
            for k in 0..3 {
                st.p.0[k] = st.p.0[k] + fr.origin[k];
            }
        }
        if let Some(jr) = &fr.joint {
            turn_const(&mut st.w, jr);
            turn_const(&mut st.g, jr);
            if !fr.at_pivot {
                turn_const(&mut st.p, jr);
            }
            if st.jm_on != 0 {
                turn_const(&mut st.jm_u, jr);
            }
            if moving {
                turn_const(&mut st.w0_dot, jr);
            }
            for i in 0..n {
                if st.jw_on & (1 << i) != 0 {
                    turn_const(&mut st.jw[i], jr);
                }
                if st.jm_on & (1 << i) != 0 {
                    turn_const(&mut st.jm[i], jr);
                }
            }
        }
        // Through the hinge. Most hinges turn by one coordinate (φ = a qⱼ + φ₀): then φ̇, the
        // gradient and the derivatives along q̇ are read off directly.
        let single = match (fr.angle.linear.as_slice(), fr.angle.quadratic.is_empty()) {
            ([(j, a)], true) => Some((*j, *a)),
            _ => None,
        };
        let phi = match single {
            Some((j, a)) => q[j] * a + fr.angle.constant,
            None => fr.angle.eval(&q[..n]),
        };
        let (s, c) = phi.sin_cos();
        let (s1, c1) = match single {
            Some((j, _)) => (
                Jet {
                    v: s.v,
                    d: [s.d[j] * u[j]],
                },
                Jet {
                    v: c.v,
                    d: [c.d[j] * u[j]],
                },
            ),
            None => (along(s, u), along(c, u)),
        };
        let (ia, ja) = match fr.axis {
            0 => (1, 2),
            1 => (2, 0),
            _ => (0, 1),
        };
        turn(&mut st.w, ia, ja, s, c);
        turn(&mut st.g, ia, ja, s, c);
        if !fr.at_pivot {
            turn(&mut st.p, ia, ja, s, c);
        }
        if st.jm_on != 0 {
            turn(&mut st.jm_u, ia, ja, s, c);
        }
        if moving {
            turn(&mut st.w0_dot, ia, ja, s.v, c.v);
        }
        for i in 0..n {
            if st.jw_on & (1 << i) != 0 {
                turn(&mut st.jw[i], ia, ja, s1, c1);
            }
            if st.jm_on & (1 << i) != 0 {
                turn(&mut st.jm[i], ia, ja, s1, c1);
            }
        }
        // The hinge's own columns, and its rate φ̇ = Σ ∂φ/∂qᵢ q̇ᵢ into ω (and the lever).
        let mut grad = [zero; N];
        let mut phi_dot = zero;
        match single {
            Some((j, a)) => {
                grad[j] = J::<T, N>::constant(T::cst(a));
                phi_dot = J::<T, N>::constant(u[j] * a);
            }
            None => {
                fr.angle.add_gradient(&q[..n], &mut grad[..n]);
                for i in 0..n {
                    if fr.reads & (1 << i) != 0 {
                        phi_dot += scale(grad[i], u[i]);
                    }
                }
            }
        }
        st.w.0[fr.axis] += phi_dot;
        let axp = if fr.at_pivot {
            vz
        } else {
            let p = &st.p.0;
            match fr.axis {
                0 => V3([zero, -p[2], p[1]]),
                1 => V3([p[2], zero, -p[0]]),
                _ => V3([-p[1], p[0], zero]),
            }
        };
        if !fr.at_pivot {
            st.jm_u = st.jm_u.add(&axp.scale(phi_dot));
        }
        let axp1 = valong(&axp, u);
        for i in 0..n {
            if fr.reads & (1 << i) == 0 || grad[i] == zero {
                continue;
            }
            let g1 = if single.is_some() {
                Jet {
                    v: grad[i].v,
                    d: [T::zero()],
                }
            } else {
                along(grad[i], u)
            };
            st.jw[i].0[fr.axis] += g1;
            st.jw_on |= 1 << i;
            if !fr.at_pivot {
                st.jm[i] = st.jm[i].add(&axp1.scale(g1));
                st.jm_on |= 1 << i;
            }
        }
        if fr.save {
            saved.push((fi, st));
        }
        let on = st.jw_on | st.jm_on;
        let jwr: [V3<T>; N] = std::array::from_fn(|i| re(&st.jw[i]));

        // Forces applied to bodies of this frame (generalised forces from real parts).
        for e in &fr.forces {
            let tau = e.torque(inp.q, &re(&st.p));
            for (i, qi) in qf.iter_mut().enumerate().take(n) {
                if st.jw_on & (1 << i) != 0 {
                    *qi += jwr[i].dot(&tau);
                }
            }
        }

        let Some(mp) = &fr.mass else {
            continue;
        };
        let m = mp.m;
        let (hv, hv_dot) = fr.rotor_momenta(spins, inp.spin_momentum);
        let has_spin = hv.iter().any(|x| *x != T::zero());
        let spin_rate = hv_dot.iter().any(|x| *x != T::zero());
        let cgp = if fr.at_pivot {
            V3::from_f64(mp.cg)
        } else {
            V3([
                st.p.0[0] + mp.cg[0],
                st.p.0[1] + mp.cg[1],
                st.p.0[2] + mp.cg[2],
            ])
        };
        // x × c
        let cross_c = |x: &V3<J<T, N>>| -> V3<J<T, N>> {
            if fr.at_pivot {
                cross_const(x, &mp.cg)
            } else {
                x.cross(&cgp)
            }
        };
        // Velocity of the centre of gravity, angular momentum, and A with pᵢ = jwᵢ·A − m jmᵢ·v.
        let v = cross_c(&st.w).sub(&st.jm_u);
        let iw = inertia_mul(mp, &st.w);
        let mut h = iw;
        if has_spin {
            for k in 0..3 {
                h.0[k].v += hv[k];
            }
        }
        let a = cross_c(&v).scale_f(-m).add(&h);
        let mut t_body = (v.dot(&v) * m + st.w.dot(&iw)) * 0.5;
        if has_spin {
            t_body += scale(st.w.0[0], hv[0]) + scale(st.w.0[1], hv[1]) + scale(st.w.0[2], hv[2]);
        }
        lagrangian += t_body;
        if fr.at_pivot {
            lagrangian += (st.g.0[0] * mp.cg[0] + st.g.0[1] * mp.cg[1] + st.g.0[2] * mp.cg[2]) * m;
        } else {
            lagrangian += st.g.dot(&cgp) * m;
        }
        let a1 = valong(&a, u);
        let v1 = valong(&v, u);
        let wd_terms = if moving {
            let cre = re(&cgp);
            let v0d = st.w0_dot.cross(&cre);
            let a_d = cre.cross(&v0d).scale_f(m).add(&inertia_mul(mp, &st.w0_dot));
            Some((v0d, a_d))
        } else {
            None
        };
        for i in 0..n {
            if on & (1 << i) == 0 {
                continue;
            }
            let lever = st.jm_on & (1 << i) != 0;
            let mut x = st.jw[i].dot(&a1);
            if lever {
                x -= st.jm[i].dot(&v1) * m;
            }
            p[i] += x;
            if let Some((v0d, a_d)) = &wd_terms {
                let mut x = jwr[i].dot(a_d);
                if lever {
                    x -= re(&st.jm[i]).dot(v0d) * m;
                }
                pt[i] += x;
            }
            if spin_rate {
                pt[i] += jwr[i].dot(&V3(hv_dot));
            }
        }
        // Mass matrix from the real parts of the Jacobians.
        let cre = re(&cgp);
        let jvr: [V3<T>; N] = std::array::from_fn(|i| {
            let x = jwr[i].cross(&cre);
            if st.jm_on & (1 << i) != 0 {
                x.sub(&re(&st.jm[i]))
            } else {
                x
            }
        });
        // Symmetric: the lower triangle here, mirrored at the end.
        for j in 0..n {
            if on & (1 << j) == 0 {
                continue;
            }
            let ijw = inertia_mul(mp, &jwr[j]);
            for i in j..n {
                if on & (1 << i) == 0 {
                    continue;
                }
                m_out[i][j] += jvr[i].dot(&jvr[j]) * m + jwr[i].dot(&ijw);
            }
        }
    }

    // Coordinate-space force elements.
    let mut damping = [T::zero(); N];
    for f in &kin.forces {
        match f {
            Force::Damper {
                expr, coefficient, ..
            } => {
                let mut g = [T::zero(); N];
                expr.add_gradient(inp.q, &mut g[..n]);
                let mut rate = T::zero();
                for i in 0..n {
                    rate += g[i] * u[i];
                }
                if rate == T::zero() {
                    continue;
                }
                for i in 0..n {
                    damping[i] -= g[i] * rate * *coefficient;
                }
            }
            Force::Spring {
                expr,
                stiffness,
                rest,
                preload,
                ..
            } => {
                let e = expr.eval(&q[..n]);
                let de = e - *rest;
                lagrangian -= de * de * (0.5 * stiffness) + e * *preload;
            }
            Force::Generalized {
                coordinate, torque, ..
            } => {
                qf[*coordinate] += torque.eval(inp.q);
            }
            Force::BodyForce { .. } => {}
        }
    }

    for i in 0..n {
        r_out[i] = qf[i] - pt[i] + lagrangian.d[i] - p[i].d[0] + damping[i];
        for j in i + 1..n {
            m_out[i][j] = m_out[j][i];
        }
    }
}
