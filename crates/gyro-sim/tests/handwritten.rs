//! The hand-written equations (`gyro_sim::accuracy::handwritten`) agree with the engine's `rhs`
//! and `jacobian` to rounding: Villarceau's eq. 44 bis against the shipped Foucault azimuth
//! gyroscope, and the Anschütz 1906 at both nonlinear fidelities against the harbour scene, at
//! the scene's start and at a few hundred random states around it (angles up to a radian or
//! more, rates well beyond the motion's). Each physical term of the hand-written Anschütz, and
//! Villarceau's δ, is shown to matter far above the tolerance: a missing term fails the test.

use gyro_model::Fidelity;
use gyro_sim::accuracy::foucault_release_scene;
use gyro_sim::accuracy::handwritten::{Anschutz1906, Foucault44Bis};
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

/// The start and `n` random states about it: coordinates moved by up to `angle` rad, rates by up
/// to `rate` rad/s.
fn states(x0: &[f64], ncoord: usize, angle: f64, rate: f64, n: usize) -> Vec<Vec<f64>> {
    let mut rng = Lcg(2024);
    let mut v = vec![x0.to_vec()];
    for _ in 0..n {
        let mut x = x0.to_vec();
        for (i, xi) in x.iter_mut().enumerate() {
            *xi += if i < ncoord { angle } else { rate } * rng.next();
        }
        v.push(x);
    }
    v
}

/// Worst differences (rhs, Jacobian) between `hand` and the engine over `xs`, each relative to the
/// largest engine term of its block over all states (blocks: the coordinates' rates, the rest of
/// ẋ, and each row of the Jacobian).
fn worst(
    sim: &Simulation,
    ncoord: usize,
    xs: &[Vec<f64>],
    rhs: &dyn Fn(&[f64], &mut [f64]) -> bool,
    jac: &dyn Fn(&[f64], &mut [f64]) -> bool,
) -> (f64, f64) {
    let m = &sim.model;
    let dim = m.dim();
    let mut blocks = vec![(0.0f64, 0.0f64); 2 + dim];
    let mut track = |b: usize, new: &[f64], reference: &[f64]| {
        for (x, y) in new.iter().zip(reference) {
            blocks[b].0 = blocks[b].0.max((x - y).abs());
            blocks[b].1 = blocks[b].1.max(y.abs());
        }
    };
    for x in xs {
        let (mut de, mut dh) = (vec![0.0; dim], vec![0.0; dim]);
        assert!(m.rhs(1.0, x, &mut de), "engine singular at {x:?}");
        assert!(rhs(x, &mut dh), "hand-written singular at {x:?}");
        track(0, &dh[..ncoord], &de[..ncoord]);
        track(1, &dh[ncoord..], &de[ncoord..]);
        let (mut je, mut jh) = (vec![0.0; dim * dim], vec![0.0; dim * dim]);
        m.jacobian(1.0, x, &mut je);
        assert!(jac(x, &mut jh));
        for row in 0..dim {
            let r = row * dim..(row + 1) * dim;
            track(2 + row, &jh[r.clone()], &je[r]);
        }
    }
    let rel = |b: &(f64, f64)| if b.1 == 0.0 { b.0 } else { b.0 / b.1 };
    let e_rhs = rel(&blocks[0]).max(rel(&blocks[1]));
    let e_jac = blocks[2..].iter().map(rel).fold(0.0, f64::max);
    (e_rhs, e_jac)
}

fn foucault() -> (Simulation, Foucault44Bis) {
    let sc = Scene::load("foucault-azimuth-45n", &SceneOverrides::default()).expect("scene");
    let lat = sc.start_latitude_rad;
    let (sim, _, _) = foucault_release_scene(sc, 90f64.to_radians()).expect("release");
    let hand = Foucault44Bis::from_simulation(&sim, lat).expect("hand-written");
    (sim, hand)
}

fn anschutz(fidelity: Fidelity) -> (Simulation, Anschutz1906) {
    let ov = SceneOverrides {
        fidelity: Some(fidelity),
        ..Default::default()
    };
    let sc = Scene::load("harbour-50n", &ov).expect("scene");
    let sim = Simulation::new(&sc).expect("compiles");
    assert_eq!(sim.model.fidelity, fidelity);
    let hand = Anschutz1906::from_simulation(&sim, sc.start_latitude_rad).expect("hand-written");
    (sim, hand)
}

fn foucault_errors(sim: &Simulation, hand: &Foucault44Bis) -> (f64, f64) {
    let xs = states(&sim.model.x0, 1, 3.0, 0.05, 300);
    let rhs = |x: &[f64], dx: &mut [f64]| {
        hand.rhs(x, dx);
        true
    };
    let jac = |x: &[f64], j: &mut [f64]| {
        hand.jacobian(x, j);
        true
    };
    worst(sim, 1, &xs, &rhs, &jac)
}

fn anschutz_errors(sim: &Simulation, hand: &Anschutz1906) -> (f64, f64) {
    let xs = states(&sim.model.x0, 4, 1.0, 0.1, 300);
    let rhs = |x: &[f64], dx: &mut [f64]| hand.rhs(x, dx);
    let jac = |x: &[f64], j: &mut [f64]| hand.jacobian(x, j);
    worst(sim, 4, &xs, &rhs, &jac)
}

const RHS_TOL: f64 = 1e-12;
const JAC_TOL: f64 = 1e-11;

#[test]
fn villarceau_44_bis_is_the_engine_to_rounding() {
    let (sim, hand) = foucault();
    let (e_rhs, e_jac) = foucault_errors(&sim, &hand);
    println!("foucault: rhs {e_rhs:.1e}, jacobian {e_jac:.1e}");
    assert!(e_rhs < RHS_TOL, "rhs differs by {e_rhs:e}");
    assert!(e_jac < JAC_TOL, "Jacobian differs by {e_jac:e}");
    // Without δ (the ring's A′ − B′ and the torus's A) eq. 44 bis is a plain pendulum: the
    // comparison must see the difference.
    let plain = Foucault44Bis { delta: 0.0, ..hand };
    let (e, _) = foucault_errors(&sim, &plain);
    assert!(e > 1e3 * RHS_TOL, "δ is invisible: {e:e}");
}

#[test]
fn anschutz_gyroscopic_is_the_engine_to_rounding() {
    let (sim, hand) = anschutz(Fidelity::Gyroscopic);
    let (e_rhs, e_jac) = anschutz_errors(&sim, &hand);
    println!("anschutz gyroscopic: rhs {e_rhs:.1e}, jacobian {e_jac:.1e}");
    assert!(e_rhs < RHS_TOL, "rhs differs by {e_rhs:e}");
    assert!(e_jac < JAC_TOL, "Jacobian differs by {e_jac:e}");
    every_term_matters(&sim, &hand);
}

#[test]
fn anschutz_full_is_the_engine_to_rounding() {
    let (sim, hand) = anschutz(Fidelity::Full);
    let (e_rhs, e_jac) = anschutz_errors(&sim, &hand);
    println!("anschutz full: rhs {e_rhs:.1e}, jacobian {e_jac:.1e}");
    assert!(e_rhs < RHS_TOL, "rhs differs by {e_rhs:e}");
    assert!(e_jac < JAC_TOL, "Jacobian differs by {e_jac:e}");
    every_term_matters(&sim, &hand);
}

/// Each term switched off in turn makes the hand-written model disagree with the engine far
/// beyond the tolerance.
fn every_term_matters(sim: &Simulation, hand: &Anschutz1906) {
    type Edit = fn(&mut Anschutz1906);
    let edits: [(&str, Edit); 9] = [
        ("Earth rate", |a| a.frame_rate_rad_per_s = [0.0; 3]),
        ("vertical Earth rate", |a| a.frame_rate_rad_per_s[2] = 0.0),
        ("spin", |a| a.spin_momentum_n_m_s = [0.0; 3]),
        ("air jets", |a| a.jet_force_n = [0.0; 3]),
        ("jets' vane lever", |a| a.jet_point_per_rad_m = [0.0; 3]),
        ("mercury drag on ζ", |a| a.drag_n_m_s_per_rad[0] = 0.0),
        ("vane mass", |a| a.vane_mass_kg = 0.0),
        ("vane inertia", |a| a.vane_inertia_kg_m2 = [[0.0; 3]; 3]),
        ("float's west overload", |a| a.float_cg_m[1] = 0.0),
    ];
    for (what, edit) in edits {
        let mut h = hand.clone();
        edit(&mut h);
        let (e_rhs, e_jac) = anschutz_errors(sim, &h);
        assert!(
            e_rhs.max(e_jac) > 1e3 * RHS_TOL,
            "{}: without the {what} the comparison still passes ({e_rhs:e}, {e_jac:e})",
            hand.fidelity
        );
    }
}
