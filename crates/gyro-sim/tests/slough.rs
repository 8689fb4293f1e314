//! The Slough simulated by the engine against Beghin's closed forms (§50–53), computed from the
//! design's own parameters: the harbour swing (period (22), damping factor (23)), the settled
//! reading and mercury level (18), and the ballistic deviation of a speed change once the
//! mercury has settled, IΩδV = (𝒫 − 2ϖω₀h²)δv/g (Schuler-tuned at one latitude, like the
//! Sperry 1911's).

use crate::support;
use gyro_model::Design;
use gyro_model::constants::{
    EARTH_RADIUS_M, EARTH_RATE_RAD_PER_S, KNOT_IN_M_PER_S, STANDARD_GRAVITY_M_PER_S2,
};
use gyro_model::theory::Slough;
use gyro_sim::solvers::Method;
use gyro_sim::{SceneOverrides, Simulation};
use std::f64::consts::TAU;
use support::*;

fn theory(d: &Design, lat_deg: f64) -> Slough {
    Slough::from_design(d, lat_deg.to_radians()).expect("the Slough's parameters")
}

/// A harbour scene for the Slough at `lat`, `hours` long, with extra `[compass]` lines.
fn harbour(lat: f64, compass: &str, hours: f64) -> String {
    support::harbour_scene("slough", lat, compass, hours, 0.1)
}

/// Released 2° off at 0°, 35° and 60°: the swing's period is that of the compass roots of
/// (20) (the damped form of eq. 22) and its envelope decays at ρK/(−2IΩ) (eq. 23), each
/// within 1 %.
#[test]
fn harbour_swing_has_the_period_and_decay_of_eqs_20_to_23() {
    for lat in [0.0, 35.0, 60.0] {
        let probe = scene_from(&harbour(lat, "", 0.1), &SceneOverrides::default());
        let th = theory(&probe.design, lat);
        let root = th.compass_roots()[0];
        let t_d = TAU / root.1.abs();
        let sc = scene_from(
            &harbour(lat, "azimuth_offset_deg = 2.0", 2.2 * t_d / 3600.0),
            &SceneOverrides::default(),
        );
        let (sim, out, _) = run(&sc, Method::Rodas4, tol(1e-9, 1e-12));
        let r0 = sim
            .model
            .readout(0.0, &sim.model.equilibrium_state())
            .reading_error_rad;
        let iz = support::coordinate(&sim, "zeta");
        let t: Vec<f64> = out.iter().map(|v| v.0).collect();
        let (y, yd): (Vec<f64>, Vec<f64>) = out
            .iter()
            .map(|(t, x)| {
                let r = sim.model.readout(*t, x);
                (r.reading_error_rad - r0, r.qd[iz])
            })
            .unzip();
        let c = upward_crossings(&t, &y, &yd);
        let period = mean_period(&c);
        // The decay: the envelope's ratio over one period, from the largest |y| of the first
        // and the second whole period after the first upward crossing.
        let peak = |from: f64| {
            t.iter()
                .zip(&y)
                .filter(|(tt, _)| **tt >= from && **tt < from + period)
                .map(|(_, v)| v.abs())
                .fold(0.0, f64::max)
        };
        let decay = (peak(c[0]) / peak(c[0] + period)).ln() / period;
        println!(
            "L = {lat}°: period {period:.1} s vs {t_d:.1} s (undamped eq. 22: {:.1} s); decay {decay:.3e} vs ρK/(−2IΩ) {:.3e}",
            th.period(),
            th.damping_factor()
        );
        assert!((period / t_d - 1.0).abs() < 0.01, "L = {lat}°: period");
        assert!(
            (decay / th.damping_factor() - 1.0).abs() < 0.01,
            "L = {lat}°: decay"
        );
    }
}

/// Settled in harbour (4 h after a 2° release at 35°N) the Slough reads −ρ tan L (East in the
/// North) with the mercury standing at u = hη and the case level (eq. 18), each within 1 %.
#[test]
fn settled_reading_and_mercury_level_are_eq_18() {
    for lat in [35.0, -35.0] {
        let sc = scene_from(
            &harbour(lat, "azimuth_offset_deg = 2.0", 6.0),
            &SceneOverrides::default(),
        );
        let th = theory(&sc.design, lat);
        let (sim, out, _) = run(&sc, Method::Rodas4, tol(1e-9, 1e-12));
        let (t, x) = out.last().expect("samples");
        let r = sim.model.readout(*t, x);
        let u = r.q[support::coordinate(&sim, "u")];
        println!(
            "L = {lat}°: reading {:.4}° vs −ρ tan L {:.4}°; u {:.3e} m vs hη {:.3e} m",
            r.reading_error_rad.to_degrees(),
            th.latitude_error().to_degrees(),
            u,
            th.equilibrium_level()
        );
        assert!((r.reading_error_rad / th.latitude_error() - 1.0).abs() < 0.01);
        assert_eq!(r.reading_error_rad < 0.0, lat > 0.0, "East in the North");
        assert!((u / th.equilibrium_level() - 1.0).abs() < 0.01);
    }
}

/// Beghin §53 (30): over a North–South speed change the mercury "obeys lazily but fully": once
/// it has settled the azimuth has moved by IΩδV = (𝒫 − 2ϖω₀h²)δv/g = (ap − K)δv/g. At the
/// latitude where K − ap = −IΩg/(Rε cos L) that is the change of the speed error, and the
/// undamped Slough lands on its new equilibrium. At the end of the 60-s stop the mercury (≈ 30 s)
/// has not yet given all of it: it lags by the first moment of its own response.
#[test]
fn speed_change_lands_once_the_mercury_has_settled() {
    let undamped = "design_overrides = { \"parameters.roller_offset_rad\" = 0.0 }";
    let probe = scene_from(&harbour(40.0, undamped, 0.1), &SceneOverrides::default());
    let th = theory(&probe.design, 40.0);
    let k_minus_ap = th.counterweight_moment() - th.overload_moment;
    let cos_l = -th.spin_momentum * STANDARD_GRAVITY_M_PER_S2
        / (EARTH_RADIUS_M * EARTH_RATE_RAD_PER_S * k_minus_ap);
    let lat = cos_l.acos().to_degrees();
    let dv = 20.0 * KNOT_IN_M_PER_S;
    let speed_error = dv / (EARTH_RADIUS_M * EARTH_RATE_RAD_PER_S * cos_l);
    let th = theory(&probe.design, lat);
    let expected = th.speed_change_deviation(dv);
    let text = format!(
        r#"name = "t"
duration_s = 7200.0
output_rate_hz = 1.0
[start]
latitude_deg = {lat}
heading_deg = 0.0
speed_kn = 20.0
[compass]
design = "slough"
{undamped}
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
"#
    );
    let sc = scene_from(&text, &SceneOverrides::default());
    let (sim, out, _) = run(&sc, Method::Rodas4, tol(1e-9, 1e-12));
    let err = |t: f64| {
        let (tt, x) = out
            .iter()
            .min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs()))
            .expect("samples");
        sim.model.readout(*tt, x).reading_error_rad
    };
    let at_end = err(660.0) - err(600.0);
    let settled = err(900.0) - err(600.0);
    // The new equilibrium: the reading at rest at this latitude.
    let rest = {
        let sc = scene_from(&harbour(lat, undamped, 0.01), &SceneOverrides::default());
        let s = Simulation::new(&sc).expect("compiles");
        s.model
            .readout(0.0, &s.model.equilibrium_state())
            .reading_error_rad
    };
    let swing = out
        .iter()
        .filter(|(t, _)| *t >= 900.0)
        .map(|(t, x)| (sim.model.readout(*t, x).reading_error_rad - rest).abs())
        .fold(0.0, f64::max);
    println!(
        "L = {lat:.2}° (Schuler latitude of K − ap): speed error change {speed_error:.5} rad, (𝒫 − 2ϖω₀h²)δv/(gIΩ) {expected:.5}\n  jump at the stop's end {at_end:.5}, 4 min later {settled:.5}; swing after {swing:.2e} rad"
    );
    assert!((expected.abs() / speed_error - 1.0).abs() < 1e-9);
    // Running North the card reads high by the speed error; stopped, it has lost it all.
    assert!(
        (settled / -speed_error - 1.0).abs() < 0.02,
        "settled jump {settled} vs −{speed_error}"
    );
    // The mercury lags the deceleration by the first moment of its response, k/(2ϖω₀) s (the
    // trinomial's 2ζ/ω₀): at the stop's end its share of the jump, 2ϖω₀h²/(2ϖω₀h² − 𝒫) of the
    // whole, is short by that time over the stop's 60 s.
    let lag_s = th.friction / th.level_stiffness;
    let liquid_share = th.liquid_moment / (th.liquid_moment - th.solid_moment - th.overload_moment);
    let expected_deficit = lag_s / 60.0 * liquid_share;
    let deficit = 1.0 - at_end / settled;
    println!(
        "  short at the stop's end by {deficit:.4} of the jump; lag {lag_s:.2} s gives {expected_deficit:.4}"
    );
    assert!(
        (deficit / expected_deficit - 1.0).abs() < 0.25,
        "the mercury's lag: {deficit} vs {expected_deficit}"
    );
    assert!(swing < 0.05 * expected.abs(), "swing {swing:e} rad");
}

/// Beghin ch. I with a fluid: the pots' Lagrangian closes the energy balance. Released 2° off at
/// 35°N, Jacobi's integral h = T₂ − T₀ + V (the mercury's columns and flow included) moves by
/// the work of the servo and of the dampers (the flow's friction k u̇² among them),
/// ∫ (P_servo + P_dampers) dt by Simpson's rule on the samples, to 1e-9 of the energy's scale,
/// over 1 h in `gyroscopic` and 5 min in `full` (whose 74-Hz nutation the trunnions damp).
#[test]
fn energy_changes_by_the_servo_and_friction_work() {
    for (fidelity, seconds, rate_hz, method, rtol) in [
        ("gyroscopic", 3600.0, 5.0, Method::Dop853, 1e-13),
        ("full", 300.0, 400.0, Method::Rodas4, 1e-11),
    ] {
        let text = format!(
            r#"name = "t"
duration_s = {seconds}
output_rate_hz = {rate_hz}
[start]
latitude_deg = 35.0
[compass]
design = "slough"
azimuth_offset_deg = 2.0
[simulation]
fidelity = "{fidelity}"
integrator = "rodas4"
"#
        );
        let sc = scene_from(&text, &SceneOverrides::default());
        let (sim, out, stats) = run(&sc, method, tol(rtol, 1e-16));
        let e: Vec<(f64, gyro_model::Energetics)> = out
            .iter()
            .map(|(t, x)| (*t, sim.model.energetics(*t, x).expect("solvable")))
            .collect();
        let scale =
            e[0].1.kinetic_j.abs() + e[0].1.frame_kinetic_j.abs() + e[0].1.potential_j.abs();
        let (mut servo, mut dampers, mut worst) = (0.0, 0.0, 0.0f64);
        for k in (2..e.len()).step_by(2) {
            let h = e[k].0 - e[k - 2].0;
            let simpson = |p: &dyn Fn(usize) -> f64| h / 6.0 * (p(k - 2) + 4.0 * p(k - 1) + p(k));
            servo += simpson(&|i| e[i].1.servo_power_w);
            dampers += simpson(&|i| e[i].1.damper_power_w);
            let closure = e[k].1.energy_j - e[0].1.energy_j - servo - dampers;
            worst = worst.max(closure.abs());
        }
        let gained = e[e.len() - 1].1.energy_j - e[0].1.energy_j;
        println!(
            "{fidelity}: energy scale {scale:.3e} J, h gained {gained:.4e} J, servo work {servo:.4e} J, dampers {dampers:.4e} J, worst closure {worst:.2e} J ({:.1e} of the scale); {} steps",
            worst / scale,
            stats.solver.steps
        );
        assert!(dampers < 0.0, "{fidelity}: friction dissipates");
        assert!(
            worst < 1e-9 * scale,
            "{fidelity}: closure {worst:e} J vs {scale:e} J"
        );
        assert!(
            worst < 1e-3 * gained.abs().max(dampers.abs()),
            "{fidelity}: closure {worst:e} J vs the work done"
        );
    }
}
