//! The command line as a user meets it: exit codes, JSON output, Ctrl-C, and the regression
//! check against the committed baseline (what CI runs on a small, fast scene set).

use crate::common;
use common::{gyrolab, succeed};

use std::path::{Path, PathBuf};
use std::process::Command;

fn tmp(name: &str) -> PathBuf {
    common::tmp("cli", name)
}

#[test]
fn bad_input_exits_2_with_a_message_naming_the_file() {
    let d = tmp("bad");
    let scene = d.join("s.toml");
    std::fs::write(&scene, "name = \"x\"\nduration_s = 10.0\n[start]\nlatitude_deg = 95.0\n[compass]\ndesign = \"anschutz-1906\"\n").expect("write");
    let out = gyrolab()
        .arg("run")
        .arg(&scene)
        .arg("-o")
        .arg(d.join("x.mcap"))
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("s.toml:4:") && err.contains("latitude_deg"),
        "{err}"
    );
    assert!(
        !d.join("x.mcap").exists() && !d.join("x.mcap.partial").exists(),
        "no output for bad input"
    );
    let out = gyrolab()
        .args(["run", "harbour-50n", "--fidelity", "exact"])
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2));
    let out = gyrolab()
        .args(["run", "harbour-50n", "--jacobian-reuse-contraction", "1.5"])
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--jacobian-reuse-contraction") && err.contains("0 < value < 1"),
        "{err}"
    );
    let out = gyrolab()
        .args(["inspect", "Cargo.toml"])
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2), "a foreign file is bad input");
    // Neither `compare` nor `view` leaves an output behind for a file that is not a recording.
    let junk = d.join("junk.mcap");
    std::fs::write(&junk, b"not an MCAP file").expect("write");
    let plots = d.join("plots");
    let out = gyrolab()
        .args(["compare", "--out"])
        .arg(&plots)
        .arg(&junk)
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("junk.mcap") && err.contains("MCAP magic"),
        "{err}"
    );
    assert!(
        !plots.exists(),
        "compare made {} for bad input",
        plots.display()
    );
    let rrd = d.join("junk.rrd");
    let out = gyrolab()
        .args(["view", "--save"])
        .arg(&rrd)
        .arg(&junk)
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2));
    assert!(
        !rrd.exists() && !d.join("junk.rrd.partial").exists(),
        "view left an .rrd for bad input"
    );
}

/// `-o` naming an existing folder puts the recording in it under the scene's name, rather
/// than running the scene and then failing to rename the recording onto the folder.
#[test]
fn run_into_a_folder_takes_the_scenes_name() {
    let d = tmp("into-folder");
    succeed(
        gyrolab()
            .args(["run", "harbour-50n", "--quiet", "--duration-s", "10", "-o"])
            .arg(&d),
    );
    assert!(d.join("harbour-50n.mcap").is_file());
    assert!(!d.join("harbour-50n.mcap.partial").exists());
}

#[test]
fn run_then_inspect_and_analyze_in_json() {
    let d = tmp("run");
    let file = d.join("h.mcap");
    let out = succeed(
        gyrolab()
            .args(["run", "harbour-50n", "--json", "--duration-s", "7200"])
            .args(["--jacobian-reuse-contraction", "0.1", "-o"])
            .arg(&file),
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(v["jacobian_reuse_contraction"], 0.1);
    assert_eq!(
        v["effects"],
        serde_json::json!(["earth_rotation", "damper", "friction"])
    );
    assert_eq!(v["samples"], 7201);
    let out = gyrolab()
        .args(["inspect", "--json"])
        .arg(&file)
        .output()
        .expect("runs");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let topics: Vec<&str> = v["channels"]
        .as_array()
        .expect("channels")
        .iter()
        .filter_map(|c| c["topic"].as_str())
        .collect();
    for t in [
        "/compass/state",
        "/ship/state",
        "/events",
        "/solver/stats",
        "/tf",
    ] {
        assert!(topics.contains(&t), "{t} missing: {topics:?}");
    }
    succeed(gyrolab().args(["analyze", "--json"]).arg(&file));
}

#[test]
fn ctrl_c_leaves_a_valid_recording_and_exits_130() {
    let d = tmp("int");
    let file = d.join("long.mcap");
    let child = gyrolab()
        .args([
            "run",
            "rolling-intercardinal",
            "--quiet",
            "--duration-s",
            "864000",
            "-o",
        ])
        .arg(&file)
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    // Let it get going (it writes a .partial), then interrupt.
    let partial = PathBuf::from(format!("{}.partial", file.display()));
    for _ in 0..100 {
        if partial.exists() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    std::thread::sleep(std::time::Duration::from_millis(800));
    let ok = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(ok.success());
    let out = child.wait_with_output().expect("wait");
    assert_eq!(out.status.code(), Some(130));
    // It says how far it got.
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains("interrupted at t = ") && said.contains("of 864000.0 s"),
        "{said}"
    );
    assert!(
        file.exists() && !partial.exists(),
        "final file written, partial renamed"
    );
    let rec = gyro_mcap::Recording::open(&file).expect("valid");
    let status = &rec.metadata()["result"]["status"];
    assert!(status.starts_with("interrupted at t = "), "{status}");
    assert!(rec.read_records("/compass/state").expect("state").len() > 1);
}

#[test]
fn regression_check_passes_against_the_committed_baseline() {
    let d = tmp("regress");
    let root = gyro_testkit::repo_root!();
    let out = gyrolab()
        .args(["regress", "--out"])
        .arg(&d)
        .arg("--baseline")
        .arg(root.join("analysis/baseline.toml"))
        .output()
        .expect("runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "regress failed:\n{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn accuracy_study_reports_errors_that_fall_with_the_tolerance_and_plots() {
    let d = tmp("accuracy");
    let plot = d.join("wp.png");
    let out = gyrolab()
        .args([
            "accuracy",
            "villarceau-small",
            "--methods",
            "dop853,rodas4",
            "--json",
            "--plot",
        ])
        .arg(&plot)
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let case = &v["cases"][0];
    assert_eq!(case["name"], "villarceau-small");
    for method in ["dop853", "rodas4"] {
        let errors: Vec<(f64, f64)> = case["points"]
            .as_array()
            .expect("points")
            .iter()
            .filter(|p| p["method"] == method)
            .filter_map(|p| Some((p["rtol"].as_f64()?, p["error"].as_f64()?)))
            .collect();
        assert!(errors.len() >= 5, "{method}: {errors:?}");
        // Ten-fold tighter tolerances, errors at least a hundred times smaller over the range.
        let (loose, tight) = (errors[0], errors[errors.len() - 1]);
        assert!(tight.1 < 1e-2 * loose.1, "{method}: {errors:?}");
        assert!(tight.1 < 1e-7, "{method}: {errors:?}");
    }
    assert!(
        case["verdict"]
            .as_str()
            .is_some_and(|s| s.starts_with("for 1e-6 on villarceau-small, use ")),
        "{}",
        case["verdict"]
    );
    let png = std::fs::read(&plot).expect("plot written");
    assert_eq!(&png[1..4], b"PNG");
    // Bad input is refused before any work: exit 2, naming what is allowed.
    let out = gyrolab()
        .args(["accuracy", "villarceau-tiny"])
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("allowed: villarceau-small"));
    let out = gyrolab()
        .args(["accuracy", "--plot"])
        .arg(d.join("wp.jpg"))
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains(".svg or .png"));
    assert!(!d.join("wp.jpg").exists());
}

#[test]
fn a_design_parameter_moved_by_5_percent_fails_regress_and_names_the_metric() {
    let d = tmp("perturbed");
    let root = gyro_testkit::repo_root!();
    let design = std::fs::read_to_string(root.join("designs/anschutz-1906.toml")).expect("design");
    let original = "pendulous_moment_n_m = \"= 15e6 * 1e-7\"";
    assert!(design.contains(original), "the shipped design changed");
    let perturbed = d.join("anschutz-1906-ap+5.toml");
    std::fs::write(
        &perturbed,
        design.replace(original, "pendulous_moment_n_m = \"= 1.05 * 15e6 * 1e-7\""),
    )
    .expect("write");
    let record = |design: &Path, out: &Path| {
        let o = gyrolab()
            .args(["run", "harbour-50n", "--quiet", "--design"])
            .arg(design)
            .arg("-o")
            .arg(out)
            .output()
            .expect("runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    let (good, bad) = (d.join("good.mcap"), d.join("bad.mcap"));
    record(&root.join("designs/anschutz-1906.toml"), &good);
    record(&perturbed, &bad);
    let regress = |rec: &Path| {
        gyrolab()
            .arg("regress")
            .arg(rec)
            .arg("--baseline")
            .arg(root.join("analysis/baseline.toml"))
            .output()
            .expect("runs")
    };
    let ok = regress(&good);
    assert!(
        ok.status.success(),
        "the unperturbed run passes:\n{}",
        String::from_utf8_lossy(&ok.stdout)
    );
    let out = regress(&bad);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{text}");
    // aP + 5 % shortens the period by ≈ 2.4 %, far outside its 0.1 % tolerance.
    assert!(
        text.contains("period_s") && text.contains("harbour-50n/anschutz-1906"),
        "{text}"
    );
}

/// The README says every command takes `--json`: each subcommand's help lists it.
#[test]
fn every_subcommand_takes_json() {
    let help = String::from_utf8_lossy(&succeed(gyrolab().arg("help")).stdout).into_owned();
    // clap's help lists subcommands under "Commands:", two spaces in, up to the next blank line.
    let subcommands: Vec<String> = help
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter_map(|l| l.split_whitespace().next().map(str::to_owned))
        .filter(|s| s != "help")
        .collect();
    assert!(subcommands.len() >= 10, "{help}");
    for sub in &subcommands {
        let out = succeed(gyrolab().args([sub.as_str(), "--help"]));
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            text.contains("--json"),
            "`gyrolab {sub}` has no --json:\n{text}"
        );
    }
}

#[test]
fn compare_in_json_gives_one_row_per_run_and_the_plots() {
    let d = tmp("compare-json");
    let mut files = Vec::new();
    for (name, stem) in [("harbour-50n", "a"), ("harbour-50n", "b")] {
        let file = d.join(format!("{stem}.mcap"));
        succeed(gyrolab().args(["run", name, "--quiet", "-o"]).arg(&file));
        files.push(file);
    }
    let out = succeed(
        gyrolab()
            .args(["compare", "--json", "--out"])
            .arg(d.join("plots"))
            .args(&files),
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let svg = v["plot_svg"].as_str().expect("plot_svg");
    assert!(Path::new(svg).exists(), "{svg}");
    let rows = v["table"]["rows"].as_array().expect("rows");
    assert_eq!(rows.len(), 2, "{v}");
    for (row, file) in rows.iter().zip(&files) {
        assert_eq!(
            row["path"].as_str(),
            Some(file.to_str().expect("utf-8")),
            "{row}"
        );
        assert_eq!(row["scene"], "harbour-50n", "{row}");
        let period = row["period_s"].as_f64().expect("a fitted period");
        assert!((4000.0..5000.0).contains(&period), "{row}");
    }
}
