//! The study file and the run-index map: grids, ranges, seeded draws, design keys, and every
//! kind of bad input refused before any run, naming the file, the line and the key.

use crate::common::{HARBOUR, refused, study};

fn f(v: &toml::Value) -> f64 {
    v.as_float().expect("a number")
}

#[test]
fn grid_index_maps_to_axis_values_slowest_first() {
    let p = study(HARBOUR).expect("the study loads");
    assert_eq!(p.total_runs(), 6);
    assert_eq!(
        p.axis_keys(),
        [
            "duration_s",
            "start.latitude_deg",
            "compass.azimuth_offset_deg"
        ]
    );
    let expect = [
        (30.0, 2.0),
        (30.0, 4.0),
        (30.0, 6.0),
        (50.0, 2.0),
        (50.0, 4.0),
        (50.0, 6.0),
    ];
    for (i, (lat, off)) in expect.iter().enumerate() {
        let r = p.run(i as u64);
        assert_eq!((f(&r.values[1]), f(&r.values[2])), (*lat, *off), "run {i}");
        let scene = p.scene(&r).expect("the run's scene loads");
        assert_eq!(scene.duration_s, 10800.0);
        assert!((scene.start_latitude_rad - lat.to_radians()).abs() < 1e-15);
        assert_eq!(scene.initial.offsets_rad[0].1, off.to_radians());
    }
}

#[test]
fn log_ranges_keep_their_ends_and_ratios() {
    let p = study(
        r#"
name = "log"
scenes = ["harbour-50n"]
[[axis]]
key = "simulation.rtol"
from = 1e-9
to = 1e-5
count = 5
spacing = "log"
"#,
    )
    .expect("loads");
    let v: Vec<f64> = (0..5).map(|i| f(&p.run(i).values[0])).collect();
    assert_eq!(v[0], 1e-9);
    assert_eq!(v[4], 1e-5);
    for w in v.windows(2) {
        assert!((w[1] / w[0] - 10.0).abs() < 1e-9, "{v:?}");
    }
    assert_eq!(p.scene(&p.run(2)).expect("scene").tolerances.rtol, v[2]);
}

const MONTE_CARLO: &str = r#"
name = "mc"
scenes = ["rolling-intercardinal"]
[[axis]]
key = "start.heading_deg"
values = [0.0, 45.0]
[monte_carlo]
samples = 4000
seed = 7
[[random]]
key = "sea.roll_amplitude_deg"
distribution = "uniform"
low = 1.0
high = 5.0
[[random]]
key = "compass.azimuth_offset_deg"
distribution = "normal"
mean = 1.0
std = 2.0
[[random]]
key = "sea.roll_period_s"
distribution = "lognormal"
median = 9.0
sigma_ln = 0.2
"#;

#[test]
fn random_draws_are_reproducible_by_index_and_distributed_as_asked() {
    let p = study(MONTE_CARLO).expect("loads");
    assert_eq!(p.total_runs(), 8000);
    let q = study(MONTE_CARLO).expect("loads");
    // The same index gives the same values, in any order, from another plan.
    for i in [7999, 0, 4321, 17] {
        assert_eq!(p.run(i), q.run(i));
    }
    // Common random numbers: sample s has the same draws at every heading.
    assert_eq!(p.run(5).values[1..], p.run(4005).values[1..]);
    assert_ne!(p.run(5).values[1], p.run(6).values[1]);
    let draws = |k: usize| -> Vec<f64> { (0..4000).map(|i| f(&p.run(i).values[k])).collect() };
    let u = draws(1);
    assert!(u.iter().all(|x| (1.0..5.0).contains(x)));
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let std = |v: &[f64]| {
        let m = mean(v);
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
    };
    // 4000 samples: the mean within 4 standard errors.
    assert!((mean(&u) - 3.0).abs() < 4.0 * (4.0 / 12f64.sqrt()) / 4000f64.sqrt());
    let n = draws(2);
    assert!(
        (mean(&n) - 1.0).abs() < 4.0 * 2.0 / 4000f64.sqrt(),
        "{}",
        mean(&n)
    );
    assert!((std(&n) / 2.0 - 1.0).abs() < 0.05, "{}", std(&n));
    let ln: Vec<f64> = draws(3).iter().map(|x| x.ln()).collect();
    assert!((mean(&ln) - 9f64.ln()).abs() < 4.0 * 0.2 / 4000f64.sqrt());
    assert!((std(&ln) / 0.2 - 1.0).abs() < 0.05);
    // A different seed draws differently.
    let other = study(&MONTE_CARLO.replace("seed = 7", "seed = 8")).expect("loads");
    assert_ne!(other.run(5).values[1], p.run(5).values[1]);
    // The drawn values reach the scene.
    let r = p.run(4005);
    let scene = p.scene(&r).expect("scene");
    assert!((scene.program.sea.roll_amplitude_rad - f(&r.values[1]).to_radians()).abs() < 1e-15);
    assert_eq!(scene.program.sea.roll_period_s, f(&r.values[3]));
}

#[test]
fn design_keys_go_through_the_design_overrides_and_designs_cross() {
    let p = study(
        r#"
name = "designs"
scenes = ["harbour-50n"]
designs = ["anschutz-1906", "sperry-1911"]
[[axis]]
key = "start.latitude_deg"
values = [10.0, 60.0]
"#,
    )
    .expect("loads");
    assert_eq!(p.total_runs(), 4);
    let names: Vec<String> = (0..4)
        .map(|i| p.scene(&p.run(i)).expect("scene").design.name)
        .collect();
    assert_eq!(
        names,
        [
            "anschutz-1906",
            "anschutz-1906",
            "sperry-1911",
            "sperry-1911"
        ]
    );
    // The Sperry's latitude dial follows the run's latitude, as the scene sets it.
    let s = p.scene(&p.run(3)).expect("scene");
    assert_eq!(s.design.parameter("latitude_dial_deg"), Some(60.0));

    let k = study(
        r#"
name = "kappa"
scenes = ["harbour-50n"]
[[axis]]
key = "design.parameters.kappa_n_m"
values = [0.05, 0.1]
"#,
    )
    .expect("loads");
    let a = k.scene(&k.run(0)).expect("scene");
    let b = k.scene(&k.run(1)).expect("scene");
    assert_eq!(a.design.parameter("kappa_n_m"), Some(0.05));
    // Parameters computed from it follow: the jets' force doubles with κ.
    let (fa, fb) = (
        a.design.parameter("jet_force_n").expect("jet_force_n"),
        b.design.parameter("jet_force_n").expect("jet_force_n"),
    );
    assert!((fb / fa - 2.0).abs() < 1e-12);
}

/// The 1-based line of the first line containing `needle` in `text`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .expect("needle")
        + 1
}

#[track_caller]
fn refused_at(text: &str, needle: &str, key: &str, says: &str) {
    let e = refused(text);
    let shown = e.to_string();
    assert!(e.file.ends_with("sweeps/test.toml"), "{shown}");
    assert_eq!(e.line, Some(line_of(text, needle)), "{shown}");
    assert!(e.key.contains(key), "key: {shown}");
    assert!(shown.contains(says), "{shown}");
}

#[test]
fn bad_studies_are_refused_naming_file_line_and_key() {
    let base = "name = \"bad\"\nscenes = [\"harbour-50n\"]\n";
    let axis = |body: &str| format!("{base}\n[[axis]]\n{body}\n");
    // An unknown scene key, and an unknown design key.
    refused_at(
        &axis("key = \"start.heading_degrees\"\nvalues = [0.0, 90.0]"),
        "heading_degrees",
        "start.heading_degrees",
        "unknown key",
    );
    refused_at(
        &axis("key = \"design.parameters.kapa_n_m\"\nvalues = [0.1]"),
        "kapa_n_m",
        "design.parameters.kapa_n_m",
        "unknown key",
    );
    // Empty ranges.
    refused_at(
        &axis("key = \"start.latitude_deg\"\nfrom = 0.0\nto = 60.0\ncount = 0"),
        "count = 0",
        "start.latitude_deg",
        "empty range",
    );
    refused_at(
        &axis("key = \"start.latitude_deg\"\nfrom = 10.0\nto = 10.0\ncount = 4"),
        "to = 10.0",
        "start.latitude_deg",
        "empty range",
    );
    refused_at(
        &axis("key = \"start.latitude_deg\"\nvalues = []"),
        "values = []",
        "start.latitude_deg",
        "empty",
    );
    // Values of the wrong type, mixed types, and out of range.
    refused_at(
        &axis("key = \"start.latitude_deg\"\nvalues = [\"north\"]"),
        "key = ",
        "start.latitude_deg",
        "value \"north\" refused",
    );
    refused_at(
        &axis("key = \"start.latitude_deg\"\nvalues = [10.0,\n \"north\"]"),
        "\"north\"",
        "start.latitude_deg",
        "one type per axis",
    );
    refused_at(
        &axis("key = \"start.latitude_deg\"\nvalues = [10.0, 95.0]"),
        "key = ",
        "start.latitude_deg",
        "value 95.0 refused",
    );
    refused_at(
        &axis("key = \"start.latitude_deg\"\nfrom = 0.0\nto = 60.0\ncount = 3\nspacing = \"log\""),
        "from = 0.0",
        "start.latitude_deg",
        "log range",
    );
    // A random draw out of range (the largest draw is checked).
    refused_at(
        &format!(
            "{base}[monte_carlo]\nsamples = 50\n[[random]]\nkey = \"sea.roll_amplitude_deg\"\ndistribution = \"uniform\"\nlow = 10.0\nhigh = 80.0\n"
        ),
        "key = \"sea",
        "sea.roll_amplitude_deg",
        "refused",
    );
    refused_at(
        &format!(
            "{base}[monte_carlo]\nsamples = 50\n[[random]]\nkey = \"sea.roll_period_s\"\ndistribution = \"gamma\"\n"
        ),
        "gamma",
        "sea.roll_period_s",
        "unknown distribution",
    );
    refused_at(
        &format!(
            "{base}[[random]]\nkey = \"sea.roll_period_s\"\ndistribution = \"uniform\"\nlow = 5.0\nhigh = 15.0\n"
        ),
        "key = \"sea",
        "random",
        "monte_carlo",
    );
    // A typo in the study's own keys, an unknown metric, a bad recordings choice.
    refused_at(
        &axis("keys = \"start.latitude_deg\""),
        "keys",
        "keys",
        "unknown field",
    );
    refused_at(
        &format!("{base}[keep]\nmetrics = [\"period_s\", \"periode_s\"]\n"),
        "metrics",
        "keep.metrics",
        "unknown metric `periode_s`",
    );
    refused_at(
        &format!("{base}[keep]\nrecordings = \"every:0\"\n"),
        "recordings",
        "keep.recordings",
        "every:N",
    );
    // A scene that does not exist.
    refused_at(
        "name = \"bad\"\nscenes = [\"harbour-51n\"]\n",
        "harbour-51n",
        "scenes",
        "no scene `harbour-51n`",
    );
}
