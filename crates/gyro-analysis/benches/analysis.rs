//! Load and fit time of a 24-hour 10-Hz recording, and `compare` over 50 runs; prints figures.
//! `cargo bench -p gyro-analysis --bench analysis`
//! (GYRO_ANALYSIS_BENCH_HOURS: length of the long run, default 24; GYRO_ANALYSIS_BENCH_RUNS and
//! GYRO_ANALYSIS_BENCH_RUN_HOURS: the compare set, default 50 runs of 6 h at 10 Hz.)

use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::time::Instant;

use gyro_analysis::fit::{FitOptions, fit_damped_sinusoid};
use gyro_analysis::load::COMPASS_TOPIC;
use gyro_analysis::metrics::analyze_loaded;
use gyro_analysis::{AnalysisOptions, LoadOptions, compare, load_run};
use gyro_mcap::{FieldSpec, RecordSchema, RecordingWriter, WriterOptions};

fn cpu_s() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .map_or("", |(_, rest)| rest)
        .split_whitespace()
        .collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|f| f.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(11) + ticks(12)) / 100.0
}

fn env(name: &str, default: f64) -> f64 {
    std::env::var(name)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// A run on the recording contract: compass state (5 + 2×2 fields), ship state, solver stats.
fn write(
    path: &Path,
    hours: f64,
    period_s: f64,
    decrement: f64,
) -> Result<u64, Box<dyn std::error::Error>> {
    let mut compass_fields = vec![FieldSpec::f64("time_s", "s")];
    for f in [
        "reading_error_rad",
        "compass_heading_rad",
        "true_heading_rad",
        "tilt_rad",
        "zeta_rad",
        "theta_rad",
        "zeta_rate_rad_per_s",
        "theta_rate_rad_per_s",
    ] {
        compass_fields.push(FieldSpec::f64(f, "rad"));
    }
    let mut ship_fields = vec![FieldSpec::f64("time_s", "s")];
    for f in [
        "latitude_rad",
        "longitude_rad",
        "heading_rad",
        "speed_m_per_s",
        "roll_rad",
        "pitch_rad",
    ] {
        ship_fields.push(FieldSpec::f64(f, ""));
    }
    let mut w = RecordingWriter::create(path, WriterOptions::default())?;
    let compass = w.add_record_channel(
        COMPASS_TOPIC,
        &RecordSchema {
            full_name: "gyrolab.CompassState".into(),
            fields: compass_fields,
        },
    )?;
    let ship = w.add_record_channel(
        "/ship/state",
        &RecordSchema {
            full_name: "gyrolab.ShipState".into(),
            fields: ship_fields,
        },
    )?;
    let mut meta = BTreeMap::new();
    meta.insert(
        "design_name".to_owned(),
        path.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
    );
    meta.insert("scene_name".to_owned(), "bench".to_owned());
    w.write_metadata("run", &meta)?;
    let n = (hours * 36_000.0) as u64;
    let sigma = decrement / period_s;
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for i in 0..n {
        let t = i as f64 * 0.1;
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let noise = ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2e-4;
        let e = 0.001 + 0.05 * (-sigma * t).exp() * (2.0 * PI * t / period_s).cos() + noise;
        let ns = i * 100_000_000;
        w.write_f64_record(compass, ns, &[t, e, e, 0.0, 0.1 * e, e, 0.1 * e, 0.0, 0.0])?;
        w.write_f64_record(ship, ns, &[t, 0.87, 0.0, 0.0, 0.0, 0.0, 0.0])?;
    }
    w.finish()?;
    Ok(n)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir: PathBuf = std::env::temp_dir().join("gyro-analysis-bench");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir)?;

    // One long run.
    let hours = env("GYRO_ANALYSIS_BENCH_HOURS", 24.0);
    let path = dir.join("day.mcap");
    let rows = write(&path, hours, 3700.0, 0.3)?;
    let bytes = std::fs::metadata(&path)?.len();
    let (w0, c0) = (Instant::now(), cpu_s());
    let run = load_run(&path, &LoadOptions::default())?;
    let (load_wall, load_cpu) = (w0.elapsed().as_secs_f64(), cpu_s() - c0);
    let total_rows: usize = run.frames.values().map(|f| f.height()).sum();
    println!(
        "load  {hours} h at 10 Hz: {total_rows} rows ({rows} per channel, {:.1} MB file) in {load_wall:.3} s wall, {load_cpu:.3} s CPU: {:.2} M rows/s",
        bytes as f64 / 1e6,
        total_rows as f64 / load_wall / 1e6
    );
    // The share of gyro-mcap's own decoding in that.
    let (w0, c0) = (Instant::now(), cpu_s());
    let recording = gyro_mcap::Recording::open(&path)?;
    let decoded: usize = ["/compass/state", "/ship/state"]
        .iter()
        .map(|t| recording.read_records(t).map(|r| r.len()))
        .sum::<Result<usize, _>>()?;
    println!(
        "      of which gyro-mcap open + read_records ({decoded} rows): {:.3} s wall, {:.3} s CPU",
        w0.elapsed().as_secs_f64(),
        cpu_s() - c0
    );
    drop(recording);
    let t = run.f64_field(COMPASS_TOPIC, "time_s")?;
    let x = run.f64_field(COMPASS_TOPIC, "reading_error_rad")?;
    let w0 = Instant::now();
    let fit = fit_damped_sinusoid(t, x, &FitOptions::default());
    let fit_wall = w0.elapsed().as_secs_f64();
    println!(
        "fit   damped sinusoid on {} samples (decimated to {}): {fit_wall:.4} s, {} LM iterations: {}",
        t.len(),
        fit.samples_used,
        fit.iterations,
        fit.message
    );
    let w0 = Instant::now();
    let analysis = analyze_loaded(&run, &AnalysisOptions::default())?;
    println!(
        "analyse every fit and detector on the loaded run: {:.4} s ({} notes)",
        w0.elapsed().as_secs_f64(),
        analysis.notes.len()
    );
    drop(run);
    std::fs::remove_file(&path)?;

    // compare over many runs.
    let runs = env("GYRO_ANALYSIS_BENCH_RUNS", 50.0) as usize;
    let run_hours = env("GYRO_ANALYSIS_BENCH_RUN_HOURS", 6.0);
    if runs == 0 {
        std::fs::remove_dir_all(&dir)?;
        return Ok(());
    }
    let set = dir.join("set");
    std::fs::create_dir_all(&set)?;
    let mut all_rows = 0;
    for k in 0..runs {
        all_rows += write(
            &set.join(format!("run{k:02}.mcap")),
            run_hours,
            3600.0 + 20.0 * k as f64,
            0.1 + 0.02 * k as f64,
        )?;
    }
    let (w0, c0) = (Instant::now(), cpu_s());
    let report = compare(std::slice::from_ref(&set), &dir.join("report"))?;
    let (wall, cpu) = (w0.elapsed().as_secs_f64(), cpu_s() - c0);
    println!(
        "compare {runs} runs of {run_hours} h at 10 Hz ({all_rows} compass rows): {wall:.2} s wall, {cpu:.2} s CPU on {} threads ({} rows in the table)",
        rayon::current_num_threads(),
        report.table.rows.len()
    );
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}
