//! The coordinate-space force elements, evaluated once for every engine: dampers, springs,
//! generalised forces and finite-gain servos act on the coordinates directly, so their terms do
//! not depend on how an engine walks the chain (body forces, which act at a point of a body,
//! are each engine's own).
//!
//! Each element's generalised force is q₀(q) + D(q) q̇: springs go into the potential V,
//! generalised forces and a servo's stiffness into Q, and the rate-proportional parts D (a
//! damper's −c ∇e ∇eᵀ, a servo's damping row) go to the engine's [`RateTerms`], which forms
//! them its own way: into K for the equations in K form, or at the rates u when K is never
//! formed (`full` fidelity's rate walk).

use crate::design::Force;
use crate::dual::{Jet, Real};

/// Where an engine takes the rate-proportional parts of the force elements.
pub(crate) trait RateTerms<T: Real> {
    /// A damper on e(q) with coefficient c: the force −c ė ∇e, with ∇e = `grad`.
    fn damper(&mut self, grad: &[T], coefficient: f64);
    /// A finite-gain servo on coordinate `row`: the torque c (ṙ − q̇ᵢ), with ∇(r − qᵢ) = `grad`.
    fn servo(&mut self, row: usize, grad: &[T], damping: f64);
}

/// Where the springs' energy goes: into V (`Potential`) or subtracted from a Lagrangian.
#[derive(Clone, Copy)]
pub(crate) enum SpringsInto {
    Potential,
    Lagrangian,
}

/// The coordinate-space elements of `forces` at q (`q_real`, and `q` as duals for the springs'
/// energy): springs into `energy` (V, or −V into a Lagrangian), generalised forces and servo
/// stiffness into `qf`, the rate terms into `rates`. Body forces are skipped.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn add<T: Real, const N: usize>(
    forces: &[Force],
    n: usize,
    q_real: &[T],
    q: &[Jet<T, N>; N],
    rates: &mut impl RateTerms<T>,
    springs_into: SpringsInto,
    energy: &mut Jet<T, N>,
    qf: &mut [T; N],
) {
    for f in forces {
        match f {
            Force::Damper {
                expr, coefficient, ..
            } => {
                let mut g = [T::zero(); N];
                expr.add_gradient(&q_real[..n], &mut g[..n]);
                rates.damper(&g[..n], *coefficient);
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
                let spring = de * de * (0.5 * stiffness) + e * *preload;
                match springs_into {
                    SpringsInto::Potential => *energy += spring,
                    SpringsInto::Lagrangian => *energy -= spring,
                }
            }
            Force::Generalized {
                coordinate, torque, ..
            } => {
                qf[*coordinate] += torque.eval(&q_real[..n]);
            }
            Force::Servo {
                coordinate,
                relation,
                stiffness,
                damping,
                ..
            } => {
                let i = *coordinate;
                qf[i] -= (q_real[i] - relation.eval(&q_real[..n])) * *stiffness;
                let mut g = [T::zero(); N];
                relation.add_gradient(&q_real[..n], &mut g[..n]);
                g[i] -= T::one();
                rates.servo(i, &g[..n], *damping);
            }
            Force::BodyForce { .. } => {}
        }
    }
}
