//! Hard cases: each asserts accuracy against a closed form (or a clear error), not just that the
//! numbers stay finite. The pole, latitude 89.9°, the separatrix of Villarceau's pendulum, a stiff
//! `full` model over a day, a month without damping, zero and near-aperiodic damping, designs
//! whose SI numbers span twelve orders of magnitude, and a vehicle that cancels the Earth's
//! surface speed. Run: `cargo test --release -p gyro-sim --test integration hard_cases::` (≈ 1 min here).

use crate::support;
use gyro_model::constants::{EARTH_RADIUS_M, EARTH_RATE_RAD_PER_S, KNOT_IN_M_PER_S};
use gyro_model::theory::Anschutz;
use gyro_model::{Design, Fidelity};
use gyro_sim::accuracy::foucault_release_scene;
use gyro_sim::solvers::{self, Method, OutputGrid};
use gyro_sim::{Scene, SceneOverrides, Simulation, run::ModelSystem};
use std::f64::consts::{PI, TAU};
use std::ops::ControlFlow;
use support::*;

// ---------------------------------------------------------------------------------------------
// Helpers

/// The stiff integrators every stiff hard case runs with.
const STIFF: [Method; 3] = [Method::Rodas4, Method::Rodas5p, Method::Radau5];

fn foucault_scene(design: &str, lat: f64, start_extra: &str, ring_elev: f64) -> Scene {
    scene_from(
        &format!(
            r#"name = "hard"
duration_s = 1.0
[start]
latitude_deg = {lat}
{start_extra}
[compass]
design = "{design}"
design_overrides = {{ "parameters.ring_axis_elevation_deg" = {ring_elev} }}
start_from_equilibrium = false
[simulation]
fidelity = "full"
integrator = "dop853"
"#
        ),
        &SceneOverrides::default(),
    )
}

/// Integrates a compiled model to `t_end`, calling `f(t, x)` every `dt`.
fn integrate(
    sim: &Simulation,
    method: Method,
    rtol: f64,
    dt: f64,
    t_end: f64,
    mut f: impl FnMut(f64, &[f64]),
) -> gyro_sim::solvers::SolverStats {
    let mut sys = ModelSystem { model: &sim.model };
    let mut x = sim.model.x0.clone();
    let grid = OutputGrid { t0: 0.0, dt, t_end };
    let (_, stats) = solvers::integrate(
        &mut sys,
        method,
        &tol(rtol, rtol * 1e-3),
        &mut x,
        &grid,
        &sim.breakpoints,
        |t, x| {
            f(t, x);
            ControlFlow::Continue(())
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    stats
}

/// Released at rest `amplitude` from the centre; after `periods` exact Villarceau periods the
/// state must be the start again. Returns (phase-space error / amplitude, period).
fn periodicity_error(
    sc: Scene,
    amplitude_deg: f64,
    periods: f64,
    method: Method,
    rtol: f64,
) -> (f64, f64) {
    let a = amplitude_deg.to_radians();
    let (sim, v, _) = foucault_release_scene(sc, a).unwrap_or_else(|e| panic!("{e}"));
    let period = v.period(a);
    let x0 = sim.model.x0.clone();
    let mut last = x0.clone();
    integrate(
        &sim,
        method,
        rtol,
        periods * period,
        periods * period,
        |_, x| last.copy_from_slice(x),
    );
    let w0 = v.g_over_a.abs().sqrt();
    let err = (last[0] - x0[0]).hypot((last[1] - x0[1]) / w0) / a;
    (err, period)
}

fn harbour(lat: f64, compass_extra: &str, sim_extra: &str, hours: f64, fidelity: &str) -> String {
    format!(
        r#"name = "hard"
duration_s = {}
output_rate_hz = 0.1
[start]
latitude_deg = {lat}
[compass]
design = "anschutz-1906"
{compass_extra}
[simulation]
fidelity = "{fidelity}"
integrator = "rodas4"
{sim_extra}
"#,
        hours * 3600.0
    )
}

fn theory(d: &Design, lat_deg: f64) -> Anschutz {
    Anschutz {
        spin_momentum: d.parameter("spin_momentum_n_m_s").expect("IΩ"),
        pendulous_moment: d.parameter("pendulous_moment_n_m").expect("aP"),
        kappa: d.parameter("kappa_n_m").expect("κ"),
        inertia_vertical: 0.08,
        inertia_east_west: 0.08,
        latitude_rad: lat_deg.to_radians(),
    }
}

/// (t, ζ − ζ_eq, ζ̇, θ − θ_eq).
fn zeta_series(sim: &Simulation, out: &[(f64, Vec<f64>)]) -> Vec<(f64, f64, f64, f64)> {
    let xe = &sim.model.x_equilibrium;
    out.iter()
        .map(|(t, x)| {
            let r = sim.model.rates(*t, x);
            (*t, x[0] - xe[0], r[0], x[1] - xe[1])
        })
        .collect()
}

fn zeta_period(s: &[(f64, f64, f64, f64)]) -> f64 {
    let t: Vec<f64> = s.iter().map(|v| v.0).collect();
    let y: Vec<f64> = s.iter().map(|v| v.1).collect();
    let yd: Vec<f64> = s.iter().map(|v| v.2).collect();
    mean_period(&upward_crossings(&t, &y, &yd))
}

// ---------------------------------------------------------------------------------------------
// The pole

#[test]
fn the_pole_is_refused_with_a_clear_error() {
    for lat in [90.0f64, -90.0, 90.5] {
        let text = harbour(0.0, "", "", 1.0, "gyroscopic")
            .replace("latitude_deg = 0", &format!("latitude_deg = {lat:.1}"));
        let e = Scene::from_toml("pole.toml", &text, None, &SceneOverrides::default())
            .expect_err("the pole must be refused");
        let msg = e.to_string();
        assert_eq!(e.key, "start.latitude_deg", "{msg}");
        assert_eq!(e.line, Some(5), "the error names the line: {msg}");
        let number = format!("{lat} is out of range");
        for word in ["pole", "North is undefined", "−90 < latitude < 90", &number] {
            assert!(msg.contains(word), "`{word}` missing from: {msg}");
        }
    }
    // A ship program that reaches 89.99° is refused too, naming the latitude it reaches.
    let text = r#"name = "to-the-pole"
duration_s = 3600.0
[start]
latitude_deg = 89.9
heading_deg = 0.0
speed_kn = 30.0
[compass]
design = "anschutz-1906"
"#;
    let e = Scene::from_toml("pole.toml", text, None, &SceneOverrides::default())
        .expect_err("a program through the pole must be refused");
    let msg = e.to_string();
    assert_eq!(e.key, "program", "{msg}");
    assert!(
        msg.contains("stops short of the pole") && msg.contains("89.99°"),
        "{msg}"
    );
}

#[test]
fn latitude_89_9_matches_the_closed_forms() {
    // Foucault's azimuth gyroscope: exact Villarceau period at 89.9°, and T ∝ 1/√cos L.
    let (err, t_899) = periodicity_error(
        foucault_scene("foucault-gyroscope", 89.9, "", 90.0),
        10.0,
        3.0,
        Method::Dop853,
        1e-12,
    );
    assert!(
        err < 1e-8,
        "89.9°: state after 3 exact periods off by {err:e}"
    );
    let (_, t_45) = periodicity_error(
        foucault_scene("foucault-gyroscope", 45.0, "", 90.0),
        10.0,
        1.0,
        Method::Dop853,
        1e-10,
    );
    let expect = (45f64.to_radians().cos() / 89.9f64.to_radians().cos()).sqrt();
    let ratio = t_899 / t_45;
    assert!(
        (ratio / expect - 1.0).abs() < 1e-6,
        "T(89.9°)/T(45°) = {ratio} vs √(cos 45°/cos 89.9°) = {expect}"
    );
    // Anschütz 1906, undamped: the slow period 2π√(IΩ/(aPε cos L)) (≈ 20 h at 89.9°).
    let lat = 89.9;
    let th = theory(
        &scene_from(
            &harbour(lat, "", "", 1.0, "gyroscopic"),
            &SceneOverrides::default(),
        )
        .design,
        lat,
    );
    let text = harbour(
        lat,
        "azimuth_offset_deg = 1.0",
        "disable_effects = [\"damper\"]",
        3.3 * th.undamped_period() / 3600.0,
        "gyroscopic",
    );
    let sc = scene_from(&text, &SceneOverrides::default());
    for method in STIFF {
        let (sim, out, _) = run(&sc, method, tol(1e-9, 1e-12));
        let period = zeta_period(&zeta_series(&sim, &out));
        let expect = th.undamped_period();
        assert!(
            (period / expect - 1.0).abs() < 0.005,
            "89.9° ({method}): Anschütz period {period:.0} s vs eq. 10 {expect:.0} s"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Villarceau's separatrix

#[test]
fn villarceau_period_holds_up_to_the_separatrix() {
    // The period diverges like ln(8/(π − γ₀)): the state after exact periods is a sharp test,
    // for both tight-tolerance methods.
    for method in [Method::Dop853, Method::Vern9] {
        for (amp, periods, bound) in [(179.0, 2.0, 1e-7), (179.9, 2.0, 1e-6), (179.99, 1.0, 1e-5)] {
            let (err, period) = periodicity_error(
                foucault_scene("foucault-gyroscope", 45.0, "", 90.0),
                amp,
                periods,
                method,
                1e-13,
            );
            println!("{method} γ₀ = {amp}°: T = {period:.6} s, periodicity error {err:.2e}");
            assert!(
                err < bound,
                "{method} γ₀ = {amp}°: error {err:e} ≥ {bound:e}"
            );
        }
    }
    // On the separatrix's saddle (γ₀ = 180° exactly) the ring stays: the unstable equilibrium
    // is kept to round-off amplified by e^(ω₀ t).
    let sc = foucault_scene("foucault-gyroscope", 45.0, "", 90.0);
    let (sim, v, _) = foucault_release_scene(sc, PI).expect("compiles");
    let x0 = sim.model.x0[0];
    let mut worst: f64 = 0.0;
    let t_end = 6.0 / v.g_over_a.sqrt(); // six e-foldings
    for method in [Method::Dop853, Method::Vern9] {
        integrate(&sim, method, 1e-12, 1.0, t_end, |_, x| {
            worst = worst.max((x[0] - x0).abs())
        });
        assert!(
            worst < 1e-9,
            "{method}: the saddle drifted by {worst:e} rad"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Stiff: a full model at 20 000 rpm over a day

#[test]
fn full_model_at_20000_rpm_over_24_hours_with_rodas4() {
    full_model_at_20000_rpm_over_24_hours(Method::Rodas4);
}

#[test]
fn full_model_at_20000_rpm_over_24_hours_with_radau5() {
    full_model_at_20000_rpm_over_24_hours(Method::Radau5);
}

fn full_model_at_20000_rpm_over_24_hours(method: Method) {
    let lat = 50.0;
    let mk = |fid: &str| {
        scene_from(
            &harbour(lat, "azimuth_offset_deg = 5.0", "", 24.0, fid),
            &SceneOverrides::default(),
        )
    };
    let full = mk("full");
    let probe = Simulation::new(&full).expect("compiles");
    // Nutation (≈ 90 Hz) is five orders of magnitude faster than the 68-minute damped mode.
    let modes = probe.model.modes();
    let fast = modes.iter().map(|m| m.1.abs()).fold(0.0, f64::max);
    let th = theory(&full.design, lat);
    let slow = th.characteristic_roots()[0].1.abs();
    assert!(fast / slow > 1e5, "stiffness ratio {:.1e}", fast / slow);
    let (sim_f, out_f, stats) = run(&full, method, tol(1e-7, 1e-11));
    let (sim_g, out_g, _) = run(&mk("gyroscopic"), Method::Rodas4, tol(1e-9, 1e-13));
    assert_eq!(sim_f.model.fidelity, Fidelity::Full);
    println!(
        "full, 24 h ({method}): {} steps, {} rhs, {} jacobians, {} LU",
        stats.solver.steps,
        stats.solver.rhs_evals,
        stats.solver.jacobian_evals,
        stats.solver.lu_decompositions
    );
    // The stiff method steps over the nutation instead of resolving it.
    assert!(
        stats.solver.steps < 20_000,
        "{} steps for 24 h",
        stats.solver.steps
    );
    let amp = 5f64.to_radians();
    let worst = out_f
        .iter()
        .zip(&out_g)
        .map(|((t, xf), (_, xg))| {
            (sim_f.model.readout(*t, xf).reading_error_rad
                - sim_g.model.readout(*t, xg).reading_error_rad)
                .abs()
        })
        .fold(0.0, f64::max);
    assert!(
        worst / amp < 1e-4,
        "full vs gyroscopic: {:.2e} of the release",
        worst / amp
    );
    // Damped period and settling against Beghin's slow roots.
    let s = zeta_series(&sim_f, &out_f);
    let early: Vec<_> = s.iter().copied().filter(|v| v.0 < 4.0 * 3600.0).collect();
    let period = zeta_period(&early);
    let t_d = TAU / slow;
    assert!(
        (period / t_d - 1.0).abs() < 0.01,
        "damped period {period:.1} s vs {t_d:.1} s"
    );
    let last = s.last().expect("samples");
    // e^(−σ·24 h) ≈ 1e-28: settled to round-off of the equilibrium.
    assert!(last.1.abs() < 1e-9, "after 24 h: ζ − ζ_eq = {:e}", last.1);
}

// ---------------------------------------------------------------------------------------------
// A month without damping

#[test]
fn thirty_days_undamped_keep_the_first_integral() {
    // Foucault's azimuth gyroscope spun at 90 rpm (period ≈ 7 min): ≈ 6 200 periods in 30 days.
    let mut sc = foucault_scene("foucault-gyroscope", 45.0, "", 90.0);
    let torus = sc.design.body_index("torus").expect("torus");
    if let Some(r) = sc.design.bodies[torus].rotor.as_mut() {
        r.spin_rad_per_s /= 100.0;
    }
    let a = 90f64.to_radians();
    let (sim, v, centre) = foucault_release_scene(sc, a).expect("compiles");
    let off = centre - v.centre();
    let i0 = v.first_integral(sim.model.x0[0] - off, sim.model.x0[1]);
    let period = v.period(a);
    let days = 30.0;
    let n = (days * 86400.0 / period).floor();
    let mut worst: f64 = 0.0;
    let mut last = sim.model.x0.clone();
    let stats = integrate(&sim, Method::Dop853, 1e-12, period, n * period, |_, x| {
        worst = worst.max((v.first_integral(x[0] - off, x[1]) - i0).abs());
        last.copy_from_slice(x);
    });
    let drift = worst / (2.0 * v.g_over_a.abs());
    println!(
        "30 days = {n} periods of {period:.1} s: first-integral drift {drift:.2e}, {} steps",
        stats.steps
    );
    assert!(drift < 1e-8, "first integral drifted {drift:e} of 2|g/a|");
    // And the phase: after exactly n periods the ring is back where it started.
    let back = (last[0] - sim.model.x0[0]).abs() / a;
    assert!(
        back < 1e-6,
        "after {n} periods: off by {back:e} of the amplitude"
    );
}

// ---------------------------------------------------------------------------------------------
// Damping: none, and near-aperiodic

#[test]
fn zero_damping_keeps_the_amplitude() {
    let lat = 50.0;
    let th = theory(
        &scene_from(
            &harbour(lat, "", "", 1.0, "gyroscopic"),
            &SceneOverrides::default(),
        )
        .design,
        lat,
    );
    let t0 = th.undamped_period();
    let text = harbour(
        lat,
        "azimuth_offset_deg = 2.0\ndesign_overrides = { \"parameters.mercury_drag_n_m_s_per_rad\" = 0.0 }",
        "disable_effects = [\"damper\"]",
        6.25 * t0 / 3600.0,
        "gyroscopic",
    );
    let sc = scene_from(&text, &SceneOverrides::default());
    // No air jets and no mercury drag on azimuth and tilt: nothing damps the slow mode. (The
    // vane's and the heel's own friction stay: without them those 0.3–1 s pendulums ring
    // forever and RODAS4 resolves them, 1.2 million steps and minutes for the same answer.)
    // RODAS4 and RADAU5 are L-stable: numerical damping would show as a shrinking amplitude.
    for method in STIFF {
        let (sim, out, stats) = run(&sc, method, tol(1e-9, 1e-13));
        println!("zero damping ({method}): {} steps", stats.solver.steps);
        let s = zeta_series(&sim, &out);
        let peak = |from: f64, to: f64| {
            s.iter()
                .filter(|v| v.0 >= from && v.0 < to)
                .map(|v| v.1.abs())
                .fold(0.0, f64::max)
        };
        let first = peak(0.0, t0);
        let last = peak(5.0 * t0, 6.0 * t0);
        println!("zero damping: amplitude {first:e} → {last:e}");
        assert!(
            (last / first - 1.0).abs() < 1e-4,
            "{method}: amplitude after 5 undamped periods: {last:e} vs {first:e}"
        );
        let period = zeta_period(&s);
        assert!(
            (period / t0 - 1.0).abs() < 0.005,
            "undamped period {period:.1} s vs eq. 10 {t0:.1} s"
        );
    }
}

#[test]
fn near_aperiodic_damping_follows_the_closed_form() {
    let lat = 50.0;
    for (xi, method) in [0.999, 1.0]
        .into_iter()
        .flat_map(|xi| STIFF.map(|m| (xi, m)))
    {
        let text = harbour(
            lat,
            &format!(
                "azimuth_offset_deg = 1.0\ndesign_overrides = {{ \"parameters.damping_ratio\" = {xi} }}"
            ),
            "",
            2.0,
            "gyroscopic",
        );
        let sc = scene_from(&text, &SceneOverrides::default());
        let th = theory(&sc.design, lat);
        let (h, ap, kappa, tau) = (th.spin_momentum, th.pendulous_moment, th.kappa, th.tau());
        // Elementary (precession) equations: ζ̈ + (κ/IΩ) ζ̇ + (aPτ/(IΩ)²) ζ = 0.
        let sigma = kappa / (2.0 * h);
        let w2 = ap * tau / (h * h) - sigma * sigma;
        assert!(
            w2.abs() < 1e-2 * ap * tau / (h * h),
            "ξ = {xi}: not near-aperiodic"
        );
        let (sim, out, _) = run(&sc, method, tol(1e-10, 1e-14));
        let s = zeta_series(&sim, &out);
        let (z0, zd0) = (s[0].1, s[0].2);
        let exact = |t: f64| {
            let (c, sn) = if w2 > 0.0 {
                let w = w2.sqrt();
                ((w * t).cos(), (w * t).sin() / w)
            } else if w2 < 0.0 {
                let m = (-w2).sqrt();
                ((m * t).cosh(), (m * t).sinh() / m)
            } else {
                (1.0, t)
            };
            (-sigma * t).exp() * (z0 * c + (zd0 + sigma * z0) * sn)
        };
        let worst = s
            .iter()
            .map(|v| (v.1 - exact(v.0)).abs())
            .fold(0.0, f64::max)
            / z0.abs();
        let undershoot = s.iter().map(|v| -v.1 / z0).fold(0.0, f64::max);
        println!(
            "ξ = {xi} ({method}): max |ζ − closed form| = {worst:.2e} of ζ₀, undershoot {undershoot:.2e}"
        );
        assert!(
            worst < 1e-2,
            "ξ = {xi}: {worst:e} of ζ₀ from the closed form"
        );
        // No overshoot beyond what ξ ≈ 1 allows (e^(−πξ/√(1−ξ²)) ≈ 1e-30).
        assert!(undershoot < 1e-3, "ξ = {xi}: overshoot {undershoot:e}");
    }
}

// ---------------------------------------------------------------------------------------------
// Twelve orders of magnitude

#[test]
fn cgs_and_kgf_designs_keep_villarceau_exact() {
    // SI numbers from 3e-9 kg·m² (CGS micro top) to 8e2 kg·m² (kgf·m·s ship-sized gyroscope),
    // spins from 94 to 6 283 rad/s, Earth rate 7e-5 rad/s.
    for design in ["foucault-top-cgs", "foucault-heavy-kgf"] {
        for method in [Method::Dop853, Method::Vern9] {
            for amp in [10.0, 170.0] {
                let sc = foucault_scene(design, 45.0, "", 90.0);
                let (err, period) = periodicity_error(sc, amp, 3.0, method, 1e-12);
                println!(
                    "{design} {method} γ₀ = {amp}°: T = {period:.6} s, periodicity error {err:.2e}"
                );
                assert!(err < 1e-8, "{design} {method}, γ₀ = {amp}°: error {err:e}");
            }
            // The latitude gyroscope exercises δ ≠ 0 (A + A′ − B′).
            let sc = foucault_scene(design, 45.0, "", 0.0);
            let (err, _) = periodicity_error(sc, 90.0, 3.0, method, 1e-12);
            assert!(
                err < 1e-8,
                "{design} {method} latitude gyroscope: error {err:e}"
            );
        }
    }
    let micro = foucault_scene("foucault-top-cgs", 45.0, "", 90.0);
    let heavy = foucault_scene("foucault-heavy-kgf", 45.0, "", 90.0);
    let c = |s: &Scene| {
        let t = s.design.body_index("torus").expect("torus");
        s.design.bodies[t]
            .rotor
            .as_ref()
            .map_or(0.0, |r| r.polar_inertia_kg_m2)
    };
    let ring_max =
        |s: &Scene| s.design.bodies[s.design.body_index("ring").expect("ring")].inertia_kg_m2[2][2];
    let torus_a = |s: &Scene| {
        s.design.bodies[s.design.body_index("torus").expect("torus")].inertia_kg_m2[0][0]
    };
    assert!(c(&heavy) / c(&micro) > 9e10 && ring_max(&heavy) / torus_a(&micro) > 1e11);
}

// ---------------------------------------------------------------------------------------------
// A vehicle that cancels the Earth's surface speed

fn cancelling_speed_kn(lat_deg: f64) -> f64 {
    EARTH_RATE_RAD_PER_S * EARTH_RADIUS_M * lat_deg.to_radians().cos() / KNOT_IN_M_PER_S
}

#[test]
fn westward_speed_cancelling_the_earth_surface_speed() {
    let lat = 80.0;
    let v = cancelling_speed_kn(lat);
    // Foucault's azimuth gyroscope: with V cos L − v sin α = 0 the local frame does not rotate
    // in inertial space (its vertical rate vanishes too): no directive force, and the ring
    // stays wherever it was released.
    let start = format!("heading_deg = 270.0\nspeed_kn = {v}");
    let mut sc = foucault_scene("foucault-gyroscope", lat, &start, 90.0);
    let gi = sc.design.coordinate_index("gamma").expect("gamma");
    sc.initial.offsets_rad = vec![(gi, 0.7)];
    let sim = Simulation::new(&sc).expect("compiles at the cancelling speed");
    let mut worst: f64 = 0.0;
    integrate(&sim, Method::Dop853, 1e-12, 60.0, 6.0 * 3600.0, |_, x| {
        worst = worst.max((x[0] - 0.7).abs().max(x[1].abs()))
    });
    assert!(
        worst < 1e-9,
        "the ring moved by {worst:e} with no directive force"
    );

    // Anschütz 1906 (undamped): the directive moment is IΩ(ε cos L − v_W/R), so the period
    // grows as 1/√(1 − f) with the fraction f of the surface speed cancelled...
    let anschutz = |f: f64, hours: f64, start_eq: bool| {
        let text = format!(
            r#"name = "west"
duration_s = {}
output_rate_hz = 0.05
[start]
latitude_deg = {lat}
heading_deg = 270.0
speed_kn = {}
[compass]
design = "anschutz-1906"
azimuth_offset_deg = 1.0
start_from_equilibrium = {start_eq}
[simulation]
fidelity = "gyroscopic"
disable_effects = ["damper"]
"#,
            hours * 3600.0,
            f * v
        );
        scene_from(&text, &SceneOverrides::default())
    };
    let th = theory(&anschutz(0.0, 1.0, true).design, lat);
    for method in STIFF {
        let mut t_prev = 0.0;
        for f in [0.0f64, 0.5, 0.75] {
            let expect = th.undamped_period() / (1.0 - f).sqrt();
            let sc = anschutz(f, 3.3 * expect / 3600.0, true);
            let (sim, out, _) = run(&sc, method, tol(1e-9, 1e-12));
            let period = zeta_period(&zeta_series(&sim, &out));
            println!("cancelled {f} ({method}): period {period:.0} s vs {expect:.0} s");
            assert!(
                (period / expect - 1.0).abs() < 0.01,
                "f = {f}: period {period:.0} s vs 2π√(IΩ/(aP(ε cos L − v_W/R))) = {expect:.0} s"
            );
            assert!(period > t_prev);
            t_prev = period;
        }
    }
    // ...and at full cancellation there is no North to seek: the run is defined (no blow-up),
    // the compass keeps no oscillation and the tilt stays small.
    for method in STIFF {
        let sc = anschutz(1.0, 6.0, false);
        let (sim, out, _) = run(&sc, method, tol(1e-9, 1e-12));
        let tilt = out
            .iter()
            .map(|(t, x)| sim.model.readout(*t, x).tilt_rad.abs())
            .fold(0.0, f64::max);
        let err: Vec<f64> = out
            .iter()
            .map(|(t, x)| sim.model.readout(*t, x).reading_error_rad)
            .collect();
        println!(
            "full cancellation ({method}): reading error {:.3}° → {:.3}°, max tilt {:.3}°",
            err[0].to_degrees(),
            err[err.len() - 1].to_degrees(),
            tilt.to_degrees()
        );
        assert!(err.iter().all(|e| e.is_finite()));
        assert!(tilt < 1f64.to_radians(), "tilt {:.3}°", tilt.to_degrees());
        // No North-seeking: the reading error drifts one way, never swings back...
        assert!(
            err.windows(2).all(|w| w[1] >= w[0]) || err.windows(2).all(|w| w[1] <= w[0]),
            "the reading error oscillates: something still directs the compass"
        );
        // ...and no faster than the largest uncompensated precession, the overload made to cancel
        // the Earth's vertical rate at 50°N (Pd = IΩε sin 50°).
        let bound = EARTH_RATE_RAD_PER_S * 50f64.to_radians().sin() * 6.0 * 3600.0;
        let drift = (err[err.len() - 1] - err[0]).abs();
        assert!(
            drift < bound,
            "drift {drift:.3} rad in 6 h > {bound:.3} rad"
        );
    }
}
