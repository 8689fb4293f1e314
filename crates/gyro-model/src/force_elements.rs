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

use crate::design::{Design, Force, Hinge};
use crate::dual::{Jet, M3, Real, V3};

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
            Force::BodyForce { .. } | Force::LinkSpring { .. } => {}
        }
    }
}

/// A link spring's potential at the distance `d` of its attachment points:
/// V = T·(d − ℓ) + ½k(d − ℓ)² (tension T at the length ℓ, rate k).
#[inline(always)]
pub(crate) fn link_spring_energy<S: Real>(d: S, stiffness: f64, length: f64, tension: f64) -> S {
    let dl = d - S::cst(length);
    dl * S::cst(tension) + dl * dl * S::cst(0.5 * stiffness)
}

/// The distance between two points given relative to the same origin.
#[inline(always)]
pub(crate) fn distance<S: Real>(a: &V3<S>, b: &V3<S>) -> S {
    let d = a.sub(b);
    d.dot(&d).sqrt()
}

/// One joint on the way from the base to a link spring's end: origin in the parent's axes, the
/// constant rotation, the hinge.
#[derive(Clone, Debug)]
struct Step {
    origin: [f64; 3],
    rotation: Option<[[f64; 3]; 3]>,
    hinge: Option<Hinge>,
}

/// A link spring's two ends as paths of joints from the base: a short walk in base axes that
/// gives the attachment points' distance without the rest of the chain (the body-axes engines
/// carry no body's position in common axes, so they take the distance from here).
#[derive(Clone, Debug)]
pub(crate) struct LinkWalk {
    ends: [(Vec<Step>, [f64; 3]); 2],
    stiffness: f64,
    length: f64,
    tension: f64,
}

impl LinkWalk {
    /// The walks of a design's link springs among `forces`.
    pub(crate) fn of(d: &Design, forces: &[Force]) -> Vec<LinkWalk> {
        let path = |mut b: usize| {
            let mut steps = Vec::new();
            loop {
                let body = &d.bodies[b];
                let ident =
                    body.joint_rotation == [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
                steps.push(Step {
                    origin: body.joint_origin_m,
                    rotation: (!ident).then_some(body.joint_rotation),
                    hinge: body.hinge.clone(),
                });
                match body.parent {
                    Some(p) => b = p,
                    None => break,
                }
            }
            steps.reverse();
            steps
        };
        forces
            .iter()
            .filter_map(|f| match f {
                Force::LinkSpring {
                    bodies,
                    points,
                    stiffness,
                    length,
                    tension,
                    ..
                } => Some(LinkWalk {
                    ends: [(path(bodies[0]), points[0]), (path(bodies[1]), points[1])],
                    stiffness: *stiffness,
                    length: *length,
                    tension: *tension,
                }),
                _ => None,
            })
            .collect()
    }

    /// The spring's potential at q (base axes: the distance does not depend on the base's turn).
    #[inline(always)]
    pub(crate) fn energy<T: Real, const N: usize>(&self, q: &[Jet<T, N>]) -> Jet<T, N> {
        let point = |(steps, pt): &(Vec<Step>, [f64; 3])| {
            let mut r = M3::<Jet<T, N>>::identity();
            let mut p = V3::<Jet<T, N>>::zero();
            for s in steps {
                p = p.add(&r.mul_v(&V3::from_f64(s.origin)));
                if let Some(jr) = &s.rotation {
                    r = r.mul_m(&M3::from_f64(*jr));
                }
                if let Some(h) = &s.hinge {
                    r = r.rotate_about_axis(h.axis, h.angle.eval(q));
                }
            }
            p.add(&r.mul_v(&V3::from_f64(*pt)))
        };
        let d = distance(&point(&self.ends[0]), &point(&self.ends[1]));
        link_spring_energy(d, self.stiffness, self.length, self.tension)
    }
}
