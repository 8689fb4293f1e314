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

use super::walk::{Carried, clear, cross_cg};
use super::{BodyAxesChain, Frame, inertia_mul, pots_terms, re, scale};
use crate::dual::{Jet, Real, V3};
use crate::force_elements::{self, RateTerms, SpringsInto};
use crate::reference_engine::EvalInput;

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
    kin: &BodyAxesChain,
    inp: &EvalInput<T>,
    spins: &[(usize, T, T)],
    m_out: &mut [[T; N]; N],
    r_out: &mut [T; N],
) {
    let n = kin.n;
    debug_assert!(N >= n);
    type J<T, const N: usize> = Jet<T, N>;
    let zero = J::<T, N>::zero();
    let q: [J<T, N>; N] = Jet::variables(inp.q, n);
    let u = &inp.qd[..n];

    let (mut st, moving) = Carried::<T, N, 1>::at_base(inp);
    let mut saved: Vec<(usize, Carried<T, N, 1>)> = Vec::new();
    if kin.frames[0].save {
        saved.push((0, st));
    }

    // L = T − V with n lanes; p along q̇ (one lane); ∂ₜp; generalised forces.
    let mut lagrangian = zero;
    let mut p = [Jet::<T, 1>::zero(); N];
    let mut pt = [T::zero(); N];
    let mut qf = [T::zero(); N];
    clear(m_out, n);

    for (fi, fr) in kin.frames.iter().enumerate().skip(1) {
        st.enter_joint(fi, fr, &saved, n, moving, true);
        hinge(&mut st, fr, &q, u, n, moving);
        if fr.save {
            saved.push((fi, st));
        }
        let on = st.jw_on | st.jm_on;
        let jwr: [V3<T>; N] = std::array::from_fn(|i| re(&st.jw[i]));

        // Forces applied to bodies of this frame (generalised forces from real parts).
        st.add_body_forces(fr, inp.q, n, &mut qf);

        let Some(mp) = &fr.mass else {
            continue;
        };
        let m = mp.m;
        let (hv, hv_dot) = fr.rotor_momenta(spins, inp.spin_momentum);
        let has_spin = hv.iter().any(|x| *x != T::zero());
        let spin_rate = hv_dot.iter().any(|x| *x != T::zero());
        let cgp = st.cg_from_pivot(fr, mp);
        let cross_c = |x: &V3<J<T, N>>| cross_cg(fr, mp, &cgp, x);
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
        lagrangian += st.g_dot_cg(fr, mp, &cgp) * m;
        let a1 = valong(&a, u);
        let v1 = valong(&v, u);
        let wd_terms = st.moving_base_terms(moving, mp, &cgp);
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
        // Mass matrix from the real parts of the Jacobians. Symmetric: the lower triangle
        // here, mirrored at the end.
        st.add_mass_matrix(mp, &cgp, &jwr, n, on, |_| true, true, m_out);
    }

    // Coordinate-space force elements.
    let mut damping = [T::zero(); N];
    force_elements::add(
        &kin.forces,
        n,
        inp.q,
        &q,
        &mut AtRates {
            damping: &mut damping,
            u,
        },
        SpringsInto::Lagrangian,
        &mut lagrangian,
        &mut qf,
    );
    for link in &kin.links {
        lagrangian -= link.energy(&q[..n]);
    }

    for i in 0..n {
        r_out[i] = qf[i] - pt[i] + lagrangian.d[i] - p[i].d[0] + damping[i];
        for j in i + 1..n {
            m_out[i][j] = m_out[j][i];
        }
    }
    // Communicating pots: their M, K, c from the reference engine, r = c + K q̇.
    if let Some(terms) = pots_terms(kin, inp) {
        for i in 0..n {
            let mut r = terms.c[i];
            for k in 0..n {
                m_out[i][k] += terms.m[i * n + k];
                r += terms.k[i * n + k] * u[k];
            }
            r_out[i] += r;
        }
    }
}

/// The force elements' rate terms taken at the rates `u` (K is never formed): a damper's
/// −c ė ∇e, a servo's c (ṙ − q̇ᵢ).
struct AtRates<'a, T, const N: usize> {
    damping: &'a mut [T; N],
    u: &'a [T],
}

impl<T: Real, const N: usize> RateTerms<T> for AtRates<'_, T, N> {
    #[inline(always)]
    fn damper(&mut self, g: &[T], coefficient: f64) {
        let mut rate = T::zero();
        for (gi, ui) in g.iter().zip(self.u) {
            rate += *gi * *ui;
        }
        if rate == T::zero() {
            return;
        }
        for (d, gi) in self.damping.iter_mut().zip(g) {
            *d -= *gi * rate * coefficient;
        }
    }
    #[inline(always)]
    fn servo(&mut self, row: usize, g: &[T], damping: f64) {
        let mut rate = T::zero();
        for (gk, uk) in g.iter().zip(self.u) {
            rate += *gk * *uk;
        }
        self.damping[row] += rate * damping;
    }
}

/// Through frame `fr`'s hinge: the carried state turned by φ, the hinge's rate φ̇ added to ω
/// (and its lever to Σ jmᵢ q̇ᵢ), and the hinge's own columns with their derivative along q̇.
#[inline(always)]
fn hinge<T: Real, const N: usize>(
    st: &mut Carried<T, N, 1>,
    fr: &Frame,
    q: &[Jet<T, N>; N],
    u: &[T],
    n: usize,
    moving: bool,
) {
    type J<T, const N: usize> = Jet<T, N>;
    let zero = J::<T, N>::zero();
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
    st.through_hinge(fr, n, moving, true, (s, c), (s1, c1));
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
    let axp = st.hinge_lever(fr);
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
}
