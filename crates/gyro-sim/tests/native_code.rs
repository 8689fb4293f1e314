//! `gyro-model/src/native/generated.rs` is what the generator writes today for the shipped
//! scenes it covers, and those scenes' tapes run as that native code.
//!
//! Regenerate the file after a change to the engine or a shipped design with
//! `GYROLAB_BLESS=1 cargo test --release -p gyro-sim --test integration native_code::`.
//!
//! Native code equals the tape's interpreter to the bit (checked here at random states) and so
//! the engine (`engine_agreement`, which holds what runs to the engine).
//!
//! Covered: every shipped scene at `full` and `gyroscopic`, and the accuracy study's and peer
//! table's Foucault gyroscopes (`accuracy::foucault_release`): right-hand sides for all, and
//! Jacobians for Foucault's gyroscope and the Anschütz 1906 (see `RHS_ONLY`). Other tapes, a
//! user's own design's among them, are interpreted.

use gyro_sim::Simulation;
use gyro_sim::accuracy::foucault_release;

/// Designs whose scenes get native right-hand sides and Jacobians.
const WHOLE: &[&str] = &["foucault-gyroscope", "anschutz-1906"];

/// Designs whose scenes get native right-hand sides only (their Jacobian tapes hold 10k–40k
/// operations each: compiled, they would cost minutes of every cold build).
const RHS_ONLY: &[&str] = &[
    "sperry-1911",
    "slough",
    "sperry-twin-1918",
    "anschutz-three-gyro-1912",
];

/// The covered models, each with whether its Jacobian is native too.
fn covered() -> Vec<(String, Simulation, bool)> {
    let mut sims: Vec<_> = crate::support::shipped_models()
        .into_iter()
        .filter(|(_, design, _)| WHOLE.contains(&&**design) || RHS_ONLY.contains(&&**design))
        .map(|(label, design, sim)| (label, sim, WHOLE.contains(&&*design)))
        .collect();
    // The accuracy study's and the peer table's Foucault gyroscopes (ring axis vertical and
    // horizontal): their own designs, not shipped files.
    for elevation_deg in [90.0, 0.0] {
        let (sim, _, _) = foucault_release(elevation_deg, 1.0).expect("compiles");
        sims.push((format!("foucault_release({elevation_deg})"), sim, true));
    }
    sims
}

#[test]
fn generated_native_code_is_current_and_runs() {
    let sims = covered();
    assert!(sims.len() >= 20, "only {} covered models", sims.len());
    let models: Vec<_> = sims.iter().map(|(_, s, j)| (&s.model, *j)).collect();
    let source = gyro_model::native_source(&models);
    let checked_in = include_str!("../../gyro-model/src/native/generated.rs");
    if std::env::var_os("GYROLAB_BLESS").is_some() {
        let path = gyro_testkit::manifest_dir!().join("../gyro-model/src/native/generated.rs");
        std::fs::write(&path, &source).expect("writes generated.rs");
        eprintln!("wrote {}; build again to use it", path.display());
        return;
    }
    assert!(
        source == checked_in,
        "gyro-model/src/native/generated.rs is stale: regenerate it with \
         GYROLAB_BLESS=1 cargo test --release -p gyro-sim --test integration native_code::"
    );
    let mut rng = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for (label, sim, jacobian) in &sims {
        // Native code and the interpreter agree to the bit away from the start (the engine
        // agreement tests hold what runs, the native code, to the engine the same way).
        let model = &sim.model;
        let dim = model.dim();
        for k in 0..8 {
            let x: Vec<f64> = model.x0.iter().map(|v| v + 0.3 * next()).collect();
            let t = 37.0 * k as f64;
            let (mut native, mut interpreted) = (vec![0.0; dim], vec![0.0; dim]);
            assert_eq!(
                model.rhs_tape(t, &x, &mut native),
                model.rhs_tape_interpreted(t, &x, &mut interpreted)
            );
            for (a, b) in native.iter().zip(&interpreted) {
                assert_eq!(a.to_bits(), b.to_bits(), "{label}: native {a:e} vs {b:e}");
            }
        }
        let rhs = sim.model.tape_size(sim.model.fidelity).expect("recorded");
        assert!(
            rhs.native && rhs.used,
            "{label}: right-hand side not native ({rhs:?})"
        );
        if *jacobian {
            let jac = sim.model.jacobian_tape_size().expect("recorded");
            assert!(
                jac.native && jac.used,
                "{label}: Jacobian not native ({jac:?})"
            );
        }
    }
}
