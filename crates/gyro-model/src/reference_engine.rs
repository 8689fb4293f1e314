//! The reference engine, in world axes: from a kinematic chain to Lagrange's equations, by exact
//! automatic differentiation.
//!
//! For every body, the absolute angular velocity and the velocity of the centre of gravity
//! (relative to the pivot, in a non-rotating frame that follows it) are linear in the rates:
//! ω = ω₀ + Σ Jwᵢ q̇ᵢ, v = ω₀ × c + Σ Jvᵢ q̇ᵢ, with columns built recursively down the chain
//! (Jwᵢ = Σ_hinges a_h ∂φ_h/∂qᵢ). So T = ½ q̇ᵀM q̇ + bᵀq̇ + T₀ with
//! M = Σ m JvᵀJv + JwᵀIJw, b = Σ m Jvᵀv₀ + Jwᵀ(Iω₀ + H ŝ), T₀ = ½m|v₀|² + ½ω₀ᵀIω₀ + H ŝ·ω₀
//! (the rotor's held momentum H enters linearly: Routh reduction of the spin, Beghin §25).
//!
//! Lagrange's equation for coordinate i, d/dt ∂L/∂q̇ᵢ − ∂L/∂qᵢ = Qᵢ, becomes
//!   M q̈ = c + K q̇,
//!   cᵢ = Qᵢ − ∂ₜp₂ᵢ − ∂ₜbᵢ + ∂T₂/∂qᵢ + ∂T₀/∂qᵢ − ∂V/∂qᵢ,
//!   Kᵢₖ = −∂p₂ᵢ/∂qₖ − (∂bᵢ/∂qₖ − ∂bₖ/∂qᵢ) − Cᵢₖ,
//! where p₂ = M u is the momentum of the quadratic part at the velocity `u` (u = q̇ in `full`
//! fidelity; with the precessional coordinates' rates zeroed in `gyroscopic` fidelity, where
//! their rows of p₂ and M vanish). One pass of the kinematics on dual numbers carrying n + 1
//! directions (the n coordinates and time) gives every derivative above; M comes from the
//! velocity Jacobians' real parts. No second-order duals, no finite differences.
//!
//! The equations are formed here for *all* coordinates, servo-driven ones included; dropping the
//! driven rows and folding their columns is the caller's step, done after (Beghin ch. I).
//!
//! This world-axes form is the reference: the model evaluates the same equations in body axes
//! (`body_axes`), about 4 times cheaper, and the tests hold the two together to round-off.

use crate::design::{Body, Design, Force, Hinge, Pots, Root, Tank};
use crate::dual::{Jet, M3, Real, V3};
use crate::force_elements::{self, RateTerms, SpringsInto};

/// The immutable, index-based form of a design's chain that the engine walks.
#[derive(Clone, Debug)]
pub struct Chain {
    pub n: usize,
    pub bodies: Vec<ChainBody>,
    pub forces: Vec<Force>,
    /// Communicating pots (their carriers are bodies of the chain).
    pub pots: Vec<Pots>,
    /// Liquid tanks (their carriers are bodies of the chain).
    pub tanks: Vec<Tank>,
    pub ship_root: bool,
}

#[derive(Clone, Debug)]
pub struct ChainBody {
    pub parent: Option<usize>,
    pub origin: [f64; 3],
    pub joint_rotation: Option<[[f64; 3]; 3]>,
    pub hinge: Option<Hinge>,
    pub mass: f64,
    pub cg: [f64; 3],
    pub inertia: [[f64; 3]; 3],
    pub rotor_axis: Option<[f64; 3]>,
    /// Whether the body contributes energy at all (massless gimbals are skipped).
    pub physical: bool,
}

impl Chain {
    pub fn from_design(d: &Design, include_force: impl Fn(&Force) -> bool) -> Chain {
        let bodies = d
            .bodies
            .iter()
            .map(|b: &Body| {
                let ident = b.joint_rotation == [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
                let physical = b.mass_kg > 0.0
                    || b.inertia_kg_m2.iter().flatten().any(|x| *x != 0.0)
                    || b.rotor.is_some();
                ChainBody {
                    parent: b.parent,
                    origin: b.joint_origin_m,
                    joint_rotation: if ident { None } else { Some(b.joint_rotation) },
                    hinge: b.hinge.clone(),
                    mass: b.mass_kg,
                    cg: b.cg_m,
                    inertia: b.inertia_kg_m2,
                    rotor_axis: b.rotor.as_ref().map(|r| r.axis),
                    physical,
                }
            })
            .collect();
        Chain {
            n: d.coordinates.len(),
            bodies,
            forces: d
                .forces
                .iter()
                .filter(|f| include_force(f))
                .cloned()
                .collect(),
            pots: d.pots.clone(),
            tanks: d.tanks.clone(),
            ship_root: d.root == Root::Ship,
        }
    }
}

/// Inputs of one evaluation.
pub struct EvalInput<'a, T: Real> {
    /// All coordinates (servo-driven ones filled from their relations).
    pub q: &'a [T],
    /// All rates.
    pub qd: &'a [T],
    /// Velocity at which the quadratic kinetic energy is taken (see module doc).
    pub u: &'a [T],
    /// Rows whose quadratic kinetic energy is dropped (gyroscopic fidelity), or empty.
    pub drop_quadratic: &'a [bool],
    /// Spin momentum per body, N·m·s (0 without rotor).
    pub spin_momentum: &'a [f64],
    pub world_from_base: &'a M3<Jet<T, 1>>,
    pub base_rate: &'a V3<Jet<T, 1>>,
    /// Apparent gravity, world axes (an input like the base motion, so a tape can take it).
    pub gravity: [T; 3],
}

/// Outputs: M (n×n, row-major), K (n×n), c (n), and the energies [T₂ (at `u`), T₀, V], J.
pub struct EvalOutput<'a, T: Real> {
    pub m: &'a mut [T],
    pub k: &'a mut [T],
    pub c: &'a mut [T],
    pub energies: [T; 3],
}

#[derive(Clone, Copy)]
struct BodyKin<S, const N: usize> {
    r: M3<S>,
    p: V3<S>,
    jw: [V3<S>; N],
    jm: [V3<S>; N],
}

#[inline(always)]
fn embed_time<T: Real, const N: usize>(x: Jet<T, 1>, slot: usize) -> Jet<T, N> {
    let mut d = [T::zero(); N];
    d[slot] = x.d[0];
    Jet { v: x.v, d }
}

/// Forms M, K, c for all coordinates. `N` must be at least `chain.n + 1`; direction `n` is time.
pub fn evaluate<T: Real, const N: usize>(
    chain: &Chain,
    inp: &EvalInput<T>,
    out: &mut EvalOutput<T>,
) {
    let n = chain.n;
    debug_assert!(N > n);
    type S<T, const N: usize> = Jet<T, N>;
    let zero = S::<T, N>::zero();
    let (q, base_r, w0) = variables::<T, N>(inp, n);

    let mut p2 = [zero; N];
    let mut b = [zero; N];
    let mut t2 = zero;
    let mut t0 = zero;
    let mut v = zero;
    for x in out.m.iter_mut() {
        *x = T::zero();
    }
    let mut kin: Vec<BodyKin<S<T, N>, N>> = Vec::with_capacity(chain.bodies.len());
    let vz = V3::<S<T, N>>::zero();
    for (bi, body) in chain.bodies.iter().enumerate() {
        let k = body_kinematics(&kin, body, &q, n, &base_r);
        kin.push(k);
        let k = &kin[bi];
        let (r_b, p_b, jw, jm) = (&k.r, &k.p, &k.jw, &k.jm);
        if !body.physical {
            continue;
        }
        let m = body.mass;
        let c_w = p_b.add(&r_b.mul_v(&V3::from_f64(body.cg)));
        let ib = M3::<S<T, N>>::from_f64(body.inertia);
        let iw = |x: &V3<S<T, N>>| r_b.mul_v(&ib.mul_v(&r_b.tmul_v(x)));
        let jv: [V3<S<T, N>>; N] = std::array::from_fn(|i| {
            if i < n {
                jw[i].cross(&c_w).sub(&jm[i])
            } else {
                vz
            }
        });
        let v0 = w0.cross(&c_w);
        let mut w_u = vz;
        let mut v_u = vz;
        for i in 0..n {
            let ui = S::<T, N>::constant(inp.u[i]);
            if inp.u[i] != T::zero() {
                w_u = w_u.add(&jw[i].scale(ui));
                v_u = v_u.add(&jv[i].scale(ui));
            }
        }
        let h_u = iw(&w_u);
        let iw0 = iw(&w0);
        let hs = inp.spin_momentum[bi];
        let mut h0 = iw0;
        let mut spin_term = zero;
        if let Some(ax) = body.rotor_axis {
            let s_w = r_b.mul_v(&V3::from_f64(ax));
            h0 = h0.add(&s_w.scale_f(hs));
            spin_term = s_w.dot(&w0) * hs;
        }
        for i in 0..n {
            if !inp.drop_quadratic.is_empty() && inp.drop_quadratic[i] {
                // no quadratic momentum for this row
            } else {
                p2[i] += jv[i].dot(&v_u) * m + jw[i].dot(&h_u);
            }
            b[i] += jv[i].dot(&v0) * m + jw[i].dot(&h0);
        }
        t2 += (v_u.dot(&v_u) * m + w_u.dot(&h_u)) * 0.5;
        t0 += (v0.dot(&v0) * m + w0.dot(&iw0)) * 0.5 + spin_term;
        v -= V3(inp.gravity.map(Jet::constant)).dot(&c_w) * m;
        // Mass matrix from the real parts of the Jacobians.
        let rr = M3(r_b.0.map(|row| row.map(|x| x.v)));
        let ibr = M3::<T>::from_f64(body.inertia);
        let jvr: [V3<T>; N] = std::array::from_fn(|i| V3(jv[i].0.map(|x| x.v)));
        let jwr: [V3<T>; N] = std::array::from_fn(|i| V3(jw[i].0.map(|x| x.v)));
        for j in 0..n {
            if inp.drop_quadratic.get(j).copied().unwrap_or(false) {
                continue;
            }
            let ijw = rr.mul_v(&ibr.mul_v(&rr.tmul_v(&jwr[j])));
            for i in 0..n {
                if inp.drop_quadratic.get(i).copied().unwrap_or(false) {
                    continue;
                }
                out.m[i * n + j] += jvr[i].dot(&jvr[j]) * m + jwr[i].dot(&ijw);
            }
        }
    }

    let terms = pots::Terms {
        p2: &mut p2,
        b: &mut b,
        t2: &mut t2,
        t0: &mut t0,
        v: &mut v,
        m: &mut *out.m,
    };
    pots::add_liquids(chain, &kin, &q, inp, &w0, terms);

    // Generalised forces.
    let mut qf = [T::zero(); N];
    for x in out.k.iter_mut() {
        *x = T::zero();
    }
    generalised_forces(chain, inp.q, &q, &kin, out.k, &mut v, &mut qf);

    out.energies = [t2.v, t0.v, v.v];
    for i in 0..n {
        out.c[i] = qf[i] - p2[i].d[n] - b[i].d[n] + t2.d[i] + t0.d[i] - v.d[i];
        for k in 0..n {
            out.k[i * n + k] -= p2[i].d[k] + b[i].d[k] - b[k].d[i];
        }
    }
}

/// The coordinates as dual variables (directions 0..n, time at n), and the base's rotation
/// and rate with their time derivatives in direction n.
#[allow(clippy::type_complexity)]
#[inline(always)]
fn variables<T: Real, const N: usize>(
    inp: &EvalInput<T>,
    n: usize,
) -> ([Jet<T, N>; N], M3<Jet<T, N>>, V3<Jet<T, N>>) {
    let q: [Jet<T, N>; N] = Jet::variables(inp.q, n);
    let base_r = M3(inp
        .world_from_base
        .0
        .map(|row| row.map(|x| embed_time::<T, N>(x, n))));
    let w0 = V3(inp.base_rate.0.map(|x| embed_time::<T, N>(x, n)));
    (q, base_r, w0)
}

/// One body's rotation, joint position and velocity Jacobian columns, from its parent's (already
/// in `kin`) through its joint and hinge.
#[inline(always)]
fn body_kinematics<T: Real, const N: usize>(
    kin: &[BodyKin<Jet<T, N>, N>],
    body: &ChainBody,
    q: &[Jet<T, N>; N],
    n: usize,
    base_r: &M3<Jet<T, N>>,
) -> BodyKin<Jet<T, N>, N> {
    let zero = Jet::<T, N>::zero();
    let vz = V3::<Jet<T, N>>::zero();
    // Start from the parent's kinematics (one copy) and extend it.
    let mut k = match body.parent {
        Some(pi) => kin[pi],
        None => BodyKin {
            r: *base_r,
            p: vz,
            jw: [vz; N],
            jm: [vz; N],
        },
    };
    k.p = k.p.add(&k.r.mul_v(&V3::from_f64(body.origin)));
    if let Some(jr) = &body.joint_rotation {
        k.r = k.r.mul_m(&M3::from_f64(*jr));
    }
    if let Some(h) = &body.hinge {
        let phi = h.angle.eval(&q[..n]);
        let mut grad = [zero; N];
        h.angle.add_gradient(&q[..n], &mut grad[..n]);
        let a = k.r.col(h.axis);
        let axp = a.cross(&k.p);
        for i in 0..n {
            if grad[i] != zero {
                k.jw[i] = k.jw[i].add(&a.scale(grad[i]));
                k.jm[i] = k.jm[i].add(&axp.scale(grad[i]));
            }
        }
        k.r = k.r.rotate_about_axis(h.axis, phi);
    }
    k
}

/// The equations' K (n × n, row-major), where the force elements' rate terms go in K form.
struct FlatK<'a, T> {
    k: &'a mut [T],
    n: usize,
}

impl<T: Real> RateTerms<T> for FlatK<'_, T> {
    /// −c ∇e ∇eᵀ.
    fn damper(&mut self, g: &[T], coefficient: f64) {
        for (i, &gi) in g.iter().enumerate() {
            for (k, &gk) in g.iter().enumerate() {
                self.k[i * self.n + k] -= gi * gk * coefficient;
            }
        }
    }
    /// The servo's row: c ∇(r − qᵢ).
    fn servo(&mut self, row: usize, g: &[T], damping: f64) {
        for (k, &gk) in g.iter().enumerate() {
            self.k[row * self.n + k] += gk * damping;
        }
    }
}

/// The force elements: the coordinate-space ones (`force_elements`: dampers into K, springs
/// into V, generalised forces and servos into Q), body forces, their moments about the pivot
/// on each body's Jacobian, and springs between two bodies, into V from the distance of their
/// points as this walk poses them.
fn generalised_forces<T: Real, const N: usize>(
    chain: &Chain,
    q_real: &[T],
    q: &[Jet<T, N>; N],
    kin: &[BodyKin<Jet<T, N>, N>],
    k_out: &mut [T],
    v: &mut Jet<T, N>,
    qf: &mut [T; N],
) {
    let n = chain.n;
    force_elements::add(
        &chain.forces,
        n,
        q_real,
        q,
        &mut FlatK { k: k_out, n },
        SpringsInto::Potential,
        v,
        qf,
    );
    for f in &chain.forces {
        if let Force::BodyForce {
            body,
            direction,
            force_n,
            point,
            ..
        } = f
        {
            let k = &kin[*body];
            let pb = V3([
                point[0].eval(&q[..n]),
                point[1].eval(&q[..n]),
                point[2].eval(&q[..n]),
            ]);
            let r_p = k.p.add(&k.r.mul_v(&pb));
            let f_w = k.r.mul_v(&V3::from_f64(*direction)).scale_f(*force_n);
            let tau = r_p.cross(&f_w);
            for (i, qi) in qf.iter_mut().enumerate().take(n) {
                *qi += k.jw[i].dot(&tau).v;
            }
        }
        if let Force::LinkSpring {
            bodies,
            points,
            stiffness,
            length,
            tension,
            ..
        } = f
        {
            // The attachment points from this walk's own poses (world axes).
            let at = |e: usize| {
                let k = &kin[bodies[e]];
                k.p.add(&k.r.mul_v(&V3::from_f64(points[e])))
            };
            let d = force_elements::distance(&at(0), &at(1));
            *v += force_elements::link_spring_energy(d, *stiffness, *length, *tension);
        }
    }
}

/// Calls `evaluate` with a jet width N ≥ n + 1 from a few buckets (unused directions stay zero).
/// Buckets rather than one instantiation per size keep the compile time of the generic engine
/// reasonable; the waste is at most a third of the derivative work.
macro_rules! dispatch_n {
    ($n:expr, $f:ident, $($arg:expr),*) => {
        match $n + 1 {
            0..=2 => $f::<_, 2>($($arg),*),
            3 => $f::<_, 3>($($arg),*),
            4 => $f::<_, 4>($($arg),*),
            5 => $f::<_, 5>($($arg),*),
            6..=7 => $f::<_, 7>($($arg),*),
            8..=10 => $f::<_, 10>($($arg),*),
            11..=13 => $f::<_, 13>($($arg),*),
            _ => $f::<_, 16>($($arg),*),
        }
    };
}

mod pots;
mod tank;

/// The liquids' (communicating pots', tanks') share of M, K, c and the energies, added into
/// `out` (for the body-axes engine, which walks the rest of the chain its own way). Nothing
/// without liquids.
pub fn evaluate_pots_any<T: Real>(chain: &Chain, inp: &EvalInput<T>, out: &mut EvalOutput<T>) {
    if !chain.pots.is_empty() || !chain.tanks.is_empty() {
        dispatch_n!(chain.n, evaluate_pots, chain, inp, out)
    }
}

fn evaluate_pots<T: Real, const N: usize>(
    chain: &Chain,
    inp: &EvalInput<T>,
    out: &mut EvalOutput<T>,
) {
    pots::evaluate::<T, N>(chain, inp, out)
}

/// Largest chain the engine compiles for.
pub const MAX_COORDINATES: usize = 15;

/// Evaluates for any supported chain size.
pub fn evaluate_any<T: Real>(chain: &Chain, inp: &EvalInput<T>, out: &mut EvalOutput<T>) {
    dispatch_n!(chain.n, evaluate, chain, inp, out)
}

/// Poses of every body for display and recording: world_from_body rotation and the body
/// origin's position relative to the pivot, in world axes (plain `f64`).
pub fn body_poses(
    chain: &Chain,
    q: &[f64],
    world_from_base: &M3<f64>,
) -> Vec<([[f64; 3]; 3], [f64; 3])> {
    let mut out: Vec<([[f64; 3]; 3], [f64; 3])> = Vec::with_capacity(chain.bodies.len());
    for body in &chain.bodies {
        let (r_par, p_par) = match body.parent {
            Some(pi) => (M3(out[pi].0), V3(out[pi].1)),
            None => (*world_from_base, V3::zero()),
        };
        let p_b = p_par.add(&r_par.mul_v(&V3::from_f64(body.origin)));
        let r_joint = match &body.joint_rotation {
            Some(jr) => r_par.mul_m(&M3::from_f64(*jr)),
            None => r_par,
        };
        let r_b = match &body.hinge {
            Some(h) => r_joint.rotate_about_axis(h.axis, h.angle.eval(q)),
            None => r_joint,
        };
        out.push((r_b.0, p_b.0));
    }
    out
}

/// Absolute angular velocity of every body (world axes) at a state, f64.
pub fn body_angular_velocities(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    world_from_base: &M3<f64>,
    base_rate: &V3<f64>,
) -> Vec<[f64; 3]> {
    let poses = body_poses(chain, q, world_from_base);
    let mut w: Vec<V3<f64>> = Vec::with_capacity(chain.bodies.len());
    for (bi, body) in chain.bodies.iter().enumerate() {
        let parent_w = match body.parent {
            Some(pi) => w[pi],
            None => *base_rate,
        };
        let wb = match &body.hinge {
            Some(h) => {
                let r_par = match body.parent {
                    Some(pi) => M3(poses[pi].0),
                    None => *world_from_base,
                };
                let r_joint = match &body.joint_rotation {
                    Some(jr) => r_par.mul_m(&M3(*jr)),
                    None => r_par,
                };
                let mut g = vec![0.0; chain.n];
                h.angle.add_gradient(q, &mut g);
                let rate: f64 = g.iter().zip(qd).map(|(a, b)| a * b).sum();
                parent_w.add(&r_joint.col(h.axis).scale(rate))
            }
            None => parent_w,
        };
        let _ = bi;
        w.push(wb);
    }
    w.into_iter().map(|v| v.0).collect()
}
