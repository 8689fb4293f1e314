//! Closed forms of the reference texts, computed from a design's own parameters. These are the
//! checks the engine is held to (the engine never uses them to move anything).
//!
//! Sources: `shared/physics/foucault-villarceau.md` (Villarceau 1855, eqs. 42–47) and
//! `shared/physics/anschutz-1906.md` (Beghin ch. II–III, eqs. 10, 18, 19–22, §30, §40),
//! `shared/physics/sperry-1911-and-slough.md` (Beghin ch. IV, eqs. 6, 10, 11, 40).

use crate::constants::{EARTH_RADIUS_M, EARTH_RATE_RAD_PER_S, STANDARD_GRAVITY_M_PER_S2};
use crate::dual::{M3, V3};
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Villarceau's pendulum form of Foucault's gyroscope: γ″ = (g/a)(−sin γ + 2δ sin γ cos γ).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Villarceau {
    /// g/a, 1/s² (negative when n < 0: the ring then oscillates about γ = π).
    pub g_over_a: f64,
    pub delta: f64,
}

/// Inputs of Villarceau's equation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VillarceauInputs {
    /// Torus transverse moment A, polar moment C, kg·m².
    pub a: f64,
    pub c: f64,
    /// Ring principal moments: A′ about the normal to the ring's plane (the plane of ring axis and
    /// torus axis), B′ about the in-plane axis ⟂ to the ring axis, C′ about the ring axis. (Read
    /// off eq. 46: the torus's A sin²η carries A′'s sign, and the engine's energy agrees.)
    pub a_ring: f64,
    pub b_ring: f64,
    pub c_ring: f64,
    /// Absolute spin of the torus about its axis, rad/s (eq. 42: n = w + ω cos θ₀).
    pub n: f64,
    /// Earth rate ω, rad/s.
    pub omega: f64,
    /// Polar distance θ′ of the ring axis, rad.
    pub theta_ring: f64,
    /// Angle η between torus axis and ring axis, rad.
    pub eta: f64,
}

impl Villarceau {
    /// Eqs. 45–46.
    pub fn new(p: &VillarceauInputs) -> Villarceau {
        let (se, ce) = p.eta.sin_cos();
        let (st, ct) = p.theta_ring.sin_cos();
        let k = p.c * p.n - p.a * p.omega * ce * ct;
        let inertia = p.a * se * se + p.c_ring;
        Villarceau {
            g_over_a: p.omega * st * se * k / inertia,
            delta: 0.5 * (p.omega * st / se) * (p.a * se * se + p.a_ring - p.b_ring) / k,
        }
    }

    /// The centre of oscillation: 0 for n > 0, π for n < 0.
    pub fn centre(&self) -> f64 {
        if self.g_over_a >= 0.0 { 0.0 } else { PI }
    }

    /// γ″ at γ (eq. 44 bis divided through).
    pub fn acceleration(&self, gamma: f64) -> f64 {
        // The engine's sine and cosine (`dual::sin_cos`), for a like-for-like benchmark.
        let (s, c) = crate::dual::sin_cos(gamma);
        self.g_over_a * (-s + 2.0 * self.delta * s * c)
    }

    /// The first integral γ′² − (2g/a)(cos γ − δ cos²γ), constant along motions (eq. 47).
    pub fn first_integral(&self, gamma: f64, gamma_rate: f64) -> f64 {
        let c = gamma.cos();
        gamma_rate * gamma_rate - 2.0 * self.g_over_a * (c - self.delta * c * c)
    }

    /// Period of the oscillation with turning point at γ₀ measured from the centre
    /// (0 < |γ₀| < π): the quadrature of eq. 47 with sin(γ/2) = sin(γ₀/2) sin φ.
    pub fn period(&self, amplitude_rad: f64) -> f64 {
        let (w2, delta) = if self.g_over_a >= 0.0 {
            (self.g_over_a, self.delta)
        } else {
            (-self.g_over_a, -self.delta)
        };
        let k = (amplitude_rad.abs() / 2.0).sin();
        let c0 = amplitude_rad.cos();
        let f = |phi: f64| {
            let s = k * phi.sin();
            let cg = 1.0 - 2.0 * s * s;
            1.0 / ((1.0 - s * s).sqrt() * (1.0 - delta * (cg + c0)).sqrt())
        };
        4.0 / w2.sqrt() * integrate(&f, 0.0, FRAC_PI_2, 1e-14)
    }

    /// Small-amplitude period 2π/√((g/a)(1 − 2δ)).
    pub fn small_amplitude_period(&self) -> f64 {
        let (w2, delta) = if self.g_over_a >= 0.0 {
            (self.g_over_a, self.delta)
        } else {
            (-self.g_over_a, -self.delta)
        };
        TAU / (w2 * (1.0 - 2.0 * delta)).sqrt()
    }
}

/// Adaptive Gauss–Kronrod (7–15) quadrature to a relative tolerance.
pub fn integrate(f: &dyn Fn(f64) -> f64, a: f64, b: f64, rel_tol: f64) -> f64 {
    const XGK: [f64; 8] = [
        0.991_455_371_120_812_6,
        0.949_107_912_342_758_5,
        0.864_864_423_359_769_1,
        0.741_531_185_599_394_4,
        0.586_087_235_467_691_1,
        0.405_845_151_377_397_2,
        0.207_784_955_007_898_5,
        0.0,
    ];
    const WGK: [f64; 8] = [
        0.022_935_322_010_529_22,
        0.063_092_092_629_978_55,
        0.104_790_010_322_250_2,
        0.140_653_259_715_525_9,
        0.169_004_726_639_267_9,
        0.190_350_578_064_785_4,
        0.204_432_940_075_298_9,
        0.209_482_141_084_728_8,
    ];
    const WG: [f64; 4] = [
        0.129_484_966_168_869_7,
        0.279_705_391_489_276_7,
        0.381_830_050_505_118_9,
        0.417_959_183_673_469_4,
    ];
    fn gk(f: &dyn Fn(f64) -> f64, a: f64, b: f64) -> (f64, f64) {
        let c = 0.5 * (a + b);
        let h = 0.5 * (b - a);
        let fc = f(c);
        let mut k = WGK[7] * fc;
        let mut g = WG[3] * fc;
        for j in 0..7 {
            let x = h * XGK[j];
            let s = f(c - x) + f(c + x);
            k += WGK[j] * s;
            if j % 2 == 1 {
                g += WG[j / 2] * s;
            }
        }
        (k * h, ((k - g) * h).abs())
    }
    let mut stack = vec![(a, b)];
    let mut total = 0.0;
    let whole = gk(f, a, b).0.abs().max(1e-300);
    let mut guard = 0;
    while let Some((x0, x1)) = stack.pop() {
        let (v, e) = gk(f, x0, x1);
        guard += 1;
        if e <= rel_tol * whole * (x1 - x0) / (b - a)
            || guard > 100_000
            || (x1 - x0) < 1e-15 * (b - a)
        {
            total += v;
        } else {
            let m = 0.5 * (x0 + x1);
            stack.push((x0, m));
            stack.push((m, x1));
        }
    }
    total
}

/// Beghin's elementary and precise Anschütz constants, SI.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Anschutz {
    /// Spin momentum IΩ, N·m·s.
    pub spin_momentum: f64,
    /// Pendulous moment aP, N·m.
    pub pendulous_moment: f64,
    /// Damper constant κ = f(c + k), N·m.
    pub kappa: f64,
    /// ℭ (about the vertical) and 𝔅 (about the East–West axis), kg·m².
    pub inertia_vertical: f64,
    pub inertia_east_west: f64,
    pub latitude_rad: f64,
}

impl Anschutz {
    /// τ = IΩε cos L.
    pub fn tau(&self) -> f64 {
        self.spin_momentum * EARTH_RATE_RAD_PER_S * self.latitude_rad.cos()
    }
    /// Undamped small-amplitude period (eq. 10): 2π√(IΩ/(aPε cos L)).
    pub fn undamped_period(&self) -> f64 {
        TAU * (self.spin_momentum
            / (self.pendulous_moment * EARTH_RATE_RAD_PER_S * self.latitude_rad.cos()))
        .sqrt()
    }
    /// Roots of (ℭr² + τ)(𝔅r² + aP) + IΩr(IΩr + κ) = 0, slow pair first, each polished by Newton.
    pub fn characteristic_roots(&self) -> [(f64, f64); 4] {
        let (c, b, h, k, ap, tau) = (
            self.inertia_vertical,
            self.inertia_east_west,
            self.spin_momentum,
            self.kappa,
            self.pendulous_moment,
            self.tau(),
        );
        // c4 r⁴ + c2 r² + c1 r + c0
        let coef = [tau * ap, h * k, c * ap + b * tau + h * h, 0.0, c * b];
        let mut roots = polynomial_roots(&coef);
        roots.sort_by(|x, y| (x.0 * x.0 + x.1 * x.1).total_cmp(&(y.0 * y.0 + y.1 * y.1)));
        [roots[0], roots[1], roots[2], roots[3]]
    }
    /// Latitude at which the tilt of the oscillation turns into revolution: θ_max = 2√(τ/aP).
    pub fn revolution_threshold_tilt(&self) -> f64 {
        2.0 * (self.tau() / self.pendulous_moment).sqrt()
    }
}

/// Beghin's Sperry 1911 constants (ch. IV, §42–45), SI. `latitude_dial_rad` is the bail's
/// setting η (Qlη + IΩε sin L_dial = 0 when the dial is set right).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sperry1911 {
    /// Main spin momentum IΩ, N·m·s.
    pub spin_momentum: f64,
    /// The bail's moment Ql, N·m.
    pub bail_moment: f64,
    /// The gyro-ballistic pendulum's moment ϖb, N·m.
    pub pendulum_moment: f64,
    /// The overload's moment ap, N·m.
    pub overload_moment: f64,
    /// The roller's offset angle ρ, rad.
    pub roller_offset: f64,
    /// The small gyro's spin momentum jω, N·m·s (its sign is the spin's).
    pub small_spin_momentum: f64,
    /// The small gyro's spring k (N·m/rad) and damper k₁ (N·m·s/rad).
    pub spring: f64,
    pub damper: f64,
    /// The bail's dial setting η, rad.
    pub dial_eta: f64,
    pub latitude_rad: f64,
}

impl Sperry1911 {
    /// The constants from a Sperry design's named parameters (`designs/sperry-1911.toml`), at
    /// `latitude_rad`; `None` if one is missing.
    pub fn from_design(d: &crate::Design, latitude_rad: f64) -> Option<Sperry1911> {
        let p = |k: &str| d.parameter(k);
        Some(Sperry1911 {
            spin_momentum: p("spin_momentum_n_m_s")?,
            bail_moment: p("bail_moment_n_m")?,
            pendulum_moment: p("pendulum_moment_n_m")?,
            overload_moment: p("overload_moment_n_m")?,
            roller_offset: p("roller_offset_rad")?,
            small_spin_momentum: p("small_spin_momentum_n_m_s")?,
            spring: p("small_gyro_spring_n_m_per_rad")?,
            damper: p("small_gyro_damper_n_m_s_per_rad")?,
            dial_eta: p("dial_eta_rad")?,
            latitude_rad,
        })
    }
    /// τ = IΩε cos L.
    pub fn tau(&self) -> f64 {
        self.spin_momentum * EARTH_RATE_RAD_PER_S * self.latitude_rad.cos()
    }
    /// 𝒫 = Ql + ϖb + ap, the precise model's whole tilt moment (§45).
    pub fn pendulous_moment(&self) -> f64 {
        self.bail_moment + self.pendulum_moment + self.overload_moment
    }
    /// The elementary undamped period (eq. 6): 2π√(IΩ/((Ql + ϖb)ε cos L)).
    pub fn elementary_period(&self) -> f64 {
        TAU * (self.spin_momentum
            / ((self.bail_moment + self.pendulum_moment)
                * EARTH_RATE_RAD_PER_S
                * self.latitude_rad.cos()))
        .sqrt()
    }
    /// The damping factor h = Qlρ/(2IΩ) of eq. 11, 1/s.
    pub fn damping_factor(&self) -> f64 {
        self.bail_moment * self.roller_offset / (2.0 * self.spin_momentum)
    }
    /// The latitude error of eq. 10 (errata: ρ restored), ζ = −ρ tan L, West positive.
    pub fn latitude_error(&self) -> f64 {
        -self.roller_offset * self.latitude_rad.tan()
    }
    /// Roots of the characteristic equation (40):
    /// (I²Ω²r² + QlρIΩr + τ𝒫)(j²ω²r² + k₁ϖb r + kϖb) + 𝒫jωr(k + k₁r)(jωr + Qlη) = 0,
    /// the compass pair first, then the gyro-ballistic pair.
    pub fn characteristic_roots(&self) -> [(f64, f64); 4] {
        let (h, ql, wb, p, j) = (
            self.spin_momentum,
            self.bail_moment,
            self.pendulum_moment,
            self.pendulous_moment(),
            self.small_spin_momentum,
        );
        let (k, k1, eta) = (self.spring, self.damper, self.dial_eta);
        let a = [self.tau() * p, ql * self.roller_offset * h, h * h];
        let b = [k * wb, k1 * wb, j * j];
        let mut coef = [0.0; 5];
        for (i, ai) in a.iter().enumerate() {
            for (l, bl) in b.iter().enumerate() {
                coef[i + l] += ai * bl;
            }
        }
        // 𝒫jω r (k + k₁r)(jωr + Qlη)
        coef[1] += p * j * k * ql * eta;
        coef[2] += p * j * (k * j + k1 * ql * eta);
        coef[3] += p * j * k1 * j;
        let mut roots = polynomial_roots(&coef);
        roots.sort_by(|x, y| (x.0 * x.0 + x.1 * x.1).total_cmp(&(y.0 * y.0 + y.1 * y.1)));
        [roots[0], roots[1], roots[2], roots[3]]
    }
}

/// The Slough (Beghin §50–53): the Sperry with its bail replaced by communicating mercury pots
/// and the spin reversed. K = 2ϖω₀h² − Ql is the liquid counterweight's moment.
#[derive(Clone, Debug)]
pub struct Slough {
    /// Main spin momentum IΩ, N·m·s: negative (the spin is reversed).
    pub spin_momentum: f64,
    /// 2ϖω₀h², N·m: the moment of the liquid that flows.
    pub liquid_moment: f64,
    /// Ql: the pendulous moment (positive below the axis) of the pots' frame and the mercury
    /// solidified at equal levels, about the frame's hinge, N·m.
    pub solid_moment: f64,
    /// ap, N·m.
    pub overload_moment: f64,
    /// ρ, rad.
    pub roller_offset: f64,
    /// η, rad.
    pub dial_eta: f64,
    /// h, m.
    pub half_spacing: f64,
    /// ℰ, kg; the level's stiffness 2ϖω₀, N/m; the flow's friction k, N·s/m.
    pub flow_inertia: f64,
    pub level_stiffness: f64,
    pub friction: f64,
    pub latitude_rad: f64,
}

impl Slough {
    /// The constants of a design with one `[[pots]]` entry, its rotor body `rotor` and the
    /// parameters `overload_moment_n_m`, `roller_offset_rad`, `dial_eta_rad`
    /// (`designs/slough.toml`). K is computed from the pots' geometry and the carrier's mass,
    /// not from the parameters that chose them. `None` if something is missing.
    pub fn from_design(d: &crate::Design, latitude_rad: f64) -> Option<Slough> {
        let g = STANDARD_GRAVITY_M_PER_S2;
        let pots = d.pots.first()?;
        let carrier = &d.bodies[pots.body];
        let rotor_body = &d.bodies[d.body_index("rotor")?];
        let rotor = rotor_body.rotor.as_ref()?;
        let rho_w0 = pots.density_kg_per_m3 * pots.section_m2;
        let c = pots.rest_level_m;
        // The open columns at rest: mass ρω₀c each, centred c/2 along the axis above the base.
        let columns_first_moment: f64 = pots
            .bases_m
            .iter()
            .map(|b| rho_w0 * c * (b[2] + 0.5 * c * pots.axis[2]))
            .sum();
        let h = pots.half_spacing_m();
        Some(Slough {
            spin_momentum: rotor.polar_inertia_kg_m2 * rotor.spin_rad_per_s,
            liquid_moment: 2.0 * rho_w0 * g * h * h,
            solid_moment: -g * (carrier.mass_kg * carrier.cg_m[2] + columns_first_moment),
            overload_moment: d.parameter("overload_moment_n_m")?,
            roller_offset: d.parameter("roller_offset_rad")?,
            dial_eta: d.parameter("dial_eta_rad")?,
            half_spacing: h,
            flow_inertia: pots.flow_inertia_kg(),
            level_stiffness: pots.level_stiffness_n_per_m(g),
            friction: pots.friction_n_s_per_m,
            latitude_rad,
        })
    }
    /// K = 2ϖω₀h² − Ql, N·m.
    pub fn counterweight_moment(&self) -> f64 {
        self.liquid_moment - self.solid_moment
    }
    /// τ = IΩε cos L (negative).
    pub fn tau(&self) -> f64 {
        self.spin_momentum * EARTH_RATE_RAD_PER_S * self.latitude_rad.cos()
    }
    /// The tilt's restoring moment with the Earth term restored: K − ap − τ. The text's (20)–(22)
    /// write K − ap, dropping τ = IΩε cos L against ap; in the tilt equation (15) it stands
    /// beside 𝒫, as (Ql + ϖb + τ) does in the Sperry's (§44). With the Slough's numbers |τ| is
    /// a tenth of ap, so the stability boundary moves by a tenth.
    pub fn restoring_moment(&self) -> f64 {
        self.counterweight_moment() - self.overload_moment - self.tau()
    }
    /// Stable (eq. 21, τ restored) when K > ap + τ with Ω < 0.
    pub fn is_stable(&self) -> bool {
        self.spin_momentum < 0.0 && self.restoring_moment() > 0.0
    }
    /// The compass period of eq. (22), τ restored: 4π²/T² = ε cos L (K − ap − τ)/(−IΩ), s.
    pub fn period(&self) -> f64 {
        let w2 = EARTH_RATE_RAD_PER_S * self.latitude_rad.cos() * self.restoring_moment()
            / (-self.spin_momentum);
        TAU / w2.sqrt()
    }
    /// The damping factor of eq. (23), ρK/(−2IΩ), 1/s.
    pub fn damping_factor(&self) -> f64 {
        self.roller_offset * self.counterweight_moment() / (-2.0 * self.spin_momentum)
    }
    /// The roots of eq. (20), τ restored, I²Ω²r² − IΩρK r − τ(K − ap − τ) = 0: the compass pair.
    pub fn compass_roots(&self) -> [(f64, f64); 2] {
        let k = self.counterweight_moment();
        let h = self.spin_momentum;
        let c = [
            -self.tau() * self.restoring_moment(),
            -h * self.roller_offset * k,
            h * h,
        ];
        let r = polynomial_roots(&c);
        [r[0], r[1]]
    }
    /// The roots of the trinomial ℰr² + kr + 2ϖω₀: the mercury's own mode in its pots held.
    pub fn mercury_roots(&self) -> [(f64, f64); 2] {
        let r = polynomial_roots(&[self.level_stiffness, self.friction, self.flow_inertia]);
        [r[0], r[1]]
    }
    /// The latitude error of eq. (18), ζ = −ρ tan L (the Sperry's), rad.
    pub fn latitude_error(&self) -> f64 {
        -self.roller_offset * self.latitude_rad.tan()
    }
    /// The level at equilibrium, u = hη (eq. 18), m.
    pub fn equilibrium_level(&self) -> f64 {
        self.half_spacing * self.dial_eta
    }
    /// The azimuth's step after a North speed change δv once the mercury has settled (eq. 30):
    /// IΩδV = (𝒫 − 2ϖω₀h²)δv/g with 𝒫 = ap + Ql, rad.
    pub fn speed_change_deviation(&self, delta_v_m_per_s: f64) -> f64 {
        (self.overload_moment + self.solid_moment - self.liquid_moment) * delta_v_m_per_s
            / (STANDARD_GRAVITY_M_PER_S2 * self.spin_momentum)
    }
}

/// The Sperry twin-gyro 1918 (Beghin ch. V, §54–58): West gyro (pendulous ap, spin North) and
/// East gyro (2ap, spin South) l either side of the frame, the East one on a torsion wire of
/// stiffness M, a spring of rate k between arms c below the pivots, the frame servo-driven to
/// follow the West ring. In the text's coordinates x = kl², y = M, and IΩr = u√(ap) (eq. 23).
#[derive(Clone, Debug)]
pub struct TwinGyro {
    /// IΩ of each gyro, N·m·s.
    pub spin_momentum: f64,
    /// ap, the West box's pendulous moment, N·m (the East box's is 2ap).
    pub pendulous_moment: f64,
    /// The East box's pendulous moment as built, N·m (2ap in the text).
    pub east_pendulous_moment: f64,
    /// k, N/m; l, c, m.
    pub spring_rate: f64,
    pub half_spacing: f64,
    pub spring_depth: f64,
    /// T₀ at the drawn length, N.
    pub spring_tension: f64,
    /// M, N·m/rad, and the pre-torque N, N·m.
    pub wire_stiffness: f64,
    pub wire_pretorque: f64,
    pub latitude_rad: f64,
}

impl TwinGyro {
    /// The constants of a design built like `designs/sperry-twin-1918.toml`, read from its
    /// bodies and forces (not from the parameters that chose them): the rotor of body
    /// `west_rotor`, the boxes `west_box` and `east_box` (their weight's moment about the
    /// pivot), the `link_spring` (k, and l and c from its first attachment point) and the
    /// `spring` named `torsion_wire` (M, N). `None` if something is missing.
    pub fn from_design(d: &crate::Design, latitude_rad: f64) -> Option<TwinGyro> {
        let g = STANDARD_GRAVITY_M_PER_S2;
        let rotor = d.bodies[d.body_index("west_rotor")?].rotor.as_ref()?;
        let moment = |name: &str| -> Option<f64> {
            let b = &d.bodies[d.body_index(name)?];
            Some(-g * b.mass_kg * b.cg_m[2])
        };
        let (k, point, tension) = d.forces.iter().find_map(|f| match f {
            crate::Force::LinkSpring {
                stiffness,
                points,
                tension,
                ..
            } => Some((*stiffness, points[0], *tension)),
            _ => None,
        })?;
        let (m, n) = d.forces.iter().find_map(|f| match f {
            crate::Force::Spring {
                name,
                stiffness,
                preload,
                ..
            } if name == "torsion_wire" => Some((*stiffness, *preload)),
            _ => None,
        })?;
        Some(TwinGyro {
            spin_momentum: rotor.polar_inertia_kg_m2 * rotor.spin_rad_per_s,
            pendulous_moment: moment("west_box")?,
            east_pendulous_moment: moment("east_box")?,
            spring_rate: k,
            half_spacing: point[1].abs(),
            spring_depth: -point[2],
            spring_tension: tension,
            wire_stiffness: m,
            wire_pretorque: n,
            latitude_rad,
        })
    }
    /// τ = IΩε cos L, N·m.
    pub fn tau(&self) -> f64 {
        self.spin_momentum * EARTH_RATE_RAD_PER_S * self.latitude_rad.cos()
    }
    /// σ = IΩε sin L, N·m.
    pub fn sigma(&self) -> f64 {
        self.spin_momentum * EARTH_RATE_RAD_PER_S * self.latitude_rad.sin()
    }
    /// x = kl², N·m.
    pub fn x(&self) -> f64 {
        self.spring_rate * self.half_spacing * self.half_spacing
    }
    /// y = M, N·m.
    pub fn y(&self) -> f64 {
        self.wire_stiffness
    }
    /// klc, N·m: the servo's coupling through c.
    pub fn klc(&self) -> f64 {
        self.spring_rate * self.half_spacing * self.spring_depth
    }
    /// γ_c = klc/√(ap), √(N·m).
    fn gamma(&self) -> f64 {
        self.klc() / self.pendulous_moment.sqrt()
    }
    /// The characteristic quartic in u (coefficients lowest first; eq. 24 for c = 0, with the
    /// c ≠ 0 terms γ_c u(2u² + 3y − 4τ) − 6γ_c²τ of the digest for c ≠ 0).
    pub fn quartic(&self) -> [f64; 5] {
        let (x, y, t, g) = (self.x(), self.y(), self.tau(), self.gamma());
        [
            2.0 * t * (y + 2.0 * x - t) - 6.0 * g * g * t,
            g * (3.0 * y - 4.0 * t),
            2.0 * y + x - t,
            2.0 * g,
            1.0,
        ]
    }
    /// The quartic's roots as r = u√(ap)/IΩ, 1/s, the long-period pair first.
    pub fn roots(&self) -> [(f64, f64); 4] {
        let s = self.pendulous_moment.sqrt() / self.spin_momentum;
        let mut r: Vec<(f64, f64)> = polynomial_roots(&self.quartic())
            .into_iter()
            .map(|(a, b)| (a * s, b * s))
            .collect();
        r.sort_by(|p, q| p.0.hypot(p.1).total_cmp(&q.0.hypot(q.1)));
        [r[0], r[1], r[2], r[3]]
    }
    /// The roots of the gyro-dominated equations (22) themselves (the 4 × 4 system in ζ, θ, α,
    /// β with IΩ the only inertia), keeping the τ-beside-ap and kc² terms the quartic drops.
    pub fn reduced_model_roots(&self) -> [(f64, f64); 4] {
        let (x, y, t, kap) = (self.x(), self.y(), self.tau(), self.klc());
        let kc2 = self.spring_rate * self.spring_depth * self.spring_depth;
        let (ap, ap2) = (self.pendulous_moment, self.east_pendulous_moment);
        let h = self.spin_momentum;
        // Rows: IΩζ′, IΩθ′, IΩα′, IΩβ′; columns ζ, θ, α, β.
        let a = [
            [-kap, kap, -(ap + t) - kc2, kc2],
            [-kap, kap, -kc2, ap2 - t + kc2],
            [t - x, x, -kap, kap],
            [x + y, t - x - y, kap, -kap],
        ];
        let flat: Vec<f64> = a.iter().flatten().map(|v| v / h).collect();
        let mut r = crate::linalg::eigenvalues(&flat, 4);
        r.sort_by(|p, q| p.0.hypot(p.1).total_cmp(&q.0.hypot(q.1)));
        [r[0], r[1], r[2], r[3]]
    }
    /// The two periods 2π/|Im r| (2πIΩ/√(ap z₁,₂) for c = 0), long first, s.
    pub fn periods(&self) -> [f64; 2] {
        let r = self.roots();
        [TAU / r[0].1.abs(), TAU / r[2].1.abs()]
    }
    /// The two damping factors −Re r, long-period mode first, 1/s. They sum to klc/IΩ.
    pub fn damping_factors(&self) -> [f64; 2] {
        let r = self.roots();
        [-r[0].0, -r[2].0]
    }
    /// The West gyro alone (no spring, no East gyro): IΩζ′ = −(ap + τ)α, IΩα′ = τζ, s.
    pub fn west_alone_period(&self) -> f64 {
        TAU * self.spin_momentum / ((self.pendulous_moment + self.tau()) * self.tau()).sqrt()
    }
    /// The wire stiffness on the hyperbola H at this design's x and τ, N·m:
    /// M = τ − x + √(x² + 6τx + τ²).
    pub fn hyperbola_wire_stiffness(&self) -> f64 {
        let (x, t) = (self.x(), self.tau());
        t - x + (x * x + 6.0 * t * x + t * t).sqrt()
    }
    /// The wire stiffness on the parabola P at this design's x and τ (the larger root of
    /// (2y + x − τ)² = 8τ(y + 2x − τ) in y, N·m), where the two periods meet.
    pub fn parabola_wire_stiffness(&self) -> f64 {
        let (x, t) = (self.x(), self.tau());
        // 4y² + 4y(x − τ) + (x − τ)² − 8τy − 16τx + 8τ² = 0
        let (a, b, c) = (
            4.0,
            4.0 * (x - t) - 8.0 * t,
            (x - t) * (x - t) - 16.0 * t * x + 8.0 * t * t,
        );
        (-b + (b * b - 4.0 * a * c).max(0.0).sqrt()) / (2.0 * a)
    }
    /// The wire's pre-torque that puts the equilibrium at ζ = 0 (eq. 21, no surcharge):
    /// N = (τ − M)[−(3c/2l)σ/ap − T₀/(kl)], N·m.
    pub fn zero_error_pretorque(&self) -> f64 {
        let (l, c) = (self.half_spacing, self.spring_depth);
        (self.tau() - self.wire_stiffness)
            * (-1.5 * c / l * self.sigma() / self.pendulous_moment
                - self.spring_tension / (self.spring_rate * l))
    }
    /// The factor of the text on the single-frame mean rolling error after compensation (54):
    /// (2/3)[2ap(y − x − τ) + 3kc²(y − τ)]/[2ap(y + 2x − τ) + 3kc²(y − τ)], → 2/3 as M ≫ x, τ.
    pub fn rolling_factor(&self) -> f64 {
        let (x, y, t, ap) = (self.x(), self.y(), self.tau(), self.pendulous_moment);
        let kc2 = self.spring_rate * self.spring_depth * self.spring_depth;
        2.0 / 3.0 * (2.0 * ap * (y - x - t) + 3.0 * kc2 * (y - t))
            / (2.0 * ap * (y + 2.0 * x - t) + 3.0 * kc2 * (y - t))
    }
}

/// The Anschütz three-gyro 1912 (Beghin ch. VI): three gyros of momentum IΩ on a float of
/// righting moment Πf, the lateral linkage's rate P, the South gyro's springs p, and the oil
/// tank of §67 (two compartment kinds, S₁ at w₁ and S₂ at w₂, joined in a ring by tubes of
/// resistance b). Inertias are the float's whole (gyros included) about its axes through O.
#[derive(Clone, Debug)]
pub struct ThreeGyro {
    /// IΩ of each gyro, N·m·s.
    pub spin_momentum: f64,
    /// Πf of the float with its gyros and oil at rest (free surfaces not counted), N·m.
    pub righting_moment: f64,
    /// ϖE, ϖF: the oil's free surfaces' moments about the East–West and North–South axes, N·m.
    pub free_surface_e: f64,
    pub free_surface_f: f64,
    /// P, the linkage springs' rate, and p, the South gyro's springs', N·m/rad.
    pub linkage_rate: f64,
    pub south_spring_rate: f64,
    /// 𝒞, ℬ, 𝒜: the whole float's moments about its vertical, East–West and North–South axes
    /// through O; c = C₁ + C₂, one gyro's box and rotor about its own vertical, kg·m².
    pub inertia_c: f64,
    pub inertia_b: f64,
    pub inertia_a: f64,
    pub box_inertia: f64,
    /// ϖ = ρg, N/m³; a, m; S₁, S₂, m²; w₁, w₂, rad; b, s/m² (the tank; zero without one).
    pub oil_weight_density: f64,
    pub tank_radius: f64,
    pub areas: [f64; 2],
    pub azimuths: [f64; 2],
    pub flow_resistance: f64,
    pub latitude_rad: f64,
}

impl ThreeGyro {
    /// The constants of a design built like `designs/anschutz-three-gyro-1912.toml`, read from
    /// its bodies, forces and tank (not from the parameters that chose them): the rotor of
    /// `south_rotor`, the bodies from `float` down, the springs `linkage_springs` and
    /// `south_springs`, the first tank's first two compartments and first tube.
    pub fn from_design(d: &crate::Design, latitude_rad: f64) -> Option<ThreeGyro> {
        let g = STANDARD_GRAVITY_M_PER_S2;
        let float = d.body_index("float")?;
        let rotor = d.bodies[d.body_index("south_rotor")?].rotor.as_ref()?;
        // Each body's rotation and origin in the float's axes at rest (hinges at zero).
        let n = d.bodies.len();
        let mut pose: Vec<Option<(M3<f64>, V3<f64>)>> = vec![None; n];
        pose[float] = Some((M3::identity(), V3::zero()));
        for i in float + 1..n {
            let b = &d.bodies[i];
            if let Some((rp, op)) = b.parent.and_then(|p| pose[p]) {
                let r = rp.mul_m(&M3::from_f64(b.joint_rotation));
                let o = op.add(&rp.mul_v(&V3::from_f64(b.joint_origin_m)));
                pose[i] = Some((r, o));
            }
        }
        let (mut inertia, mut moment) = ([[0.0; 3]; 3], 0.0);
        for (i, p) in pose.iter().enumerate() {
            let Some((r, o)) = p else { continue };
            let b = &d.bodies[i];
            let c = o.add(&r.mul_v(&V3::from_f64(b.cg_m))).0;
            moment -= g * b.mass_kg * c[2];
            // R I Rᵀ: the body's inertia in the float's axes.
            let ri = r.mul_m(&M3::from_f64(b.inertia_kg_m2));
            let rot = ri.mul_m(&M3([0, 1, 2].map(|j| r.col(j).0))).0;
            let c2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
            for (j, row) in inertia.iter_mut().enumerate() {
                for (k, x) in row.iter_mut().enumerate() {
                    *x += rot[j][k] + b.mass_kg * (if j == k { c2 } else { 0.0 } - c[j] * c[k]);
                }
            }
        }
        let box_inertia = d.bodies[d.body_index("south_box")?].inertia_kg_m2[2][2]
            + d.bodies[d.body_index("south_rotor")?].inertia_kg_m2[2][2];
        let spring = |name: &str| {
            d.forces.iter().find_map(|f| match f {
                crate::Force::Spring {
                    name: n, stiffness, ..
                } if n == name => Some(*stiffness),
                _ => None,
            })
        };
        let mut th = ThreeGyro {
            spin_momentum: rotor.polar_inertia_kg_m2 * rotor.spin_rad_per_s,
            righting_moment: moment,
            free_surface_e: 0.0,
            free_surface_f: 0.0,
            linkage_rate: spring("linkage_springs")?,
            south_spring_rate: spring("south_springs")?,
            inertia_c: inertia[2][2],
            inertia_b: inertia[1][1],
            inertia_a: inertia[0][0],
            box_inertia,
            oil_weight_density: 0.0,
            tank_radius: 0.0,
            areas: [0.0; 2],
            azimuths: [0.0; 2],
            flow_resistance: 0.0,
            latitude_rad,
        };
        if let Some(t) = d.tanks.first() {
            let w = t.density_kg_per_m3 * g;
            let z = t.floor_height_m + 0.5 * t.rest_depth_m;
            let (c0, c1) = (&t.compartments[0], &t.compartments[1]);
            th.righting_moment -=
                w * t.rest_depth_m * z * t.compartments.iter().map(|c| c.area_m2).sum::<f64>();
            th.free_surface_e = w * t
                .compartments
                .iter()
                .map(|c| c.free_surface_m4[1])
                .sum::<f64>();
            th.free_surface_f = w * t
                .compartments
                .iter()
                .map(|c| c.free_surface_m4[0])
                .sum::<f64>();
            th.oil_weight_density = w;
            th.tank_radius = c0.centroid_m[0].hypot(c0.centroid_m[1]);
            th.areas = [c0.area_m2, c1.area_m2];
            th.azimuths = [
                c0.centroid_m[1].atan2(c0.centroid_m[0]),
                c1.centroid_m[1].atan2(c1.centroid_m[0]),
            ];
            th.flow_resistance = t.tubes.first().map_or(0.0, |tb| tb.2);
        }
        Some(th)
    }
    /// τ = IΩε cos L of one gyro, N·m.
    pub fn tau(&self) -> f64 {
        self.spin_momentum * EARTH_RATE_RAD_PER_S * self.latitude_rad.cos()
    }
    /// 𝓗 = IΩ(1 + √3), N·m·s (eq. 1 at β = 0).
    pub fn total_momentum(&self) -> f64 {
        self.spin_momentum * (1.0 + 3f64.sqrt())
    }
    /// Πf − ϖE, N·m.
    pub fn effective_righting_moment(&self) -> f64 {
        self.righting_moment - self.free_surface_e
    }
    /// Eq. (5): T = 2π√(IΩ(1 + √3)/((Πf − ϖE) ε cos L)), s.
    pub fn azimuth_period_s(&self) -> f64 {
        TAU * (self.total_momentum()
            / (self.effective_righting_moment() * EARTH_RATE_RAD_PER_S * self.latitude_rad.cos()))
        .sqrt()
    }
    /// Eq. (10) with (54)'s P + τ√3: T₁ = 2πIΩ/√((P + τ√3)(Πf − ϖF)), s.
    pub fn lateral_period_s(&self) -> f64 {
        TAU * self.spin_momentum
            / ((self.linkage_rate + self.tau() * 3f64.sqrt())
                * (self.righting_moment - self.free_surface_f))
                .sqrt()
    }
    /// The mean azimuth error under a horizontal acceleration J₀ sin σt athwartships on heading
    /// Δ (a rolling sea), from the second-order terms of (51) the text names (§70, L3131),
    /// re-derived: τ(1 + √3)ζ = Πf⟨J_x λ⟩/g + ϖ(E − F)⟨J_x J_y⟩/g², with ⟨J_x J_y⟩ = ½J₀² sinΔ cosΔ.
    /// The heel λ is the lateral group's forced response (eqs. 10, 54 without the oil), far
    /// above its 1-min frequency: λ/(J_y/g) = (Πf − ϖF)/(σ²I²Ω²/(P + τ√3 − 2cσ²) + 𝒜σ² − (Πf − ϖF)),
    /// ≈ (T_swell/T₁)², "une oscillation forcée d'amplitude très faible". The oil's v₁, v₂ lag
    /// the swell by a quarter period (their time constants are minutes) and are left out.
    /// Returns (the heel's term, the free surfaces' term), rad, signed as they add.
    pub fn rolling_error_terms_rad(&self, j0: f64, sigma: f64, heading_rad: f64) -> (f64, f64) {
        let g = STANDARD_GRAVITY_M_PER_S2;
        let (h, s2) = (self.spin_momentum, sigma * sigma);
        let pf_lateral = self.righting_moment - self.free_surface_f;
        let p_lateral = self.linkage_rate + self.tau() * 3f64.sqrt();
        let gain = pf_lateral
            / (s2 * h * h / (p_lateral - 2.0 * self.box_inertia * s2) + self.inertia_a * s2
                - pf_lateral);
        let jj = 0.5 * j0 * j0 * heading_rad.sin() * heading_rad.cos() / (g * g);
        let directive = self.tau() * (1.0 + 3f64.sqrt());
        (
            self.righting_moment * gain * jj / directive,
            (self.free_surface_e - self.free_surface_f) * jj / directive,
        )
    }
    /// The five root families of the precise undamped model (10)–(12), as angular frequencies
    /// |r| (1/s): the South springs' mode r₁ ≈ √(p(1 + √3)²/(𝒞 + 2c)), the azimuth r₂ =
    /// √(τΠf/(I²Ω²(1 + √3))), the nutation r₃ = IΩ√((𝒞 + 2c)/((𝒞 − c)ℬc)), the lateral r₄ =
    /// √(PΠf)/IΩ, the lateral nutation r₅ = IΩ/√(2c𝒜).
    pub fn root_families(&self) -> [f64; 5] {
        let (h, s3) = (self.spin_momentum, 1.0 + 3f64.sqrt());
        let (cc, bb, aa, c) = (
            self.inertia_c,
            self.inertia_b,
            self.inertia_a,
            self.box_inertia,
        );
        let pf = self.effective_righting_moment();
        [
            (self.south_spring_rate * s3 * s3 / (cc + 2.0 * c)).sqrt(),
            (self.tau() * pf / (h * h * s3)).sqrt(),
            h * ((cc + 2.0 * c) / ((cc - c) * bb * c)).sqrt(),
            ((self.linkage_rate + self.tau() * 3f64.sqrt())
                * (self.righting_moment - self.free_surface_f))
                .sqrt()
                / h,
            h / (2.0 * c * aa).sqrt(),
        ]
    }
    fn cos2(&self) -> (f64, f64) {
        (self.azimuths[0].cos(), self.azimuths[1].cos())
    }
    /// k of eq. (59), 1/m: (Πf − ϖE)k = 4ϖa²(cos²w₁ − 2cos w₁cos w₂ + 3cos²w₂).
    pub fn tank_k(&self) -> f64 {
        let (c1, c2) = self.cos2();
        4.0 * self.oil_weight_density
            * self.tank_radius.powi(2)
            * (c1 * c1 - 2.0 * c1 * c2 + 3.0 * c2 * c2)
            / self.effective_righting_moment()
    }
    /// The left side of (62) over its right, 4ϖa²(S₁cos²w₁ + S₂cos²w₂)/(Πf − ϖE): the azimuth
    /// motion is unstable above 1 (kal above ≈ 0.31 for the tank of table (61)).
    pub fn free_surface_ratio(&self) -> f64 {
        let (c1, c2) = self.cos2();
        4.0 * self.oil_weight_density
            * self.tank_radius.powi(2)
            * (self.areas[0] * c1 * c1 + self.areas[1] * c2 * c2)
            / self.effective_righting_moment()
    }
    /// m₁, m₂ (roots of (57), the tank's own antisymmetric modes per unit flow y = 1/b) and m₃
    /// of (60), 1/m².
    pub fn tank_m(&self) -> [f64; 3] {
        let [s1, s2] = self.areas;
        let (c1, c2) = self.cos2();
        let disc = ((3.0 * s1 + s2).powi(2) - 8.0 * s1 * s2).sqrt();
        let m1 = (-(3.0 * s1 + s2) + disc) / (2.0 * s1 * s2);
        let m2 = (-(3.0 * s1 + s2) - disc) / (2.0 * s1 * s2);
        let shape = c1 * c1 - 2.0 * c1 * c2 + 3.0 * c2 * c2;
        let m3 = -2.0 * (s1 * c1 * c1 + s2 * c2 * c2) / (s1 * s2 * shape);
        [m1, m2, m3]
    }
    /// K of (56), s²: Kτ(Πf − ϖE) = I²Ω²(1 + √3); 2π√K is the undamped azimuth period.
    pub fn tank_big_k(&self) -> f64 {
        self.spin_momentum.powi(2) * (1.0 + 3f64.sqrt())
            / (self.tau() * self.effective_righting_moment())
    }
    /// The four roots of (55), (r − μy)(r − μ′y) + Kr²(r − m₁y)(r − m₂y) = 0, for the flow
    /// y = 1/b (m²/s), as (re, im) in 1/s, μ and μ′ the roots of (58).
    pub fn tank_roots(&self, y: f64) -> Vec<(f64, f64)> {
        let [m1, m2, m3] = self.tank_m();
        let k = self.tank_k();
        // μ² − (m₁ + m₂ + k)μ + m₁m₂ + k m₃ = 0: only the sum and product enter.
        let (mu_sum, mu_prod) = (m1 + m2 + k, m1 * m2 + k * m3);
        let kk = self.tank_big_k();
        polynomial_roots(&[
            mu_prod * y * y,
            -mu_sum * y,
            1.0 + kk * m1 * m2 * y * y,
            -kk * (m1 + m2) * y,
            kk,
        ])
    }
    /// The oscillating pair of (55) at flow y, r = −p ± iq (1/s): the complex pair of the
    /// largest frequency; `None` if all four roots are real.
    pub fn tank_pair(&self, y: f64) -> Option<(f64, f64)> {
        self.tank_roots(y)
            .into_iter()
            .filter(|r| r.1.abs() > 1e-9 * r.0.hypot(r.1))
            .map(|r| (r.0, r.1.abs()))
            .max_by(|a, b| a.1.total_cmp(&b.1))
    }
    /// The oscillating pair of (55) at flow y: its log-decrement 2π|re|/|im| and its period
    /// 2π/|im| (s); `None` if all four roots are real.
    pub fn tank_oscillation(&self, y: f64) -> Option<(f64, f64)> {
        let (re, im) = self.tank_pair(y)?;
        Some((TAU * -re / im, TAU / im))
    }
    /// The flow y = 1/b (m²/s) of §68's "maximum d'amortissement": the largest damping factor
    /// −p of the oscillating pair (the distance M₁P₁ of fig. 14 that the text maximises by its
    /// tangent construction (67)), by golden-section search on ln y over the range where the
    /// pair oscillates. It is the flow §69 adjusts to and under which §70's back-swing is
    /// "exactement le double" of the Slough's. (The largest log-decrement 2πp/q is another
    /// optimum, ≈ 14 % more flow at kal = 0.2, with a longer period: 1.37 × 2π√K against 1.28.)
    pub fn optimal_flow(&self) -> f64 {
        let damping = |ly: f64| self.tank_pair(ly.exp()).map_or(-1.0, |r| -r.0);
        // A coarse scan brackets the maximum, golden sections refine it.
        let (lo, hi) = (-25.0f64, 0.0f64);
        let steps = 700;
        let best = (0..=steps)
            .map(|i| lo + (hi - lo) * i as f64 / steps as f64)
            .max_by(|a, b| damping(*a).total_cmp(&damping(*b)))
            .unwrap_or(0.0);
        let h = (hi - lo) / steps as f64;
        let (mut a, mut b) = (best - h, best + h);
        let gr = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..80 {
            let (c, d) = (b - gr * (b - a), a + gr * (b - a));
            if damping(c) > damping(d) {
                b = d;
            } else {
                a = c;
            }
        }
        (0.5 * (a + b)).exp()
    }
}

/// Roots of Σ cᵢ rⁱ (coefficients lowest first) as (re, im), by the companion matrix, then
/// polished by complex Newton on the polynomial (so tiny roots next to huge ones keep their
/// relative accuracy).
pub fn polynomial_roots(c: &[f64]) -> Vec<(f64, f64)> {
    let deg = c.len() - 1;
    let lead = c[deg];
    let mut comp = vec![0.0; deg * deg];
    for i in 1..deg {
        comp[i * deg + i - 1] = 1.0;
    }
    for i in 0..deg {
        comp[i * deg + deg - 1] = -c[i] / lead;
    }
    let mut roots = crate::linalg::eigenvalues(&comp, deg);
    for r in roots.iter_mut() {
        for _ in 0..50 {
            // Horner in complex arithmetic for p and p'.
            let (mut p, mut dp) = ((0.0, 0.0), (0.0, 0.0));
            for &ci in c.iter().rev() {
                dp = cadd(cmul(dp, *r), p);
                p = cadd(cmul(p, *r), (ci, 0.0));
            }
            let d = dp.0 * dp.0 + dp.1 * dp.1;
            if d == 0.0 {
                break;
            }
            let step = ((p.0 * dp.0 + p.1 * dp.1) / d, (p.1 * dp.0 - p.0 * dp.1) / d);
            r.0 -= step.0;
            r.1 -= step.1;
            if step.0.hypot(step.1) <= 1e-16 * r.0.hypot(r.1) {
                break;
            }
        }
    }
    roots
}

fn cmul(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
}
fn cadd(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    (a.0 + b.0, a.1 + b.1)
}

/// Speed error (Beghin §30): tan ζ = v cos α / (V cos L − v sin α), V = εR, α the course
/// measured toward West (so v sin α is the westward speed). Returned as ζ (West positive).
pub fn speed_error_rad(speed_m_per_s: f64, heading_rad: f64, latitude_rad: f64) -> f64 {
    let v_north = speed_m_per_s * heading_rad.cos();
    let v_west = -speed_m_per_s * heading_rad.sin();
    let v_surface = EARTH_RATE_RAD_PER_S * EARTH_RADIUS_M * latitude_rad.cos();
    // The spin axis settles along the horizontal absolute rate of the local frame,
    // (ε cos L − v_W/R, v_N/R) in (North, West): West of North on northerly courses.
    v_north.atan2(v_surface - v_west)
}

/// Schuler tuning: the spin momentum that makes an Anschütz compass's period 2π√(R/g).
pub fn schuler_spin_momentum(pendulous_moment: f64, latitude_rad: f64) -> f64 {
    pendulous_moment * EARTH_RATE_RAD_PER_S * latitude_rad.cos() * EARTH_RADIUS_M
        / STANDARD_GRAVITY_M_PER_S2
}

/// Mean reading error under rolling (Beghin §40, corrected): τζ₀ = −½ sinΔ cosΔ (J₀/g)² aP.
/// Returned as the magnitude ½ |sinΔ cosΔ| (J₀/g)² aP/τ, rad.
pub fn rolling_error_magnitude_rad(
    j0_m_per_s2: f64,
    roll_plane_azimuth_rad: f64,
    pendulous_moment: f64,
    tau: f64,
) -> f64 {
    let r = j0_m_per_s2 / STANDARD_GRAVITY_M_PER_S2;
    0.5 * (roll_plane_azimuth_rad.sin() * roll_plane_azimuth_rad.cos()).abs()
        * r
        * r
        * pendulous_moment
        / tau
}

/// Villarceau's constants for a design built like the shipped `foucault-gyroscope` (a body
/// `ring` hinged about its z axis on the base, carrying a body `torus` with a rotor), from the
/// design's own numbers and the model's spin momentum, at a latitude. Also returns the hinge
/// angle of the hour plane (Villarceau's γ = hinge angle − offset).
pub fn foucault_villarceau(
    design: &crate::Design,
    torus_spin_momentum: f64,
    latitude_rad: f64,
) -> Option<(Villarceau, f64)> {
    let ring = &design.bodies[design.body_index("ring")?];
    let torus = &design.bodies[design.body_index("torus")?];
    let rotor = torus.rotor.as_ref()?;
    let jr = ring.joint_rotation;
    let col = |j: usize| [jr[0][j], jr[1][j], jr[2][j]];
    let (x, y, z) = (col(0), col(1), col(2));
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let e = [latitude_rad.cos(), 0.0, latitude_rad.sin()];
    let cos_tp = dot(z, e);
    let ex = [
        e[0] - cos_tp * z[0],
        e[1] - cos_tp * z[1],
        e[2] - cos_tp * z[2],
    ];
    let offset = dot(ex, y).atan2(dot(ex, x));
    // The torus axis in ring axes: angle η from the ring axis.
    let tj = torus.joint_rotation;
    let a_ring = [
        tj[0][0] * rotor.axis[0] + tj[0][1] * rotor.axis[1] + tj[0][2] * rotor.axis[2],
        0.0,
        tj[2][0] * rotor.axis[0] + tj[2][1] * rotor.axis[1] + tj[2][2] * rotor.axis[2],
    ];
    let eta = a_ring[0].atan2(a_ring[2]);
    let v = Villarceau::new(&VillarceauInputs {
        a: torus.inertia_kg_m2[0][0],
        c: rotor.polar_inertia_kg_m2,
        // A′ about the normal of the ring's plane (ring y), B′ in the plane (ring x): see
        // `VillarceauInputs`.
        a_ring: ring.inertia_kg_m2[1][1],
        b_ring: ring.inertia_kg_m2[0][0],
        c_ring: ring.inertia_kg_m2[2][2],
        n: torus_spin_momentum / rotor.polar_inertia_kg_m2,
        omega: EARTH_RATE_RAD_PER_S,
        theta_ring: cos_tp.clamp(-1.0, 1.0).acos(),
        eta,
    });
    Some((v, offset))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pendulum_period_matches_the_elliptic_integral() {
        // δ = 0: T = 4K(k)/√(g/a); K(sin 45°) = 1.854074677301372.
        let v = Villarceau {
            g_over_a: 4.0,
            delta: 0.0,
        };
        let t = v.period(PI / 2.0);
        assert!((t - 4.0 * 1.854_074_677_301_372 / 2.0).abs() < 1e-13);
    }

    #[test]
    fn quartic_roots_are_polished() {
        // (r² + 1e-6)(r² + 1e6) = r⁴ + (1e6 + 1e-6) r² + 1
        let roots = polynomial_roots(&[1.0, 0.0, 1e6 + 1e-6, 0.0, 1.0]);
        let small = roots
            .iter()
            .map(|r| r.1.abs())
            .fold(f64::INFINITY, f64::min);
        assert!((small - 1e-3).abs() < 1e-15);
    }
}
