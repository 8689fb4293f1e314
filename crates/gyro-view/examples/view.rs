//! The viewer without the CLI (what `gyrolab view` does, with the library's options):
//! `cargo run --release -p gyro-view --example view --
//! [--save FILE.rrd | --connect URL] [--tilt K] [--error K] [--pose-rate HZ] RUN.mcap…`
//! (spawns the viewer by default). Prints the report.

use std::path::PathBuf;

use gyro_view::{Sink, ViewOptions, view};

fn main() {
    let mut opts = ViewOptions::default();
    let mut runs = Vec::new();
    let mut args = std::env::args().skip(1);
    let number = |v: Option<String>, name: &str| -> f64 {
        v.and_then(|s| s.parse().ok()).unwrap_or_else(|| {
            eprintln!("{name} needs a number");
            std::process::exit(2)
        })
    };
    while let Some(a) = args.next() {
        match a.as_str() {
            "--save" => opts.sink = Sink::Save(PathBuf::from(args.next().unwrap_or_default())),
            "--connect" => opts.sink = Sink::Connect(args.next().unwrap_or_default()),
            "--tilt" => opts.tilt_exaggeration = number(args.next(), "--tilt"),
            "--error" => opts.error_exaggeration = number(args.next(), "--error"),
            "--pose-rate" => opts.max_pose_rate_hz = number(args.next(), "--pose-rate"),
            _ => runs.push(PathBuf::from(a)),
        }
    }
    match view(&runs, &opts) {
        Ok(report) => {
            println!("{report:#?}");
            for n in &report.notes {
                println!("note: {n}");
            }
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
