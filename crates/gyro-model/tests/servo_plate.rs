//! Beghin ch. I §17: a plate hinged at C on a turntable that a servo drives so that α − β = π/2.
//! Declared as a servo relation (substituted after the equations are formed), the engine must
//! give M(b² + k²)β″ − MRbβ′² + Fa sin β = 0 (the turntable's inertia plays no part); declared
//! as a rigid contact (substituted into L first), [M(R² + b² + k²) + I₁]β″ + F(a sin β + R cos β) = 0.
//! The force is the plate's weight (F = Mg at its centre of gravity, a = b); angles are measured
//! from the downward vertical in a vertical plane.

use gyro_model::constants::STANDARD_GRAVITY_M_PER_S2 as G;
use gyro_model::{
    CompiledModel, Design, Effects, Fidelity, InitialCondition, ModelOptions, Moored,
};

const M: f64 = 2.0;
const R: f64 = 0.3;
const B: f64 = 0.2;
const K: f64 = 0.1;
const I1: f64 = 0.7;

fn design(servo: bool) -> Design {
    let (coords, table_angle, plate_angle) = if servo {
        (
            "[[coordinate]]\nname = \"alpha\"\nservo = \"beta + pi/2\"\n[[coordinate]]\nname = \"beta\"\n",
            "alpha",
            "beta - alpha",
        )
    } else {
        ("[[coordinate]]\nname = \"beta\"\n", "beta + pi/2", "-pi/2")
    };
    let text = format!(
        r#"name = "plate"
description = "Beghin §17"
root = "earth"
{coords}
[[body]]
name = "turntable"
parent = "base"
joint_rotation = [{{ axis = "y", angle_deg = 90.0 }}]
hinge = {{ axis = "y", angle_rad = "{table_angle}" }}
mass_kg = 5.0
inertia_kg_m2 = [{I1}, {I1}, {I1}]
[[body]]
name = "plate"
parent = "turntable"
joint_origin_m = [{R}, 0.0, 0.0]
hinge = {{ axis = "y", angle_rad = "{plate_angle}" }}
mass_kg = {M}
cg_m = [{B}, 0.0, 0.0]
inertia_kg_m2 = [0.0, {mk2}, {mk2}]
[reading]
body = "plate"
axis = [1.0, 0.0, 0.0]
"#,
        mk2 = M * K * K
    );
    Design::from_toml("plate.toml", &text, &[]).expect("design")
}

fn model(servo: bool) -> CompiledModel<Moored> {
    CompiledModel::compile(
        design(servo),
        Moored {
            latitude_rad: 0.5,
            heading_rad: 0.0,
        },
        ModelOptions {
            fidelity: Fidelity::Full,
            effects: Effects::default(),
            pivot_m: [0.0; 3],
            initial: InitialCondition::default(),
        },
    )
    .expect("compiles")
}

#[test]
fn servo_and_rigid_contact_give_beghins_two_equations() {
    let servo = model(true);
    let rigid = model(false);
    assert_eq!(
        servo.independent.len(),
        1,
        "the driven turntable has no equation of its own"
    );
    let f = M * G;
    let mut worst: f64 = 0.0;
    for k in 0..25 {
        let beta = -2.9 + 0.24 * k as f64;
        for rate in [0.0, 0.8, -2.3] {
            let mut dx = [0.0; 2];
            assert!(servo.rhs(0.0, &[beta, rate], &mut dx));
            // M(b² + k²)β″ − MRbβ′² + F b sin β = 0
            let expect_servo =
                (M * R * B * rate * rate - f * B * beta.sin()) / (M * (B * B + K * K));
            assert!(rigid.rhs(0.0, &[beta, rate], &mut dx.clone()));
            let mut dr = [0.0; 2];
            rigid.rhs(0.0, &[beta, rate], &mut dr);
            // [M(R² + b² + k²) + I₁]β″ + F(b sin β + R cos β) = 0
            let expect_rigid =
                -f * (B * beta.sin() + R * beta.cos()) / (M * (R * R + B * B + K * K) + I1);
            let scale = f * (B + R) / (M * K * K) + rate * rate;
            worst = worst
                .max((dx[1] - expect_servo).abs() / scale)
                .max((dr[1] - expect_rigid).abs() / scale);
        }
    }
    assert!(
        worst < 1e-13,
        "engine vs Beghin §17: worst relative difference {worst:e}"
    );
}

#[test]
fn substituting_the_servo_first_would_be_the_rigid_contact() {
    // The order matters: the turntable's inertia I₁ enters only the rigid equation, and the
    // rate-squared term only the servo one. Check both at one state.
    let servo = model(true);
    let rigid = model(false);
    let (mut a, mut b) = ([0.0; 2], [0.0; 2]);
    servo.rhs(0.0, &[0.4, 1.5], &mut a);
    rigid.rhs(0.0, &[0.4, 1.5], &mut b);
    assert!(
        (a[1] - b[1]).abs() > 1.0,
        "servo {} vs rigid {}",
        a[1],
        b[1]
    );
}
