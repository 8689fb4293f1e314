//! Malformed or out-of-range scenes and designs fail with an error naming the file, the line,
//! the key and what is allowed — never a panic.

use gyro_model::Design;
use gyro_sim::{Scene, SceneOverrides};

fn design_text() -> String {
    crate::support::design_text("anschutz-1906")
}

fn design_error(text: &str) -> gyro_model::InputError {
    match std::panic::catch_unwind(|| Design::from_toml("my-design.toml", text, &[])) {
        Ok(Ok(_)) => panic!("accepted a bad design"),
        Ok(Err(e)) => e,
        Err(_) => panic!("panicked on a bad design"),
    }
}

fn scene_error(text: &str) -> gyro_model::InputError {
    let dir = gyro_testkit::repo_root!().join("scenes");
    match std::panic::catch_unwind(|| {
        Scene::from_toml(
            "my-scene.toml",
            text,
            Some(&dir),
            &SceneOverrides::default(),
        )
    }) {
        Ok(Ok(_)) => panic!("accepted a bad scene"),
        Ok(Err(e)) => e,
        Err(_) => panic!("panicked on a bad scene"),
    }
}

fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .expect("needle")
        + 1
}

#[test]
fn negative_inertia_names_file_line_key_and_range() {
    let text = design_text().replace(
        "inertia_kg_m2 = [0.035, 0.040, 0.045]",
        "inertia_kg_m2 = [-0.035, 0.040, 0.045]",
    );
    let e = design_error(&text);
    assert_eq!(e.file, "my-design.toml");
    assert_eq!(e.key, "body.float.inertia_kg_m2");
    assert_eq!(e.line, Some(line_of(&text, "inertia_kg_m2 = [-0.035")));
    assert!(e.message.contains("≥ 0"), "{e}");
    assert!(
        e.to_string()
            .starts_with(&format!("my-design.toml:{}:", e.line.unwrap_or(0)))
    );
}

#[test]
fn zero_spin_is_refused() {
    let foucault = crate::support::design_text("foucault-gyroscope");
    let text = foucault.replace("spin_rpm = 9000.0", "spin_rpm = 0.0");
    let e = design_error(&text);
    assert_eq!(e.key, "body.torus.rotor.spin_rpm");
    assert!(e.message.contains("non-zero"), "{e}");
    assert_eq!(e.line, Some(line_of(&text, "spin_rpm = 0.0")));
    // Where the spin feeds other numbers, the first number it breaks is named.
    let e = design_error(&design_text().replace("spin_rpm = 20000.0", "spin_rpm = 0.0"));
    assert!(e.key.starts_with("parameters.") && e.line.is_some(), "{e}");
}

#[test]
fn unknown_design_key_is_refused_with_its_line() {
    let text = design_text().replace(
        "mass_kg = \"= float_mass_kg\"",
        "mass_kg = \"= float_mass_kg\"\nmas_kg = 3.0",
    );
    let e = design_error(&text);
    assert_eq!(e.key, "mas_kg");
    assert_eq!(e.line, Some(line_of(&text, "mas_kg = 3.0")));
    assert!(e.message.contains("unknown field"), "{e}");
}

#[test]
fn unknown_names_in_relations_and_expressions_are_refused() {
    let e = design_error(&design_text().replace("angle_rad = \"theta\"", "angle_rad = \"thetta\""));
    assert!(
        e.message.contains("unknown name `thetta`") && e.key == "body.tilt_frame.hinge.angle_rad",
        "{e}"
    );
    let e = design_error(
        &design_text().replace("moving_mass_kg = 9.5", "moving_mass_kg = \"= 9.5 * nope\""),
    );
    assert!(
        e.key == "parameters.moving_mass_kg" && e.message.contains("unknown name `nope`"),
        "{e}"
    );
}

fn scene(lat: &str, extra_sim: &str, program: &str) -> String {
    format!(
        "name = \"x\"\nduration_s = 100.0\n[start]\nlatitude_deg = {lat}\nspeed_kn = 10.0\n[compass]\ndesign = \"anschutz-1906\"\n{program}\n[simulation]\n{extra_sim}\n"
    )
}

/// A value of the wrong type is named by its dotted key and line, though the parser's own
/// message says only what it expected.
#[test]
fn a_value_of_the_wrong_type_names_its_key() {
    let text = scene("50.0", "", "").replace("duration_s = 100.0", "duration_s = \"long\"");
    let e = scene_error(&text);
    assert_eq!(e.key, "duration_s", "{e}");
    assert_eq!(e.line, Some(line_of(&text, "duration_s")), "{e}");
    assert!(e.message.contains("expected f64"), "{e}");
    let text = scene("\"north\"", "", "");
    let e = scene_error(&text);
    assert_eq!(e.key, "start.latitude_deg", "{e}");
    assert_eq!(e.line, Some(line_of(&text, "latitude_deg")), "{e}");
}

#[test]
fn latitude_at_or_beyond_the_pole_is_refused() {
    for lat in ["90.0", "-90.0", "91.5"] {
        let text = scene(lat, "", "");
        let e = scene_error(&text);
        assert_eq!(e.key, "start.latitude_deg");
        assert_eq!(e.line, Some(line_of(&text, "latitude_deg")));
        assert!(e.message.contains("−90 < latitude < 90"), "{e}");
    }
    // A program that steams to the pole is refused too.
    let text = scene(
        "89.0",
        "",
        "[[program]]\nkind = \"steady\"\nduration_s = 100000.0",
    );
    let e = scene_error(&text.replace("duration_s = 100.0", "duration_s = 100000.0"));
    assert!(e.message.contains("pole"), "{e}");
}

#[test]
fn unknown_effect_and_fidelity_are_refused() {
    let text = scene("50.0", "disable_effects = [\"tides\"]", "");
    let e = scene_error(&text);
    assert_eq!(e.key, "simulation.disable_effects");
    assert!(
        e.message.contains("unknown effect `tides`") && e.message.contains("earth_rotation"),
        "{e}"
    );
    let e = scene_error(&scene("50.0", "fidelity = \"exact\"", ""));
    assert!(
        e.message.contains("allowed: full, gyroscopic, linear"),
        "{e}"
    );
    let e = scene_error(&scene("50.0", "integrator = \"euler\"", ""));
    assert!(
        e.message.contains("allowed:") && e.message.contains("rodas4"),
        "{e}"
    );
    // A fixed rk4 step that is not a positive number of seconds is named as such.
    for bad in ["rk4:-1", "rk4:0", "rk4:fast", "rk4:inf"] {
        let e = scene_error(&scene("50.0", &format!("integrator = \"{bad}\""), ""));
        assert!(
            e.message.contains("positive number of seconds") && e.key == "simulation.integrator",
            "{bad}: {e}"
        );
    }
    // Checked when the file loads, though this run is gyroscopic and would never use it.
    let text = scene("50.0", "full_integrator = \"euler\"", "");
    let e = scene_error(&text);
    assert!(
        e.message.contains("rodas4") && e.key == "simulation.full_integrator",
        "{e}"
    );
    assert_eq!(e.line, Some(line_of(&text, "full_integrator")), "{e}");
    // RADAU5's Jacobian-reuse threshold is a contraction factor, in (0, 1).
    for bad in ["0.0", "1.0", "-0.1", "nan"] {
        let text = scene("50.0", &format!("jacobian_reuse_contraction = {bad}"), "");
        let e = scene_error(&text);
        assert_eq!(e.key, "simulation.jacobian_reuse_contraction", "{e}");
        assert_eq!(e.line, Some(line_of(&text, "jacobian_reuse")), "{e}");
        assert!(e.message.contains("0 < value < 1"), "{e}");
    }
    let ok = scene("50.0", "jacobian_reuse_contraction = 0.1", "");
    let dir = gyro_testkit::repo_root!().join("scenes");
    let sc = Scene::from_toml("my-scene.toml", &ok, Some(&dir), &SceneOverrides::default())
        .expect("0.1 is allowed");
    assert_eq!(sc.tolerances.jacobian_reuse_contraction, 0.1);
}

/// `full_integrator` is what a scene runs at `full` fidelity, from the file or the command line;
/// the other fidelities keep `integrator`, and `--integrator` overrides both.
#[test]
fn full_fidelity_runs_the_scenes_full_integrator() {
    use gyro_model::Fidelity;
    use gyro_sim::solvers::Method;
    let load = |ov: SceneOverrides| Scene::load("rolling-intercardinal", &ov).expect("loads");
    assert_eq!(load(SceneOverrides::default()).method, Method::Dop853);
    let full = SceneOverrides {
        fidelity: Some(Fidelity::Full),
        ..Default::default()
    };
    assert_eq!(load(full.clone()).method, Method::Rodas4);
    let asked = SceneOverrides {
        method: Some(Method::Radau5),
        ..full
    };
    assert_eq!(load(asked).method, Method::Radau5);
}

#[test]
fn contradictory_options_are_refused() {
    let text = scene(
        "50.0",
        "",
        "[[program]]\nkind = \"turn\"\nby_deg = 90.0\nrate_deg_per_s = 1.0\nradius_m = 500.0",
    );
    let e = scene_error(&text);
    assert!(e.message.contains("contradictory"), "{e}");
    let text = scene(
        "50.0",
        "",
        "[[program]]\nkind = \"speed_change\"\nto_speed_kn = 0.0\nacceleration_m_per_s2 = 0.1\nduration_s = 60.0",
    );
    let e = scene_error(&text);
    assert!(e.message.contains("contradictory"), "{e}");
}

#[test]
fn unknown_scene_key_and_missing_design_are_refused() {
    let text = scene("50.0", "", "").replace("[start]\n", "[start]\nlatitude = 3\n");
    let e = scene_error(&text);
    assert_eq!(e.line, Some(line_of(&text, "latitude = 3")));
    assert!(e.message.contains("unknown field `latitude`"), "{e}");
    let e = scene_error(&scene("50.0", "", "").replace("anschutz-1906", "no-such-design"));
    assert!(
        e.message.contains("no shipped design") && e.message.contains("anschutz-1906"),
        "{e}"
    );
}

#[test]
fn design_override_of_a_missing_key_names_it() {
    let text = scene("50.0", "", "").replace(
        "[compass]\n",
        "[compass]\ndesign_overrides = { \"body.flaot.mass_kg\" = 3.0 }\n",
    );
    let e = scene_error(&text);
    assert_eq!(e.key, "body.flaot.mass_kg");
    assert!(
        e.message.contains("no entry named `flaot`") && e.message.contains("float"),
        "{e}"
    );
}

fn sperry_text() -> String {
    crate::support::design_text("sperry-1911")
}

/// The Sperry's relations: a contact naming an unknown coordinate, a servo reading itself, a
/// servo naming an unknown coordinate, each refused with file, line and key.
#[test]
fn bad_contact_and_servo_relations_are_refused() {
    let contact = "theta + (zeta - xi) * (alpha - roller_offset_rad) + dial_eta_rad";
    let text = sperry_text().replace(
        contact,
        "theta + (zeta - psi) * (alpha - roller_offset_rad)",
    );
    let e = design_error(&text);
    assert_eq!(e.key, "body.bail.hinge.angle_rad", "{e}");
    assert!(e.message.contains("unknown name `psi`"), "{e}");
    assert_eq!(e.line, Some(line_of(&text, "(zeta - psi)")));

    let text = sperry_text().replace("servo = \"zeta\"", "servo = \"xi\"");
    let e = design_error(&text);
    assert_eq!(e.key, "coordinate.xi.servo", "{e}");
    assert!(e.message.contains("itself servo-driven"), "{e}");
    assert_eq!(e.line, Some(line_of(&text, "servo = \"xi\"")));

    let text = sperry_text().replace("servo = \"zeta\"", "servo = \"zeta_ring\"");
    let e = design_error(&text);
    assert_eq!(e.key, "coordinate.xi.servo", "{e}");
    assert!(e.message.contains("unknown name `zeta_ring`"), "{e}");

    let text = sperry_text().replace("servo = \"zeta\"", "servo = \"zeta * theta\"");
    let e = design_error(&text);
    assert!(e.message.contains("linear"), "{e}");
}

/// A spin reversal the design does not allow: the Anschütz with a negative spin (it would seek
/// South) is refused at the rotor's line; Foucault's torus, reversible in Villarceau, is not.
#[test]
fn spin_reversal_is_refused_unless_the_design_allows_it() {
    let text = design_text().replace(
        r#"spin_rpm = "= spin_rpm", spin = "held""#,
        r#"spin_rpm = "= -spin_rpm", spin = "held""#,
    );
    let e = design_error(&text);
    assert!(e.message.contains("does not allow"), "{e}");
    assert_eq!(e.key, "body.rotor.rotor.spin_rpm", "{e}");
    assert_eq!(e.line, Some(line_of(&text, "= -spin_rpm")));
    let foucault = crate::support::design_text("foucault-gyroscope");
    let reversed = foucault.replace("spin_rpm = 9000.0", "spin_rpm = -9000.0");
    Design::from_toml("foucault.toml", &reversed, &[]).expect("reversible");
}

fn slough_text() -> String {
    crate::support::design_text("slough")
}

/// The Slough's pots: a zero open section, a level that is also a hinge angle, an unknown
/// carrier and pots whose bases coincide, each refused with file, line and key.
#[test]
fn bad_pots_are_refused() {
    let text = slough_text().replace(
        r#"section_m2 = "= pot_open_section_m2""#,
        "section_m2 = 0.0",
    );
    let e = design_error(&text);
    assert_eq!(e.key, "pots.mercury.section_m2", "{e}");
    assert!(e.message.contains("allowed: > 0"), "{e}");
    assert_eq!(e.line, Some(line_of(&text, "section_m2 = 0.0")));

    let text = slough_text().replace(
        r#"hinge = { axis = "z", angle_rad = "xi" }"#,
        r#"hinge = { axis = "z", angle_rad = "xi + u" }"#,
    );
    let e = design_error(&text);
    assert_eq!(e.key, "pots.mercury.level", "{e}");
    assert!(e.message.contains("hinge angle"), "{e}");

    let text = slough_text().replace(r#"body = "pots_frame""#, r#"body = "pot_frame""#);
    let e = design_error(&text);
    assert_eq!(e.key, "pots.mercury.body", "{e}");
    assert!(e.message.contains("unknown body `pot_frame`"), "{e}");
    assert_eq!(e.line, Some(line_of(&text, r#"body = "pot_frame""#)));

    let text = slough_text().replace(
        r#"second_base_m = ["= -pot_half_spacing_m""#,
        r#"second_base_m = ["= pot_half_spacing_m""#,
    );
    let e = design_error(&text);
    assert!(e.message.contains("coincide"), "{e}");
}
