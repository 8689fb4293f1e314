//! A fixed number of right-hand sides (or Jacobians) of a shipped design moored at 50°N, for
//! counting instructions and cycles with `perf stat`, which busy machines disturb far less than
//! wall time:
//!
//! `cargo bench -p gyro-model --bench rhs_loop -- anschutz-1906 full rhs 1000000`, or under
//! `perf stat -e instructions:u,cycles:u` on the executable `cargo bench -p gyro-model --bench
//! rhs_loop --no-run` names (a bench target, so `cargo test` does not build it).

use gyro_model::{
    BaseEffects, CompiledModel, Design, Effects, Fidelity, InitialCondition, ModelOptions, Moored,
};
use std::hint::black_box;

fn main() {
    // `cargo bench` appends `--bench`; the tool takes positional arguments only.
    let args: Vec<String> = std::env::args().filter(|a| a != "--bench").collect();
    if args.len() != 5 {
        eprintln!("usage: rhs_loop DESIGN full|gyroscopic rhs|jacobian COUNT");
        std::process::exit(2);
    }
    let name = &args[1];
    let fidelity = match args[2].as_str() {
        "full" => Fidelity::Full,
        "gyroscopic" => Fidelity::Gyroscopic,
        other => {
            eprintln!("unknown fidelity {other:?} (allowed: full, gyroscopic)");
            std::process::exit(2);
        }
    };
    let count: u64 = match args[4].parse() {
        Ok(c) => c,
        Err(_) => {
            eprintln!("COUNT must be a whole number, got {:?}", args[4]);
            std::process::exit(2);
        }
    };
    let path = gyro_testkit::repo_root!()
        .join(format!("designs/{name}.toml"))
        .display()
        .to_string();
    let design = std::fs::read_to_string(&path)
        .map_err(|e| format!("{path}: {e}"))
        .and_then(|t| Design::from_toml(&path, &t, &[]).map_err(|e| e.to_string()));
    let design = match design {
        Ok(d) => d,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let mut effects = Effects::all();
    effects.base = BaseEffects {
        earth_rotation: true,
        ..Default::default()
    };
    let model = CompiledModel::compile(
        design,
        Moored {
            latitude_rad: 50f64.to_radians(),
            heading_rad: 0.0,
        },
        ModelOptions {
            fidelity,
            effects,
            pivot_m: [0.0; 3],
            initial: InitialCondition {
                from_equilibrium: true,
                offsets_rad: vec![(0, 0.1)],
                ..Default::default()
            },
        },
    );
    let m = match model {
        Ok(m) => m,
        Err(e) => {
            eprintln!("{name}: {e}");
            std::process::exit(1);
        }
    };
    let x = m.x0.clone();
    let dim = x.len();
    let mut dx = vec![0.0; dim];
    let mut jac = vec![0.0; dim * dim];
    let start = std::time::Instant::now();
    match args[3].as_str() {
        "rhs" => {
            for _ in 0..count {
                black_box(m.rhs(black_box(1.0), black_box(&x), &mut dx));
            }
        }
        "jacobian" => {
            for _ in 0..count {
                m.jacobian(black_box(1.0), black_box(&x), &mut jac);
                black_box(&jac);
            }
        }
        other => {
            eprintln!("unknown operation {other:?} (allowed: rhs, jacobian)");
            std::process::exit(2);
        }
    }
    let per = start.elapsed().as_secs_f64() / count as f64;
    println!(
        "{name} {fidelity} {}: {:.1} ns each (wall)",
        args[3],
        per * 1e9
    );
}
