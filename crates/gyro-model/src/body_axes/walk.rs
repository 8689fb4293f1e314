//! The per-frame setup both body-axes walks share ([`super::evaluate`] and
//! [`super::evaluate_rates`]): the base's rate and gravity in its own axes, the state carried down
//! the chain and restored at a branch, the step to a frame's hinge point and through its joint's
//! constant rotation, the turn through the hinge, the hinge's lever, and the centre of gravity's
//! and the mass matrix's terms of a frame's bodies. The walks differ only in what they carry
//! along the Jacobian columns (`L` derivative lanes) and in the energies they form.

use super::{EvalInput, Frame, MassProps, cross_const, inertia_mul, re, turn, turn_const};
use crate::dual::{Jet, M3, Real, V3};

/// What is carried down the chain, in the current frame's axes. The Jacobian columns have `L`
/// derivative lanes: `N` (every coordinate direction) in `evaluate`, one (along q̇) in
/// `evaluate_rates`.
#[derive(Clone, Copy)]
pub(super) struct Carried<T: Real, const N: usize, const L: usize> {
    /// Angular velocity: the base rate ω₀ in `evaluate`; the absolute rate (base rate plus the
    /// chain's rates) in `evaluate_rates`.
    pub(super) w: V3<Jet<T, N>>,
    /// dω₀/dt at fixed coordinates (only for a moving base).
    pub(super) w0_dot: V3<T>,
    /// Apparent gravity.
    pub(super) g: V3<Jet<T, N>>,
    /// Frame origin relative to the pivot.
    pub(super) p: V3<Jet<T, N>>,
    /// Σ jmᵢ q̇ᵢ: the hinges' lever contribution to the origin's velocity (`evaluate_rates`
    /// only: it stays zero, and is not turned, in `evaluate`).
    pub(super) jm_u: V3<Jet<T, N>>,
    /// Angular velocity Jacobian columns, and the lever terms Σ (a × p_hinge) ∂φ/∂qᵢ.
    pub(super) jw: [V3<Jet<T, L>>; N],
    pub(super) jm: [V3<Jet<T, L>>; N],
    /// Columns of jw (jm) that may be non-zero.
    pub(super) jw_on: u32,
    pub(super) jm_on: u32,
}

impl<T: Real, const N: usize> Carried<T, N, N> {
    /// The hinge's own Jacobian columns (`evaluate`'s, with a lane per coordinate): its axis,
    /// and its lever off the pivot, times ∂φ/∂qᵢ for the n coordinates `q`.
    #[inline(always)]
    pub(super) fn add_hinge_columns(&mut self, fr: &Frame, q: &[Jet<T, N>]) {
        let zero = Jet::<T, N>::zero();
        let n = q.len();
        let mut grad = [zero; N];
        fr.angle.add_gradient(q, &mut grad[..n]);
        let axp = self.hinge_lever(fr);
        for i in 0..n {
            if fr.reads & (1 << i) == 0 || grad[i] == zero {
                continue;
            }
            self.jw[i].0[fr.axis] += grad[i];
            self.jw_on |= 1 << i;
            if !fr.at_pivot {
                self.jm[i] = self.jm[i].add(&axp.scale(grad[i]));
                self.jm_on |= 1 << i;
            }
        }
    }
}

impl<T: Real, const N: usize, const L: usize> Carried<T, N, L> {
    /// At the base: its rate and gravity in its own axes, nothing else yet; and whether the
    /// base moves (its rate changes in time).
    #[inline(always)]
    pub(super) fn at_base(inp: &EvalInput<T>) -> (Self, bool) {
        let vz = V3::<Jet<T, N>>::zero();
        let vzl = V3::<Jet<T, L>>::zero();
        let r = inp.world_from_base;
        let w_base = r.tmul_v(inp.base_rate);
        let moving = w_base.0.iter().any(|x| x.d[0] != T::zero());
        let g_world = V3(inp.gravity);
        let g_base = M3(r.0.map(|row| row.map(|x| x.v))).tmul_v(&g_world);
        let st = Carried {
            w: V3(w_base.0.map(|x| Jet::<T, N>::constant(x.v))),
            w0_dot: V3(w_base.0.map(|x| x.d[0])),
            g: V3(g_base.0.map(Jet::<T, N>::constant)),
            p: vz,
            jm_u: vz,
            jw: [vzl; N],
            jm: [vzl; N],
            jw_on: 0,
            jm_on: 0,
        };
        (st, moving)
    }

    /// Into frame `fr`'s joint axes: the parent's state (restored from `saved` when the parent is
    /// not the frame just walked), moved to the hinge point and turned by the joint's constant
    /// rotation. `lever_rate`: carry `jm_u` too.
    #[inline(always)]
    pub(super) fn enter_joint(
        &mut self,
        fi: usize,
        fr: &Frame,
        saved: &[(usize, Self)],
        n: usize,
        moving: bool,
        lever_rate: bool,
    ) {
        if fr.parent + 1 != fi {
            *self = match saved.iter().rev().find(|(i, _)| *i == fr.parent) {
                Some((_, s)) => *s,
                None => unreachable!("the parent frame's state is saved at compile time"),
            };
        }
        if fr.origin_nonzero {
            for k in 0..3 {
                self.p.0[k] = self.p.0[k] + fr.origin[k];
            }
        }
        if let Some(jr) = &fr.joint {
            turn_const(&mut self.w, jr);
            turn_const(&mut self.g, jr);
            if !fr.at_pivot {
                turn_const(&mut self.p, jr);
            }
            if lever_rate && self.jm_on != 0 {
                turn_const(&mut self.jm_u, jr);
            }
            if moving {
                turn_const(&mut self.w0_dot, jr);
            }
            for i in 0..n {
                if self.jw_on & (1 << i) != 0 {
                    turn_const(&mut self.jw[i], jr);
                }
                if self.jm_on & (1 << i) != 0 {
                    turn_const(&mut self.jm[i], jr);
                }
            }
        }
    }

    /// Through the hinge: every carried vector turned by φ = (sin φ, cos φ) about the hinge
    /// axis, the columns by (`s1`, `c1`), the same angle with the columns' lanes.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn through_hinge(
        &mut self,
        fr: &Frame,
        n: usize,
        moving: bool,
        lever_rate: bool,
        (s, c): (Jet<T, N>, Jet<T, N>),
        (s1, c1): (Jet<T, L>, Jet<T, L>),
    ) {
        let (ia, ja) = match fr.axis {
            0 => (1, 2),
            1 => (2, 0),
            _ => (0, 1),
        };
        turn(&mut self.w, ia, ja, s, c);
        turn(&mut self.g, ia, ja, s, c);
        if !fr.at_pivot {
            turn(&mut self.p, ia, ja, s, c);
        }
        if lever_rate && self.jm_on != 0 {
            turn(&mut self.jm_u, ia, ja, s, c);
        }
        if moving {
            turn(&mut self.w0_dot, ia, ja, s.v, c.v);
        }
        for i in 0..n {
            if self.jw_on & (1 << i) != 0 {
                turn(&mut self.jw[i], ia, ja, s1, c1);
            }
            if self.jm_on & (1 << i) != 0 {
                turn(&mut self.jm[i], ia, ja, s1, c1);
            }
        }
    }

    /// The hinge's lever e_axis × p (zero for a frame at the pivot).
    #[inline(always)]
    pub(super) fn hinge_lever(&self, fr: &Frame) -> V3<Jet<T, N>> {
        let zero = Jet::<T, N>::zero();
        if fr.at_pivot {
            V3::zero()
        } else {
            let p = &self.p.0;
            match fr.axis {
                0 => V3([zero, -p[2], p[1]]),
                1 => V3([p[2], zero, -p[0]]),
                _ => V3([-p[1], p[0], zero]),
            }
        }
    }

    /// Generalised forces (real parts) of the forces applied to bodies of frame `fr`.
    #[inline(always)]
    pub(super) fn add_body_forces(&self, fr: &Frame, q: &[T], n: usize, qf: &mut [T; N]) {
        for e in &fr.forces {
            let tau = e.torque(q, &re(&self.p));
            for (i, qi) in qf.iter_mut().enumerate().take(n) {
                if self.jw_on & (1 << i) != 0 {
                    *qi += re(&self.jw[i]).dot(&tau);
                }
            }
        }
    }

    /// The centre of gravity of frame `fr`'s bodies, from the pivot: a constant in frame axes
    /// when the frame turns about the pivot (then every product with it is a product with plain
    /// numbers).
    #[inline(always)]
    pub(super) fn cg_from_pivot(&self, fr: &Frame, mp: &MassProps) -> V3<Jet<T, N>> {
        if fr.at_pivot {
            V3::from_f64(mp.cg)
        } else {
            V3([
                self.p.0[0] + mp.cg[0],
                self.p.0[1] + mp.cg[1],
                self.p.0[2] + mp.cg[2],
            ])
        }
    }

    /// g·c, gravity's product with the centre of gravity from the pivot (`cgp`).
    #[inline(always)]
    pub(super) fn g_dot_cg(&self, fr: &Frame, mp: &MassProps, cgp: &V3<Jet<T, N>>) -> Jet<T, N> {
        if fr.at_pivot {
            self.g.0[0] * mp.cg[0] + self.g.0[1] * mp.cg[1] + self.g.0[2] * mp.cg[2]
        } else {
            self.g.dot(cgp)
        }
    }

    /// The moving base's terms of ∂ₜp: the velocity ω̇₀ × c and A_d = m c × (ω̇₀ × c) + I ω̇₀
    /// (`None` for a base whose rate is constant).
    #[inline(always)]
    pub(super) fn moving_base_terms(
        &self,
        moving: bool,
        mp: &MassProps,
        cgp: &V3<Jet<T, N>>,
    ) -> Option<(V3<T>, V3<T>)> {
        if moving {
            let cre = re(cgp);
            let v0d = self.w0_dot.cross(&cre);
            let a_d = cre
                .cross(&v0d)
                .scale_f(mp.m)
                .add(&inertia_mul(mp, &self.w0_dot));
            Some((v0d, a_d))
        } else {
            None
        }
    }

    /// Adds frame `fr`'s bodies to the mass matrix, from the real parts of the Jacobians:
    /// Mᵢⱼ += m jvᵢ·jvⱼ + jwᵢ·I jwⱼ over the columns `on` that `keep` keeps; only the lower
    /// triangle (i ≥ j) when `lower` (the caller mirrors it).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn add_mass_matrix(
        &self,
        mp: &MassProps,
        cgp: &V3<Jet<T, N>>,
        jwr: &[V3<T>; N],
        n: usize,
        on: u32,
        keep: impl Fn(usize) -> bool,
        lower: bool,
        m_out: &mut [[T; N]; N],
    ) {
        let cre = re(cgp);
        let jvr: [V3<T>; N] = std::array::from_fn(|i| {
            let x = jwr[i].cross(&cre);
            if self.jm_on & (1 << i) != 0 {
                x.sub(&re(&self.jm[i]))
            } else {
                x
            }
        });
        for j in 0..n {
            if on & (1 << j) == 0 || !keep(j) {
                continue;
            }
            let ijw = inertia_mul(mp, &jwr[j]);
            let first = if lower { j } else { 0 };
            for i in first..n {
                if on & (1 << i) == 0 || !keep(i) {
                    continue;
                }
                m_out[i][j] += jvr[i].dot(&jvr[j]) * mp.m + jwr[i].dot(&ijw);
            }
        }
    }
}

/// x × c, c the centre of gravity from the pivot (`cgp`, or the constant `mp.cg` at the pivot).
#[inline(always)]
pub(super) fn cross_cg<T: Real, const N: usize>(
    fr: &Frame,
    mp: &MassProps,
    cgp: &V3<Jet<T, N>>,
    x: &V3<Jet<T, N>>,
) -> V3<Jet<T, N>> {
    if fr.at_pivot {
        cross_const(x, &mp.cg)
    } else {
        x.cross(cgp)
    }
}

/// Zeroes the first `n` rows and columns.
#[inline(always)]
pub(super) fn clear<T: Real, const N: usize>(m: &mut [[T; N]; N], n: usize) {
    for row in m.iter_mut().take(n) {
        for x in row.iter_mut().take(n) {
            *x = T::zero();
        }
    }
}
