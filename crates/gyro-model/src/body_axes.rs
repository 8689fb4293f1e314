//! The body-axes engine, as the model evaluates it: the same Lagrangian and the same equations
//! as the world-axes reference engine ([`crate::reference_engine::evaluate`], which stays as the
//! plain reference the tests hold this to), but computed in each body's own axes, where most of
//! the work disappears. Both walks here ([`evaluate`], and [`evaluate_rates`] for the `full`
//! right-hand side) share their per-frame setup (`walk`).
//!
//! Why it is cheaper, with the same mathematics:
//! - Every energy is a sum of dot products, which do not depend on the axes they are taken in.
//!   In a body's own axes its inertia, centre of gravity and rotor axis are constants, the
//!   gravity and base rate are carried down the chain as vectors, and crossing a hinge rotates
//!   each carried vector by an elementary rotation (4 multiplications instead of the 27 of a
//!   rotation matrix product).
//! - The base's orientation drops out of every dot product, so time enters only through the
//!   base rate ω₀(t): the momentum of the quadratic part p₂ = M u does not depend on time
//!   explicitly (∂ₜp₂ = 0 exactly, where the world-axes reference computes it as round-off), and
//!   ∂ₜb is b's linear part evaluated at ω̇₀ — a plain real-valued pass, zero in harbour. The
//!   dual numbers carry only the n coordinate directions, no time direction.
//! - Bodies without a hinge (a rotor in its case) are rigidly attached to their parent: they
//!   are merged into the parent's frame once, at compile time (combined mass, centre of gravity,
//!   inertia by the parallel-axis theorem, and the rotors' momenta along their axes).
//! - Hinges at the pivot (no lever arm) skip the translational Jacobian terms, and columns of the
//!   velocity Jacobians that are still zero (coordinates below this frame) are skipped.
//!
//! Nothing here allocates for chains without branches; a branching chain keeps the state of a
//! branching frame in a small vector while its branches are walked.

use crate::design::{Design, Force};
use crate::dual::{Jet, M3, Real, V3};
use crate::expr::QuadExpr;
use crate::force_elements::{self, LinkWalk, RateTerms, SpringsInto};
use crate::reference_engine::{Chain, EvalInput, EvalOutput, evaluate_pots_any};

mod rates;
mod walk;
pub use rates::evaluate_rates;
use walk::{Carried, clear, cross_cg};

/// Mass properties of a frame (its own body and every body rigidly attached to it).
#[derive(Clone, Debug, PartialEq)]
struct MassProps {
    m: f64,
    /// Centre of gravity in frame axes, from the frame's origin.
    cg: [f64; 3],
    /// Inertia about the centre of gravity, frame axes.
    inertia: [[f64; 3]; 3],
    diagonal: bool,
}

#[derive(Clone, Debug)]
struct BodyForceElement {
    /// Point of application: origin and rotation of the force's body in frame axes, and the
    /// point in body axes (expressions of the coordinates).
    origin: [f64; 3],
    rotation: Option<[[f64; 3]; 3]>,
    point: [QuadExpr; 3],
    /// Force vector (direction × magnitude) in frame axes: constant.
    force: [f64; 3],
}

#[derive(Clone, Debug)]
struct Frame {
    parent: usize,
    /// Hinge point in the parent frame's axes, from the parent frame's origin.
    origin: [f64; 3],
    origin_nonzero: bool,
    /// parent_frame_from_joint (None: identity).
    joint: Option<[[f64; 3]; 3]>,
    axis: usize,
    angle: QuadExpr,
    /// Every coordinate the hinge angle reads (bit mask).
    reads: u32,
    /// The frame's origin is the pivot whatever the coordinates (every hinge above it and its
    /// own sits at the pivot): no translational Jacobian terms.
    at_pivot: bool,
    /// A later frame that is not the next one hangs on this one: keep a copy of its state.
    save: bool,
    mass: Option<MassProps>,
    /// (body, spin axis in frame axes) of the rotors in this frame.
    rotors: Vec<(usize, [f64; 3])>,
    forces: Vec<BodyForceElement>,
}

impl BodyForceElement {
    /// Moment about the pivot (frame axes) of the force applied at its point, the frame's
    /// origin being at `p` from the pivot: the force's generalised force is jwᵢ·τ.
    fn torque<T: Real>(&self, q: &[T], p: &V3<T>) -> V3<T> {
        let pt: [T; 3] = std::array::from_fn(|k| self.point[k].eval(q));
        let pt = match &self.rotation {
            Some(rm) => M3::<T>::from_f64(*rm).mul_v(&V3(pt)).0,
            None => pt,
        };
        let rp = V3([
            p.0[0] + pt[0] + self.origin[0],
            p.0[1] + pt[1] + self.origin[1],
            p.0[2] + pt[2] + self.origin[2],
        ]);
        rp.cross(&V3::from_f64(self.force))
    }
}

impl Frame {
    /// The rotors' momenta along their axes in frame axes, and their rates: held (a number), or
    /// a motor's state H = CΩ with its rate Ḣ (whose reaction on the case is −Ḣ ŝ).
    fn rotor_momenta<T: Real>(&self, spins: &[(usize, T, T)], held: &[f64]) -> ([T; 3], [T; 3]) {
        let mut hv = [T::zero(); 3];
        let mut hv_dot = [T::zero(); 3];
        for &(bi, ax) in &self.rotors {
            match spins.iter().find(|s| s.0 == bi) {
                Some(&(_, h, h_dot)) => {
                    for k in 0..3 {
                        hv[k] += h * ax[k];
                        hv_dot[k] += h_dot * ax[k];
                    }
                }
                None => {
                    for k in 0..3 {
                        hv[k] += T::cst(ax[k] * held[bi]);
                    }
                }
            }
        }
        (hv, hv_dot)
    }
}

/// A design's chain compiled for evaluation in body axes. Frame 0 is the base.
#[derive(Clone, Debug)]
pub struct BodyAxesChain {
    pub n: usize,
    frames: Vec<Frame>,
    /// Dampers, springs and generalised forces (coordinate-space elements).
    forces: Vec<Force>,
    /// Springs between two bodies, each with its ends' paths from the base.
    links: Vec<LinkWalk>,
    /// The world-axes chain down to the carriers of communicating pots, whose share of the
    /// equations the reference engine forms (`pots_terms`); `None` without pots.
    pots: Option<Chain>,
}

type Mat = [[f64; 3]; 3];
const IDENTITY: Mat = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

fn mat_mul(a: &Mat, b: &Mat) -> Mat {
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    r
}
fn mat_vec(a: &Mat, v: &[f64; 3]) -> [f64; 3] {
    [
        a[0][0] * v[0] + a[0][1] * v[1] + a[0][2] * v[2],
        a[1][0] * v[0] + a[1][1] * v[1] + a[1][2] * v[2],
        a[2][0] * v[0] + a[2][1] * v[1] + a[2][2] * v[2],
    ]
}
fn transpose(a: &Mat) -> Mat {
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = a[j][i];
        }
    }
    r
}

impl BodyAxesChain {
    /// Compiles a design's chain; `include_force` selects the force elements (effects).
    pub fn from_design(d: &Design, include_force: impl Fn(&Force) -> bool) -> BodyAxesChain {
        let nb = d.bodies.len();
        // Where each body sits: (frame, origin of the body in frame axes, frame_from_body).
        let mut place: Vec<(usize, [f64; 3], Mat)> = Vec::with_capacity(nb);
        let mut frames = vec![Frame {
            parent: 0,
            origin: [0.0; 3],
            origin_nonzero: false,
            joint: None,
            axis: 0,
            angle: QuadExpr::constant(0.0),
            reads: 0,
            at_pivot: true,
            save: false,
            mass: None,
            rotors: Vec::new(),
            forces: Vec::new(),
        }];
        // (frame, body) lists for mass merging.
        let mut members: Vec<Vec<usize>> = vec![Vec::new()];
        for b in &d.bodies {
            let (pf, po, pr) = match b.parent {
                Some(pi) => place[pi],
                None => (0, [0.0; 3], IDENTITY),
            };
            // The body's joint in its parent frame's axes.
            let o = mat_vec(&pr, &b.joint_origin_m);
            let origin = [po[0] + o[0], po[1] + o[1], po[2] + o[2]];
            let rot = mat_mul(&pr, &b.joint_rotation);
            match &b.hinge {
                Some(h) => {
                    let f = frames.len();
                    let origin_nonzero = origin.iter().any(|x| *x != 0.0);
                    let mut reads = 0u32;
                    for i in h.angle.coordinates() {
                        reads |= 1 << i;
                    }
                    frames.push(Frame {
                        parent: pf,
                        origin,
                        origin_nonzero,
                        joint: if rot == IDENTITY { None } else { Some(rot) },
                        axis: h.axis,
                        angle: h.angle.clone(),
                        reads,
                        at_pivot: frames[pf].at_pivot && !origin_nonzero,
                        save: false,
                        mass: None,
                        rotors: Vec::new(),
                        forces: Vec::new(),
                    });
                    members.push(Vec::new());
                    place.push((f, [0.0; 3], IDENTITY));
                }
                None => place.push((pf, origin, rot)),
            }
        }
        for (bi, b) in d.bodies.iter().enumerate() {
            let (f, o, r) = place[bi];
            let physical = b.mass_kg > 0.0
                || b.inertia_kg_m2.iter().flatten().any(|x| *x != 0.0)
                || b.rotor.is_some();
            if physical {
                members[f].push(bi);
            }
            if let Some(rot) = &b.rotor {
                frames[f].rotors.push((bi, mat_vec(&r, &rot.axis)));
            }
            let _ = o;
        }
        for (f, list) in members.iter().enumerate() {
            if list.is_empty() {
                continue;
            }
            let props: Vec<(f64, [f64; 3], Mat)> = list
                .iter()
                .map(|&bi| {
                    let b = &d.bodies[bi];
                    let (_, o, r) = place[bi];
                    if r == IDENTITY && o == [0.0; 3] {
                        (b.mass_kg, b.cg_m, b.inertia_kg_m2)
                    } else {
                        let c = mat_vec(&r, &b.cg_m);
                        let cg = [o[0] + c[0], o[1] + c[1], o[2] + c[2]];
                        let i = mat_mul(&mat_mul(&r, &b.inertia_kg_m2), &transpose(&r));
                        (b.mass_kg, cg, i)
                    }
                })
                .collect();
            let mass = merged_mass(&props);
            let mut mass = mass;
            mass.diagonal = (0..3).all(|i| (0..3).all(|j| i == j || mass.inertia[i][j] == 0.0));
            frames[f].mass = Some(mass);
        }
        let mut forces = Vec::new();
        for force in d.forces.iter().filter(|f| include_force(f)) {
            match force {
                Force::BodyForce {
                    body,
                    direction,
                    force_n,
                    point,
                    ..
                } => {
                    let (f, o, r) = place[*body];
                    let dir = mat_vec(&r, direction);
                    frames[f].forces.push(BodyForceElement {
                        origin: o,
                        rotation: if r == IDENTITY { None } else { Some(r) },
                        point: point.clone(),
                        force: [dir[0] * force_n, dir[1] * force_n, dir[2] * force_n],
                    });
                }
                other => forces.push(other.clone()),
            }
        }
        for f in 1..frames.len() {
            let p = frames[f].parent;
            if p + 1 != f {
                frames[p].save = true;
            }
        }
        BodyAxesChain {
            n: d.coordinates.len(),
            frames,
            links: LinkWalk::of(d, &forces),
            forces,
            pots: (!d.pots.is_empty() || !d.tanks.is_empty())
                .then(|| Chain::from_design(d, |_| false)),
        }
    }
}

/// The mass properties of rigidly attached bodies, (mass, centre of gravity, inertia about it)
/// each in the frame's axes, combined: total mass, common centre of gravity, inertia by the
/// parallel-axis theorem.
fn merged_mass(props: &[(f64, [f64; 3], Mat)]) -> MassProps {
    if props.len() == 1 {
        let (m, cg, inertia) = props[0];
        MassProps {
            m,
            cg,
            inertia,
            diagonal: false,
        }
    } else {
        let m: f64 = props.iter().map(|p| p.0).sum();
        let mut cg = [0.0; 3];
        if m > 0.0 {
            for k in 0..3 {
                cg[k] = props.iter().map(|p| p.0 * p.1[k]).sum::<f64>() / m;
            }
        }
        let mut inertia = [[0.0; 3]; 3];
        for (mk, ck, ik) in props {
            let dv = [ck[0] - cg[0], ck[1] - cg[1], ck[2] - cg[2]];
            let d2 = dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2];
            for i in 0..3 {
                for j in 0..3 {
                    let delta = if i == j { d2 } else { 0.0 };
                    inertia[i][j] += ik[i][j] + mk * (delta - dv[i] * dv[j]);
                }
            }
        }
        MassProps {
            m,
            cg,
            inertia,
            diagonal: false,
        }
    }
}

#[inline(always)]
fn scale<T: Real, const N: usize>(x: Jet<T, N>, s: T) -> Jet<T, N> {
    let mut d = x.d;
    for v in d.iter_mut() {
        *v *= s;
    }
    Jet { v: x.v * s, d }
}

#[inline(always)]
fn vscale<T: Real, const N: usize>(x: &V3<Jet<T, N>>, s: T) -> V3<Jet<T, N>> {
    V3([scale(x.0[0], s), scale(x.0[1], s), scale(x.0[2], s)])
}

#[inline(always)]
fn re<T: Real, const N: usize>(x: &V3<Jet<T, N>>) -> V3<T> {
    V3([x.0[0].v, x.0[1].v, x.0[2].v])
}

/// Rotates x into the axes of a frame turned by φ about `axis`: x ← E(φ)ᵀ x.
#[inline(always)]
fn turn<S: Real>(x: &mut V3<S>, i: usize, j: usize, s: S, c: S) {
    let a = x.0[i];
    let b = x.0[j];
    x.0[i] = a * c + b * s;
    x.0[j] = b * c - a * s;
}

/// x × c for a constant c.
#[inline(always)]
fn cross_const<T: Real, const N: usize>(x: &V3<Jet<T, N>>, c: &[f64; 3]) -> V3<Jet<T, N>> {
    let a = &x.0;
    V3([
        a[1] * c[2] - a[2] * c[1],
        a[2] * c[0] - a[0] * c[2],
        a[0] * c[1] - a[1] * c[0],
    ])
}

/// x ← Jᵀ x for a constant rotation.
#[inline(always)]
fn turn_const<S: Real>(x: &mut V3<S>, j: &Mat) {
    let v = x.0;
    for k in 0..3 {
        x.0[k] = v[0] * j[0][k] + v[1] * j[1][k] + v[2] * j[2][k];
    }
}

#[inline(always)]
fn inertia_mul<S: Real>(mp: &MassProps, x: &V3<S>) -> V3<S> {
    let i = &mp.inertia;
    if mp.diagonal {
        V3([x.0[0] * i[0][0], x.0[1] * i[1][1], x.0[2] * i[2][2]])
    } else {
        V3([
            x.0[0] * i[0][0] + x.0[1] * i[0][1] + x.0[2] * i[0][2],
            x.0[0] * i[1][0] + x.0[1] * i[1][1] + x.0[2] * i[1][2],
            x.0[0] * i[2][0] + x.0[1] * i[2][1] + x.0[2] * i[2][2],
        ])
    }
}

/// Forms M, K, c (the same equations as [`crate::reference_engine::evaluate`]) for all
/// coordinates.
/// `N` must be at least `kin.n`; the outputs' first n rows and columns are written, the rest is
/// left as it was.
pub fn evaluate<T: Real, const N: usize>(
    kin: &BodyAxesChain,
    inp: &EvalInput<T>,
    spins: &[(usize, T, T)],
    m_out: &mut [[T; N]; N],
    k_out: &mut [[T; N]; N],
    c_out: &mut [T; N],
) {
    let n = kin.n;
    debug_assert!(N >= n);
    type J<T, const N: usize> = Jet<T, N>;
    let zero = J::<T, N>::zero();
    let vz = V3::<J<T, N>>::zero();
    let q: [J<T, N>; N] = Jet::variables(inp.q, n);
    let dropped = |i: usize| inp.drop_quadratic.get(i).copied().unwrap_or(false);

    // The base: rate and gravity in its own axes.
    let (mut st, moving) = Carried::<T, N, N>::at_base(inp);
    let mut saved: Vec<(usize, Carried<T, N, N>)> = Vec::new();
    if kin.frames[0].save {
        saved.push((0, st));
    }

    let mut p2 = [zero; N];
    let mut b = [zero; N];
    let mut bt = [T::zero(); N];
    let mut t2 = zero;
    let mut t0 = zero;
    let mut v = zero;
    let mut qf = [T::zero(); N];
    clear(m_out, n);

    for (fi, fr) in kin.frames.iter().enumerate().skip(1) {
        // To the hinge point, into the joint's axes, through the hinge.
        st.enter_joint(fi, fr, &saved, n, moving, false);
        let phi = fr.angle.eval(&q[..n]);
        let (s, c) = phi.sin_cos();
        st.through_hinge(fr, n, moving, false, (s, c), (s, c));
        st.add_hinge_columns(fr, &q[..n]);
        if fr.save {
            saved.push((fi, st));
        }
        let on = st.jw_on | st.jm_on;

        // Forces applied to bodies of this frame (generalised forces from real parts).
        st.add_body_forces(fr, inp.q, n, &mut qf);

        // Energies of the bodies in this frame.
        let Some(mp) = &fr.mass else {
            continue;
        };
        let m = mp.m;
        // Rotors' momenta along their axes: held (a number), or a motor's state H = CΩ with
        // its rate Ḣ (whose reaction on the case is −Ḣ ŝ: the ∂ₜb term below).
        let (hv, hv_dot) = fr.rotor_momenta(spins, inp.spin_momentum);
        let has_spin = hv.iter().any(|x| *x != T::zero());
        let spin_rate = hv_dot.iter().any(|x| *x != T::zero());
        let cgp = st.cg_from_pivot(fr, mp);
        let cross_c = |x: &V3<J<T, N>>| cross_cg(fr, mp, &cgp, x);
        // The velocity Jacobian of the centre of gravity is jvᵢ = jwᵢ × c − jmᵢ, and every
        // product with it is taken as jvᵢ·X = jwᵢ·(c × X) − jmᵢ·X: no jvᵢ is ever formed.
        let mut w_u = vz;
        let mut jm_u = vz;
        for i in 0..n {
            if on & (1 << i) != 0 && inp.u[i] != T::zero() {
                w_u = w_u.add(&vscale(&st.jw[i], inp.u[i]));
                if st.jm_on & (1 << i) != 0 {
                    jm_u = jm_u.add(&vscale(&st.jm[i], inp.u[i]));
                }
            }
        }
        let v_u = cross_c(&w_u).sub(&jm_u);
        let v0 = cross_c(&st.w);
        let h_u = inertia_mul(mp, &w_u);
        let iw0 = inertia_mul(mp, &st.w);
        let mut h0 = iw0;
        if has_spin {
            for k in 0..3 {
                h0.0[k].v += hv[k];
            }
        }
        // c × X = −(X × c)
        let a_u = cross_c(&v_u).scale_f(-m).add(&h_u);
        let a_0 = cross_c(&v0).scale_f(-m).add(&h0);
        let wd_terms = st.moving_base_terms(moving, mp, &cgp);
        for i in 0..n {
            if on & (1 << i) == 0 {
                continue;
            }
            let lever = st.jm_on & (1 << i) != 0;
            if !dropped(i) {
                let mut x = st.jw[i].dot(&a_u);
                if lever {
                    x -= st.jm[i].dot(&v_u) * m;
                }
                p2[i] += x;
            }
            let mut x = st.jw[i].dot(&a_0);
            if lever {
                x -= st.jm[i].dot(&v0) * m;
            }
            b[i] += x;
            if let Some((v0d, a_d)) = &wd_terms {
                let mut x = re(&st.jw[i]).dot(a_d);
                if lever {
                    x -= re(&st.jm[i]).dot(v0d) * m;
                }
                bt[i] += x;
            }
            if spin_rate {
                bt[i] += re(&st.jw[i]).dot(&V3(hv_dot));
            }
        }
        t2 += (v_u.dot(&v_u) * m + w_u.dot(&h_u)) * 0.5;
        let mut t0_body = (v0.dot(&v0) * m + st.w.dot(&iw0)) * 0.5;
        if has_spin {
            t0_body += scale(st.w.0[0], hv[0]) + scale(st.w.0[1], hv[1]) + scale(st.w.0[2], hv[2]);
        }
        t0 += t0_body;
        v -= st.g_dot_cg(fr, mp, &cgp) * m;
        // Mass matrix from the real parts of the Jacobians.
        let jwr: [V3<T>; N] = std::array::from_fn(|i| re(&st.jw[i]));
        st.add_mass_matrix(mp, &cgp, &jwr, n, on, |i| !dropped(i), false, m_out);
    }

    // Coordinate-space force elements.
    clear(k_out, n);
    force_elements::add(
        &kin.forces,
        n,
        inp.q,
        &q,
        &mut KForm(k_out),
        SpringsInto::Potential,
        &mut v,
        &mut qf,
    );
    // Springs between two bodies: their distance from a short walk in base axes.
    for link in &kin.links {
        v += link.energy(&q[..n]);
    }

    for i in 0..n {
        c_out[i] = qf[i] - bt[i] + t2.d[i] + t0.d[i] - v.d[i];
        for k in 0..n {
            k_out[i][k] -= p2[i].d[k] + b[i].d[k] - b[k].d[i];
        }
    }
    add_pots(kin, inp, m_out, k_out, c_out);
}

/// Adds the communicating pots' M, K and c (nothing without pots).
#[inline(always)]
fn add_pots<T: Real, const N: usize>(
    kin: &BodyAxesChain,
    inp: &EvalInput<T>,
    m_out: &mut [[T; N]; N],
    k_out: &mut [[T; N]; N],
    c_out: &mut [T; N],
) {
    let Some(terms) = pots_terms(kin, inp) else {
        return;
    };
    let n = kin.n;
    for i in 0..n {
        c_out[i] += terms.c[i];
        for k in 0..n {
            m_out[i][k] += terms.m[i * n + k];
            k_out[i][k] += terms.k[i * n + k];
        }
    }
}

/// M, K and c of communicating pots (row-major n × n), from the reference engine: the pots'
/// Lagrangian reads only their carriers' kinematics, which a short world-axes walk gives.
pub(super) struct PotsTerms<T> {
    m: [T; 256],
    k: [T; 256],
    c: [T; 16],
}

pub(super) fn pots_terms<T: Real>(kin: &BodyAxesChain, inp: &EvalInput<T>) -> Option<PotsTerms<T>> {
    let chain = kin.pots.as_ref()?;
    let n = kin.n;
    let mut t = PotsTerms {
        m: [T::zero(); 256],
        k: [T::zero(); 256],
        c: [T::zero(); 16],
    };
    let mut out = EvalOutput {
        m: &mut t.m[..n * n],
        k: &mut t.k[..n * n],
        c: &mut t.c[..n],
        energies: [T::zero(); 3],
    };
    evaluate_pots_any(chain, inp, &mut out);
    Some(t)
}

/// The equations' K, where the force elements' rate terms go in K form.
pub(super) struct KForm<'a, T, const N: usize>(pub &'a mut [[T; N]; N]);

impl<T: Real, const N: usize> RateTerms<T> for KForm<'_, T, N> {
    /// −c ∇e ∇eᵀ.
    #[inline(always)]
    fn damper(&mut self, g: &[T], coefficient: f64) {
        for (i, &gi) in g.iter().enumerate() {
            if gi == T::zero() {
                continue;
            }
            for (k, &gk) in g.iter().enumerate() {
                self.0[i][k] -= gi * gk * coefficient;
            }
        }
    }
    /// The servo's row: c ∇(r − qᵢ).
    #[inline(always)]
    fn servo(&mut self, row: usize, g: &[T], damping: f64) {
        for (k, &gk) in g.iter().enumerate() {
            self.0[row][k] += gk * damping;
        }
    }
}
