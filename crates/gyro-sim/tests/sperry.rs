//! Sperry 1911 simulated by the engine against Beghin's closed forms (ch. IV), computed from the
//! design's own parameters: the harbour swing (period, decay, azimuth/tilt ratio, latitude
//! error) and the ballistic deviation of a speed change, against the Anschütz 1906's.

use crate::support;
use gyro_model::Design;
use gyro_model::constants::{
    EARTH_RADIUS_M, EARTH_RATE_RAD_PER_S, KNOT_IN_M_PER_S, STANDARD_GRAVITY_M_PER_S2,
};
use gyro_model::theory::Sperry1911;
use gyro_sim::solvers::Method;
use gyro_sim::{SceneOverrides, Simulation};
use std::f64::consts::TAU;
use support::*;

fn theory(d: &Design, lat_deg: f64) -> Sperry1911 {
    let p = |k: &str| d.parameter(k).unwrap_or_else(|| panic!("parameter {k}"));
    Sperry1911 {
        spin_momentum: p("spin_momentum_n_m_s"),
        bail_moment: p("bail_moment_n_m"),
        pendulum_moment: p("pendulum_moment_n_m"),
        overload_moment: p("overload_moment_n_m"),
        roller_offset: p("roller_offset_rad"),
        small_spin_momentum: p("small_spin_momentum_n_m_s"),
        spring: p("small_gyro_spring_n_m_per_rad"),
        damper: p("small_gyro_damper_n_m_s_per_rad"),
        dial_eta: p("dial_eta_rad"),
        latitude_rad: lat_deg.to_radians(),
    }
}

/// A harbour scene for the Sperry at `lat`, `hours` long, with extra `[compass]` lines.
fn harbour(lat: f64, compass: &str, hours: f64) -> String {
    format!(
        r#"name = "t"
duration_s = {}
output_rate_hz = 0.1
[start]
latitude_deg = {lat}
[compass]
design = "sperry-1911"
{compass}
[simulation]
fidelity = "gyroscopic"
integrator = "rodas4"
rtol = 1e-9
atol = 1e-12
"#,
        hours * 3600.0
    )
}

/// (t, reading error − its equilibrium, its rate, θ − its equilibrium) from the readouts (the
/// card sits on the phantom, which does not tilt: the tilt is the gyro case's coordinate).
fn swing(sim: &Simulation, out: &[(f64, Vec<f64>)]) -> Vec<(f64, f64, f64, f64)> {
    let xe = &sim.model.x_equilibrium;
    let r0 = sim.model.readout(0.0, xe);
    let iz = sim
        .model
        .role(gyro_model::CoordinateRole::Azimuth)
        .expect("azimuth");
    let it = sim
        .model
        .role(gyro_model::CoordinateRole::Tilt)
        .expect("tilt");
    out.iter()
        .map(|(t, x)| {
            let r = sim.model.readout(*t, x);
            (
                *t,
                r.reading_error_rad - r0.reading_error_rad,
                r.qd[iz],
                r.q[it] - r0.q[it],
            )
        })
        .collect()
}

fn crossings(s: &[(f64, f64, f64, f64)]) -> Vec<f64> {
    let t: Vec<f64> = s.iter().map(|v| v.0).collect();
    let y: Vec<f64> = s.iter().map(|v| v.1).collect();
    let yd: Vec<f64> = s.iter().map(|v| v.2).collect();
    upward_crossings(&t, &y, &yd)
}

/// Undamped (ρ = 0), released 1° off: the swing's period is 2π√(IΩ/(𝒫ε cos L)) (eq. 6 with the
/// precise model's 𝒫 = Ql + ϖb + ap) within 0.5 %, and the azimuth swings √(𝒫/τ) times the
/// tilt (§45, eq. 44; ≈ 22 at 35°) within 2 %.
#[test]
fn undamped_swing_has_the_period_of_eq_6_and_the_ratio_of_eq_44() {
    for lat in [0.0, 35.0, 60.0] {
        let compass = "azimuth_offset_deg = 1.0\ndesign_overrides = { \"parameters.roller_offset_rad\" = 0.0 }";
        let probe = scene_from(&harbour(lat, compass, 0.1), &SceneOverrides::default());
        let th = theory(&probe.design, lat);
        let expected = th.elementary_period()
            * ((th.bail_moment + th.pendulum_moment) / th.pendulous_moment()).sqrt();
        let sc = scene_from(
            &harbour(lat, compass, 3.3 * expected / 3600.0),
            &SceneOverrides::default(),
        );
        let (sim, out, _) = run(&sc, Method::Rodas4, tol(1e-9, 1e-12));
        let s = swing(&sim, &out);
        let period = mean_period(&crossings(&s));
        let zmax = s.iter().map(|v| v.1.abs()).fold(0.0, f64::max);
        let tmax = s.iter().map(|v| v.3.abs()).fold(0.0, f64::max);
        let ratio = zmax / tmax;
        let expected_ratio = (th.pendulous_moment() / th.tau()).sqrt();
        println!(
            "L = {lat}°: period {period:.1} s vs {expected:.1} s; azimuth/tilt {ratio:.2} vs √(𝒫/τ) {expected_ratio:.2}"
        );
        assert!(
            (period / expected - 1.0).abs() < 0.005,
            "L = {lat}°: period"
        );
        assert!(
            (ratio / expected_ratio - 1.0).abs() < 0.02,
            "L = {lat}°: ratio"
        );
    }
}

/// Damped by the roller, released 2° off: the swing's period is the compass root of (40) and
/// its envelope decays at h = Qlρ/(2IΩ), each within 2 %; a half swing is about a third of the
/// one before (L1540).
#[test]
fn damped_swing_decays_at_ql_rho_over_2_i_omega() {
    for lat in [0.0, 35.0, 60.0] {
        let probe = scene_from(&harbour(lat, "", 0.1), &SceneOverrides::default());
        let th = theory(&probe.design, lat);
        let root = th.characteristic_roots()[0];
        let t_d = TAU / root.1.abs();
        let sc = scene_from(
            &harbour(lat, "azimuth_offset_deg = 2.0", 2.4 * t_d / 3600.0),
            &SceneOverrides::default(),
        );
        let (sim, out, _) = run(&sc, Method::Rodas4, tol(1e-9, 1e-12));
        let s = swing(&sim, &out);
        let c = crossings(&s);
        let period = c[1] - c[0];
        let peak = |from: f64| {
            s.iter()
                .filter(|v| v.0 >= from && v.0 < from + period)
                .map(|v| v.1)
                .fold(f64::MIN, f64::max)
        };
        let trough = |from: f64| {
            s.iter()
                .filter(|v| v.0 >= from && v.0 < from + period)
                .map(|v| v.1)
                .fold(f64::MAX, f64::min)
        };
        let decay = (peak(c[0]) / peak(c[1])).ln() / period;
        let half = -trough(c[0]) / peak(c[0] - period / 2.0).max(peak(c[0]));
        println!(
            "L = {lat}°: period {period:.1} s vs {t_d:.1} s; decay {decay:e} /s vs h {:e}; half-swing ratio {half:.3}",
            th.damping_factor()
        );
        assert!((period / t_d - 1.0).abs() < 0.02, "L = {lat}°: period");
        assert!(
            (decay / th.damping_factor() - 1.0).abs() < 0.02,
            "L = {lat}°: decay"
        );
    }
}

/// Started at its equilibrium the compass stays there, reading the latitude error −ρ tan L
/// (East in the North, West in the South) plus the small gyro's −jω/IΩ, within 2 %.
#[test]
fn harbour_reading_is_the_latitude_error() {
    for lat in [35.0, 60.0, -35.0] {
        let sc = scene_from(&harbour(lat, "", 1.0), &SceneOverrides::default());
        let th = theory(&sc.design, lat);
        let expected = th.latitude_error() - th.small_spin_momentum / th.spin_momentum;
        let (sim, out, _) = run(&sc, Method::Rodas4, tol(1e-9, 1e-12));
        let last = &out[out.len() - 1];
        let r = sim.model.readout(last.0, &last.1);
        println!(
            "L = {lat}°: reading error {:.4}° vs {:.4}°",
            r.reading_error_rad.to_degrees(),
            expected.to_degrees()
        );
        assert!((r.reading_error_rad / expected - 1.0).abs() < 0.02);
        assert_eq!(r.reading_error_rad < 0.0, lat > 0.0, "East in the North");
    }
}

/// A speed change scene: `design` heading North at `lat`, 20 kn, stopping in 60 s after 10 min.
fn speed_change(design: &str, lat: f64, compass: &str, hours: f64) -> String {
    format!(
        r#"name = "t"
duration_s = {}
output_rate_hz = 0.2
[start]
latitude_deg = {lat}
heading_deg = 0.0
speed_kn = 20.0
[compass]
design = "{design}"
{compass}
[[program]]
kind = "steady"
duration_s = 600.0
[[program]]
kind = "speed_change"
to_speed_kn = 0.0
duration_s = 60.0
[simulation]
fidelity = "gyroscopic"
integrator = "rodas4"
rtol = 1e-9
atol = 1e-12
"#,
        hours * 3600.0
    )
}

/// (jump of the reading over the manoeuvre, largest swing about the new equilibrium after it).
fn ballistic(text: &str, settled: f64) -> (f64, f64) {
    let sc = scene_from(text, &SceneOverrides::default());
    let (sim, out, _) = run(&sc, Method::Rodas4, tol(1e-9, 1e-12));
    let err = |t: f64| {
        let (tt, x) = out
            .iter()
            .min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs()))
            .expect("samples");
        sim.model.readout(*tt, x).reading_error_rad
    };
    let jump = err(660.0) - err(600.0);
    let swing = out
        .iter()
        .filter(|(t, _)| *t >= 660.0)
        .map(|(t, x)| (sim.model.readout(*t, x).reading_error_rad - settled).abs())
        .fold(0.0, f64::max);
    (jump, swing)
}

/// Beghin §44, §47 (52): over a North–South speed change the Sperry's azimuth moves by
/// IΩδζ = 𝒫δv/g, and at the latitude where 𝒫 = IΩg/(Rε cos L) that is the change of its speed
/// error: undamped it lands on its new equilibrium with no swing at all. The Anschütz 1906 on
/// the same manoeuvre at the same latitude jumps aPδv/(gIΩ), 1.85 times the speed error's
/// change, and swings by the difference. With the roller kept, the Sperry's damping tilt
/// δθ = 2hδv/g (53) leaves a swing of its own (printed).
#[test]
fn schuler_tuned_speed_change_lands_on_the_new_equilibrium() {
    let probe = scene_from(&harbour(40.0, "", 0.1), &SceneOverrides::default());
    let th = theory(&probe.design, 40.0);
    let h = th.spin_momentum;
    let cos_l = h * STANDARD_GRAVITY_M_PER_S2
        / (EARTH_RADIUS_M * EARTH_RATE_RAD_PER_S * th.pendulous_moment());
    let lat = cos_l.acos().to_degrees();
    let dv = 20.0 * KNOT_IN_M_PER_S;
    let speed_error = dv / (EARTH_RADIUS_M * EARTH_RATE_RAD_PER_S * cos_l);
    let expected_jump = th.pendulous_moment() * dv / (STANDARD_GRAVITY_M_PER_S2 * h);
    // The new equilibrium: the harbour reading at this latitude.
    let settled = |design: &str, compass: &str| {
        let sc = scene_from(
            &speed_change(design, lat, compass, 0.01).replace("speed_kn = 20.0", "speed_kn = 0.0"),
            &SceneOverrides::default(),
        );
        let sim = Simulation::new(&sc).expect("compiles");
        sim.model
            .readout(0.0, &sim.model.x_equilibrium)
            .reading_error_rad
    };
    let undamped = "design_overrides = { \"parameters.roller_offset_rad\" = 0.0 }";
    let (jump, swing) = ballistic(
        &speed_change("sperry-1911", lat, undamped, 3.0),
        settled("sperry-1911", undamped),
    );
    let (jump_damped, swing_damped) = ballistic(
        &speed_change("sperry-1911", lat, "", 3.0),
        settled("sperry-1911", ""),
    );
    let (jump_a, swing_a) = ballistic(
        &speed_change("anschutz-1906", lat, "", 3.0),
        settled("anschutz-1906", ""),
    );
    println!(
        "L = {lat:.2}° (Schuler latitude of 𝒫): speed error change {speed_error:.5} rad, 𝒫δv/(gIΩ) {expected_jump:.5}\n  Sperry undamped: jump {jump:.5}, swing after {swing:.2e}\n  Sperry damped:   jump {jump_damped:.5}, swing after {swing_damped:.2e} (damping tilt 2hδv/g √(𝒫/τ) = {:.2e})\n  Anschütz 1906:   jump {jump_a:.5}, swing after {swing_a:.2e}",
        2.0 * th.damping_factor() * dv / STANDARD_GRAVITY_M_PER_S2
            * (th.pendulous_moment() / th.tau()).sqrt()
    );
    assert!((expected_jump / speed_error - 1.0).abs() < 1e-9);
    assert!(
        (jump.abs() / expected_jump - 1.0).abs() < 0.02,
        "jump {jump}"
    );
    assert!(
        swing < 0.03 * expected_jump,
        "undamped Sperry swings {swing:e} rad"
    );
    assert!(
        swing_a > 0.3 * expected_jump,
        "the Anschütz swings {swing_a:e} rad"
    );
    assert!(swing < 0.1 * swing_a);
}
