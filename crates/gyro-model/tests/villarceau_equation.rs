//! The engine's equation of Foucault's gyroscope equals Villarceau's exact eq. 44 bis
//! (instantaneous check at many states; no integrator involved).

use gyro_model::constants::EARTH_RATE_RAD_PER_S;
use gyro_model::theory::{Villarceau, VillarceauInputs};
use gyro_model::{
    CompiledModel, Design, Effects, Fidelity, InitialCondition, ModelOptions, Moored,
};

fn design(overrides: &[(&str, f64)]) -> Design {
    let text =
        std::fs::read_to_string(gyro_testkit::repo_root!().join("designs/foucault-gyroscope.toml"))
            .expect("design file");
    let ov: Vec<(String, toml::Value)> = overrides
        .iter()
        .map(|(k, v)| (k.to_string(), toml::Value::Float(*v)))
        .collect();
    Design::from_toml("foucault-gyroscope.toml", &text, &ov).expect("valid design")
}

fn compile(d: Design, lat_deg: f64, gamma0: f64) -> CompiledModel<Moored> {
    let gi = d.coordinate_index("gamma").expect("gamma");
    CompiledModel::compile(
        d,
        Moored {
            latitude_rad: lat_deg.to_radians(),
            heading_rad: 0.0,
        },
        ModelOptions {
            fidelity: Fidelity::Full,
            effects: Effects {
                base: gyro_model::BaseEffects {
                    earth_rotation: true,
                    ..Default::default()
                },
                ..Default::default()
            },
            pivot_m: [0.0; 3],
            initial: InitialCondition {
                from_equilibrium: false,
                offsets_rad: vec![(gi, gamma0)],
                rates_rad_per_s: vec![],
                slow_start: false,
            },
        },
    )
    .expect("compiles")
}

/// Villarceau's constants from the design's own numbers and the compiled model's spin.
fn villarceau_of(m: &CompiledModel<Moored>, lat_deg: f64) -> (Villarceau, f64) {
    let d = &m.design;
    let ring = &d.bodies[d.body_index("ring").expect("present")];
    let torus_i = d.body_index("torus").expect("present");
    let torus = &d.bodies[torus_i];
    let rotor = torus.rotor.as_ref().expect("present");
    // Ring axis in the local frame and its polar distance.
    let z = [
        ring.joint_rotation[0][2],
        ring.joint_rotation[1][2],
        ring.joint_rotation[2][2],
    ];
    let l = lat_deg.to_radians();
    let cos_tp = z[0] * l.cos() + z[2] * l.sin();
    // Offset of the hour plane: the hinge angle at which the ring's x axis lies in the plane of
    // the ring axis and the Earth's axis, on the pole side.
    let e = [l.cos(), 0.0, l.sin()];
    let ex = [
        e[0] - cos_tp * z[0],
        e[1] - cos_tp * z[1],
        e[2] - cos_tp * z[2],
    ];
    let x = [
        ring.joint_rotation[0][0],
        ring.joint_rotation[1][0],
        ring.joint_rotation[2][0],
    ];
    let y = [
        ring.joint_rotation[0][1],
        ring.joint_rotation[1][1],
        ring.joint_rotation[2][1],
    ];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let offset = dot(ex, y).atan2(dot(ex, x));
    let v = Villarceau::new(&VillarceauInputs {
        a: torus.inertia_kg_m2[0][0],
        c: rotor.polar_inertia_kg_m2,
        // Villarceau's A′ is the ring's moment about the normal to its plane (the plane holding
        // the ring axis and the torus axis): here the ring's y axis; B′ is in the plane (x).
        // The torus term A sin²η of eq. 46 has A′'s sign, which fixes this reading.
        a_ring: ring.inertia_kg_m2[1][1],
        b_ring: ring.inertia_kg_m2[0][0],
        c_ring: ring.inertia_kg_m2[2][2],
        n: m.spin_momentum[torus_i] / rotor.polar_inertia_kg_m2,
        omega: EARTH_RATE_RAD_PER_S,
        theta_ring: cos_tp.clamp(-1.0, 1.0).acos(),
        eta: d.parameter("eta_deg").expect("present").to_radians(),
    });
    (v, offset)
}

fn check(overrides: &[(&str, f64)], lat_deg: f64) {
    let m = compile(design(overrides), lat_deg, 0.3);
    let (v, offset) = villarceau_of(&m, lat_deg);
    let mut worst: f64 = 0.0;
    for k in 0..40 {
        let gamma = -3.1 + 0.155 * k as f64;
        for rate in [0.0, 0.37, -1.9] {
            let x = [gamma + offset, rate];
            let mut dx = [0.0; 2];
            assert!(m.rhs(0.0, &x, &mut dx));
            let expect = v.acceleration(gamma);
            // Natural size of the terms: the restoring term and the rate-squared terms that
            // cancel exactly in the equation of a single hinge.
            let scale = v.g_over_a.abs() + rate * rate;
            worst = worst.max((dx[1] - expect).abs() / scale);
        }
    }
    assert!(
        worst < 1e-11,
        "engine vs eq. 44 bis: worst relative difference {worst:e} ({overrides:?}, L = {lat_deg}°)"
    );
}

#[test]
fn azimuth_gyroscope_obeys_eq_44_bis() {
    check(&[], 45.0);
}

#[test]
fn latitude_gyroscope_obeys_eq_44_bis() {
    check(&[("parameters.ring_axis_elevation_deg", 0.0)], 45.0);
}

#[test]
fn oblique_rotor_exercises_the_delta_term() {
    // η = 20°, slow spin: δ is no longer negligible, and A′ ≠ B′ enters.
    check(
        &[
            ("parameters.eta_deg", 20.0),
            ("body.torus.rotor.spin_rpm", 0.5),
            ("parameters.ring_axis_elevation_deg", 30.0),
        ],
        50.0,
    );
}

#[test]
fn reversed_spin_oscillates_about_pi() {
    let m = compile(design(&[("body.torus.rotor.spin_rpm", -9000.0)]), 45.0, 0.3);
    let (v, _) = villarceau_of(&m, 45.0);
    assert!(v.g_over_a < 0.0);
    assert!((v.centre() - std::f64::consts::PI).abs() < 1e-15);
    check(&[("body.torus.rotor.spin_rpm", -9000.0)], 45.0);
}
