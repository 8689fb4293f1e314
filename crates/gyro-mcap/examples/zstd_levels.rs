//! Chunk compression of a recording at several zstd levels: compression speed (the best of
//! `REPS` timings per chunk, all levels timed in turn on each chunk, so a busy machine slows
//! every level alike) and compressed size, on the recording's own decompressed chunks. This is
//! how the writer's default level was chosen.
//!
//! `cargo run --release -p gyro-mcap --example zstd_levels -- FILE.mcap [LEVEL[:PARAM=V,...] ...]`
//! (default levels: 1 -1 -2 -3 -4 -5). Parameters override the level's: `mm` minimum match
//! length, `hl` hash log, `wl` window log, `tl` target length; `-4:mm=7,hl=14` is level -4 with those two changed.

use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: zstd_levels FILE.mcap [LEVEL ...]")?;
    let mut levels: Vec<String> = args.collect();
    if levels.is_empty() {
        levels = ["1", "-1", "-2", "-3", "-4", "-5"]
            .map(String::from)
            .to_vec();
    }
    let reps: usize = std::env::var("REPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    let buf = std::fs::read(&path)?;
    let mut chunks = Vec::new();
    let mut file_compressed = 0usize;
    for rec in mcap::read::LinearReader::new(&buf)? {
        if let mcap::records::Record::Chunk { header, data } = rec? {
            file_compressed += data.len();
            chunks.push(zstd::bulk::decompress(
                &data,
                usize::try_from(header.uncompressed_size)?,
            )?);
        }
    }
    let total: usize = chunks.iter().map(Vec::len).sum();
    println!(
        "{path}: {} MB, {} chunks, {:.1} MB of records compressed to {:.1} MB in the file",
        buf.len() / 1_000_000,
        chunks.len(),
        total as f64 / 1e6,
        file_compressed as f64 / 1e6
    );
    let mut compressors = Vec::new();
    for spec in &levels {
        let (level, params) = spec.split_once(':').unwrap_or((spec, ""));
        let mut c = zstd::bulk::Compressor::new(level.parse()?)?;
        for p in params.split(',').filter(|p| !p.is_empty()) {
            use zstd::zstd_safe::CParameter;
            let (key, v) = p.split_once('=').ok_or("parameters are KEY=VALUE")?;
            let v: u32 = v.parse()?;
            c.set_parameter(match key {
                "mm" => CParameter::MinMatch(v),
                "hl" => CParameter::HashLog(v),
                "wl" => CParameter::WindowLog(v),
                "tl" => CParameter::TargetLength(v),
                _ => return Err(format!("unknown parameter {key} (mm hl wl tl)").into()),
            })?;
        }
        compressors.push(c);
    }
    let mut seconds = vec![0.0; levels.len()];
    let mut sizes = vec![0usize; levels.len()];
    let mut out = Vec::new();
    for chunk in &chunks {
        out.reserve(zstd::zstd_safe::compress_bound(chunk.len()));
        let mut best = vec![f64::INFINITY; levels.len()];
        for _ in 0..reps {
            for (b, c) in best.iter_mut().zip(&mut compressors) {
                out.clear();
                let t0 = Instant::now();
                c.compress_to_buffer(chunk, &mut out)?;
                *b = b.min(t0.elapsed().as_secs_f64());
            }
        }
        for (i, c) in compressors.iter_mut().enumerate() {
            out.clear();
            sizes[i] += c.compress_to_buffer(chunk, &mut out)?;
            seconds[i] += best[i];
        }
    }
    let base = sizes[0] as f64;
    for ((level, s), size) in levels.iter().zip(&seconds).zip(&sizes) {
        println!(
            "level {level:>5}: {:5.0} MB/s, ratio {:.2}, {:.1} MB compressed ({:+.1} % against level {}), \
             file {:+.1} MB",
            total as f64 / s / 1e6,
            total as f64 / *size as f64,
            *size as f64 / 1e6,
            100.0 * (*size as f64 / base - 1.0),
            levels[0],
            (*size as f64 - file_compressed as f64) / 1e6
        );
    }
    Ok(())
}
