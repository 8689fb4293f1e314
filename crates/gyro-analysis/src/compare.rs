//! Comparison of runs side by side: one column per run (design), one row per metric, for the
//! terminal and as Markdown, and an overlay plot of the reading error against time with each
//! run's fitted damped sinusoid drawn dashed over its window.

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::error::{AnalysisError, Result};
use crate::metrics::{AnalysisOptions, MetricsTable, RunAnalysis, RunMetrics, analyze_all};
use crate::plot::{Figure, PALETTE, Series};
use crate::table::Table;

/// The comparison of a set of runs.
#[derive(Debug, Clone, Serialize)]
pub struct ComparisonReport {
    pub table: MetricsTable,
    #[serde(skip)]
    pub analyses: Vec<RunAnalysis>,
    /// The overlay plot, once written.
    pub plot_svg: Option<PathBuf>,
    pub plot_png: Option<PathBuf>,
}

/// Analyses the runs the arguments name (in parallel), and writes `reading_error.svg` and
/// `reading_error.png` into `out_dir` (created when missing).
pub fn compare<P: AsRef<Path> + Sync>(inputs: &[P], out_dir: &Path) -> Result<ComparisonReport> {
    let analyses = analyze_all(inputs, &AnalysisOptions::default())?;
    let mut report = ComparisonReport::from_analyses(analyses);
    report.write_plots(out_dir)?;
    Ok(report)
}

/// A row of the side-by-side table: label and how to show a run's value.
type RowFn = fn(&RunMetrics) -> String;

fn deg(v: Option<f64>) -> String {
    v.map_or("–".to_owned(), |v| format!("{:.3}", v.to_degrees()))
}

fn pm(v: Option<f64>, s: Option<f64>, scale: f64, digits: usize) -> String {
    match (v, s) {
        (Some(v), Some(s)) => format!("{:.digits$} ± {:.1e}", v * scale, s * scale),
        (Some(v), None) => format!("{:.digits$}", v * scale),
        _ => "–".to_owned(),
    }
}

fn plain<T: ToString>(v: Option<T>) -> String {
    v.map_or("–".to_owned(), |v| v.to_string())
}

fn text(s: &str) -> String {
    if s.is_empty() {
        "–".to_owned()
    } else {
        s.to_owned()
    }
}

const ROWS: &[(&str, RowFn)] = &[
    ("scene", |r| text(&r.scene)),
    ("design", |r| text(&r.design)),
    ("fidelity", |r| text(&r.fidelity)),
    ("integrator", |r| text(&r.integrator)),
    ("rtol", |r| plain(r.rtol)),
    ("fit (azimuth)", |r| text(&r.azimuth_quality)),
    ("period (min)", |r| {
        pm(r.period_s, r.period_sigma_s, 1.0 / 60.0, 3)
    }),
    ("log decrement Λ", |r| {
        pm(r.log_decrement, r.log_decrement_sigma, 1.0, 4)
    }),
    ("damping ratio ζ", |r| {
        pm(r.damping_ratio, r.damping_ratio_sigma, 1.0, 4)
    }),
    ("fit (tilt)", |r| text(&r.tilt_quality)),
    ("tilt period (min)", |r| {
        pm(r.tilt_period_s, r.tilt_period_sigma_s, 1.0 / 60.0, 3)
    }),
    ("steady error (°)", |r| {
        pm(
            r.steady_error_rad,
            r.steady_error_sigma_rad,
            180.0 / std::f64::consts::PI,
            4,
        )
    }),
    ("drift (°/h)", |r| {
        pm(
            r.steady_drift_rad_per_s,
            r.steady_drift_sigma_rad_per_s,
            3600.0 * 180.0 / std::f64::consts::PI,
            4,
        )
    }),
    ("manoeuvres", |r| r.ballistic_events.to_string()),
    ("ballistic peak (°)", |r| deg(r.ballistic_peak_rad)),
    ("expected peak (°)", |r| deg(r.ballistic_expected_peak_rad)),
    ("settle (min)", |r| {
        r.ballistic_settle_s
            .map_or("–".to_owned(), |s| format!("{:.1}", s / 60.0))
    }),
    ("rolling error (°)", |r| {
        pm(
            r.rolling_error_rad,
            r.rolling_error_sigma_rad,
            180.0 / std::f64::consts::PI,
            4,
        )
    }),
    ("steps", |r| plain(r.steps)),
    ("rhs evals", |r| plain(r.rhs_evals)),
    ("wall time (s)", |r| {
        r.wall_time_s.map_or("–".to_owned(), |s| format!("{s:.2}"))
    }),
];

impl ComparisonReport {
    pub fn from_analyses(analyses: Vec<RunAnalysis>) -> Self {
        Self {
            table: MetricsTable {
                rows: analyses.iter().map(|a| a.metrics.clone()).collect(),
            },
            analyses,
            plot_svg: None,
            plot_png: None,
        }
    }

    fn grid(&self) -> (Vec<String>, Vec<Vec<String>>) {
        let header: Vec<String> = std::iter::once("metric".to_owned())
            .chain(self.table.rows.iter().map(|r| r.run_id.clone()))
            .collect();
        let rows = ROWS
            .iter()
            .map(|(label, f)| {
                std::iter::once((*label).to_owned())
                    .chain(self.table.rows.iter().map(f))
                    .collect()
            })
            .collect();
        (header, rows)
    }

    /// The grid as one table: metrics as rows, runs as right-aligned columns.
    fn grid_table(&self) -> Table {
        let (header, rows) = self.grid();
        let mut t = Table::new(&header).numbers_right();
        for r in rows {
            t.row(r);
        }
        t
    }

    /// Aligned columns for a terminal.
    pub fn render_terminal(&self) -> String {
        let mut out = self.grid_table().rule().render();
        self.push_notes(&mut out, "");
        if let (Some(svg), Some(png)) = (&self.plot_svg, &self.plot_png) {
            out.push_str(&format!("plot: {} and {}\n", svg.display(), png.display()));
        }
        out
    }

    /// A Markdown table (metrics as rows, runs as columns), then the notes and plot.
    pub fn render_markdown(&self) -> String {
        let mut out = self.grid_table().render_markdown();
        self.push_notes(&mut out, "- ");
        if let Some(png) = &self.plot_png {
            out.push_str(&format!(
                "\n![reading error against time]({})\n",
                png.file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default()
            ));
        }
        out
    }

    fn push_notes(&self, out: &mut String, bullet: &str) {
        let notes: Vec<&String> = self.analyses.iter().flat_map(|a| &a.notes).collect();
        if !notes.is_empty() {
            out.push_str("\nnotes:\n");
            for n in notes {
                out.push_str(&format!("{bullet}{n}\n"));
            }
        }
    }

    /// Reading error (°) against time (h) of every run, with the fitted curves dashed.
    pub fn figure(&self) -> Figure {
        let mut fig = Figure::new(
            "Reading error (fits dashed)",
            "time (h)",
            "reading error (deg)",
        );
        for (k, a) in self.analyses.iter().enumerate() {
            let color = PALETTE[k % PALETTE.len()];
            fig.series.push(Series {
                name: a.metrics.run_id.clone(),
                x: a.series.time_s.iter().map(|t| t / 3600.0).collect(),
                y: a.series.error_rad.iter().map(|e| e.to_degrees()).collect(),
                color,
                dashed: false,
                width_px: 1.6,
            });
            if let Some(m) = a.azimuth.model {
                let (t0, t1) = a.azimuth.window_s;
                let n = 600;
                let ts: Vec<f64> = (0..=n)
                    .map(|i| t0 + (t1 - t0) * i as f64 / n as f64)
                    .collect();
                fig.series.push(Series {
                    name: String::new(),
                    x: ts.iter().map(|t| t / 3600.0).collect(),
                    y: ts.iter().map(|t| m.eval(*t).to_degrees()).collect(),
                    color: [
                        (color[0] / 2).saturating_add(20),
                        (color[1] / 2).saturating_add(20),
                        (color[2] / 2).saturating_add(20),
                    ],
                    dashed: true,
                    width_px: 1.4,
                });
            }
        }
        fig
    }

    /// Writes `reading_error.svg` and `.png` into `out_dir`.
    pub fn write_plots(&mut self, out_dir: &Path) -> Result<()> {
        std::fs::create_dir_all(out_dir).map_err(AnalysisError::io(out_dir, "creating"))?;
        let (svg, png) = self.figure().write(&out_dir.join("reading_error"))?;
        self.plot_svg = Some(svg);
        self.plot_png = Some(png);
        Ok(())
    }
}
