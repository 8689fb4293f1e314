//! The Ray engine against a real local Ray cluster (pinned Ray in a cached venv): `ray start
//! --head` on free loopback ports with a private temp dir and an explicit auth token, stopped by
//! a guard that runs on failure too. On it: the same study gives the same table as the local
//! engine; a worker killed (SIGKILL) mid-task is retried and the sweep completes with no
//! `gyrolab` left behind and no half-written file; a driver killed mid-sweep is resumed by
//! running `sweep run` again, which runs only what was missing and ends with the same table.
//!
//! One test, one cluster: starting and stopping one costs seconds, so the cases run in order
//! on the same cluster.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::{gyrolab, succeed, tmp};
use polars::prelude::*;
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A local Ray cluster of this test; dropping it stops every process it started.
struct Cluster {
    ray: PathBuf,
    python: PathBuf,
    temp_dir: PathBuf,
    address: String,
    token: String,
}

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free loopback port")
}

/// `n` distinct free loopback ports, none in `avoid`: Ray refuses to start when a component's
/// port falls inside the worker port range (seen once in CI: the runtime-env agent's).
fn free_ports(n: usize, avoid: std::ops::RangeInclusive<u16>) -> Vec<u16> {
    let mut ports = Vec::with_capacity(n);
    while ports.len() < n {
        let p = free_port();
        if !avoid.contains(&p) && !ports.contains(&p) {
            ports.push(p);
        }
    }
    ports
}

/// Process ids whose command line contains `needle`, and their descendants.
fn processes_with(needle: &str) -> Vec<u32> {
    let mut all: Vec<(u32, u32, String)> = Vec::new();
    for e in std::fs::read_dir("/proc").into_iter().flatten().flatten() {
        let Ok(pid) = e.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        let cmd = std::fs::read(e.path().join("cmdline"))
            .map(|b| String::from_utf8_lossy(&b).replace('\0', " "))
            .unwrap_or_default();
        let ppid = std::fs::read_to_string(e.path().join("stat"))
            .ok()
            .and_then(|s| {
                let after = s.rsplit_once(')')?.1.to_string();
                after.split_whitespace().nth(1)?.parse().ok()
            })
            .unwrap_or(0);
        all.push((pid, ppid, cmd));
    }
    let mut found: Vec<u32> = all
        .iter()
        .filter(|(_, _, c)| c.contains(needle))
        .map(|p| p.0)
        .collect();
    let mut k = 0;
    while k < found.len() {
        let parent = found[k];
        for (pid, ppid, _) in &all {
            if *ppid == parent && !found.contains(pid) {
                found.push(*pid);
            }
        }
        k += 1;
    }
    found
}

fn alive(pid: u32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat"))
        .map(|s| {
            !s.rsplit_once(')')
                .is_some_and(|(_, r)| r.trim_start().starts_with('Z'))
        })
        .unwrap_or(false)
}

fn signal(sig: &str, pids: &[u32]) {
    if pids.is_empty() {
        return;
    }
    let _ = Command::new("kill")
        .arg(format!("-{sig}"))
        .args(pids.iter().map(u32::to_string))
        .stderr(Stdio::null())
        .status();
}

impl Cluster {
    fn start(python: &Path) -> Cluster {
        let bin = python.parent().expect("the venv's bin");
        let token = format!(
            "gyrolab-test-{}-{:x}",
            std::process::id(),
            Instant::now().elapsed().as_nanos() ^ 0x5eed
        );
        // A short private temp dir: Ray's socket paths must fit in 107 bytes.
        let temp_dir = PathBuf::from(format!("/tmp/gyrolab-ray-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&temp_dir);
        let worker_low = free_port().clamp(20000, 60000);
        let ports = free_ports(7, worker_low..=worker_low + 200);
        let port = ports[0];
        let cluster = Cluster {
            ray: bin.join("ray"),
            python: python.to_path_buf(),
            temp_dir,
            address: format!("127.0.0.1:{port}"),
            token,
        };
        let started = Instant::now();
        let out = cluster
            .command(&cluster.ray)
            .args([
                "start",
                "--head",
                "--node-ip-address=127.0.0.1",
                "--num-cpus=2",
            ])
            .arg(format!("--port={port}"))
            .arg(format!("--temp-dir={}", cluster.temp_dir.display()))
            .args(["--include-dashboard=false", "--disable-usage-stats"])
            .arg(format!("--min-worker-port={worker_low}"))
            .arg(format!("--max-worker-port={}", worker_low + 200))
            .arg(format!("--dashboard-agent-listen-port={}", ports[1]))
            .arg(format!("--dashboard-agent-grpc-port={}", ports[2]))
            .arg(format!("--runtime-env-agent-port={}", ports[3]))
            .arg(format!("--metrics-export-port={}", ports[4]))
            .arg(format!("--node-manager-port={}", ports[5]))
            .arg(format!("--object-manager-port={}", ports[6]))
            .output()
            .expect("ray start runs");
        println!("ray start --head: {:.1} s", started.elapsed().as_secs_f64());
        assert!(
            out.status.success(),
            "ray start failed:\n{}\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        cluster
    }

    /// A command with this cluster's authentication in its environment.
    fn command(&self, program: &Path) -> Command {
        let mut c = Command::new(program);
        c.env("RAY_AUTH_MODE", "token")
            .env("RAY_AUTH_TOKEN", &self.token)
            .env("GYROLAB_PYTHON", &self.python);
        c
    }

    /// `gyrolab` with this cluster's environment.
    fn gyrolab(&self) -> Command {
        let mut c = gyrolab();
        c.env("RAY_AUTH_MODE", "token")
            .env("RAY_AUTH_TOKEN", &self.token)
            .env("GYROLAB_PYTHON", &self.python);
        c
    }

    fn sweep_args(&self, study: &str, out: &Path) -> Vec<String> {
        vec![
            "sweep".into(),
            "run".into(),
            study.into(),
            "--out".into(),
            out.display().to_string(),
            "--engine".into(),
            "ray".into(),
            "--address".into(),
            self.address.clone(),
            "--chunk".into(),
            "1".into(),
            "--quiet".into(),
        ]
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        // Only this cluster's processes (their command lines name its private temp dir, or
        // descend from one that does), never another Ray on the machine.
        let needle = self.temp_dir.display().to_string();
        signal("TERM", &processes_with(&needle));
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(5)
            && processes_with(&needle).iter().any(|p| alive(*p))
        {
            std::thread::sleep(Duration::from_millis(100));
        }
        signal("KILL", &processes_with(&needle));
        println!("ray cluster stopped in {:.1} s", t0.elapsed().as_secs_f64());
        let _ = std::fs::remove_dir_all(&self.temp_dir);
    }
}

fn table(out: &Path) -> DataFrame {
    let df =
        gyro_study::table::read_parquet(&gyro_study::table::metrics_path(out)).expect("the table");
    df.drop_many(gyro_study::table::TIMING_COLUMNS)
}

fn partial_files(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.to_string_lossy().ends_with(".partial") {
                found.push(p);
            }
        }
    }
    found
}

/// Six one-hour rolling runs: about a second each, so the driver can be killed mid-sweep.
const STUDY: &str = r#"
name = "ray-rolling"
scenes = ["rolling-intercardinal"]

[[axis]]
key = "duration_s"
values = [3600.0]

# The run length this test is timed for: the shipped scene's atol (1e-6) makes runs 3x shorter.
[[axis]]
key = "simulation.atol"
values = [1e-10]

[[axis]]
key = "start.heading_deg"
values = [30.0, 60.0, 120.0]

[[axis]]
key = "sea.roll_period_s"
values = [8.0, 10.0]

[keep]
recordings = "every:3"
"#;

/// Two long rolling runs, so that a worker can be killed while its task runs.
const SLOW: &str = r#"
name = "ray-slow"
scenes = ["rolling-intercardinal"]

[[axis]]
key = "duration_s"
values = [43200.0]

# The run length this test is timed for: the shipped scene's atol (1e-6) makes runs 3x shorter.
[[axis]]
key = "simulation.atol"
values = [1e-10]

[[axis]]
key = "start.heading_deg"
values = [30.0, 60.0]
"#;

fn wait_for<T>(what: &str, limit: Duration, mut f: impl FnMut() -> Option<T>) -> T {
    let t0 = Instant::now();
    loop {
        if let Some(v) = f() {
            return v;
        }
        assert!(t0.elapsed() < limit, "waited {limit:?} for {what}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// 1. The same study on Ray: the same table, the same recordings kept, and pandas (through
///    pyarrow) reads the table with its types.
fn same_table_on_ray(
    cluster: &Cluster,
    python: &Path,
    dir: &Path,
    study: &str,
    reference: &DataFrame,
) {
    let on_ray = dir.join("ray");
    let out = succeed(
        cluster
            .gyrolab()
            .args(cluster.sweep_args(study, &on_ray))
            .arg("--json"),
    );
    let s: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (s["ran"].as_u64(), s["failed"].as_u64()),
        (Some(6), Some(0)),
        "{s}"
    );
    let got = table(&on_ray);
    assert!(
        got.equals_missing(reference),
        "ray:\n{got}\nlocal:\n{reference}"
    );
    for i in [0, 3] {
        assert!(on_ray.join(format!("recordings/run-{i:09}.mcap")).is_file());
    }
    assert!(partial_files(&on_ray).is_empty());
    // pandas (through pyarrow) reads the table with its types.
    let read = Command::new(python)
        .arg("-c")
        .arg(
            "import sys, pandas, pyarrow.parquet as pq\n\
             t = pq.read_table(sys.argv[1]); df = pandas.read_parquet(sys.argv[1])\n\
             print(len(df), t.schema.field('run_index').type, t.schema.field('start.heading_deg').type, \
             t.schema.field('rolling_error_rad').type, t.schema.field('status').type, list(df['status']).count('ok'))",
        )
        .arg(gyro_study::table::metrics_path(&on_ray))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&read.stdout);
    assert!(
        read.status.success(),
        "{}",
        String::from_utf8_lossy(&read.stderr)
    );
    let f: Vec<&str> = text.split_whitespace().collect();
    assert_eq!(
        (f[0], f[1], f[2], f[3], f[5]),
        ("6", "uint64", "double", "double", "6"),
        "{text}"
    );
    assert!(f[4].contains("string"), "{text}");
}

/// 2. A worker killed mid-task: the task is retried, the sweep completes, nothing is left.
fn worker_killed_mid_task(cluster: &Cluster, dir: &Path, slow: &str) {
    let killed = dir.join("killed");
    let needle = killed.display().to_string();
    let sweep = cluster
        .gyrolab()
        .args(cluster.sweep_args(slow, &killed))
        .arg("--json")
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let exec_pid = wait_for("a gyrolab task to start", Duration::from_secs(120), || {
        processes_with(&needle).into_iter().find(|p| {
            std::fs::read(format!("/proc/{p}/cmdline"))
                .map(|b| String::from_utf8_lossy(&b).contains("exec"))
                .unwrap_or(false)
        })
    });
    std::thread::sleep(Duration::from_millis(500));
    let worker = std::fs::read_to_string(format!("/proc/{exec_pid}/stat"))
        .ok()
        .and_then(|s| {
            s.rsplit_once(')')?
                .1
                .split_whitespace()
                .nth(1)?
                .parse::<u32>()
                .ok()
        })
        .expect("the task's worker");
    signal("KILL", &[worker]);
    println!("killed Ray worker {worker} (running gyrolab {exec_pid}) mid-task");
    let out = sweep.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (s["ran"].as_u64(), s["failed"].as_u64()),
        (Some(2), Some(0)),
        "{s}"
    );
    wait_for(
        "the orphaned gyrolab to exit",
        Duration::from_secs(10),
        || (!alive(exec_pid)).then_some(()),
    );
    let left: Vec<u32> = processes_with(&needle)
        .into_iter()
        .filter(|p| alive(*p))
        .collect();
    assert!(left.is_empty(), "processes left behind: {left:?}");
    assert!(
        partial_files(&killed).is_empty(),
        "{:?}",
        partial_files(&killed)
    );
    let t = table(&killed);
    let status: Vec<&str> = t["status"]
        .str()
        .unwrap()
        .iter()
        .map(|s| s.unwrap_or(""))
        .collect();
    assert_eq!(status, ["ok", "ok"]);
}

/// 3. The driver killed mid-sweep; the same command again finishes it, running only what was
///    missing, and the table equals the uninterrupted one.
fn driver_killed_and_resumed(cluster: &Cluster, dir: &Path, study: &str, reference: &DataFrame) {
    let resumed = dir.join("resumed");
    let sweep = cluster
        .gyrolab()
        .args(cluster.sweep_args(study, &resumed))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let parts = gyro_study::table::parts_dir(&resumed);
    wait_for("a first part", Duration::from_secs(120), || {
        gyro_study::table::part_files(&resumed)
            .ok()
            .filter(|p| !p.is_empty())
            .map(|_| ())
    });
    let driver = resumed.join("ray").join("driver.py").display().to_string();
    let drivers: Vec<u32> = processes_with(&driver);
    assert!(!drivers.is_empty(), "the driver runs");
    signal("KILL", &drivers[..1]);
    let out = sweep.wait_with_output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(parts.is_dir());
    let before = gyro_study::sweep::status(&resumed).unwrap();
    assert!(before.ok >= 1 && before.ok < 6, "{before:?}");
    // Tasks of the dead driver may still be finishing: wait for their workers to go.
    wait_for(
        "the dead driver's tasks to stop",
        Duration::from_secs(30),
        || {
            processes_with(&format!("{} ", resumed.display()))
                .into_iter()
                .all(|p| !alive(p))
                .then_some(())
        },
    );
    let done_before = gyro_study::sweep::status(&resumed).unwrap().ok;
    println!("driver killed with {done_before} of 6 runs done");
    let out = succeed(
        cluster
            .gyrolab()
            .args(cluster.sweep_args(study, &resumed))
            .arg("--json"),
    );
    let s: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(s["already_done"].as_u64(), Some(done_before), "{s}");
    assert_eq!(
        s["ran"].as_u64(),
        Some(6 - done_before),
        "finished runs are not run again: {s}"
    );
    let got = table(&resumed);
    assert!(
        got.equals_missing(reference),
        "resumed:\n{got}\nlocal:\n{reference}"
    );
    assert!(partial_files(&resumed).is_empty());
}

#[test]
fn ray_engine_on_a_local_cluster_matches_local_survives_kills_and_resumes() {
    let Some(python) = gyro_testkit::venv("sweep-venv", &gyro_testkit::SWEEP) else {
        return;
    };
    let dir = tmp("sweep", "ray");
    let study = dir.join("study.toml");
    std::fs::write(&study, STUDY).unwrap();
    let study = study.display().to_string();
    let slow = dir.join("slow.toml");
    std::fs::write(&slow, SLOW).unwrap();
    let slow = slow.display().to_string();

    // The local engine's table: what every Ray sweep below must equal.
    let local = dir.join("local");
    succeed(
        gyrolab()
            .args(["sweep", "run", &study, "--out"])
            .arg(&local)
            .arg("--quiet"),
    );
    let reference = table(&local);
    assert_eq!(reference.height(), 6);

    let cluster = Cluster::start(&python);

    same_table_on_ray(&cluster, &python, &dir, &study, &reference);
    worker_killed_mid_task(&cluster, &dir, &slow);
    driver_killed_and_resumed(&cluster, &dir, &study, &reference);
    drop(cluster);
}
