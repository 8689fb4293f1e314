//! The shipped studies reproduce known physics: the Anschütz's rolling error is a sin 2Δ against
//! heading whose amplitude follows ½ sinΔ cosΔ (J₀/g)² aP/τ over roll periods of 5–15 s, and the
//! damped periods and latitude errors of the Anschütz, the Sperry and the Slough follow their
//! characteristic equations (periods within 1 %, also where the damping ratio passes 0.45 and the
//! release overshoots only once above 3 % of its swing) and eqs. 18 / 10 at every latitude from 0
//! to 75°N.

use crate::common::tmp;
use gyro_model::constants::EARTH_RATE_RAD_PER_S;
use gyro_model::theory::{Anschutz, Slough, Sperry1911, rolling_error_magnitude_rad};
use gyro_study::sweep::run_local;
use gyro_study::{Plan, Study, report, table};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

fn shipped(name: &str) -> Plan {
    let path = gyro_testkit::repo_root!()
        .join("sweeps")
        .join(format!("{name}.toml"));
    Plan::new(Study::load(&path).expect("the shipped study reads")).expect("its scenes load")
}

fn sweep(plan: &Plan, name: &str) -> std::path::PathBuf {
    let out = tmp(name);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let s = run_local(
        plan,
        &out,
        threads,
        &Arc::new(AtomicBool::new(false)),
        |_, _| {},
    )
    .expect("the sweep runs");
    assert_eq!(s.failed, 0, "no run fails");
    out
}

fn column(df: &polars::prelude::DataFrame, name: &str) -> Vec<f64> {
    df[name]
        .f64()
        .expect("f64")
        .iter()
        .map(|v| v.unwrap_or(f64::NAN))
        .collect()
}

#[test]
fn anschutz_rolling_error_is_the_closed_form_sin_2_delta() {
    let plan = shipped("anschutz-rolling");
    assert_eq!(plan.total_runs(), 40);
    let out = sweep(&plan, "shipped-rolling");
    let r = report::report(&out).expect("the report");
    assert_eq!(r.harmonics.len(), 5, "one fit per roll period");
    for h in &r.harmonics {
        let period: f64 = h
            .group
            .iter()
            .find(|(k, _)| k == "sea.roll_period_s")
            .and_then(|(_, v)| v.parse().ok())
            .expect("the group's roll period");
        // The closed form from the run's own numbers.
        let index = (0..plan.total_runs())
            .find(|&i| plan.run(i).values[3].as_float() == Some(period))
            .expect("a run at this period");
        let scene = plan.scene(&plan.run(index)).expect("scene");
        let d = &scene.design;
        let ap = d.parameter("pendulous_moment_n_m").expect("aP");
        let tau = d.parameter("spin_momentum_n_m_s").expect("IΩ")
            * EARTH_RATE_RAD_PER_S
            * scene.start_latitude_rad.cos();
        let w = std::f64::consts::TAU / scene.program.sea.roll_period_s;
        let j0 = scene.pivot_m[2] * scene.program.sea.roll_amplitude_rad.sin() * w * w;
        let expect = rolling_error_magnitude_rad(j0, std::f64::consts::FRAC_PI_4, ap, tau);
        println!(
            "roll {period:4.1} s: sin 2Δ amplitude {:.4}° (cos 2Δ {:.4}°, mean {:.4}°, rms residual {:.4}°) vs ¼ (J₀/g)² aP/τ = {:.4}°",
            h.sin_coefficient.to_degrees(),
            h.cos_coefficient.to_degrees(),
            h.mean.to_degrees(),
            h.rms_residual.to_degrees(),
            expect.to_degrees()
        );
        assert!(
            (h.amplitude / expect - 1.0).abs() < 0.2,
            "roll {period} s: fitted sin 2Δ amplitude {:.4}° vs closed form {:.4}°",
            h.amplitude.to_degrees(),
            expect.to_degrees()
        );
        // The shape is sin 2Δ: nothing on cardinal headings (no cos 2Δ), little else.
        assert!(h.cos_coefficient.abs() < 0.1 * h.amplitude, "{h:?}");
        assert!(h.rms_residual < 0.15 * h.amplitude, "{h:?}");
    }
}

#[test]
fn damped_periods_and_latitude_errors_follow_theory_at_every_latitude() {
    for name in ["anschutz-latitude", "sperry-latitude", "slough-latitude"] {
        let plan = shipped(name);
        let out = sweep(&plan, name);
        let df = table::read_parquet(&table::metrics_path(&out)).expect("table");
        let lat = column(&df, "start.latitude_deg");
        let period = column(&df, "period_s");
        let steady = column(&df, "steady_error_rad");
        let quality: Vec<String> = df["azimuth_quality"]
            .str()
            .expect("str")
            .iter()
            .map(|s| s.unwrap_or("").to_string())
            .collect();
        assert_eq!(lat.len(), 16);
        let mut fitted = 0;
        for (i, l) in lat.iter().enumerate() {
            let scene = plan.scene(&plan.run(i as u64)).expect("scene");
            let d = &scene.design;
            let lr = l.to_radians();
            let (root, error) = if name == "sperry-latitude" {
                let th = Sperry1911::from_design(d, lr).expect("the Sperry's parameters");
                (
                    th.characteristic_roots()[0],
                    th.latitude_error() - th.small_spin_momentum / th.spin_momentum,
                )
            } else if name == "slough-latitude" {
                let th = Slough::from_design(d, lr).expect("the Slough's parameters");
                (th.compass_roots()[0], th.latitude_error())
            } else {
                let th = Anschutz {
                    spin_momentum: d.parameter("spin_momentum_n_m_s").expect("IΩ"),
                    pendulous_moment: d.parameter("pendulous_moment_n_m").expect("aP"),
                    kappa: d.parameter("kappa_n_m").expect("κ"),
                    // ℭ and 𝔅 move the slow roots by ~ℭaP/(IΩ)² ≈ 1e-4 only.
                    inertia_vertical: 0.08,
                    inertia_east_west: 0.08,
                    latitude_rad: lr,
                };
                let l0 = d
                    .parameter("compensation_latitude_deg")
                    .expect("L₀")
                    .to_radians();
                // Eq. 18: κ (sin L₀ − sin L)/(aP cos L).
                let e = th.kappa * (l0.sin() - lr.sin()) / (th.pendulous_moment * lr.cos());
                (th.characteristic_roots()[0], e)
            };
            let t_d = std::f64::consts::TAU / root.1.abs();
            let zeta = -root.0 / root.0.hypot(root.1);
            println!(
                "{name} {l:4.1}°N (ζ {zeta:.2}): period {:.1} s vs {t_d:.1} s ({:+.3} %), latitude error {:.4}° vs {:.4}°",
                period[i],
                (period[i] / t_d - 1.0) * 100.0,
                steady[i].to_degrees(),
                error.to_degrees()
            );
            assert_eq!(
                quality[i], "ok",
                "{name} at {l}°N: the fit refused the period at a damping ratio of {zeta:.3}"
            );
            fitted += 1;
            assert!(
                (period[i] / t_d - 1.0).abs() < 0.01,
                "{name} at {l}°N: fitted period {:.1} s vs the slow roots' {t_d:.1} s",
                period[i]
            );
            assert!(
                (steady[i] - error).abs() < 0.02 * error.abs() + 3e-5,
                "{name} at {l}°N: settled error {:.4}° vs {:.4}°",
                steady[i].to_degrees(),
                error.to_degrees()
            );
        }
        assert_eq!(fitted, 16, "{name}: every latitude's period fitted");
    }
}
