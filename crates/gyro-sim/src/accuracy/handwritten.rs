//! Hand-written equations of motion: the yardstick the engine's cost is measured against.
//!
//! Two systems, written out for one scene each in plain `f64` Rust (no chain walk, no dual
//! numbers in the right-hand side), each agreeing with the engine's `rhs`/`jacobian` to rounding
//! (`tests/handwritten.rs`):
//! - [`Foucault44Bis`]: Foucault's azimuth gyroscope, Villarceau's eq. 44 bis in its pendulum
//!   form γ″ = (g/a)(−sin γ + 2δ sin γ cos γ), state [γ, γ̇] in the engine's layout (the ring's
//!   hinge angle, γ plus the hinge angle of the hour plane). g/a and δ are eqs. 45–46 of the
//!   design's numbers (`theory::foucault_villarceau`). Its Jacobian is hand-derived.
//! - [`Anschutz1906`]: the Anschütz 1906 (float + rotor + vane, air jets, mercury drag) on the
//!   moored ship of `scenes/harbour-50n.toml`, at `full` (state [ζ, θ, λ, α, ζ̇, θ̇, λ̇, α̇]) or
//!   `gyroscopic` fidelity (state [ζ, θ, λ, α, λ̇, α̇]: ζ, θ are precessional, first order).
//!   Derived by Kane's method (Euler's equations of the float-and-rotor and of the vane about the
//!   fixed pivot, projected on the partial angular velocities — equivalent to the engine's
//!   Lagrange equations), with the bias split by degree in the rates (f₀ + f₁ + f₂): the
//!   `gyroscopic` model is the same Lagrangian with the quadratic kinetic energy of ζ̇, θ̇ dropped,
//!   so it keeps f₀, f₁ and the part of f₂ that comes from the (λ, α) block of the mass matrix.
//!   Its Jacobian is by forward-mode duals (`Jet`) on the same hand-written code, one pass.
//!
//! Only what the harbour scene compiles is here: Earth rotation, air jets, dampers, held spin,
//! plumb-line gravity; no transport rate, no ship motion (the constructor refuses other models).
//! The numbers (inertias, levers, drag coefficients, spin momentum) are read from the compiled
//! model's design so that both sides run the same compass.
//!
//! The engine-over-hand-written cost ratio is measured by
//! `cargo bench -p gyro-sim --bench handwritten`.

// Small fixed-size kernels index parallel arrays with one loop variable; a NaN-rejecting test is
// written `!(x > 0.0)` on purpose.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use crate::run::Simulation;
use crate::solvers::OdeSystem;
use gyro_model::constants::EARTH_RATE_RAD_PER_S;
use gyro_model::theory::foucault_villarceau;
use gyro_model::{Design, Fidelity, Force, Jet, Real, Root, SpinMode};

/// Villarceau's eq. 44 bis for the `foucault-gyroscope` design: γ″ = (g/a)(−sin γ + 2δ sin γ cos γ).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Foucault44Bis {
    /// g/a, 1/s² (eq. 45).
    pub g_over_a: f64,
    /// δ (eq. 46).
    pub delta: f64,
    /// Hinge angle of the hour plane, rad: γ = hinge angle − offset.
    pub offset_rad: f64,
}

impl Foucault44Bis {
    /// The constants of the compiled Foucault gyroscope `sim` (its torus's spin momentum, which
    /// depends on the start through n = w + ω cos θ₀) at latitude `latitude_rad`.
    pub fn from_simulation(sim: &Simulation, latitude_rad: f64) -> Result<Foucault44Bis, String> {
        let m = &sim.model;
        if m.design.coordinates.len() != 1 || m.fidelity != Fidelity::Full {
            return Err("Foucault44Bis needs the one-coordinate gyroscope at full fidelity".into());
        }
        let torus = m.design.body_index("torus").ok_or("no body torus")?;
        let (v, offset) = foucault_villarceau(&m.design, m.spin_momentum[torus], latitude_rad)
            .ok_or("not a Foucault gyroscope")?;
        Ok(Foucault44Bis {
            g_over_a: v.g_over_a,
            delta: v.delta,
            offset_rad: offset,
        })
    }

    /// ẋ = [γ̇, γ″].
    #[inline]
    pub fn rhs(&self, x: &[f64], dx: &mut [f64]) {
        let (s, c) = gyro_model::sin_cos(x[0] - self.offset_rad);
        dx[0] = x[1];
        dx[1] = self.g_over_a * s * (2.0 * self.delta * c - 1.0);
    }

    /// [[0, 1], [∂γ″/∂γ, 0]] with ∂γ″/∂γ = (g/a)(−cos γ + 2δ cos 2γ).
    #[inline]
    pub fn jacobian(&self, x: &[f64], jac: &mut [f64]) {
        let (s, c) = gyro_model::sin_cos(x[0] - self.offset_rad);
        jac[0] = 0.0;
        jac[1] = 1.0;
        jac[2] = self.g_over_a * (2.0 * self.delta * (c * c - s * s) - c);
        jac[3] = 0.0;
    }
}

impl OdeSystem for Foucault44Bis {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
        Foucault44Bis::rhs(self, x, dx)
    }
    fn jacobian(&mut self, _t: f64, x: &[f64], jac: &mut [f64]) -> bool {
        Foucault44Bis::jacobian(self, x, jac);
        true
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

type V<T> = [T; 3];

#[inline(always)]
fn dot<T: Real>(a: &V<T>, b: &V<T>) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline(always)]
fn cross<T: Real>(a: &V<T>, b: &V<T>) -> V<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
#[inline(always)]
fn add<T: Real>(a: &V<T>, b: &V<T>) -> V<T> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
#[inline(always)]
fn scale<T: Real>(a: &V<T>, s: T) -> V<T> {
    [a[0] * s, a[1] * s, a[2] * s]
}
/// A constant 3×3 matrix times a vector.
#[inline(always)]
fn mul_c<T: Real>(m: &[[f64; 3]; 3], v: &V<T>) -> V<T> {
    [
        v[0] * m[0][0] + v[1] * m[0][1] + v[2] * m[0][2],
        v[0] * m[1][0] + v[1] * m[1][1] + v[2] * m[1][2],
        v[0] * m[2][0] + v[1] * m[2][1] + v[2] * m[2][2],
    ]
}
#[inline(always)]
fn mul<T: Real>(m: &[V<T>; 3], v: &V<T>) -> V<T> {
    [dot(&m[0], v), dot(&m[1], v), dot(&m[2], v)]
}

/// The Anschütz 1906 of `designs/anschutz-1906.toml` on a moored ship (the harbour scene),
/// written out by hand. Axes are the float's (x along the spin, y West when level on the
/// meridian, z up); coordinates ζ (azimuth, about the vertical), θ (tilt, about the azimuth
/// frame's y), λ (heel, about the float's x), α (vane, about the float's y).
///
/// Fields are public so that a test can switch one term off and see the engine disagree.
#[derive(Clone, Debug, PartialEq)]
pub struct Anschutz1906 {
    /// `Full` or `Gyroscopic`.
    pub fidelity: Fidelity,
    /// Absolute rate of the North–West–Up frame, its own axes: ε(cos L, 0, sin L), rad/s.
    pub frame_rate_rad_per_s: [f64; 3],
    /// Apparent gravity, North–West–Up axes, m/s².
    pub gravity_m_per_s2: [f64; 3],
    /// Float and rotor about the pivot, float axes: J = I_float + I_rotor + m(|c|²1 − c cᵀ), kg·m².
    pub inertia_kg_m2: [[f64; 3]; 3],
    /// The rotor's held spin momentum H·ŝ, float axes, N·m·s.
    pub spin_momentum_n_m_s: [f64; 3],
    /// Float mass (kg) and centre of gravity (float axes, m).
    pub float_mass_kg: f64,
    pub float_cg_m: [f64; 3],
    /// Vane: mass, hinge point (float axes), centre of gravity (vane axes), inertia about its cg.
    pub vane_mass_kg: f64,
    pub vane_hinge_m: [f64; 3],
    pub vane_cg_m: [f64; 3],
    pub vane_inertia_kg_m2: [[f64; 3]; 3],
    /// Air jets: force f·d (float axes, N) applied at p₀ + α p₁ (float axes, m).
    pub jet_force_n: [f64; 3],
    pub jet_point_m: [f64; 3],
    pub jet_point_per_rad_m: [f64; 3],
    /// Viscous drag per coordinate (ζ, θ, λ, α), N·m·s/rad.
    pub drag_n_m_s_per_rad: [f64; 4],
}

/// Position-dependent quantities of one evaluation (float axes).
struct Kin<T: Real> {
    /// Hinge axes of ζ, θ, λ (λ's is x) and the vane's (y).
    e: [V<T>; 3],
    /// Absolute rate of the world frame.
    nu: V<T>,
    /// Gravity.
    g: V<T>,
    /// Vane cg from the pivot, its α-derivative and second derivative.
    r: V<T>,
    rp: V<T>,
    rpp: V<T>,
    /// Vane inertia about its cg, float axes.
    iv: [V<T>; 3],
    /// Angular momenta of the frame rotation alone: J ν + H ŝ, and I_v ν.
    h0f: V<T>,
    h0v: V<T>,
    alpha: T,
}

impl Anschutz1906 {
    /// The hand-written twin of the compiled Anschütz 1906 `sim` at latitude `latitude_rad`:
    /// numbers from its design, checked to be the harbour scene's model (Earth-rooted chain,
    /// ship at rest, no ship-motion effect, held spin, no motor).
    pub fn from_simulation(sim: &Simulation, latitude_rad: f64) -> Result<Anschutz1906, String> {
        let m = &sim.model;
        let fx = m.effects;
        let b = fx.base;
        if b.transport_rate
            || b.ship_acceleration
            || b.turn_rate
            || b.roll_pitch
            || b.base_coriolis
            || fx.spin_motor
            || !m.is_autonomous()
        {
            return Err("the hand-written Anschütz is the harbour scene's: ship at rest, Earth rotation, jets and dampers only".into());
        }
        let fidelity = match m.fidelity {
            Fidelity::Linear => return Err("no hand-written linear model".into()),
            f => f,
        };
        let mut a = Self::from_design(&m.design, latitude_rad, fidelity)?;
        a.gravity_m_per_s2 = m.apparent_gravity(0.0);
        if !b.earth_rotation {
            a.frame_rate_rad_per_s = [0.0; 3];
        }
        if !fx.damper {
            a.jet_force_n = [0.0; 3];
        }
        if !fx.friction {
            a.drag_n_m_s_per_rad = [0.0; 4];
        }
        let names: Vec<String> = m.state_names();
        let expect: &[&str] = match fidelity {
            Fidelity::Gyroscopic => &[
                "zeta",
                "theta",
                "lambda",
                "alpha",
                "lambda_rate",
                "alpha_rate",
            ],
            _ => &[
                "zeta",
                "theta",
                "lambda",
                "alpha",
                "zeta_rate",
                "theta_rate",
                "lambda_rate",
                "alpha_rate",
            ],
        };
        if names != expect {
            return Err(format!("state layout {names:?}, expected {expect:?}"));
        }
        Ok(a)
    }

    /// The numbers of a design built like `anschutz-1906` (bodies `float`, `rotor`, `vane`;
    /// coordinates ζ, θ, λ, α in that order; one body force on the float; dampers on single
    /// coordinates), with plumb-line gravity and the Earth rate at `latitude_rad`.
    pub fn from_design(
        d: &Design,
        latitude_rad: f64,
        fidelity: Fidelity,
    ) -> Result<Anschutz1906, String> {
        let body = |n: &str| {
            d.body_index(n)
                .map(|i| (i, &d.bodies[i]))
                .ok_or(format!("no body {n}"))
        };
        let coord = |n: &str| d.coordinate_index(n).ok_or(format!("no coordinate {n}"));
        if d.root != Root::Earth
            || [
                coord("zeta")?,
                coord("theta")?,
                coord("lambda")?,
                coord("alpha")?,
            ] != [0, 1, 2, 3]
            || d.coordinates.len() != 4
            || !d.pots.is_empty()
            || !d.tanks.is_empty()
        {
            return Err("not built like anschutz-1906 (coordinates ζ, θ, λ, α)".into());
        }
        let ident = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let (fi, float) = body("float")?;
        let (ri, rotor) = body("rotor")?;
        let (vi, vane) = body("vane")?;
        let spin = rotor.rotor.as_ref().ok_or("the rotor has no rotor")?;
        if d.bodies.len() != 5
            || float.joint_rotation != ident
            || float.joint_origin_m != [0.0; 3]
            || rotor.parent != Some(fi)
            || rotor.joint_rotation != ident
            || rotor.joint_origin_m != [0.0; 3]
            || rotor.cg_m != [0.0; 3]
            || rotor.hinge.is_some()
            || spin.mode != SpinMode::Held
            || vane.parent != Some(fi)
            || vane.joint_rotation != ident
            || vane.hinge.as_ref().map(|h| h.axis) != Some(1)
            || float.hinge.as_ref().map(|h| h.axis) != Some(0)
        {
            return Err(
                "not built like anschutz-1906 (float, rotor on it, vane hinged on y)".into(),
            );
        }
        for (i, b) in d.bodies.iter().enumerate() {
            if i != fi && i != ri && i != vi && (b.mass_kg != 0.0 || b.rotor.is_some()) {
                return Err(format!("body {} should be a massless frame", b.name));
            }
        }
        let c = float.cg_m;
        let m = float.mass_kg;
        let cc = dot(&c, &c);
        let mut j = [[0.0; 3]; 3];
        for r in 0..3 {
            for k in 0..3 {
                let delta = if r == k { 1.0 } else { 0.0 };
                j[r][k] = float.inertia_kg_m2[r][k]
                    + rotor.inertia_kg_m2[r][k]
                    + m * (cc * delta - c[r] * c[k]);
            }
        }
        let h = spin.polar_inertia_kg_m2 * spin.spin_rad_per_s;
        let mut jet_force = [0.0; 3];
        let mut jet_point = [0.0; 3];
        let mut jet_rate = [0.0; 3];
        let mut drag = [0.0; 4];
        let q0 = [0.0; 4];
        let q1 = [0.0, 0.0, 0.0, 1.0];
        for f in &d.forces {
            match f {
                Force::BodyForce {
                    body,
                    direction,
                    force_n,
                    point,
                    ..
                } if *body == fi => {
                    for k in 0..3 {
                        if point[k].coordinates().iter().any(|&i| i != 3) || !point[k].is_linear() {
                            return Err("the jets' point must be linear in α only".into());
                        }
                        jet_force[k] += direction[k] * force_n;
                        jet_point[k] = point[k].eval(&q0);
                        jet_rate[k] = point[k].eval(&q1) - jet_point[k];
                    }
                }
                Force::Damper {
                    expr, coefficient, ..
                } => {
                    let cs = expr.coordinates();
                    if cs.len() != 1 || !expr.is_linear() {
                        return Err("dampers must act on one coordinate".into());
                    }
                    let mut g = [0.0; 4];
                    expr.add_gradient(&q0, &mut g);
                    drag[cs[0]] += coefficient * g[cs[0]] * g[cs[0]];
                }
                other => return Err(format!("force {} is not hand-written", other.name())),
            }
        }
        let (sl, cl) = gyro_model::sin_cos(latitude_rad);
        Ok(Anschutz1906 {
            fidelity,
            frame_rate_rad_per_s: [EARTH_RATE_RAD_PER_S * cl, 0.0, EARTH_RATE_RAD_PER_S * sl],
            gravity_m_per_s2: [0.0, 0.0, -gyro_model::constants::STANDARD_GRAVITY_M_PER_S2],
            inertia_kg_m2: j,
            spin_momentum_n_m_s: scale(&spin.axis, h),
            float_mass_kg: m,
            float_cg_m: c,
            vane_mass_kg: vane.mass_kg,
            vane_hinge_m: vane.joint_origin_m,
            vane_cg_m: vane.cg_m,
            vane_inertia_kg_m2: vane.inertia_kg_m2,
            jet_force_n: jet_force,
            jet_point_m: jet_point,
            jet_point_per_rad_m: jet_rate,
            drag_n_m_s_per_rad: drag,
        })
    }

    pub fn dim(&self) -> usize {
        if self.fidelity == Fidelity::Gyroscopic {
            6
        } else {
            8
        }
    }

    /// The float-axes quantities at q = (ζ, θ, λ, α).
    #[inline(always)]
    fn kinematics<T: Real>(&self, q: &[T]) -> Kin<T> {
        let (sz, cz) = q[0].sin_cos();
        let (st, ct) = q[1].sin_cos();
        let (sl, cl) = q[2].sin_cos();
        let (sa, ca) = q[3].sin_cos();
        let zero = T::zero();
        // Rᵀ w for R = R_z(ζ) R_y(θ) R_x(λ), w in world axes.
        let to_float = |w: &[f64; 3]| -> V<T> {
            let u0 = cz * w[0] + sz * w[1];
            let u1 = cz * w[1] - sz * w[0];
            let u2 = T::cst(w[2]);
            let v0 = ct * u0 - st * u2;
            let v2 = st * u0 + ct * u2;
            [v0, cl * u1 + sl * v2, cl * v2 - sl * u1]
        };
        let e = [
            [-st, sl * ct, cl * ct],
            [zero, cl, -sl],
            [T::one(), zero, zero],
        ];
        let nu = to_float(&self.frame_rate_rad_per_s);
        let g = to_float(&self.gravity_m_per_s2);
        // Vane: R_y(α) of its cg and inertia.
        let p = &self.vane_cg_m;
        let pr = [ca * p[0] + sa * p[2], T::cst(p[1]), ca * p[2] - sa * p[0]];
        let o = &self.vane_hinge_m;
        let r = [pr[0] + o[0], pr[1] + o[1], pr[2] + o[2]];
        // e_y × x = (x_z, 0, −x_x).
        let rp = [pr[2], zero, -pr[0]];
        let rpp = [rp[2], zero, -rp[0]];
        // I' = P I Pᵀ, P = R_y(α).
        let i = &self.vane_inertia_kg_m2;
        let rot = |v: [f64; 3]| [ca * v[0] + sa * v[2], T::cst(v[1]), ca * v[2] - sa * v[0]];
        // P I (columns of I rotated), then (P I) Pᵀ: rows of P I rotated.
        let pi: [V<T>; 3] = [
            rot([i[0][0], i[1][0], i[2][0]]),
            rot([i[0][1], i[1][1], i[2][1]]),
            rot([i[0][2], i[1][2], i[2][2]]),
        ];
        // pi[c] is column c of P I; row r of P I is (pi[0][r], pi[1][r], pi[2][r]).
        let rotr = |v: V<T>| [ca * v[0] + sa * v[2], v[1], ca * v[2] - sa * v[0]];
        let iv = [
            rotr([pi[0][0], pi[1][0], pi[2][0]]),
            rotr([pi[0][1], pi[1][1], pi[2][1]]),
            rotr([pi[0][2], pi[1][2], pi[2][2]]),
        ];
        let hs = &self.spin_momentum_n_m_s;
        let jn = mul_c(&self.inertia_kg_m2, &nu);
        let h0f = [jn[0] + hs[0], jn[1] + hs[1], jn[2] + hs[2]];
        let h0v = mul(&iv, &nu);
        Kin {
            e,
            nu,
            g,
            r,
            rp,
            rpp,
            iv,
            h0f,
            h0v,
            alpha: q[3],
        }
    }

    /// Projects the float's torque `tf`, the vane's torque `tv` (about its cg) and the vane's
    /// force `fv` on the partial angular velocities and velocities: the generalised forces.
    #[inline(always)]
    fn project<T: Real>(k: &Kin<T>, tf: &V<T>, tv: &V<T>, fv: &V<T>) -> [T; 4] {
        let t = add(&add(tf, tv), &cross(&k.r, fv));
        [
            dot(&k.e[0], &t),
            dot(&k.e[1], &t),
            t[0],
            tv[1] + dot(&k.rp, fv),
        ]
    }

    /// The generalised forces other than inertia and drag: weight and jets.
    #[inline(always)]
    fn applied<T: Real>(&self, k: &Kin<T>) -> [T; 4] {
        let tg = cross(
            &self.float_cg_m.map(T::cst),
            &scale(&k.g, T::cst(self.float_mass_kg)),
        );
        let p = [0, 1, 2].map(|i| k.alpha * self.jet_point_per_rad_m[i] + self.jet_point_m[i]);
        let tj = cross(&p, &self.jet_force_n.map(T::cst));
        let t = add(&tg, &tj);
        let fv = scale(&k.g, T::cst(self.vane_mass_kg));
        Self::project(k, &t, &[T::zero(); 3], &fv)
    }

    /// f₀: the inertia forces of the frame's rotation alone (centrifugal), rates zero.
    #[inline(always)]
    fn f0<T: Real>(&self, k: &Kin<T>) -> [T; 4] {
        let tf = cross(&k.nu, &k.h0f);
        let tv = cross(&k.nu, &k.h0v);
        let a = cross(&k.nu, &cross(&k.nu, &k.r));
        Self::project(k, &tf, &tv, &scale(&a, T::cst(self.vane_mass_kg)))
    }

    /// f₁ = B q̇: the inertia forces linear in the rates (gyroscopic, Coriolis of the frame).
    #[inline(always)]
    fn f1<T: Real>(&self, k: &Kin<T>, qd: &[T; 4]) -> [T; 4] {
        let w = add(
            &add(&scale(&k.e[0], qd[0]), &scale(&k.e[1], qd[1])),
            &[qd[2], T::zero(), T::zero()],
        );
        let wv = [w[0], w[1] + qd[3], w[2]];
        let j = &self.inertia_kg_m2;
        let tf = add(
            &add(&cross(&w, &k.h0f), &cross(&k.nu, &mul_c(j, &w))),
            &mul_c(j, &cross(&k.nu, &w)),
        );
        let tv = add(
            &add(&cross(&wv, &k.h0v), &cross(&k.nu, &mul(&k.iv, &wv))),
            &mul(&k.iv, &cross(&k.nu, &wv)),
        );
        let vrel = add(&cross(&w, &k.r), &scale(&k.rp, qd[3]));
        let a = scale(&cross(&k.nu, &vrel), T::cst(2.0 * self.vane_mass_kg));
        Self::project(k, &tf, &tv, &a)
    }

    /// f₂: the inertia forces quadratic in the rates (relative motion alone).
    #[inline(always)]
    fn f2<T: Real>(&self, k: &Kin<T>, qd: &[T; 4]) -> [T; 4] {
        let w = add(
            &add(&scale(&k.e[0], qd[0]), &scale(&k.e[1], qd[1])),
            &[qd[2], T::zero(), T::zero()],
        );
        let wv = [w[0], w[1] + qd[3], w[2]];
        // Ė q̇ = ζ̇ e_ζ × (θ̇ e_θ + λ̇ e_x) + θ̇ λ̇ e_θ × e_x.
        let inner = [qd[2], k.e[1][1] * qd[1], k.e[1][2] * qd[1]];
        let et_x = [T::zero(), k.e[1][2], -k.e[1][1]];
        let wd = add(
            &scale(&cross(&k.e[0], &inner), qd[0]),
            &scale(&et_x, qd[1] * qd[2]),
        );
        let j = &self.inertia_kg_m2;
        let tf = add(&mul_c(j, &wd), &cross(&w, &mul_c(j, &w)));
        // ω × α̇ e_y = α̇ (−ω_z, 0, ω_x).
        let wxa = [-w[2] * qd[3], T::zero(), w[0] * qd[3]];
        let tv = add(&mul(&k.iv, &add(&wd, &wxa)), &cross(&wv, &mul(&k.iv, &wv)));
        let a = add(
            &add(
                &scale(&k.rpp, qd[3] * qd[3]),
                &scale(&cross(&w, &k.rp), qd[3] * 2.0),
            ),
            &add(&cross(&wd, &k.r), &cross(&w, &cross(&w, &k.r))),
        );
        Self::project(k, &tf, &tv, &scale(&a, T::cst(self.vane_mass_kg)))
    }

    /// The mass matrix (4×4, symmetric): Σ Gᵀ I G + m Vᵀ V.
    #[inline(always)]
    fn mass<T: Real>(&self, k: &Kin<T>) -> [[T; 4]; 4] {
        let ey = [T::zero(), T::one(), T::zero()];
        let g = [k.e[0], k.e[1], k.e[2], ey];
        let v = [
            cross(&g[0], &k.r),
            cross(&g[1], &k.r),
            cross(&g[2], &k.r),
            k.rp,
        ];
        let mut m = [[T::zero(); 4]; 4];
        for c in 0..4 {
            let ivg = mul(&k.iv, &g[c]);
            let jg = mul_c(&self.inertia_kg_m2, &g[c]);
            for r in 0..=c {
                let mut s = dot(&g[r], &ivg) + dot(&v[r], &v[c]) * self.vane_mass_kg;
                if r < 3 && c < 3 {
                    s += dot(&g[r], &jg);
                }
                m[r][c] = s;
                m[c][r] = s;
            }
        }
        m
    }

    /// ẋ at state x (this model's layout); false where the equations are singular.
    pub fn rhs<T: Real>(&self, x: &[T], dx: &mut [T]) -> bool {
        let k = self.kinematics(x);
        let f = self.applied(&k);
        let f0 = self.f0(&k);
        let d = &self.drag_n_m_s_per_rad;
        match self.fidelity {
            Fidelity::Gyroscopic => {
                let z = T::zero();
                let (la, al) = (x[4], x[5]);
                // B's ζ and θ columns, and B q̇ₘ.
                let bz = self.f1(&k, &[T::one(), z, z, z]);
                let bt = self.f1(&k, &[z, T::one(), z, z]);
                let bm = self.f1(&k, &[z, z, la, al]);
                // (B_gg + D_g) q̇_g = F_g − f₀_g − (B q̇ₘ)_g.
                let a00 = bz[0] + d[0];
                let a01 = bt[0];
                let a10 = bz[1];
                let a11 = bt[1] + d[1];
                let r0 = f[0] - f0[0] - bm[0];
                let r1 = f[1] - f0[1] - bm[1];
                let det = a00 * a11 - a01 * a10;
                if det.re() == 0.0 || !det.re().is_finite() {
                    return false;
                }
                let zd = (r0 * a11 - r1 * a01) / det;
                let td = (a00 * r1 - a10 * r0) / det;
                // M_mm q̈ₘ = F_m − D_m q̇ₘ − (B q̇)_m − f₀_m − f₂(0, 0, λ̇, α̇)_m.
                let f2 = self.f2(&k, &[z, z, la, al]);
                let m = self.mass(&k);
                let b2 = bm[2] + bz[2] * zd + bt[2] * td;
                let b3 = bm[3] + bz[3] * zd + bt[3] * td;
                let r2 = f[2] - la * d[2] - b2 - f0[2] - f2[2];
                let r3 = f[3] - al * d[3] - b3 - f0[3] - f2[3];
                let det = m[2][2] * m[3][3] - m[2][3] * m[3][2];
                if det.re() == 0.0 || !det.re().is_finite() {
                    return false;
                }
                dx[0] = zd;
                dx[1] = td;
                dx[2] = la;
                dx[3] = al;
                dx[4] = (r2 * m[3][3] - r3 * m[2][3]) / det;
                dx[5] = (m[2][2] * r3 - m[3][2] * r2) / det;
                true
            }
            _ => {
                let qd = [x[4], x[5], x[6], x[7]];
                let f1 = self.f1(&k, &qd);
                let f2 = self.f2(&k, &qd);
                let mut r = [T::zero(); 4];
                for i in 0..4 {
                    r[i] = f[i] - qd[i] * d[i] - f0[i] - f1[i] - f2[i];
                }
                let m = self.mass(&k);
                if !solve_spd4(m, &mut r) {
                    return false;
                }
                dx[..4].copy_from_slice(&qd);
                dx[4..].copy_from_slice(&r);
                true
            }
        }
    }

    /// ∂ẋ/∂x (row-major), by one pass of forward-mode duals through [`Self::rhs`].
    pub fn jacobian(&self, x: &[f64], jac: &mut [f64]) -> bool {
        match self.fidelity {
            Fidelity::Gyroscopic => self.jacobian_n::<6>(x, jac),
            _ => self.jacobian_n::<8>(x, jac),
        }
    }

    fn jacobian_n<const D: usize>(&self, x: &[f64], jac: &mut [f64]) -> bool {
        let xj: [Jet<f64, D>; D] = std::array::from_fn(|i| Jet::variable(x[i], i));
        let mut dxj = [Jet::<f64, D>::constant(0.0); D];
        if !self.rhs(&xj, &mut dxj) {
            return false;
        }
        for (r, d) in dxj.iter().enumerate() {
            jac[r * D..(r + 1) * D].copy_from_slice(&d.d);
        }
        true
    }
}

/// Solves M y = r for a symmetric positive definite 4×4 M by LDLᵀ (r is overwritten by y).
#[inline(always)]
fn solve_spd4<T: Real>(m: [[T; 4]; 4], r: &mut [T; 4]) -> bool {
    let mut l = [[T::zero(); 4]; 4];
    let mut d = [T::zero(); 4];
    for j in 0..4 {
        let mut s = m[j][j];
        for k in 0..j {
            s -= l[j][k] * l[j][k] * d[k];
        }
        if !(s.re() > 0.0) {
            return false;
        }
        d[j] = s;
        for i in j + 1..4 {
            let mut s = m[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k] * d[k];
            }
            l[i][j] = s / d[j];
        }
    }
    for i in 0..4 {
        for k in 0..i {
            let t = l[i][k] * r[k];
            r[i] -= t;
        }
    }
    for i in 0..4 {
        r[i] = r[i] / d[i];
    }
    for i in (0..4).rev() {
        for k in i + 1..4 {
            let t = l[k][i] * r[k];
            r[i] -= t;
        }
    }
    true
}

impl OdeSystem for Anschutz1906 {
    fn dim(&self) -> usize {
        Anschutz1906::dim(self)
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
        if !Anschutz1906::rhs(self, x, dx) {
            dx.fill(f64::NAN);
        }
    }
    fn jacobian(&mut self, _t: f64, x: &[f64], jac: &mut [f64]) -> bool {
        Anschutz1906::jacobian(self, x, jac)
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}
