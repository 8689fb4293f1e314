//! The report of a sweep: tables and plots of the metrics against the axes. One grid axis gives
//! lines (one per scene, design and value of the other axes); two give a heat map too; Monte
//! Carlo samples give spreads (mean, standard deviation, the 5/25/50/75/95 % quantiles) per grid
//! point and a histogram. A study's `[[report.harmonic]]` fits a metric against an angle axis
//! with a Fourier series, per value of the other axes (e.g. the sin 2Δ of the rolling error).

use crate::plan::Plan;
use crate::table::{self, OK};
use gyro_analysis::plot::{Figure, PALETTE, Series};
use gyro_analysis::table::Table;
use polars::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A harmonic fit of a metric against an angle axis, for one value of the other axes.
#[derive(Clone, Debug, Serialize)]
pub struct HarmonicFit {
    pub metric: String,
    pub axis: String,
    pub order: u32,
    /// The other axes' values (scene, design, grid axes) of this group.
    pub group: Vec<(String, String)>,
    /// a₀ (the mean over the angle).
    pub mean: f64,
    /// √(aₙ² + bₙ²) of the `order`-th harmonic, and its phase: aₙ cos nx + bₙ sin nx =
    /// amplitude · sin(nx + phase).
    pub amplitude: f64,
    pub phase_rad: f64,
    /// The coefficients of sin nx and cos nx.
    pub sin_coefficient: f64,
    pub cos_coefficient: f64,
    pub rms_residual: f64,
    pub points: usize,
}

/// Spread of a metric over the Monte Carlo samples of one grid point.
#[derive(Clone, Debug, Serialize)]
pub struct Spread {
    pub metric: String,
    pub group: Vec<(String, String)>,
    pub n: usize,
    pub mean: f64,
    pub std: f64,
    /// 5, 25, 50, 75, 95 %.
    pub quantiles: [f64; 5],
}

/// The report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub study: String,
    pub total_runs: u64,
    pub rows: usize,
    pub ok: usize,
    pub failed: usize,
    /// Axes of one value (they set the study's scenes; no column of the summary).
    pub fixed: Vec<(String, String)>,
    pub harmonics: Vec<HarmonicFit>,
    pub spreads: Vec<Spread>,
    /// The table of grid points (Markdown).
    pub summary_markdown: String,
    pub plots: Vec<PathBuf>,
}

/// The values of the other axes that a line, a fit or a spread is for: (axis, value as text).
type Group = Vec<(String, String)>;

/// A grid axis's column: its key, its values as text, and as numbers when they are numbers.
type AxisColumn = (String, Vec<String>, Option<Vec<Option<f64>>>);

/// A harmonic fit's data for one group: its first row, the angles (rad), the metric's values.
type FitData = (usize, Vec<f64>, Vec<f64>);

/// A line of a plot: x (as a key for grouping) → (x, the metric's values there).
type Line = BTreeMap<i64, (f64, Vec<f64>)>;

/// Quantile levels of [`Spread::quantiles`].
pub const QUANTILES: [f64; 5] = [0.05, 0.25, 0.5, 0.75, 0.95];

fn f64_column(df: &DataFrame, name: &str) -> Option<Vec<Option<f64>>> {
    let c = df.column(name).ok()?.cast(&DataType::Float64).ok()?;
    Some(c.f64().ok()?.iter().collect())
}

fn str_column(df: &DataFrame, name: &str) -> Option<Vec<String>> {
    let c = df.column(name).ok()?.cast(&DataType::String).ok()?;
    Some(
        c.str()
            .ok()?
            .iter()
            .map(|s| s.unwrap_or("").to_string())
            .collect(),
    )
}

/// The value of an angle axis in radians (by its key's unit).
fn radians(key: &str, x: f64) -> f64 {
    if key.ends_with("_deg") {
        x.to_radians()
    } else {
        x
    }
}

/// Least-squares fit of y = a₀ + Σₖ (aₖ cos kx + bₖ sin kx), k = 1…order; returns the
/// coefficients [a₀, a₁, b₁, …] and the rms residual, or None with too few points.
pub fn fit_fourier(x: &[f64], y: &[f64], order: u32) -> Option<(Vec<f64>, f64)> {
    let m = 1 + 2 * order as usize;
    if x.len() < m {
        return None;
    }
    let basis = |x: f64| {
        let mut b = vec![1.0];
        for k in 1..=order {
            b.push((k as f64 * x).cos());
            b.push((k as f64 * x).sin());
        }
        b
    };
    let mut a = vec![vec![0.0; m + 1]; m];
    for (&xi, &yi) in x.iter().zip(y) {
        let b = basis(xi);
        for r in 0..m {
            for c in 0..m {
                a[r][c] += b[r] * b[c];
            }
            a[r][m] += b[r] * yi;
        }
    }
    // Gaussian elimination with partial pivoting.
    for col in 0..m {
        let piv = (col..m).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() < 1e-12 {
            return None;
        }
        a.swap(col, piv);
        for r in 0..m {
            if r != col {
                let f = a[r][col] / a[col][col];
                let pivot = a[col].clone();
                for (x, p) in a[r].iter_mut().zip(&pivot).skip(col) {
                    *x -= f * p;
                }
            }
        }
    }
    let coef: Vec<f64> = (0..m).map(|i| a[i][m] / a[i][i]).collect();
    let rss: f64 = x
        .iter()
        .zip(y)
        .map(|(&xi, &yi)| {
            let f: f64 = basis(xi).iter().zip(&coef).map(|(b, c)| b * c).sum();
            (yi - f).powi(2)
        })
        .sum();
    Some((coef, (rss / x.len() as f64).sqrt()))
}

fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let pos = q * (sorted.len() - 1) as f64;
    let (i, f) = (pos.floor() as usize, pos.fract());
    let j = (i + 1).min(sorted.len() - 1);
    sorted[i] * (1.0 - f) + sorted[j] * f
}

/// Mean over the samples against x, one line per group (at most 12).
fn lines_figure(title: &str, xname: &str, m: &str, lines: &BTreeMap<Group, Line>) -> Figure {
    let mut f = Figure::new(title, xname, m);
    for (k, (g, pts)) in lines.iter().enumerate().take(12) {
        let name = if g.is_empty() {
            m.to_owned()
        } else {
            g.iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let (xs, ys): (Vec<f64>, Vec<f64>) = pts
            .values()
            .map(|(x, v)| (*x, v.iter().sum::<f64>() / v.len() as f64))
            .unzip();
        f.series.push(Series {
            name,
            x: xs,
            y: ys,
            color: PALETTE[k % PALETTE.len()],
            dashed: false,
            width_px: 2.0,
        });
    }
    f
}

/// A histogram of the samples `v` of metric `m` (√n bins, 5–40); `None` with fewer than two
/// samples or no spread.
fn histogram(study: &str, m: &str, v: &[f64]) -> Option<Figure> {
    if v.len() < 2 {
        return None;
    }
    let (lo, hi) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(*x), b.max(*x))
        });
    if hi <= lo {
        return None;
    }
    let bins = ((v.len() as f64).sqrt().ceil() as usize).clamp(5, 40);
    let w = (hi - lo) / bins as f64;
    let mut counts = vec![0.0; bins];
    for x in v {
        counts[(((x - lo) / w) as usize).min(bins - 1)] += 1.0;
    }
    let (mut xs, mut ys) = (vec![lo], vec![0.0]);
    for (k, c) in counts.iter().enumerate() {
        xs.extend([lo + k as f64 * w, lo + (k + 1) as f64 * w]);
        ys.extend([*c, *c]);
    }
    xs.push(hi);
    ys.push(0.0);
    let mut f = Figure::new(&format!("{study} — {m}: {} samples", v.len()), m, "runs");
    f.series.push(Series {
        name: "samples".into(),
        x: xs,
        y: ys,
        color: PALETTE[0],
        dashed: false,
        width_px: 2.0,
    });
    Some(f)
}

/// The metrics table as the report reads it: rows, which of them succeeded, and the columns
/// that tell groups apart.
struct Rows<'a> {
    study: &'a crate::study::Study,
    df: DataFrame,
    n: usize,
    status: Vec<String>,
    ok: Vec<usize>,
    scene: Vec<String>,
    design: Vec<String>,
    /// Grid axes, with their values as text (group keys) and as numbers (x).
    grid: Vec<AxisColumn>,
    /// The metrics that are numbers (not `_quality` labels).
    numeric: Vec<&'a String>,
}

impl<'a> Rows<'a> {
    fn new(study: &'a crate::study::Study, df: DataFrame) -> Self {
        let n = df.height();
        let status = str_column(&df, "status").unwrap_or_default();
        let ok = (0..n).filter(|&i| status[i] == OK).collect();
        let grid = study
            .grid
            .iter()
            .map(|a| {
                let name = a.key.name.clone();
                let text = str_column(&df, &name).unwrap_or_else(|| vec![String::new(); n]);
                let num = matches!(a.values.first(), Some(toml::Value::Float(_)))
                    .then(|| f64_column(&df, &name))
                    .flatten();
                (name, text, num)
            })
            .collect();
        Rows {
            study,
            scene: str_column(&df, "scene").unwrap_or_default(),
            design: str_column(&df, "design").unwrap_or_default(),
            numeric: study
                .metrics
                .iter()
                .filter(|m| !m.ends_with("_quality"))
                .collect(),
            df,
            n,
            status,
            ok,
            grid,
        }
    }

    /// Row `i`'s group: its scene and design when the study has several, and its value of every
    /// grid axis that varies, but `except`.
    fn group_of(&self, i: usize, except: Option<&str>) -> Group {
        let mut g = Vec::new();
        if self.study.scenes.len() > 1 {
            g.push(("scene".to_string(), self.scene[i].clone()));
        }
        if self.study.designs.len() > 1 {
            g.push(("design".to_string(), self.design[i].clone()));
        }
        // Axes of one value set the study, they tell no group apart.
        for ((name, text, _), a) in self.grid.iter().zip(&self.study.grid) {
            if Some(name.as_str()) != except && a.values.len() > 1 {
                g.push((name.clone(), text[i].clone()));
            }
        }
        g
    }

    /// The numeric metrics that are plotted and tabled (not the samples' sigmas).
    fn shown(&self) -> impl Iterator<Item = &'a String> + '_ {
        self.numeric
            .iter()
            .copied()
            .filter(|m| !m.contains("sigma"))
    }
}

/// The study's `[[report.harmonic]]` fits, one per metric, axis and group.
fn harmonic_fits(rows: &Rows) -> Vec<HarmonicFit> {
    let mut harmonics = Vec::new();
    for h in &rows.study.harmonics {
        let Some(y) = f64_column(&rows.df, &h.metric) else {
            continue;
        };
        let Some((_, _, Some(x))) = rows.grid.iter().find(|(n, _, _)| *n == h.axis) else {
            continue;
        };
        // Per group: its first row (the fits come in run-index order), the angles, the values.
        let mut groups: BTreeMap<Group, FitData> = BTreeMap::new();
        for &i in &rows.ok {
            if let (Some(xi), Some(yi)) = (x[i], y[i]) {
                let e = groups.entry(rows.group_of(i, Some(&h.axis))).or_insert((
                    i,
                    Vec::new(),
                    Vec::new(),
                ));
                e.1.push(radians(&h.axis, xi));
                e.2.push(yi);
            }
        }
        let mut groups: Vec<(Group, FitData)> = groups.into_iter().collect();
        groups.sort_by_key(|(_, (first, _, _))| *first);
        for (group, (_, xs, ys)) in groups {
            if let Some((c, rms)) = fit_fourier(&xs, &ys, h.order) {
                let k = 2 * h.order as usize;
                let (a, b) = (c[k - 1], c[k]);
                harmonics.push(HarmonicFit {
                    metric: h.metric.clone(),
                    axis: h.axis.clone(),
                    order: h.order,
                    group,
                    mean: c[0],
                    amplitude: a.hypot(b),
                    phase_rad: a.atan2(b),
                    sin_coefficient: b,
                    cos_coefficient: a,
                    rms_residual: rms,
                    points: xs.len(),
                });
            }
        }
    }
    harmonics
}

/// Spreads over the Monte Carlo samples, per metric and grid point (none without samples).
fn spreads(rows: &Rows) -> Vec<Spread> {
    let mut spreads = Vec::new();
    if rows.study.random.is_empty() {
        return spreads;
    }
    for m in &rows.numeric {
        let Some(y) = f64_column(&rows.df, m) else {
            continue;
        };
        let mut groups: BTreeMap<Group, Vec<f64>> = BTreeMap::new();
        for &i in &rows.ok {
            if let Some(v) = y[i] {
                groups.entry(rows.group_of(i, None)).or_default().push(v);
            }
        }
        for (group, mut v) in groups {
            v.sort_by(f64::total_cmp);
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            let var =
                v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len().max(2) - 1) as f64;
            spreads.push(Spread {
                metric: (*m).clone(),
                group,
                n: v.len(),
                mean,
                std: var.sqrt(),
                quantiles: QUANTILES.map(|q| quantile(&v, q)),
            });
        }
    }
    spreads
}

/// The summary table (Markdown): one line per grid point in run-index order, its succeeded
/// runs, and the mean of up to six metrics.
fn summary_table(rows: &Rows) -> String {
    let (df, n) = (&rows.df, rows.n);
    let shown: Vec<&String> = rows
        .shown()
        .filter(|m| f64_column(df, m).is_some_and(|c| c.iter().any(Option::is_some)))
        .take(6)
        .collect();
    let mut columns: Vec<String> = if n == 0 {
        Vec::new()
    } else {
        rows.group_of(0, None).into_iter().map(|(k, _)| k).collect()
    };
    columns.push("ok".into());
    columns.extend(shown.iter().map(|m| (*m).clone()));
    let mut t = Table::new(&columns);
    let ycols: Vec<Vec<Option<f64>>> = shown
        .iter()
        .map(|m| f64_column(df, m).unwrap_or_else(|| vec![None; n]))
        .collect();
    // Grid points in run-index order (the table's), not sorted as text.
    let mut points: Vec<(Group, Vec<usize>)> = Vec::new();
    let mut seen: BTreeMap<Group, usize> = BTreeMap::new();
    for i in 0..n {
        let g = rows.group_of(i, None);
        match seen.get(&g) {
            Some(&k) => points[k].1.push(i),
            None => {
                seen.insert(g.clone(), points.len());
                points.push((g, vec![i]));
            }
        }
    }
    for (g, members) in &points {
        let ok: Vec<usize> = members
            .iter()
            .copied()
            .filter(|&i| rows.status[i] == OK)
            .collect();
        let mut cells: Vec<String> = g.iter().map(|(_, v)| v.clone()).collect();
        cells.push(format!("{}/{}", ok.len(), members.len()));
        for y in &ycols {
            let v: Vec<f64> = ok.iter().filter_map(|&i| y[i]).collect();
            cells.push(if v.is_empty() {
                "-".into()
            } else {
                gyro_analysis::metrics::format_number(v.iter().sum::<f64>() / v.len() as f64)
            });
        }
        t.row(cells);
    }
    t.render_markdown()
}

/// Writes the plots into `dir`: per metric, lines against the first numeric axis that varies
/// (and a heat map over the first two numeric axes), or a histogram of Monte Carlo samples.
fn write_plots(rows: &Rows, dir: &Path) -> Result<Vec<PathBuf>, String> {
    let name = &rows.study.name;
    let mut plots = Vec::new();
    let xaxis = rows.grid.iter().find(|(_, t, x)| {
        x.is_some() && {
            let mut u = t.clone();
            u.sort();
            u.dedup();
            u.len() > 1
        }
    });
    for m in rows.shown() {
        let Some(y) = f64_column(&rows.df, m) else {
            continue;
        };
        if let Some((xname, _, Some(x))) = xaxis {
            // Lines: mean over samples against the first numeric axis, one per other group.
            let mut lines: BTreeMap<Group, Line> = BTreeMap::new();
            for &i in &rows.ok {
                if let (Some(xi), Some(yi)) = (x[i], y[i]) {
                    lines
                        .entry(rows.group_of(i, Some(xname)))
                        .or_default()
                        .entry((xi * 1e9).round() as i64)
                        .or_insert((xi, Vec::new()))
                        .1
                        .push(yi);
                }
            }
            if lines.is_empty() {
                continue;
            }
            let f = lines_figure(&format!("{name} — {m}"), xname, m, &lines);
            let p = dir.join(format!("{m}.svg"));
            table::write_atomically(&p, f.to_svg().as_bytes())?;
            plots.push(p);
            // A heat map over the first two numeric axes.
            let numeric_axes: Vec<_> = rows.grid.iter().filter(|(_, _, x)| x.is_some()).collect();
            if let [(an, _, Some(ax)), (bn, _, Some(bx)), ..] = numeric_axes[..] {
                let svg = heat_map(&format!("{name} — {m}"), an, bn, m, &rows.ok, ax, bx, &y);
                let p = dir.join(format!("{m}-map.svg"));
                table::write_atomically(&p, svg.as_bytes())?;
                plots.push(p);
            }
        } else if !rows.study.random.is_empty() {
            // A histogram of the samples.
            let v: Vec<f64> = rows.ok.iter().filter_map(|&i| y[i]).collect();
            let Some(f) = histogram(name, m, &v) else {
                continue;
            };
            let p = dir.join(format!("{m}-histogram.svg"));
            table::write_atomically(&p, f.to_svg().as_bytes())?;
            plots.push(p);
        }
    }
    Ok(plots)
}

/// Builds the report of sweep folder `out` and writes its plots (SVG) and summary under
/// `out/report/`.
pub fn report(out: &Path) -> Result<Report, String> {
    let plan = Plan::load_frozen(out)?;
    let path = table::metrics_path(out);
    if !path.is_file() {
        return Err(format!(
            "{}: no table yet (run `gyrolab sweep run` first; `gyrolab sweep status` tells what is done)",
            path.display()
        ));
    }
    let study = &plan.study;
    let rows = Rows::new(study, table::read_parquet(&path)?);
    let dir = out.join("report");
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let report = Report {
        study: study.name.clone(),
        total_runs: plan.total_runs(),
        rows: rows.n,
        ok: rows.ok.len(),
        failed: rows.n - rows.ok.len(),
        fixed: study
            .grid
            .iter()
            .filter(|a| a.values.len() == 1)
            .map(|a| (a.key.name.clone(), a.values[0].to_string()))
            .collect(),
        harmonics: harmonic_fits(&rows),
        spreads: spreads(&rows),
        summary_markdown: summary_table(&rows),
        plots: write_plots(&rows, &dir)?,
    };
    let json = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
    table::write_atomically(&dir.join("report.json"), json.as_bytes())?;
    table::write_atomically(&dir.join("summary.md"), report.render().as_bytes())?;
    Ok(report)
}

impl Report {
    /// The report as text (Markdown tables).
    pub fn render(&self) -> String {
        let fixed = if self.fixed.is_empty() {
            String::new()
        } else {
            format!(
                "for every run: {}\n\n",
                self.fixed
                    .iter()
                    .map(|(k, v)| format!("{k} = {v}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        };
        let mut s = format!(
            "# {}: {} of {} runs in the table, {} ok, {} failed\n\n{fixed}{}\n",
            self.study, self.rows, self.total_runs, self.ok, self.failed, self.summary_markdown
        );
        if !self.harmonics.is_empty() {
            let mut t = Table::new(&[
                "metric",
                "against",
                "group",
                "order",
                "mean",
                "amplitude",
                "phase °",
                "rms residual",
                "points",
            ]);
            for h in &self.harmonics {
                t.row([
                    h.metric.clone(),
                    h.axis.clone(),
                    h.group
                        .iter()
                        .map(|(k, v)| format!("{k}={v}"))
                        .collect::<Vec<_>>()
                        .join(", "),
                    h.order.to_string(),
                    format!("{:.4e}", h.mean),
                    format!("{:.4e}", h.amplitude),
                    format!("{:.1}", h.phase_rad.to_degrees()),
                    format!("{:.2e}", h.rms_residual),
                    h.points.to_string(),
                ]);
            }
            s.push_str("\n## Harmonic fits\n\n");
            s.push_str(&t.render_markdown());
        }
        if !self.spreads.is_empty() {
            let mut t = Table::new(&[
                "metric", "group", "n", "mean", "std", "5 %", "25 %", "50 %", "75 %", "95 %",
            ]);
            for sp in &self.spreads {
                let mut cells = vec![
                    sp.metric.clone(),
                    sp.group
                        .iter()
                        .map(|(k, v)| format!("{k}={v}"))
                        .collect::<Vec<_>>()
                        .join(", "),
                    sp.n.to_string(),
                    format!("{:.4e}", sp.mean),
                    format!("{:.4e}", sp.std),
                ];
                cells.extend(sp.quantiles.iter().map(|q| format!("{q:.4e}")));
                t.row(cells);
            }
            s.push_str("\n## Spreads over the Monte Carlo samples\n\n");
            s.push_str(&t.render_markdown());
        }
        if !self.plots.is_empty() {
            s.push_str("\n## Plots\n\n");
            for p in &self.plots {
                s.push_str(&format!("- {}\n", p.display()));
            }
        }
        s
    }
}

/// A heat map (SVG) of the mean of `y` over two numeric axes.
#[allow(clippy::too_many_arguments)]
fn heat_map(
    title: &str,
    an: &str,
    bn: &str,
    metric: &str,
    rows: &[usize],
    ax: &[Option<f64>],
    bx: &[Option<f64>],
    y: &[Option<f64>],
) -> String {
    let key = |v: f64| (v * 1e9).round() as i64;
    let mut cells: BTreeMap<(i64, i64), (f64, f64, Vec<f64>)> = BTreeMap::new();
    for &i in rows {
        if let (Some(a), Some(b), Some(v)) = (ax[i], bx[i], y[i]) {
            cells
                .entry((key(a), key(b)))
                .or_insert((a, b, Vec::new()))
                .2
                .push(v);
        }
    }
    let mut avals: Vec<(i64, f64)> = cells.values().map(|c| (key(c.0), c.0)).collect();
    let mut bvals: Vec<(i64, f64)> = cells.values().map(|c| (key(c.1), c.1)).collect();
    avals.sort_by_key(|a| a.0);
    avals.dedup_by_key(|a| a.0);
    bvals.sort_by_key(|b| b.0);
    bvals.dedup_by_key(|b| b.0);
    let means: Vec<f64> = cells
        .values()
        .map(|c| c.2.iter().sum::<f64>() / c.2.len() as f64)
        .collect();
    let (lo, hi) = means
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(*x), b.max(*x))
        });
    let (w, h, left, top) = (900.0, 560.0, 110.0, 50.0);
    let (pw, ph) = (w - left - 140.0, h - top - 70.0);
    let cw = pw / avals.len().max(1) as f64;
    let chh = ph / bvals.len().max(1) as f64;
    let colour = |v: f64| {
        let t = if hi > lo { (v - lo) / (hi - lo) } else { 0.5 };
        // Blue → white → red.
        let (r, g, b) = if t < 0.5 {
            let s = t * 2.0;
            (s, s, 1.0)
        } else {
            let s = (1.0 - t) * 2.0;
            (1.0, s, s)
        };
        format!(
            "rgb({},{},{})",
            (r * 255.0) as u8,
            (g * 255.0) as u8,
            (b * 255.0) as u8
        )
    };
    let esc = |s: &str| {
        s.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"{}\" y=\"24\" font-size=\"15\">{}</text>\n",
        left,
        esc(title)
    );
    for ((ka, kb), (_, _, v)) in &cells {
        let i = avals.iter().position(|a| a.0 == *ka).unwrap_or(0);
        let j = bvals.iter().position(|b| b.0 == *kb).unwrap_or(0);
        let m = v.iter().sum::<f64>() / v.len() as f64;
        s.push_str(&format!(
            "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"{}\"><title>{an}={}, {bn}={}: {m:.4e}</title></rect>\n",
            left + i as f64 * cw,
            top + ph - (j + 1) as f64 * chh,
            cw,
            chh,
            colour(m),
            avals[i].1,
            bvals[j].1
        ));
    }
    let every_a = avals.len().div_ceil(12).max(1);
    for (i, a) in avals.iter().enumerate().step_by(every_a) {
        s.push_str(&format!(
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>\n",
            left + (i as f64 + 0.5) * cw,
            top + ph + 16.0,
            gyro_analysis::metrics::format_number(a.1)
        ));
    }
    let every_b = bvals.len().div_ceil(12).max(1);
    for (j, b) in bvals.iter().enumerate().step_by(every_b) {
        s.push_str(&format!(
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>\n",
            left - 6.0,
            top + ph - (j as f64 + 0.5) * chh + 4.0,
            gyro_analysis::metrics::format_number(b.1)
        ));
    }
    s.push_str(&format!(
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>\n<text x=\"16\" y=\"{:.1}\" transform=\"rotate(-90 16 {:.1})\" text-anchor=\"middle\">{}</text>\n",
        left + pw / 2.0,
        h - 20.0,
        esc(an),
        top + ph / 2.0,
        top + ph / 2.0,
        esc(bn)
    ));
    // Colour bar.
    for k in 0..20 {
        let v = lo + (hi - lo) * k as f64 / 19.0;
        s.push_str(&format!(
            "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"20\" height=\"{:.1}\" fill=\"{}\"/>\n",
            left + pw + 30.0,
            top + ph - (k + 1) as f64 * ph / 20.0,
            ph / 20.0 + 0.5,
            colour(v)
        ));
    }
    s.push_str(&format!(
        "<text x=\"{:.1}\" y=\"{:.1}\">{}</text>\n<text x=\"{:.1}\" y=\"{:.1}\">{}</text>\n<text x=\"{:.1}\" y=\"{:.1}\">{}</text>\n</svg>\n",
        left + pw + 55.0,
        top + 10.0,
        gyro_analysis::metrics::format_number(hi),
        left + pw + 55.0,
        top + ph,
        gyro_analysis::metrics::format_number(lo),
        left + pw + 10.0,
        top - 8.0,
        esc(metric)
    ));
    s
}
