//! The body-axes engine that `CompiledModel::rhs` and `jacobian` use gives the same equations as
//! the world-axes reference engine (`rhs_reference`, the engine as first written), to round-off:
//! on every shipped scene at both nonlinear fidelities, at states away from equilibrium and at
//! several times (so moving bases, rolling and turning are covered), and on a made-up design
//! that walks every path of the body-axes engine (branches, constant joint rotations, hinges off
//! the pivot, a hingeless body with an offset and a turn merged into its parent, products of
//! inertia, a quadratic hinge relation, a servo relation, springs, generalised and body forces).
//! Jacobians are compared against the reference's column-by-column nested duals.
//!
//! `rhs` and `jacobian` run the model's recorded tape (`gyro_model`'s `tape`) where it pays and
//! the generic engine elsewhere; at every state compared here both they and the recorded tapes
//! themselves (`rhs_tape`, `jacobian_tape`) are held to the generic engine the tapes were
//! recorded from (`rhs_engine`, `jacobian_engine`): the right-hand side to the bit, the
//! Jacobian to 1e-13.
//!
//! Where `gyroscopic` fidelity carries the gyros (a rolling sea: `gyro_model`'s `gyroscopic`),
//! the precession rates' time derivative is a central difference whose two points lie on the
//! base's motion to first order only: there the two engines, which agree on consistent base
//! inputs, may differ by the O(h²) the points stray, and the bound is 1e-9 (right-hand side)
//! and 1e-8 (Jacobian); measured 5e-11 and 2e-10 at most. The same difference divides the
//! rounding of a recorded Jacobian by 2h = 2e-3 s, so the tape's Jacobian is held to the engine's
//! to 5e-11 of its scale there (measured 3e-13).

use gyro_model::{CompiledModel, Design, Effects, Fidelity, InitialCondition, Jet, ModelOptions};
use gyro_model::{Moored, ShipMotion};
use gyro_sim::{Scene, SceneOverrides, Simulation};

/// Deterministic pseudo-random numbers in [−1, 1].
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

fn reference_jacobian<M: ShipMotion>(
    model: &CompiledModel<M>,
    fidelity: Fidelity,
    t: f64,
    x: &[f64],
) -> Vec<f64> {
    let dim = x.len();
    let mut jac = vec![0.0; dim * dim];
    let mut xj = vec![Jet::<f64, 1>::constant(0.0); dim];
    let mut dxj = vec![Jet::<f64, 1>::constant(0.0); dim];
    for col in 0..dim {
        for i in 0..dim {
            xj[i] = Jet {
                v: x[i],
                d: [if i == col { 1.0 } else { 0.0 }],
            };
        }
        assert!(model.rhs_reference(fidelity, Jet::constant(t), &xj, &mut dxj));
        for row in 0..dim {
            jac[row * dim + col] = dxj[row].d[0];
        }
    }
    jac
}

/// Compares rhs and Jacobian at `x0` and at five perturbed states and times, returning the worst
/// differences (rhs, Jacobian) relative to the largest term of each block over all the states
/// (at equilibrium the accelerations are round-off themselves, so each state alone is no scale).
fn compare<M: ShipMotion>(
    label: &str,
    model: &CompiledModel<M>,
    rng: &mut Lcg,
    angle: f64,
    rate: f64,
) -> (f64, f64) {
    let fidelity = model.fidelity;
    let dim = model.dim();
    let ni = model.independent.len();
    // Per block: (largest difference, largest reference term). Blocks: rhs rates, rhs
    // accelerations, then one per Jacobian row.
    let mut blocks = vec![(0.0f64, 0.0f64); 2 + dim];
    let mut track = |b: usize, new: &[f64], reference: &[f64]| {
        for (x, y) in new.iter().zip(reference) {
            blocks[b].0 = blocks[b].0.max((x - y).abs());
            blocks[b].1 = blocks[b].1.max(y.abs());
        }
    };
    for k in 0..6 {
        let t = [0.0, 7.3, 61.9, 1234.5, 4000.25, 20000.0][k];
        let mut x = model.x0.clone();
        if k > 0 {
            for (i, xi) in x.iter_mut().enumerate() {
                *xi += if i < ni { angle } else { rate } * rng.next();
            }
        }
        let mut dx = vec![0.0; dim];
        let mut dr = vec![0.0; dim];
        assert!(model.rhs(t, &x, &mut dx), "{label}: rhs singular");
        assert!(
            model.rhs_reference(fidelity, t, &x, &mut dr),
            "{label}: reference singular"
        );
        let mut de = vec![0.0; dim];
        assert!(model.rhs_engine(t, &x, &mut de), "{label}: engine singular");
        assert!(
            dx == de,
            "{label}: rhs differs from the engine at t = {t}: {dx:?} vs {de:?}"
        );
        // The recorded tape, whether or not the model runs it (it runs where it pays).
        if fidelity != Fidelity::Linear {
            let mut dt = vec![0.0; dim];
            assert_eq!(
                model.rhs_tape(t, &x, &mut dt),
                Some(true),
                "{label}: the equations are recorded and regular"
            );
            assert!(
                dt == de,
                "{label}: tape differs from the engine at t = {t}: {dt:?} vs {de:?}"
            );
        }
        track(0, &dx[..ni], &dr[..ni]);
        track(1, &dx[ni..], &dr[ni..]);
        let mut jac = vec![0.0; dim * dim];
        model.jacobian(t, &x, &mut jac);
        let mut je = vec![0.0; dim * dim];
        model.jacobian_engine(t, &x, &mut je);
        let mut jt = vec![0.0; dim * dim];
        assert!(
            fidelity == Fidelity::Linear || model.jacobian_tape(t, &x, &mut jt),
            "{label}: the Jacobian is recorded and regular"
        );
        let scale = je.iter().fold(0.0f64, |m, v| m.max(v.abs()))
            * if model.carries_gyros() {
                // The central difference divides the tape's rounding by 2h = 2e-3 s.
                500.0
            } else {
                1.0
            };
        let worst = |a: &[f64]| {
            a.iter()
                .zip(&je)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
        };
        assert!(
            worst(&jac) <= 1e-13 * scale,
            "{label}: Jacobian differs from the engine's by {:e} (scale {scale:e})",
            worst(&jac)
        );
        if fidelity != Fidelity::Linear {
            assert!(
                worst(&jt) <= 1e-13 * scale,
                "{label}: tape Jacobian differs from the engine's by {:e} (scale {scale:e})",
                worst(&jt)
            );
        }
        let jr = reference_jacobian(model, fidelity, t, &x);
        for row in 0..dim {
            let r = row * dim..(row + 1) * dim;
            track(2 + row, &jac[r.clone()], &jr[r]);
        }
    }
    let rel = |b: &(f64, f64)| if b.1 == 0.0 { b.0 } else { b.0 / b.1 };
    let e_rhs = rel(&blocks[0]).max(rel(&blocks[1]));
    let e_jac = blocks[2..].iter().map(rel).fold(0.0, f64::max);
    let tape = model
        .tape_size(if fidelity == Fidelity::Linear {
            Fidelity::Full
        } else {
            fidelity
        })
        .expect("the equations are recorded");
    println!(
        "{label}: rhs {e_rhs:.1e}, jacobian {e_jac:.1e} (relative to each block's largest term); tape {} operations for the engine's {} ({})",
        tape.ops,
        tape.engine_ops,
        if tape.used {
            "runs"
        } else {
            "kept for the tests"
        }
    );
    (e_rhs, e_jac)
}

/// The agreement asked of a model (right-hand side, Jacobian): to round-off, or to the carried
/// reduction's central difference (module doc).
fn bounds<M: ShipMotion>(model: &CompiledModel<M>) -> (f64, f64) {
    if model.carries_gyros() {
        (1e-9, 1e-8)
    } else {
        (1e-12, 1e-10)
    }
}

#[test]
fn body_axes_engine_matches_the_reference_on_every_shipped_scene() {
    let mut rng = Lcg(7);
    for (label, _, sim) in crate::support::shipped_models() {
        let (e_rhs, e_jac) = compare(&label, &sim.model, &mut rng, 0.2, 1e-3);
        let (rhs_bound, jac_bound) = bounds(&sim.model);
        assert!(e_rhs < rhs_bound, "{label}: rhs differs by {e_rhs:e}");
        assert!(e_jac < jac_bound, "{label}: Jacobian differs by {e_jac:e}");
    }
}

/// A model that calls itself autonomous (a stationary base: RODAS4 then skips its ∂f/∂t
/// difference) is so to the bit: its right-hand side and Jacobian at hours apart are equal.
/// And the moving scenes do not claim it.
#[test]
fn models_that_claim_autonomy_do_not_depend_on_time() {
    let mut rng = Lcg(11);
    let (mut autonomous, mut moving) = (0, 0);
    for (label, _, sim) in crate::support::shipped_models() {
        let m = &sim.model;
        if !m.is_autonomous() {
            moving += 1;
            continue;
        }
        autonomous += 1;
        let n = m.dim();
        let mut x = m.x0.clone();
        for v in x.iter_mut().take(n / 2) {
            *v += 0.1 * rng.next();
        }
        let (mut f0, mut f1) = (vec![0.0; n], vec![0.0; n]);
        let (mut j0, mut j1) = (vec![0.0; n * n], vec![0.0; n * n]);
        assert!(m.rhs(0.0, &x, &mut f0), "{label}: singular at t = 0");
        m.jacobian(0.0, &x, &mut j0);
        for t in [1e-7, 1.0, 7_654.321] {
            assert!(m.rhs(t, &x, &mut f1), "{label}: singular at t = {t}");
            m.jacobian(t, &x, &mut j1);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&f0), bits(&f1), "{label}: f depends on t ({t} s)");
            assert_eq!(bits(&j0), bits(&j1), "{label}: df/dx depends on t ({t} s)");
        }
    }
    println!("{autonomous} autonomous models, {moving} on a moving base");
    assert!(autonomous >= 20 && moving >= 20, "{autonomous} / {moving}");
}

/// Every path of the body-axes engine in one (physically arbitrary) chain.
const ODD_DESIGN: &str = r#"
name = "odd-chain"
description = "test chain: branches, joint rotations, offsets, merged bodies, servo, forces, a spring between two branches"
root = "earth"

[[coordinate]]
name = "a"
[[coordinate]]
name = "b"
[[coordinate]]
name = "c"
servo = "0.5 * a - b + 0.1"
[[coordinate]]
name = "d"
[[coordinate]]
name = "e"

[[body]]
name = "outer"
parent = "base"
joint_origin_m = [0.01, -0.02, 0.03]
joint_rotation = [{ axis = "x", angle_deg = 20.0 }]
hinge = { axis = "z", angle_rad = "a" }
mass_kg = 1.5
cg_m = [0.02, 0.01, -0.05]
inertia_kg_m2 = [0.02, 0.03, 0.025]
products_of_inertia_kg_m2 = [0.001, -0.002, 0.0005]

[[body]]
name = "inner"
parent = "outer"
joint_origin_m = [0.0, 0.05, -0.01]
hinge = { axis = "y", angle_rad = "b + 0.3 * a * d" }
mass_kg = 2.0
cg_m = [0.0, 0.0, -0.08]
inertia_kg_m2 = [0.01, 0.012, 0.014]

[[body]]
name = "rotor"
parent = "inner"
joint_origin_m = [0.01, 0.0, -0.02]
joint_rotation = [{ axis = "y", angle_deg = 30.0 }]
mass_kg = 0.8
cg_m = [0.005, 0.0, 0.0]
inertia_kg_m2 = [0.0, 0.002, 0.002]
rotor = { axis = [1.0, 0.0, 0.0], polar_inertia_kg_m2 = 0.004, spin_rpm = 12000.0, spin = "held" }

[[body]]
name = "pendant"
parent = "rotor"
joint_origin_m = [0.0, 0.0, -0.04]
hinge = { axis = "x", angle_rad = "d" }
mass_kg = 0.3
cg_m = [0.0, 0.01, -0.03]
inertia_kg_m2 = [1e-4, 2e-4, 1.5e-4]

[[body]]
name = "side"
parent = "outer"
joint_origin_m = [0.06, 0.0, 0.0]
joint_rotation = [{ axis = "z", angle_deg = -45.0 }]
hinge = { axis = "x", angle_rad = "c" }
mass_kg = 0.4
cg_m = [0.0, 0.02, -0.01]
inertia_kg_m2 = [3e-4, 2e-4, 2e-4]

[[body]]
name = "tip"
parent = "side"
hinge = { axis = "z", angle_rad = "e - 0.2 * c" }
mass_kg = 0.1
cg_m = [0.03, 0.0, 0.0]
inertia_kg_m2 = [1e-5, 2e-5, 2e-5]

[[force]]
kind = "body_force"
name = "jet"
body = "rotor"
direction = [0.0, -1.0, 0.0]
force_n = 0.7
point_m = ["0.02 * d", "0", "-0.03 + 0.01 * b"]

[[force]]
kind = "damper"
name = "drag"
expr_rad = "a - 0.5 * d"
coefficient_n_m_s_per_rad = 0.01

[[force]]
kind = "spring"
name = "wire"
expr_rad = "e + 0.1 * a * b"
stiffness_n_m_per_rad = 0.05
rest_rad = 0.1
preload_n_m = 0.002

[[force]]
kind = "generalized"
name = "torque"
coordinate = "b"
torque_n_m = "0.003 * a - 0.001 * a * e"

[[force]]
kind = "link_spring"
name = "tie"
bodies = ["pendant", "tip"]
points_m = [[0.01, -0.02, -0.05], [0.04, 0.01, 0.0]]
stiffness_n_per_m = 3.0
length_m = 0.05
tension_n = 0.2

[reading]
body = "inner"
axis = [1.0, 0.0, 0.0]
"#;

#[test]
fn body_axes_engine_matches_the_reference_on_a_chain_that_uses_every_path() {
    let ideal = Design::from_toml("odd-chain.toml", ODD_DESIGN, &[]).expect("design");
    // The same chain with its servo as a finite-gain motor (a torque on the follower only).
    let pd = ideal.with_pd_servos(0.8, 0.05);
    let mut rng = Lcg(11);
    for (design, fidelity) in [
        (&ideal, Fidelity::Full),
        (&ideal, Fidelity::Gyroscopic),
        (&pd, Fidelity::Full),
        (&pd, Fidelity::Gyroscopic),
    ] {
        let servo = if design.forces.len() > ideal.forces.len() {
            "pd servo"
        } else {
            "ideal servo"
        };
        let model = CompiledModel::compile(
            design.clone(),
            Moored {
                latitude_rad: 0.7,
                heading_rad: 0.4,
            },
            ModelOptions {
                fidelity,
                effects: Effects::all(),
                pivot_m: [0.0; 3],
                initial: InitialCondition::default(),
            },
        )
        .expect("compiles");
        let (e_rhs, e_jac) = compare(
            &format!(
                "odd-chain/{servo}/{fidelity} (fidelity used: {})",
                model.fidelity
            ),
            &model,
            &mut rng,
            0.5,
            0.3,
        );
        assert!(
            e_rhs < 1e-12,
            "odd chain {servo} {fidelity}: rhs differs by {e_rhs:e}"
        );
        assert!(
            e_jac < 1e-10,
            "odd chain {servo} {fidelity}: Jacobian differs by {e_jac:e}"
        );
    }
}

#[test]
fn body_axes_engine_matches_the_reference_on_a_rolling_turning_ship() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("engine-agreement");
    std::fs::create_dir_all(&dir).expect("tmp dir");
    let mut rng = Lcg(13);
    for root in ["earth", "ship"] {
        let path = dir.join(format!("odd-chain-{root}.toml"));
        std::fs::write(
            &path,
            ODD_DESIGN.replace("root = \"earth\"", &format!("root = \"{root}\"")),
        )
        .expect("write design");
        for fidelity in ["full", "gyroscopic"] {
            let scene = format!(
                r#"name = "odd-moving"
description = "every base motion at once"
duration_s = 3000.0
[start]
latitude_deg = 40.0
heading_deg = 30.0
speed_kn = 15.0
[compass]
design = "{}"
start_from_equilibrium = false
start_rates = "rest"
pivot_m = [1.0, -0.5, 8.0]
[[program]]
kind = "speed_change"
to_speed_kn = 5.0
acceleration_m_per_s2 = 0.01
[[program]]
kind = "turn"
by_deg = 90.0
rate_deg_per_s = 1.0
[sea]
roll_amplitude_deg = 5.0
roll_period_s = 8.0
pitch_amplitude_deg = 2.0
pitch_period_s = 6.0
[simulation]
fidelity = "{fidelity}"
"#,
                path.display()
            );
            let sc = Scene::from_toml("odd-moving.toml", &scene, None, &SceneOverrides::default())
                .expect("scene");
            let sim = Simulation::new(&sc).expect("compiles");
            let (e_rhs, e_jac) = compare(
                &format!("odd-chain on a {root} root, rolling and turning, {fidelity}"),
                &sim.model,
                &mut rng,
                0.5,
                0.3,
            );
            let (rhs_bound, jac_bound) = bounds(&sim.model);
            assert!(
                e_rhs < rhs_bound,
                "{root}/{fidelity}: rhs differs by {e_rhs:e}"
            );
            assert!(
                e_jac < jac_bound,
                "{root}/{fidelity}: Jacobian differs by {e_jac:e}"
            );
        }
    }
}
