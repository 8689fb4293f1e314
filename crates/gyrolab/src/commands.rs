//! The subcommands: each turns arguments into calls on the library crates and prints the result.

use clap::Args;
use gyro_analysis::table::{Align, Table};
use gyro_mcap::contract::{compass_state, design_constants_record, status};
use gyro_model::Fidelity;
use gyro_sim::solvers::Method;
use gyro_sim::{RecordOptions, Scene, SceneOverrides};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// An error with its exit code.
pub struct CliError {
    pub code: u8,
    pub message: String,
}

pub const BAD_INPUT: u8 = 2;
pub const FAILED: u8 = 1;
pub const INTERRUPTED: u8 = 130;

fn bad(m: impl std::fmt::Display) -> CliError {
    CliError {
        code: BAD_INPUT,
        message: m.to_string(),
    }
}
fn failed(m: impl std::fmt::Display) -> CliError {
    CliError {
        code: FAILED,
        message: m.to_string(),
    }
}

#[derive(Args)]
pub struct RunArgs {
    /// Scene file, or the name of a shipped scene (see `gyrolab scenes`).
    pub scene: String,
    /// Design file or shipped design name, replacing the scene's.
    #[arg(long)]
    pub design: Option<String>,
    /// Output file (default: recordings/<scene>.mcap); an existing folder gets
    /// <folder>/<scene>.mcap.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// full, gyroscopic or linear.
    #[arg(long)]
    pub fidelity: Option<String>,
    /// dopri5, dop853, vern9, rk4[:step_s], rodas4, rodas5p or radau5.
    #[arg(long)]
    pub integrator: Option<String>,
    #[arg(long)]
    pub rtol: Option<f64>,
    #[arg(long)]
    pub atol: Option<f64>,
    /// RADAU5 keeps its Jacobian while its Newton iteration contracts by at most this per
    /// iteration (0 < value < 1; default 0.001, or the scene's; ≈ 0.1 where Jacobians are dear).
    #[arg(long)]
    pub jacobian_reuse_contraction: Option<f64>,
    /// Output rate, Hz.
    #[arg(long)]
    pub rate_hz: Option<f64>,
    /// Duration, s (replacing the scene's).
    #[arg(long)]
    pub duration_s: Option<f64>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

fn overrides(a: &RunArgs) -> Result<SceneOverrides, CliError> {
    let fidelity = match &a.fidelity {
        Some(f) => Some(
            f.parse::<Fidelity>()
                .map_err(|e| bad(format!("--fidelity: {e}")))?,
        ),
        None => None,
    };
    let method = match &a.integrator {
        Some(m) => Some(
            m.parse::<Method>()
                .map_err(|e| bad(format!("--integrator: {e}")))?,
        ),
        None => None,
    };
    for (name, v) in [
        ("--rtol", a.rtol),
        ("--atol", a.atol),
        ("--rate-hz", a.rate_hz),
        ("--duration-s", a.duration_s),
    ] {
        if let Some(x) = v
            && !(x > 0.0 && x.is_finite())
        {
            return Err(bad(format!(
                "{name}: {x} is out of range (allowed: a positive number)"
            )));
        }
    }
    if let Some(x) = a.jacobian_reuse_contraction
        && !(x > 0.0 && x < 1.0)
    {
        return Err(bad(format!(
            "--jacobian-reuse-contraction: {x} is out of range (allowed: 0 < value < 1)"
        )));
    }
    Ok(SceneOverrides {
        design: a.design.clone(),
        fidelity,
        method,
        rtol: a.rtol,
        atol: a.atol,
        jacobian_reuse_contraction: a.jacobian_reuse_contraction,
        output_rate_hz: a.rate_hz,
        duration_s: a.duration_s,
    })
}

pub fn run(a: RunArgs) -> Result<ExitCode, CliError> {
    let scene = Scene::load(&a.scene, &overrides(&a)?).map_err(bad)?;
    let file_name = format!("{}.mcap", scene.name);
    // A folder given as the output takes the default file name, as `cp` would; found out
    // before the run, not when its recording is renamed onto the folder at the end.
    let out = match a.output.clone() {
        Some(o) if o.is_dir() => o.join(file_name),
        Some(o) => o,
        None => PathBuf::from("recordings").join(file_name),
    };
    let summary = record_scene(&scene, &out, a.quiet || a.json)?;
    print_summary(&summary, &scene, a.json);
    Ok(if summary.interrupted_at_s.is_some() {
        ExitCode::from(INTERRUPTED)
    } else {
        ExitCode::SUCCESS
    })
}

fn record_scene(
    scene: &Scene,
    out: &Path,
    quiet: bool,
) -> Result<gyro_sim::RecordSummary, CliError> {
    if let Some(dir) = out.parent()
        && !dir.as_os_str().is_empty()
    {
        std::fs::create_dir_all(dir)
            .map_err(|e| failed(format!("cannot create {}: {e}", dir.display())))?;
    }
    let interrupt = Arc::new(AtomicBool::new(false));
    {
        let i = interrupt.clone();
        // A second handler registration fails (e.g. in the demo's second run): keep the first.
        let _ = ctrlc::set_handler(move || i.store(true, Ordering::Relaxed));
    }
    let bar = if quiet {
        None
    } else {
        let b = indicatif::ProgressBar::new(scene.duration_s.ceil() as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{msg} [{bar:40}] {pos}/{len} s simulated ({eta} left)",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b.set_message(scene.name.clone());
        // Only show it for runs that take more than a second.
        b.set_draw_target(indicatif::ProgressDrawTarget::hidden());
        Some(b)
    };
    let started = std::time::Instant::now();
    let mut progress = |t: f64| {
        if let Some(b) = &bar {
            if started.elapsed().as_secs_f64() > 1.0 && b.is_hidden() {
                b.set_draw_target(indicatif::ProgressDrawTarget::stderr());
            }
            b.set_position(t as u64);
        }
    };
    let summary = gyro_sim::record(
        scene,
        out,
        RecordOptions {
            interrupt: Some(interrupt),
            progress: Some(&mut progress),
            writer: Default::default(),
        },
    );
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    summary.map_err(|e| match e {
        gyro_sim::RunError::Model(m) => bad(format!("{}: {m}", scene.source_path)),
        other => failed(format!(
            "{}: {other} (a partial recording may be left as {}.partial: see `gyrolab recover`)",
            scene.source_path,
            out.display()
        )),
    })
}

fn print_summary(s: &gyro_sim::RecordSummary, scene: &Scene, json: bool) {
    let st = &s.stats.solver;
    if json {
        let v = json!({
            "scene": scene.name,
            "design": scene.design.name,
            "path": s.path,
            "bytes": s.bytes,
            "messages": s.messages,
            "samples": s.stats.samples,
            "effects": s.effects,
            "fidelity": scene.fidelity.to_string(),
            "integrator": scene.method.to_string(),
            "rtol": scene.tolerances.rtol,
            "atol": scene.tolerances.atol,
            "jacobian_reuse_contraction": scene.tolerances.jacobian_reuse_contraction,
            "steps": st.steps,
            "rejected_steps": st.rejected_steps,
            "rhs_evals": st.rhs_evals,
            "jacobian_evals": st.jacobian_evals,
            "integration_wall_time_s": st.wall_time_s,
            "wall_time_s": s.wall_time_s,
            "rhs_cost_ns": s.rhs_cost_ns,
            "interrupted_at_s": s.interrupted_at_s,
        });
        println!("{v}");
        return;
    }
    if let Some(t) = s.interrupted_at_s {
        println!(
            "{}{t:.1} s of {:.1} s; the recording is closed and valid",
            status::INTERRUPTED_PREFIX,
            scene.duration_s
        );
    }
    println!(
        "{} — {} on {} ({}, {} rtol {:e})",
        s.path.display(),
        scene.design.name,
        scene.name,
        scene.fidelity,
        scene.method,
        scene.tolerances.rtol
    );
    println!("  effects:  {}", s.effects.join(", "));
    println!(
        "  solver:   {} steps ({} rejected), {} rhs, {} jacobians; rhs {:.0} ns",
        st.steps, st.rejected_steps, st.rhs_evals, st.jacobian_evals, s.rhs_cost_ns
    );
    println!(
        "  time:     {:.3} s integrating, {:.3} s in all",
        st.wall_time_s, s.wall_time_s
    );
    println!(
        "  file:     {:.2} MB, {} messages, {} samples",
        s.bytes as f64 / 1e6,
        s.messages,
        s.stats.samples
    );
}

/// The demo: a few shipped scenes recorded, with what each shows.
pub fn demo(out: &Path, json: bool) -> Result<ExitCode, CliError> {
    let scenes = [
        "foucault-azimuth-45n",
        "harbour-50n",
        "run-north-30kn",
        "speed-change-20kn",
        "sperry-harbour-35n",
        "sperry-speed-change-20kn",
        "slough-harbour-35n",
        "slough-speed-change-20kn",
        "twin-harbour-35n",
        "twin-speed-change-20kn",
        "three-gyro-harbour-35n",
        "three-gyro-speed-change-20kn",
    ];
    let mut rows = Vec::new();
    let mut lines = Table::new(&[
        "scene",
        "MB",
        "steps",
        "wall s",
        "max |error|",
        "error at end",
        "end s",
        "slow mode s",
    ])
    .numbers_right();
    for name in scenes {
        let scene = Scene::load(name, &SceneOverrides::default()).map_err(bad)?;
        let path = out.join(format!("{name}.mcap"));
        let s = record_scene(&scene, &path, true)?;
        let rec = gyro_mcap::Recording::open(&s.path).map_err(failed)?;
        let table = rec.read_records(compass_state::TOPIC).map_err(failed)?;
        let err = table
            .column(compass_state::READING_ERROR_RAD)
            .and_then(|c| c.as_f64())
            .map(|v| v.to_vec())
            .unwrap_or_default();
        let t = table
            .column(compass_state::TIME_S)
            .and_then(|c| c.as_f64())
            .map(|v| v.to_vec())
            .unwrap_or_default();
        let last = err.last().copied().unwrap_or(f64::NAN);
        let max = err.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let dc = rec
            .metadata()
            .get(design_constants_record::NAME)
            .cloned()
            .unwrap_or_default();
        let period = dc
            .get(design_constants_record::MODE_PERIOD_S)
            .cloned()
            .unwrap_or_default();
        let tend = t.last().copied().unwrap_or(0.0);
        lines.row([
            name.to_string(),
            format!("{:.2}", s.bytes as f64 / 1e6),
            s.stats.solver.steps.to_string(),
            format!("{:.3}", s.wall_time_s),
            format!("{:.3}°", max.to_degrees()),
            format!("{:.3}°", last.to_degrees()),
            format!("{tend:.0}"),
            period.split('.').next().unwrap_or("-").to_string(),
        ]);
        rows.push((name, s, last, max, period));
    }
    if json {
        let v: Vec<_> = rows
            .iter()
            .map(|(n, s, last, max, period)| json!({"scene": n, "path": s.path, "bytes": s.bytes, "steps": s.stats.solver.steps, "wall_time_s": s.wall_time_s, "final_reading_error_deg": last.to_degrees(), "max_reading_error_deg": max.to_degrees(), "mode_period_s": period}))
            .collect();
        println!("{}", serde_json::Value::Array(v));
    } else {
        print!("{}", lines.render());
        println!(
            "recordings are in {}/ (open one with `gyrolab inspect`)",
            out.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}

pub fn recover(partial: &Path, output: Option<PathBuf>, json: bool) -> Result<ExitCode, CliError> {
    let out = output.unwrap_or_else(|| {
        let s = partial.to_string_lossy();
        PathBuf::from(
            s.strip_suffix(".partial")
                .map(str::to_string)
                .unwrap_or_else(|| format!("{s}.recovered.mcap")),
        )
    });
    let r = gyro_mcap::recover(partial, &out).map_err(bad)?;
    if json {
        println!(
            "{}",
            json!({"out": r.out, "messages": r.messages, "chunks": r.chunks, "bytes_dropped": r.bytes_dropped, "stopped_because": r.stopped_because})
        );
    } else {
        println!(
            "{}: {} messages in {} chunks recovered ({} bytes after the last whole chunk dropped)",
            r.out.display(),
            r.messages,
            r.chunks,
            r.bytes_dropped
        );
        if let Some(why) = r.stopped_because {
            println!("  stopped because: {why}");
        }
        println!("  {} is left as it was", partial.display());
    }
    Ok(ExitCode::SUCCESS)
}

pub fn list(items: &[(&str, &str)], what: &str, json: bool) -> Result<ExitCode, CliError> {
    if json {
        let v: Vec<_> = items
            .iter()
            .map(|(n, t)| json!({"name": n, "description": gyro_sim::library::describe(t)}))
            .collect();
        println!("{}", serde_json::Value::Array(v));
    } else {
        println!("shipped {what}:");
        let mut table = Table::headless(2).indent("  ");
        for (n, t) in items {
            table.row([n.to_string(), gyro_sim::library::describe(t)]);
        }
        print!("{}", table.render());
    }
    Ok(ExitCode::SUCCESS)
}

pub fn inspect(path: &Path, json: bool) -> Result<ExitCode, CliError> {
    let rec = gyro_mcap::Recording::open(path).map_err(bad)?;
    let chans = rec.channels();
    if json {
        let c: Vec<_> = chans
            .iter()
            .map(|c| json!({"topic": c.topic, "schema": c.schema_name, "encoding": c.message_encoding, "messages": c.message_count, "first_s": c.first_log_time_ns.map(|t| t as f64 * 1e-9), "last_s": c.last_log_time_ns.map(|t| t as f64 * 1e-9), "fields": c.field_names}))
            .collect();
        let md: serde_json::Map<String, serde_json::Value> = rec
            .metadata()
            .iter()
            .map(|(k, v)| {
                (
                    k.clone(),
                    json!(
                        v.iter()
                            .filter(|(kk, _)| kk.as_str() != "toml")
                            .collect::<std::collections::BTreeMap<_, _>>()
                    ),
                )
            })
            .collect();
        let att: Vec<_> = rec
            .attachments()
            .iter()
            .map(|a| json!({"name": a.name, "media_type": a.media_type, "bytes": a.data.len()}))
            .collect();
        println!(
            "{}",
            json!({"path": path, "channels": c, "metadata": md, "attachments": att})
        );
        return Ok(ExitCode::SUCCESS);
    }
    println!("{}", path.display());
    println!("channels:");
    let mut table = Table::headless(4).indent("  ").align(2, Align::Right);
    for c in &chans {
        let range = match (c.first_log_time_ns, c.last_log_time_ns) {
            (Some(a), Some(b)) => format!("{:.3} … {:.3} s", a as f64 * 1e-9, b as f64 * 1e-9),
            _ => "-".into(),
        };
        table.row([
            c.topic.clone(),
            c.schema_name.clone(),
            format!("{} msgs", c.message_count),
            range,
        ]);
    }
    print!("{}", table.render());
    println!("metadata:");
    for (name, m) in rec.metadata() {
        let keys: Vec<String> = m
            .iter()
            .filter(|(k, _)| k.as_str() != "toml")
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        println!("  {name}: {}", keys.join(", "));
    }
    for a in rec.attachments() {
        println!(
            "attachment: {} ({}, {} bytes)",
            a.name,
            a.media_type,
            a.data.len()
        );
    }
    Ok(ExitCode::SUCCESS)
}

pub fn analyze(runs: &[String], json: bool, table: Option<&Path>) -> Result<ExitCode, CliError> {
    if json {
        let all =
            gyro_analysis::metrics::analyze_all(runs, &gyro_analysis::AnalysisOptions::default())
                .map_err(bad)?;
        println!("{}", serde_json::to_string_pretty(&all).map_err(failed)?);
    } else {
        let t = gyro_analysis::analyze_runs(runs).map_err(bad)?;
        println!("{}", t.render_text());
        if let Some(stem) = table {
            for p in t.write_all(stem).map_err(failed)? {
                println!("wrote {}", p.display());
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}

pub fn compare(
    runs: &[String],
    out: &Path,
    markdown: bool,
    json: bool,
) -> Result<ExitCode, CliError> {
    // The plots' folder is made only once every run has been read (`write_plots`), so a bad
    // input leaves nothing behind.
    let r = gyro_analysis::compare(runs, out).map_err(bad)?;
    if json {
        // The metrics table (one row per run) and the plots' paths.
        println!("{}", serde_json::to_string_pretty(&r).map_err(failed)?);
        return Ok(ExitCode::SUCCESS);
    }
    println!(
        "{}",
        if markdown {
            r.render_markdown()
        } else {
            r.render_terminal()
        }
    );
    println!("plots: {}/reading_error.svg and .png", out.display());
    Ok(ExitCode::SUCCESS)
}

/// The baseline scene set: small and fast, covering settling, speed error, a speed change and
/// the exact Foucault reference, for every compass that has them.
pub const REGRESS_SCENES: [&str; 12] = [
    "foucault-azimuth-45n",
    "harbour-50n",
    "run-north-30kn",
    "speed-change-20kn",
    "sperry-harbour-35n",
    "sperry-speed-change-20kn",
    "slough-harbour-35n",
    "slough-speed-change-20kn",
    "twin-harbour-35n",
    "twin-speed-change-20kn",
    "three-gyro-harbour-35n",
    "three-gyro-speed-change-20kn",
];

pub fn regress(
    runs: &[String],
    baseline: &Path,
    update: bool,
    out: &Path,
    json: bool,
) -> Result<ExitCode, CliError> {
    let paths: Vec<String> = if runs.is_empty() {
        let mut v = Vec::new();
        for name in REGRESS_SCENES {
            let scene = Scene::load(name, &SceneOverrides::default()).map_err(bad)?;
            let path = out.join(format!("{name}.mcap"));
            record_scene(&scene, &path, true)?;
            v.push(path.display().to_string());
        }
        v
    } else {
        runs.to_vec()
    };
    let table = gyro_analysis::analyze_runs(&paths).map_err(bad)?;
    if update {
        gyro_analysis::update_baseline(&table, baseline, None).map_err(failed)?;
        println!(
            "baseline {} rewritten from {} runs: review the diff before committing",
            baseline.display(),
            paths.len()
        );
        return Ok(ExitCode::SUCCESS);
    }
    let mut report = gyro_analysis::regress(&table, baseline, None).map_err(bad)?;
    // Recordings named on the command line are checked alone: the baseline's other runs are
    // not missing, just not asked about.
    let mut unchecked = Vec::new();
    if !runs.is_empty() {
        report.findings.retain(|f| {
            let missing = f.status == gyro_analysis::regress::Status::MissingRun;
            if missing {
                unchecked.push(f.run.clone());
            }
            !missing
        });
    }
    if json {
        println!("{}", serde_json::to_string_pretty(&report).map_err(failed)?);
    } else {
        print!("{}", report.render_terminal());
        if !unchecked.is_empty() {
            println!(
                "not checked (no recording of them given): {}",
                unchecked.join(", ")
            );
        }
    }
    Ok(if report.passed() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(FAILED)
    })
}

pub fn view(
    runs: &[PathBuf],
    save: Option<PathBuf>,
    connect: Option<String>,
    tilt_exaggeration: f64,
    json: bool,
) -> Result<ExitCode, CliError> {
    if !(tilt_exaggeration >= 1.0 && tilt_exaggeration.is_finite()) {
        return Err(bad(format!(
            "--tilt-exaggeration: {tilt_exaggeration} is out of range (allowed: ≥ 1)"
        )));
    }
    let sink = match (save, connect) {
        (Some(p), _) => gyro_view::Sink::Save(p),
        (None, Some(url)) => gyro_view::Sink::Connect(url),
        (None, None) => gyro_view::Sink::Spawn,
    };
    let opts = gyro_view::ViewOptions {
        sink,
        tilt_exaggeration,
        ..Default::default()
    };
    let report = gyro_view::view(runs, &opts).map_err(bad)?;
    let (where_, bytes) = match &report.output {
        gyro_view::Output::Saved { path, bytes } => (
            format!(
                "saved {} — open it with `rerun {}`",
                path.display(),
                path.display()
            ),
            Some(*bytes),
        ),
        gyro_view::Output::Spawned => ("sent to a new Rerun viewer".to_string(), None),
        gyro_view::Output::Connected { url } => (format!("sent to {url}"), None),
    };
    if json {
        let runs: Vec<_> = report.runs.iter().map(|r| json!({"path": r.path, "entity": r.entity, "samples": r.samples, "frames": r.frames})).collect();
        println!(
            "{}",
            json!({"output": where_, "bytes": bytes, "runs": runs, "notes": report.notes, "elapsed_s": report.elapsed_s})
        );
    } else {
        for r in &report.runs {
            println!(
                "{} → {}: {} samples, {} bodies",
                r.path.display(),
                r.entity,
                r.samples,
                r.frames.len()
            );
        }
        for n in &report.notes {
            println!("note: {n}");
        }
        println!("{where_} ({:.2} s)", report.elapsed_s);
    }
    Ok(ExitCode::SUCCESS)
}

/// What `gyrolab accuracy` runs.
pub struct AccuracyArgs {
    pub cases: Vec<String>,
    pub json: bool,
    pub plot: Option<PathBuf>,
    pub target_error: Option<f64>,
    pub methods: Vec<String>,
    pub list: bool,
}

pub fn accuracy(a: AccuracyArgs) -> Result<ExitCode, CliError> {
    use gyro_sim::accuracy::{StudyOptions, case_descriptions, run_study};
    if a.list {
        let cases = case_descriptions();
        if a.json {
            let v: Vec<_> = cases
                .iter()
                .map(|(n, d)| json!({"name": n, "description": d}))
                .collect();
            println!("{}", serde_json::Value::Array(v));
        } else {
            let mut table = Table::headless(2);
            for (n, d) in cases {
                table.row([n.to_string(), d.to_string()]);
            }
            print!("{}", table.render());
        }
        return Ok(ExitCode::SUCCESS);
    }
    let mut opts = StudyOptions::default();
    if let Some(e) = a.target_error {
        if !(e > 0.0 && e < 1.0) {
            return Err(bad(format!(
                "--target-error: {e} is out of range (allowed: 0 < error < 1)"
            )));
        }
        opts.target_error = e;
    }
    if !a.methods.is_empty() {
        opts.methods = a
            .methods
            .iter()
            .map(|m| {
                m.parse::<Method>()
                    .map_err(|e| bad(format!("--methods: {e}")))
            })
            .collect::<Result<_, _>>()?;
    }
    // Check the plot's extension before spending a minute on the study.
    let plot_kind = match &a.plot {
        None => None,
        Some(p) => match p.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("svg") => Some(false),
            Some(e) if e.eq_ignore_ascii_case("png") => Some(true),
            _ => {
                return Err(bad(format!(
                    "--plot {}: unknown image type (allowed: .svg or .png)",
                    p.display()
                )));
            }
        },
    };
    let report = run_study(&a.cases, &opts).map_err(|e| match e {
        gyro_sim::accuracy::StudyError::UnknownCase(_) => bad(e),
        _ => failed(e),
    })?;
    if let (Some(path), Some(png)) = (&a.plot, plot_kind) {
        let figures = accuracy_figures(&report);
        let bytes = if png {
            gyro_analysis::plot::Figure::grid_png(&figures, 2)
                .map_err(|e| failed(format!("{}: encoding PNG: {e}", path.display())))?
        } else {
            gyro_analysis::plot::Figure::grid_svg(&figures, 2).into_bytes()
        };
        write_whole(path, &bytes)?;
    }
    if a.json {
        println!("{}", report.to_json());
    } else {
        print!("{}", report.table());
        if let Some(p) = &a.plot {
            println!("plot: {}", p.display());
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Writes `bytes` to `path` through a temporary name, so a failure never leaves half a file
/// under the final name.
fn write_whole(path: &Path, bytes: &[u8]) -> Result<(), CliError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| failed(format!("cannot create {}: {e}", dir.display())))?;
    }
    gyro_analysis::file::write_bytes(path, bytes).map_err(|e| failed(format!("cannot write {e}")))
}

/// One log-log panel per case: achieved error against wall time, one curve per method (per
/// method and fidelity where the case has several), and the target error dashed.
fn accuracy_figures(r: &gyro_sim::accuracy::StudyReport) -> Vec<gyro_analysis::plot::Figure> {
    use gyro_analysis::plot::{Figure, PALETTE, Series};
    let mut colours: Vec<String> = Vec::new();
    let mut figures = Vec::new();
    for c in &r.cases {
        let several = c.points.iter().any(|p| p.fidelity != c.points[0].fidelity);
        let mut f = Figure::new(&c.name, "wall time [s]", "achieved error");
        (f.width_px, f.height_px) = (1040, 560);
        (f.log_x, f.log_y) = (true, true);
        let mut curves: Vec<String> = Vec::new();
        for p in &c.points {
            let k = p.curve(several).replace("gyroscopic", "gyro");
            if !curves.contains(&k) {
                curves.push(k);
            }
        }
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        for k in curves {
            let mut pts: Vec<(f64, f64)> = c
                .points
                .iter()
                .filter(|p| p.curve(several).replace("gyroscopic", "gyro") == k)
                .filter_map(|p| p.error.filter(|e| *e > 0.0).map(|e| (p.wall_s, e)))
                .collect();
            if pts.is_empty() {
                continue;
            }
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            lo = pts.iter().fold(lo, |m, p| m.min(p.0));
            hi = pts.iter().fold(hi, |m, p| m.max(p.0));
            // The same colour for a curve in every panel.
            let i = colours.iter().position(|n| *n == k).unwrap_or_else(|| {
                colours.push(k.clone());
                colours.len() - 1
            });
            let (x, y) = pts.into_iter().unzip();
            f.series.push(Series {
                name: k,
                x,
                y,
                color: PALETTE[i % PALETTE.len()],
                dashed: false,
                width_px: 2.0,
            });
        }
        if lo < hi {
            f.series.push(Series {
                name: format!("target {:.0e}", r.target_error),
                x: vec![lo, hi],
                y: vec![r.target_error; 2],
                color: [120, 120, 120],
                dashed: true,
                width_px: 1.0,
            });
        }
        figures.push(f);
    }
    figures
}
