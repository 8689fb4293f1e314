//! What recording costs a run: the same scene integrated with an observer that does nothing and
//! recorded to MCAP (`gyro_sim::record`), the recording's share of the wall time, its cost per
//! output sample, and the per-sample cost of each model call the recorder makes.
//!
//! `cargo bench -p gyro-sim --bench record_overhead -- [SCENE] [DURATION_S] [RATE_HZ]`
//! (default: harbour-50n for 86400 s at the scene's own output rate). Times are the best of
//! `GYRO_REPEATS` (default 3) runs, to see through a shared machine's noise.

use std::hint::black_box;
use std::ops::ControlFlow;
use std::time::Instant;

use gyro_model::ShipMotion;
use gyro_sim::{RecordOptions, Scene, SceneOverrides, Simulation, record};

fn best_of<T>(n: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..n {
        let t0 = Instant::now();
        let r = f();
        best = best.min(t0.elapsed().as_secs_f64());
        last = Some(r);
    }
    (best, last.expect("at least one run"))
}

/// CPU seconds (user + system) of this process, all threads, from /proc (0 where unavailable).
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

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // `cargo bench` appends `--bench`; the tool takes positional arguments only.
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let name = args.first().map_or("harbour-50n", String::as_str);
    let duration_s: f64 = args.get(1).map_or(Ok(86400.0), |s| s.parse())?;
    let rate_hz: Option<f64> = args.get(2).map(|s| s.parse()).transpose()?;
    let repeats: usize = std::env::var("GYRO_REPEATS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    let ov = SceneOverrides {
        duration_s: Some(duration_s),
        output_rate_hz: rate_hz,
        ..Default::default()
    };
    let scene = Scene::load(name, &ov)?;
    let dir = std::env::temp_dir().join("gyro-sim-record-overhead");
    std::fs::create_dir_all(&dir)?;
    let path = dir.join(format!("{name}.mcap"));

    // 1. The run alone: integrate and sample, the observer only counts.
    let sim = Simulation::new(&scene)?;
    let (bare_s, samples) = best_of(repeats, || {
        let mut n = 0u64;
        sim.run(scene.method, &scene.tolerances, |t, x| {
            black_box((t, x));
            n += 1;
            ControlFlow::Continue(())
        })
        .map(|_| n)
    });
    let samples = samples?;

    // 2. The same run recorded (model set-up, rhs cost probe, writing, summary, sync included).
    let mut opts = gyro_mcap::WriterOptions::default();
    if let Some(level) = std::env::var("GYRO_ZSTD_LEVEL")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        opts.zstd_level = level;
    }
    let cpu0 = cpu_s();
    let (recorded_s, summary) = best_of(repeats, || {
        let ro = RecordOptions {
            writer: opts,
            ..Default::default()
        };
        record(&scene, &path, ro)
    });
    let recorded_cpu_s = (cpu_s() - cpu0) / repeats as f64;
    let summary = summary?;
    let extra_s = recorded_s - bare_s;
    println!(
        "{name}: {duration_s} s simulated, {samples} samples at {} Hz, poses every {} samples",
        scene.output_rate_hz,
        (scene.output_rate_hz / scene.pose_rate_hz).round().max(1.0)
    );
    println!("  run alone:      {bare_s:.3} s wall (best of {repeats})");
    println!(
        "  run recorded:   {recorded_s:.3} s wall; recording's share {:.1} %, {:.2} µs per sample",
        100.0 * extra_s / recorded_s,
        extra_s / samples as f64 * 1e6
    );
    println!(
        "  recorded run's CPU: {recorded_cpu_s:.3} s in all threads (mean of {repeats}), \
         {:.2} µs per sample more than the run alone",
        (recorded_cpu_s - bare_s) / samples as f64 * 1e6
    );
    println!(
        "  file:           {:.2} MB, {} messages, {:.3} MB per simulated hour at {} Hz",
        summary.bytes as f64 / 1e6,
        summary.messages,
        summary.bytes as f64 / 1e6 / (duration_s / 3600.0),
        scene.output_rate_hz
    );

    // 3. What the recorder's model calls cost, per call, on states of this run.
    let mut states: Vec<(f64, Vec<f64>)> = Vec::new();
    let every = (samples / 2000).max(1);
    let mut k = 0u64;
    sim.run(scene.method, &scene.tolerances, |t, x| {
        if k.is_multiple_of(every) {
            states.push((t, x.to_vec()));
        }
        k += 1;
        ControlFlow::Continue(())
    })?;
    let m = &sim.model;
    let per_call = |f: &mut dyn FnMut(f64, &[f64])| {
        let (s, _) = best_of(repeats, || {
            for (t, x) in &states {
                f(*t, x);
            }
        });
        s / states.len() as f64 * 1e6
    };
    let readout = per_call(&mut |t, x| {
        black_box(m.readout(t, x));
    });
    let kinematics = per_call(&mut |t, _| {
        black_box(m.motion.kinematics(t));
    });
    let gravity = per_call(&mut |t, _| {
        black_box(m.apparent_gravity(t));
    });
    let base = per_call(&mut |t, _| {
        black_box(m.world_from_base(t));
    });
    let q: Vec<Vec<f64>> = states.iter().map(|(t, x)| m.readout(*t, x).q).collect();
    let mut i = 0;
    let poses = per_call(&mut |t, _| {
        black_box(m.body_poses(t, &q[i % q.len()]));
        i += 1;
    });
    let rates = per_call(&mut |t, x| {
        black_box(m.rates(t, x));
    });
    println!(
        "  model calls per sample (µs): readout {readout:.2} (of which rates {rates:.2}), \
         kinematics {kinematics:.2}, apparent_gravity {gravity:.2}, world_from_base {base:.2}, \
         body_poses {poses:.2}"
    );
    println!(
        "{}",
        serde_json::json!({
            "scene": name,
            "duration_s": duration_s,
            "output_rate_hz": scene.output_rate_hz,
            "samples": samples,
            "run_alone_s": bare_s,
            "run_recorded_s": recorded_s,
            "recording_share": extra_s / recorded_s,
            "recording_us_per_sample": extra_s / samples as f64 * 1e6,
            "run_recorded_cpu_s": recorded_cpu_s,
            "zstd_level": opts.zstd_level,
            "bytes": summary.bytes,
            "messages": summary.messages,
            "mb_per_simulated_hour": summary.bytes as f64 / 1e6 / (duration_s / 3600.0),
            "us_per_call": {
                "readout": readout, "rates": rates, "kinematics": kinematics,
                "apparent_gravity": gravity, "world_from_base": base, "body_poses": poses,
            },
        })
    );
    std::fs::remove_file(&path)?;
    Ok(())
}
