//! The study's results: one point per run, one report per case, and the plain-text table.

use serde::Serialize;
use std::fmt::Write as _;

/// One run of one configuration.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    /// `dopri5`, `dop853`, `vern9`, `rodas4`, `rodas5p`, `radau5`, `rk4`, or `expm` (exact
    /// propagation of `linear`).
    pub method: String,
    pub fidelity: String,
    /// Relative tolerance asked for (for RK4: the tolerance its step was chosen from).
    pub rtol: f64,
    /// RK4's fixed step, s.
    pub step_s: Option<f64>,
    /// Achieved error (see the case's `error_measure`); `None` when the run failed.
    pub error: Option<f64>,
    pub wall_s: f64,
    pub rhs_evals: u64,
    pub jacobian_evals: u64,
    /// LU decompositions of the implicit methods' iteration matrices.
    pub lu_decompositions: u64,
    pub steps: u64,
    pub rejected_steps: u64,
    /// Why the run failed or was skipped.
    pub note: Option<String>,
}

impl Point {
    /// The curve this point belongs to: the method, and the fidelity when the case has several.
    pub fn curve(&self, several_fidelities: bool) -> String {
        if several_fidelities {
            format!("{}/{}", self.method, self.fidelity)
        } else {
            self.method.clone()
        }
    }
}

/// One case's results.
#[derive(Clone, Debug, Serialize)]
pub struct CaseReport {
    pub name: String,
    pub description: String,
    /// What the exact answer is.
    pub reference: String,
    /// How the error is measured.
    pub error_measure: String,
    /// Wall time of the reference run when there is one, s.
    pub reference_wall_s: Option<f64>,
    pub points: Vec<Point>,
    /// "for 1e-6 on this case, use …, it costs …".
    pub verdict: String,
}

/// The whole study.
#[derive(Clone, Debug, Serialize)]
pub struct StudyReport {
    pub target_error: f64,
    pub tolerances: Vec<f64>,
    pub cases: Vec<CaseReport>,
    pub total_wall_s: f64,
    pub version: String,
}

fn describe_config(p: &Point) -> String {
    let fid = if p.method == "expm" {
        String::new()
    } else {
        format!(" at {} fidelity", p.fidelity)
    };
    match (p.method.as_str(), p.step_s) {
        ("expm", _) => "the linear model (exact matrix exponential)".into(),
        (_, Some(h)) => format!("rk4 with h = {h:.3e} s{fid}"),
        (m, None) => format!("{m} at rtol {:.0e}{fid}", p.rtol),
    }
}

pub(super) fn verdict(r: &CaseReport, target: f64) -> String {
    let best = r
        .points
        .iter()
        .filter(|p| p.error.is_some_and(|e| e <= target))
        .min_by(|a, b| a.wall_s.total_cmp(&b.wall_s));
    match best {
        Some(p) => format!(
            "for {target:.0e} on {}, use {}: it costs {} ({} RHS, {} steps), error {:.1e}",
            r.name,
            describe_config(p),
            fmt_time(p.wall_s),
            p.rhs_evals,
            p.steps,
            p.error.unwrap_or(f64::NAN)
        ),
        None => {
            let closest = r
                .points
                .iter()
                .filter(|p| p.error.is_some())
                .min_by(|a, b| {
                    a.error
                        .unwrap_or(f64::INFINITY)
                        .total_cmp(&b.error.unwrap_or(f64::INFINITY))
                });
            match closest {
                Some(p) => format!(
                    "{target:.0e} is out of reach on {}: the best is {:.1e} with {} ({})",
                    r.name,
                    p.error.unwrap_or(f64::NAN),
                    describe_config(p),
                    fmt_time(p.wall_s)
                ),
                None => format!("no run succeeded on {}", r.name),
            }
        }
    }
}

pub(super) fn fmt_time(s: f64) -> String {
    if s < 1e-3 {
        format!("{:.0} µs", s * 1e6)
    } else if s < 1.0 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{s:.2} s")
    }
}

impl StudyReport {
    /// A plain-text table per case, then the verdicts.
    pub fn table(&self) -> String {
        let mut s = String::new();
        for c in &self.cases {
            let _ = writeln!(s, "== {} — {}", c.name, c.description);
            let _ = writeln!(s, "   reference: {}", c.reference);
            let _ = writeln!(s, "   error:     {}", c.error_measure);
            if let Some(w) = c.reference_wall_s {
                let _ = writeln!(s, "   reference run: {}", fmt_time(w));
            }
            let _ = writeln!(
                s,
                "   {:<8} {:<11} {:>7} {:>10} {:>10} {:>11} {:>9} {:>8} {:>6} {:>6}",
                "method",
                "fidelity",
                "rtol",
                "rk4 step",
                "error",
                "wall",
                "rhs",
                "steps",
                "jac",
                "lu"
            );
            for p in &c.points {
                let err = match p.error {
                    Some(e) => format!("{e:.2e}"),
                    None => "—".into(),
                };
                let _ = writeln!(
                    s,
                    "   {:<8} {:<11} {:>7} {:>10} {:>10} {:>11} {:>9} {:>8} {:>6} {:>6}{}",
                    p.method,
                    p.fidelity,
                    if p.rtol > 0.0 {
                        format!("{:.0e}", p.rtol)
                    } else {
                        "—".into()
                    },
                    p.step_s.map_or("—".into(), |h| format!("{h:.2e}")),
                    err,
                    if p.error.is_some() {
                        fmt_time(p.wall_s)
                    } else {
                        "—".into()
                    },
                    p.rhs_evals,
                    p.steps,
                    p.jacobian_evals,
                    p.lu_decompositions,
                    p.note.as_ref().map_or(String::new(), |n| format!("  {n}"))
                );
            }
            let _ = writeln!(s);
        }
        let _ = writeln!(s, "Verdicts (target error {:.0e}):", self.target_error);
        for c in &self.cases {
            let _ = writeln!(s, "  {}", c.verdict);
        }
        let _ = writeln!(s, "study wall time: {:.1} s", self.total_wall_s);
        s
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }
}
