//! Anschütz 1906: the engine's equilibrium and modes against Beghin's closed forms
//! (`shared/physics/anschutz-1906.md` §3–4): the latitude equilibrium (§34, eq. 18) and the
//! roots of the characteristic equation (ℭr² + τ)(𝔅r² + aP) + IΩr(IΩr + κ) = 0 (eqs. 19–22),
//! with ℭ and 𝔅 summed from the design's own bodies.

use gyro_model::constants::EARTH_RATE_RAD_PER_S;
use gyro_model::theory::Anschutz;
use gyro_model::{
    CompiledModel, CoordinateRole, Design, Effects, Fidelity, InitialCondition, ModelOptions,
    Moored,
};

fn design() -> Design {
    let text =
        std::fs::read_to_string(gyro_testkit::repo_root!().join("designs/anschutz-1906.toml"))
            .expect("design");
    Design::from_toml("anschutz-1906.toml", &text, &[]).expect("valid")
}

fn model(lat_deg: f64, fidelity: Fidelity) -> CompiledModel<Moored> {
    let mut fx = Effects::all();
    fx.base = gyro_model::BaseEffects {
        earth_rotation: true,
        ..Default::default()
    };
    CompiledModel::compile(
        design(),
        Moored {
            latitude_rad: lat_deg.to_radians(),
            heading_rad: 0.0,
        },
        ModelOptions {
            fidelity,
            effects: fx,
            pivot_m: [0.0; 3],
            initial: InitialCondition {
                from_equilibrium: true,
                ..Default::default()
            },
        },
    )
    .expect("compiles")
}

/// Moment of inertia of every body, all angles zero, about the pivot's axis `k` (0 = x North,
/// 1 = y West, 2 = z up): Σ I_kk + m (|p|² − p_k²), p the body's centre of gravity from the
/// pivot. The rotors count with their transverse inertia only (IΩ is the spin's). The
/// Anschütz chain has no constant joint rotations, so the offsets simply add up.
fn inertia_about_pivot(d: &Design, k: usize) -> f64 {
    let origin = |mut i: usize| {
        let mut o = [0.0; 3];
        loop {
            let b = &d.bodies[i];
            assert_eq!(
                b.joint_rotation,
                [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                "{}: a joint rotation",
                b.name
            );
            for (o, j) in o.iter_mut().zip(b.joint_origin_m) {
                *o += j;
            }
            match b.parent {
                Some(p) => i = p,
                None => return o,
            }
        }
    };
    d.bodies
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let o = origin(i);
            let p: Vec<f64> = o.iter().zip(b.cg_m).map(|(o, c)| o + c).collect();
            let r2: f64 = p.iter().map(|v| v * v).sum();
            b.inertia_kg_m2[k][k] + b.mass_kg * (r2 - p[k] * p[k])
        })
        .sum()
}

fn theory(d: &Design, lat_deg: f64) -> Anschutz {
    Anschutz {
        spin_momentum: d.parameter("spin_momentum_n_m_s").expect("present"),
        pendulous_moment: d.parameter("pendulous_moment_n_m").expect("present"),
        kappa: d.parameter("kappa_n_m").expect("present"),
        inertia_vertical: inertia_about_pivot(d, 2),
        inertia_east_west: inertia_about_pivot(d, 1),
        latitude_rad: lat_deg.to_radians(),
    }
}

const LATITUDES_DEG: [f64; 4] = [0.0, 30.0, 50.0, 70.0];

/// The equilibrium the model starts from is Beghin's latitude equilibrium (§34, eq. 17–18): with
/// the overload d compensating σ at L₀, aPθ = IΩε(sin L₀ − sin L) (precisely (aP + τ)θ, τ ≪ aP)
/// and τζ = κθ, i.e. aP cos L ζ = κ(sin L₀ − sin L); the heel is zero and the vane hangs plumb.
#[test]
fn equilibrium_is_the_latitude_equilibrium_of_eq_18() {
    for lat in LATITUDES_DEG {
        let m = model(lat, Fidelity::Full);
        let d = &m.design;
        let th = theory(d, lat);
        let l0 = d
            .parameter("compensation_latitude_deg")
            .expect("L0")
            .to_radians();
        let l = lat.to_radians();
        let h = th.spin_momentum;
        let ap = th.pendulous_moment;
        let theta = h * EARTH_RATE_RAD_PER_S * (l0.sin() - l.sin()) / (ap + th.tau());
        let zeta = th.kappa * theta / th.tau();
        let x = &m.x_equilibrium;
        let iz = m.role(CoordinateRole::Azimuth).expect("azimuth");
        let it = m.role(CoordinateRole::Tilt).expect("tilt");
        println!(
            "L = {lat}°: ζ_eq {:.6e} (eq. 18 {zeta:.6e}), θ_eq {:.6e} (§34 {theta:.6e}), x_eq {x:?}",
            x[iz], x[it]
        );
        // At L₀ both vanish: compare against the scale of the 0°-latitude offsets.
        let scale_theta = h * EARTH_RATE_RAD_PER_S * l0.sin() / ap;
        let scale_zeta = th.kappa * l0.sin() / ap;
        assert!(
            (x[it] - theta).abs() < 1e-3 * scale_theta,
            "L = {lat}°: θ_eq {:e} vs {theta:e}",
            x[it]
        );
        assert!(
            (x[iz] - zeta).abs() < 1e-3 * scale_zeta,
            "L = {lat}°: ζ_eq {:e} vs {zeta:e}",
            x[iz]
        );
        // The vane hangs plumb: its angle to the float is minus the float's tilt.
        let ia = d
            .coordinates
            .iter()
            .position(|c| c.name == "alpha")
            .expect("vane angle");
        assert!(
            (x[ia] + x[it]).abs() < 1e-3 * scale_theta,
            "L = {lat}°: vane α_eq {:e} vs −θ_eq {:e}",
            x[ia],
            -x[it]
        );
        for (i, v) in x.iter().enumerate() {
            if i != iz && i != it && i != ia {
                assert!(
                    v.abs() < 1e-3 * scale_theta,
                    "L = {lat}°: state {i} at equilibrium {v:e}, expected 0"
                );
            }
        }
    }
}

/// The modes of the linearisation at equilibrium hold Beghin's four roots: the slow (compass)
/// pair, damped by κ/(2IΩ) at T_d = 2πIΩ/√(τaP − κ²/4), and the nutation pair at
/// ≈ IΩ/√(𝔅ℭ). The nutation's real part is not Beghin's +κ/(2IΩ) (anti-damped): the design
/// adds the mercury's drag so that it decays. The remaining modes (heel, vane) are not in the
/// four-state theory.
#[test]
fn modes_are_the_roots_of_the_characteristic_equation() {
    for lat in LATITUDES_DEG {
        let m = model(lat, Fidelity::Full);
        let th = theory(&m.design, lat);
        let roots = th.characteristic_roots();
        let mut modes = m.modes();
        modes.sort_by(|a, b| a.0.hypot(a.1).total_cmp(&b.0.hypot(b.1)));
        println!("L = {lat}°: modes {modes:?}\n  Beghin's roots {roots:?}");
        assert_eq!(
            modes.len(),
            2 * m.independent.len(),
            "L = {lat}°: mode count"
        );

        // Slow pair: the two smallest modes, complex conjugates.
        let (slow, slow_theory) = (modes[0], roots[0]);
        assert!(
            (modes[0].0 - modes[1].0).abs() <= 1e-12 * slow.0.abs()
                && (modes[0].1 + modes[1].1).abs() <= 1e-12 * slow.1.abs(),
            "L = {lat}°: the slow modes {:?}, {:?} are not a conjugate pair",
            modes[0],
            modes[1]
        );
        let rel_re = (slow.0 / slow_theory.0 - 1.0).abs();
        let rel_im = (slow.1.abs() / slow_theory.1.abs() - 1.0).abs();
        assert!(
            rel_re < 1e-3,
            "L = {lat}°: slow decay rate {:e} /s vs {:e} /s ({:.3} %)",
            slow.0,
            slow_theory.0,
            rel_re * 100.0
        );
        assert!(
            rel_im < 1e-3,
            "L = {lat}°: slow frequency {:e} rad/s vs {:e} rad/s ({:.4} %)",
            slow.1.abs(),
            slow_theory.1.abs(),
            rel_im * 100.0
        );
        // Beghin's closed forms of that root.
        let (h, k, tau, ap) = (th.spin_momentum, th.kappa, th.tau(), th.pendulous_moment);
        let t_d = std::f64::consts::TAU * h / (tau * ap - k * k / 4.0).sqrt();
        assert!(
            (std::f64::consts::TAU / slow.1.abs() / t_d - 1.0).abs() < 1e-3,
            "L = {lat}°: damped period {} s vs 2πIΩ/√(τaP − κ²/4) = {t_d} s",
            std::f64::consts::TAU / slow.1.abs()
        );
        assert!(
            (-slow.0 / (k / (2.0 * h)) - 1.0).abs() < 1e-3,
            "L = {lat}°: decay {} /s vs κ/(2IΩ) = {} /s",
            -slow.0,
            k / (2.0 * h)
        );

        // Nutation: the fastest pair.
        let nut = modes[modes.len() - 1];
        let nut_theory = roots[3];
        let rel = (nut.1.abs() / nut_theory.1.abs() - 1.0).abs();
        assert!(
            rel < 3e-3,
            "L = {lat}°: nutation {} rad/s vs {} rad/s ({:.2} %)",
            nut.1.abs(),
            nut_theory.1.abs(),
            rel * 100.0
        );
        assert!(
            nut.0 < 0.0,
            "L = {lat}°: nutation {nut:?} is not damped by the mercury"
        );
    }
}
