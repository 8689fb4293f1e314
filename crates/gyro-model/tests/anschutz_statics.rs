//! Anschütz 1906: the engine's equilibrium and modes against Beghin's closed forms.

use gyro_model::theory::Anschutz;
use gyro_model::{
    CompiledModel, Design, Effects, Fidelity, InitialCondition, ModelOptions, Moored,
};

fn design() -> Design {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../designs/anschutz-1906.toml"
    ))
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

#[test]
fn print_equilibrium_and_modes() {
    for lat in [0.0, 30.0, 50.0, 70.0] {
        let m = model(lat, Fidelity::Full);
        let d = &m.design;
        let th = Anschutz {
            spin_momentum: d.parameter("spin_momentum_n_m_s").expect("present"),
            pendulous_moment: d.parameter("pendulous_moment_n_m").expect("present"),
            kappa: d.parameter("kappa_n_m").expect("present"),
            inertia_vertical: 0.05,
            inertia_east_west: 0.05,
            latitude_rad: lat.to_radians(),
        };
        let mut modes = m.modes();
        modes.sort_by(|a, b| a.1.abs().total_cmp(&b.1.abs()));
        println!("L={lat}: x_eq={:?}", m.x_equilibrium);
        println!("  modes {:?}", modes);
        println!(
            "  theory roots {:?} T0={}",
            th.characteristic_roots(),
            th.undamped_period()
        );
    }
}
