//! The study file: base scenes and designs, grid axes and random axes over any scene or design
//! key, what to keep of each run. Read from TOML (values in the units of the key they set, which
//! names them); every error names the study file, the line and the key, and says what is allowed.
//!
//! ```toml
//! name = "anschutz-rolling"
//! scenes = ["rolling-intercardinal"]      # paths (relative to the study) or shipped names
//! designs = ["anschutz-1906"]             # optional: replaces each scene's design, crossed
//!
//! [[axis]]                                # a grid axis: `values`, or `from`/`to`/`count`
//! key = "start.heading_deg"               # a scene key; `design.parameters.kappa_n_m` a design's
//! from = 0.0
//! to = 330.0
//! count = 12
//! spacing = "linear"                      # or "log"
//!
//! [monte_carlo]                           # `samples` runs per grid point, drawn by run index
//! samples = 100
//! seed = 1906
//!
//! [[random]]
//! key = "sea.roll_amplitude_deg"
//! distribution = "uniform"                # uniform: low, high; normal: mean, std;
//! low = 1.0                               # lognormal: median, sigma_ln
//! high = 6.0
//!
//! [keep]
//! recordings = "none"                     # all | none | every:N | failed
//! metrics = ["steady_error_rad"]          # fitted metrics in the table (default: all)
//! max_storage_mb = 2000.0                 # more needs `--yes`
//! ```

use gyro_model::error::{InputError, from_toml};
use serde::Deserialize;
use std::ops::Range;
use toml::Spanned;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyFile {
    name: Spanned<String>,
    #[serde(default)]
    description: String,
    scenes: Spanned<Vec<Spanned<String>>>,
    #[serde(default)]
    designs: Vec<Spanned<String>>,
    #[serde(default)]
    axis: Vec<AxisFile>,
    #[serde(default)]
    monte_carlo: Option<MonteCarloFile>,
    #[serde(default)]
    random: Vec<RandomFile>,
    #[serde(default)]
    keep: Option<KeepFile>,
    #[serde(default)]
    report: Option<ReportFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AxisFile {
    key: Spanned<String>,
    #[serde(default)]
    values: Option<Spanned<Vec<Spanned<toml::Value>>>>,
    #[serde(default)]
    from: Option<Spanned<f64>>,
    #[serde(default)]
    to: Option<Spanned<f64>>,
    #[serde(default)]
    count: Option<Spanned<i64>>,
    #[serde(default)]
    spacing: Option<Spanned<String>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MonteCarloFile {
    samples: Spanned<i64>,
    #[serde(default)]
    seed: Option<Spanned<i64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RandomFile {
    key: Spanned<String>,
    distribution: Spanned<String>,
    #[serde(default)]
    low: Option<Spanned<f64>>,
    #[serde(default)]
    high: Option<Spanned<f64>>,
    #[serde(default)]
    mean: Option<Spanned<f64>>,
    #[serde(default)]
    std: Option<Spanned<f64>>,
    #[serde(default)]
    median: Option<Spanned<f64>>,
    #[serde(default)]
    sigma_ln: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct KeepFile {
    #[serde(default)]
    recordings: Option<Spanned<String>>,
    #[serde(default)]
    metrics: Option<Spanned<Vec<Spanned<String>>>>,
    #[serde(default)]
    max_storage_mb: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ReportFile {
    #[serde(default)]
    harmonic: Vec<HarmonicFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HarmonicFile {
    metric: Spanned<String>,
    axis: Spanned<String>,
    order: Spanned<i64>,
}

/// Where an axis's value goes: a scene key (dotted path into the scene file; arrays of tables by
/// `name` or index) or a design key (a dotted path into the design file, applied through the
/// scene's `[compass] design_overrides`).
#[derive(Clone, Debug, PartialEq)]
pub enum Target {
    Scene(Vec<String>),
    Design(String),
}

/// A key a study sets, as written (`start.heading_deg`, `design.parameters.kappa_n_m`) and
/// where it goes.
#[derive(Clone, Debug, PartialEq)]
pub struct Key {
    pub name: String,
    pub target: Target,
    /// 1-based line of the axis in the study file.
    pub line: usize,
}

/// The design prefix of a key.
pub const DESIGN_PREFIX: &str = "design.";

impl Key {
    fn parse(name: &str, line: usize) -> Result<Key, String> {
        let parts: Vec<&str> = name.split('.').collect();
        if name.is_empty() || parts.iter().any(|p| p.trim().is_empty() || p.trim() != *p) {
            return Err(format!(
                "`{name}` is not a dotted key path (allowed: e.g. `start.heading_deg`, `sea.roll_period_s`, `design.parameters.kappa_n_m`)"
            ));
        }
        let target = match name.strip_prefix(DESIGN_PREFIX) {
            Some(rest) => Target::Design(rest.to_string()),
            None => {
                if parts[0] == "name" || parts[0] == "description" {
                    return Err(format!(
                        "`{name}` names the scene, it is not a quantity to vary"
                    ));
                }
                if parts.len() >= 2 && parts[0] == "compass" && parts[1] == "design" {
                    return Err(format!(
                        "`{name}`: the design is chosen with the study's `designs` list, its keys with `design.…`"
                    ));
                }
                Target::Scene(parts.iter().map(|s| s.to_string()).collect())
            }
        };
        Ok(Key {
            name: name.to_string(),
            target,
            line,
        })
    }
}

/// A random axis's distribution, in the key's units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Distribution {
    Uniform {
        low: f64,
        high: f64,
    },
    Normal {
        mean: f64,
        std: f64,
    },
    /// exp(N(ln median, sigma_ln²)).
    LogNormal {
        median: f64,
        sigma_ln: f64,
    },
}

/// A grid axis: its values, in order.
#[derive(Clone, Debug, PartialEq)]
pub struct GridAxis {
    pub key: Key,
    pub values: Vec<toml::Value>,
}

/// A random axis.
#[derive(Clone, Debug, PartialEq)]
pub struct RandomAxis {
    pub key: Key,
    pub distribution: Distribution,
}

/// Which runs keep their MCAP recording.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeepRecordings {
    All,
    None,
    /// Runs whose index is a multiple of N.
    Every(u64),
    Failed,
}

impl KeepRecordings {
    /// Whether run `index` keeps its recording, given whether it failed.
    pub fn keeps(&self, index: u64, failed: bool) -> bool {
        match self {
            KeepRecordings::All => true,
            KeepRecordings::None => false,
            KeepRecordings::Every(n) => index.is_multiple_of(*n),
            KeepRecordings::Failed => failed,
        }
    }
}

impl std::fmt::Display for KeepRecordings {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            KeepRecordings::All => write!(f, "all"),
            KeepRecordings::None => write!(f, "none"),
            KeepRecordings::Every(n) => write!(f, "every:{n}"),
            KeepRecordings::Failed => write!(f, "failed"),
        }
    }
}

/// A fit of a metric against an angle axis: a₀ + Σ (aₖ cos kx + bₖ sin kx) up to `order`, per
/// value of the other axes; the report gives the amplitude of the `order`-th harmonic.
#[derive(Clone, Debug, PartialEq)]
pub struct Harmonic {
    pub metric: String,
    pub axis: String,
    pub order: u32,
}

/// A checked study.
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    pub name: String,
    pub description: String,
    /// The study file as named on the command line (for errors).
    pub file: String,
    pub text: String,
    /// Base scenes and designs as written (paths relative to the study, or shipped names), with
    /// their lines.
    pub scenes: Vec<(String, usize)>,
    pub designs: Vec<(String, usize)>,
    pub grid: Vec<GridAxis>,
    pub random: Vec<RandomAxis>,
    /// Monte Carlo samples per grid point (1 without random axes).
    pub samples: u64,
    pub seed: u64,
    pub recordings: KeepRecordings,
    /// The fitted metrics the table keeps (every one when the study does not say).
    pub metrics: Vec<String>,
    pub max_storage_mb: f64,
    pub harmonics: Vec<Harmonic>,
}

/// The fitted metrics a study may keep (columns of `gyrolab analyze`'s table).
pub const METRICS: &[&str] = &[
    "azimuth_quality",
    "period_s",
    "period_sigma_s",
    "log_decrement",
    "log_decrement_sigma",
    "damping_ratio",
    "damping_ratio_sigma",
    "amplitude_rad",
    "tilt_quality",
    "tilt_period_s",
    "tilt_period_sigma_s",
    "tilt_log_decrement",
    "tilt_log_decrement_sigma",
    "steady_error_rad",
    "steady_error_sigma_rad",
    "steady_drift_rad_per_s",
    "steady_drift_sigma_rad_per_s",
    "start_error_rad",
    "ballistic_events",
    "ballistic_peak_rad",
    "ballistic_expected_peak_rad",
    "ballistic_settle_s",
    "ballistic_swing_rad",
    "ballistic_backswing_rate_rad_per_s",
    "rolling_error_rad",
    "rolling_error_sigma_rad",
    "roll_period_s",
];

/// Default storage limit of a study (MB) past which `sweep run` asks for `--yes`.
pub const DEFAULT_MAX_STORAGE_MB: f64 = 2000.0;

/// Largest number of runs a study may have.
pub const MAX_RUNS: u64 = 1_000_000_000;

struct Src<'a> {
    file: &'a str,
    text: &'a str,
}

impl Src<'_> {
    fn line(&self, span: Range<usize>) -> usize {
        self.text[..span.start.min(self.text.len())]
            .matches('\n')
            .count()
            + 1
    }
    fn err(&self, span: Range<usize>, key: &str, message: impl Into<String>) -> InputError {
        InputError {
            file: self.file.to_string(),
            line: Some(self.line(span)),
            key: key.to_string(),
            message: message.into(),
        }
    }
}

impl Study {
    /// Reads a study file.
    pub fn load(path: &std::path::Path) -> Result<Study, InputError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| InputError {
            file: file.clone(),
            line: None,
            key: "(file)".into(),
            message: format!("cannot read: {e}"),
        })?;
        Study::from_toml(&file, &text)
    }

    /// Reads and checks a study's text (the syntax and the study's own rules; the keys against
    /// the scenes and designs are checked by [`crate::Plan`]).
    pub fn from_toml(file: &str, text: &str) -> Result<Study, InputError> {
        let f: StudyFile = toml::from_str(text).map_err(|e| from_toml(file, text, &e))?;
        let src = Src { file, text };
        let name = f.name.get_ref().trim().to_string();
        if name.is_empty()
            || !name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return Err(src.err(
                f.name.span(),
                "name",
                format!(
                    "`{name}` is not a study name (allowed: letters, digits, `-` and `_`, not empty)"
                ),
            ));
        }
        if f.scenes.get_ref().is_empty() {
            return Err(src.err(
                f.scenes.span(),
                "scenes",
                "no base scene (allowed: a list of scene paths or shipped names, at least one)",
            ));
        }
        let scenes = name_list(f.scenes.get_ref(), "scenes", &src)?;
        let designs = name_list(&f.designs, "designs", &src)?;

        let mut grid = Vec::new();
        for (k, a) in f.axis.iter().enumerate() {
            grid.push(grid_axis(a, k, &src)?);
        }
        let (samples, seed) = monte_carlo(f.monte_carlo.as_ref(), &src)?;
        let mut random = Vec::new();
        for (k, r) in f.random.iter().enumerate() {
            random.push(random_axis(r, k, &src)?);
        }
        if !random.is_empty() && f.monte_carlo.is_none() {
            let r = &f.random[0];
            return Err(src.err(
                r.key.span(),
                "random",
                "random axes need a `[monte_carlo]` table with `samples` (and a `seed`)",
            ));
        }
        one_axis_per_key(&grid, &random, file)?;

        let (recordings, metrics, max_storage_mb) = keep(f.keep.as_ref(), &src)?;
        let harmonics = harmonics(f.report.as_ref(), &grid, &src)?;

        let study = Study {
            name,
            description: f.description,
            file: file.to_string(),
            text: text.to_string(),
            scenes,
            designs,
            grid,
            random,
            samples,
            seed,
            recordings,
            metrics,
            max_storage_mb,
            harmonics,
        };
        let total = study.dimensions().iter().try_fold(1u64, |acc, &d| {
            acc.checked_mul(d).filter(|t| *t <= MAX_RUNS)
        });
        if total.is_none() {
            return Err(InputError {
                file: file.to_string(),
                line: None,
                key: "axis".into(),
                message: format!("the study has more than {MAX_RUNS} runs (allowed: at most that)"),
            });
        }
        Ok(study)
    }

    /// The sizes of the run index's digits, slowest first: scenes, designs, each grid axis, the
    /// Monte Carlo samples.
    pub fn dimensions(&self) -> Vec<u64> {
        let mut d = vec![self.scenes.len() as u64, self.designs.len().max(1) as u64];
        d.extend(self.grid.iter().map(|a| a.values.len() as u64));
        d.push(self.samples);
        d
    }

    /// How many runs the study has.
    pub fn total_runs(&self) -> u64 {
        self.dimensions().iter().product()
    }

    /// The line of `key` (an axis key) in the study file.
    pub fn line_of(&self, key: &str) -> Option<usize> {
        self.grid
            .iter()
            .map(|a| &a.key)
            .chain(self.random.iter().map(|a| &a.key))
            .find(|k| k.name == key)
            .map(|k| k.line)
    }
}

/// A list of scene or design names: none empty, none twice; with each one's line.
fn name_list(
    v: &[Spanned<String>],
    key: &str,
    src: &Src,
) -> Result<Vec<(String, usize)>, InputError> {
    let mut out: Vec<(String, usize)> = Vec::new();
    for s in v {
        let r = s.get_ref().trim().to_string();
        if r.is_empty() {
            return Err(src.err(s.span(), key, "an empty name"));
        }
        if out.iter().any(|(x, _)| *x == r) {
            return Err(src.err(s.span(), key, format!("`{r}` is listed twice")));
        }
        out.push((r, src.line(s.span())));
    }
    Ok(out)
}

/// The `[monte_carlo]` table: (samples, seed); one sample and seed 0 without it.
fn monte_carlo(mc: Option<&MonteCarloFile>, src: &Src) -> Result<(u64, u64), InputError> {
    let Some(mc) = mc else {
        return Ok((1, 0));
    };
    let n = *mc.samples.get_ref();
    if n < 1 {
        return Err(src.err(
            mc.samples.span(),
            "monte_carlo.samples",
            format!("{n} is out of range (allowed: ≥ 1)"),
        ));
    }
    let seed = match &mc.seed {
        None => 0,
        Some(s) if *s.get_ref() < 0 => {
            return Err(src.err(
                s.span(),
                "monte_carlo.seed",
                format!("{} is out of range (allowed: ≥ 0)", s.get_ref()),
            ));
        }
        Some(s) => *s.get_ref() as u64,
    };
    Ok((n as u64, seed))
}

/// No key is set by two axes (grid or random).
fn one_axis_per_key(
    grid: &[GridAxis],
    random: &[RandomAxis],
    file: &str,
) -> Result<(), InputError> {
    let mut seen: Vec<&str> = Vec::new();
    for (name, line) in grid
        .iter()
        .map(|a| (&a.key.name, a.key.line))
        .chain(random.iter().map(|a| (&a.key.name, a.key.line)))
    {
        if seen.contains(&name.as_str()) {
            return Err(InputError {
                file: file.to_string(),
                line: Some(line),
                key: name.clone(),
                message: "this key is set by two axes (allowed: one axis per key)".into(),
            });
        }
        seen.push(name);
    }
    Ok(())
}

/// The `[[report.harmonic]]` fits: a known metric, a grid axis of this study, order 1 … 8.
fn harmonics(
    report: Option<&ReportFile>,
    grid: &[GridAxis],
    src: &Src,
) -> Result<Vec<Harmonic>, InputError> {
    let mut harmonics = Vec::new();
    for h in report.iter().flat_map(|r| &r.harmonic) {
        let metric = h.metric.get_ref().clone();
        if !METRICS.contains(&metric.as_str()) {
            return Err(src.err(
                h.metric.span(),
                "report.harmonic.metric",
                format!(
                    "unknown metric `{metric}` (allowed: {})",
                    METRICS.join(", ")
                ),
            ));
        }
        let axis = h.axis.get_ref().clone();
        if !grid.iter().any(|a| a.key.name == axis) {
            return Err(src.err(
                h.axis.span(),
                "report.harmonic.axis",
                format!(
                    "`{axis}` is not a grid axis of this study (allowed: {})",
                    grid.iter()
                        .map(|a| a.key.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        let order = *h.order.get_ref();
        if !(1..=8).contains(&order) {
            return Err(src.err(
                h.order.span(),
                "report.harmonic.order",
                format!("{order} is out of range (allowed: 1 … 8)"),
            ));
        }
        harmonics.push(Harmonic {
            metric,
            axis,
            order: order as u32,
        });
    }
    Ok(harmonics)
}

fn grid_axis(a: &AxisFile, k: usize, src: &Src) -> Result<GridAxis, InputError> {
    let name = a.key.get_ref().clone();
    let line = src.line(a.key.span());
    let key = Key::parse(&name, line).map_err(|m| src.err(a.key.span(), "axis.key", m))?;
    let here = |span: Range<usize>, m: String| src.err(span, &name, m);
    let range_keys = a.from.is_some() || a.to.is_some() || a.count.is_some();
    let values: Vec<toml::Value> = match (&a.values, range_keys) {
        (Some(_), true) => {
            return Err(here(
                a.key.span(),
                format!(
                    "axis {} has both `values` and `from`/`to`/`count` (allowed: one of them)",
                    k + 1
                ),
            ));
        }
        (Some(v), false) => {
            if let Some(s) = &a.spacing {
                return Err(here(
                    s.span(),
                    "`spacing` belongs to a range (`from`/`to`/`count`)".into(),
                ));
            }
            if v.get_ref().is_empty() {
                return Err(here(
                    v.span(),
                    "empty `values` (allowed: at least one value)".into(),
                ));
            }
            let mut out = Vec::new();
            for x in v.get_ref() {
                let value = match x.get_ref() {
                    toml::Value::Integer(i) => toml::Value::Float(*i as f64),
                    toml::Value::Float(f) if !f.is_finite() => {
                        return Err(here(
                            x.span(),
                            format!("{f} is not finite (allowed: finite numbers)"),
                        ));
                    }
                    v @ (toml::Value::Float(_)
                    | toml::Value::String(_)
                    | toml::Value::Boolean(_)) => v.clone(),
                    other => {
                        return Err(here(
                            x.span(),
                            format!(
                                "a {} (allowed: numbers, strings or booleans)",
                                other.type_str()
                            ),
                        ));
                    }
                };
                if let Some(first) = out.first()
                    && std::mem::discriminant(first) != std::mem::discriminant(&value)
                {
                    return Err(here(
                        x.span(),
                        format!(
                            "a {} among {}s (allowed: values of one type per axis)",
                            value.type_str(),
                            toml::Value::type_str(first)
                        ),
                    ));
                }
                if out.contains(&value) {
                    return Err(here(x.span(), format!("{value} is listed twice")));
                }
                out.push(value);
            }
            out
        }
        (None, true) => {
            let (Some(from), Some(to), Some(count)) = (&a.from, &a.to, &a.count) else {
                return Err(here(
                    a.key.span(),
                    "a range needs `from`, `to` and `count`".into(),
                ));
            };
            let (x0, x1, n) = (*from.get_ref(), *to.get_ref(), *count.get_ref());
            if n < 1 {
                return Err(here(
                    count.span(),
                    format!("empty range: count = {n} (allowed: count ≥ 1)"),
                ));
            }
            if !x0.is_finite() || !x1.is_finite() {
                return Err(here(from.span(), "`from` and `to` must be finite".into()));
            }
            if n > 1 && x0 == x1 {
                return Err(here(
                    to.span(),
                    format!(
                        "empty range: from = to = {x0} with count = {n} (allowed: from ≠ to, or count = 1)"
                    ),
                ));
            }
            let log = match a.spacing.as_ref().map(|s| (s.get_ref().as_str(), s.span())) {
                None | Some(("linear", _)) => false,
                Some(("log", _)) => true,
                Some((other, span)) => {
                    return Err(here(
                        span,
                        format!("unknown spacing `{other}` (allowed: linear, log)"),
                    ));
                }
            };
            if log && !(x0 > 0.0 && x1 > 0.0) {
                return Err(here(
                    from.span(),
                    format!("a log range from {x0} to {x1} (allowed: from > 0 and to > 0)"),
                ));
            }
            if n > 100_000 {
                return Err(here(
                    count.span(),
                    format!("count = {n} is out of range (allowed: ≤ 100000 per axis)"),
                ));
            }
            (0..n)
                .map(|i| {
                    let steps = (n - 1).max(1) as f64;
                    // (x1 − x0)·i/(n − 1): exact for round steps (0 … 75 by 5 gives 55, not
                    // 54.999…).
                    let x = if log {
                        (x0.ln() + (x1.ln() - x0.ln()) * i as f64 / steps).exp()
                    } else {
                        x0 + (x1 - x0) * i as f64 / steps
                    };
                    // The ends exactly as written.
                    let x = if i == 0 {
                        x0
                    } else if i == n - 1 {
                        x1
                    } else {
                        x
                    };
                    toml::Value::Float(x)
                })
                .collect()
        }
        (None, false) => {
            return Err(here(
                a.key.span(),
                "an axis needs `values`, or `from`, `to` and `count`".into(),
            ));
        }
    };
    Ok(GridAxis { key, values })
}

fn random_axis(r: &RandomFile, _k: usize, src: &Src) -> Result<RandomAxis, InputError> {
    let name = r.key.get_ref().clone();
    let line = src.line(r.key.span());
    let key = Key::parse(&name, line).map_err(|m| src.err(r.key.span(), "random.key", m))?;
    let here = |span: Range<usize>, m: String| src.err(span, &name, m);
    let need = |v: &Option<Spanned<f64>>,
                what: &str,
                dist: &str|
     -> Result<(f64, Range<usize>), InputError> {
        match v {
            Some(x) if x.get_ref().is_finite() => Ok((*x.get_ref(), x.span())),
            Some(x) => Err(here(x.span(), format!("`{what}` must be finite"))),
            None => Err(here(
                r.distribution.span(),
                format!("a {dist} distribution needs `{what}`"),
            )),
        }
    };
    let present = |fields: &[(&str, bool)], dist: &str| -> Result<(), InputError> {
        for (f, p) in fields {
            if *p {
                return Err(here(
                    r.distribution.span(),
                    format!("`{f}` does not belong to a {dist} distribution"),
                ));
            }
        }
        Ok(())
    };
    let d = r.distribution.get_ref().as_str();
    let distribution = match d {
        "uniform" => {
            present(
                &[
                    ("mean", r.mean.is_some()),
                    ("std", r.std.is_some()),
                    ("median", r.median.is_some()),
                    ("sigma_ln", r.sigma_ln.is_some()),
                ],
                d,
            )?;
            let (low, _) = need(&r.low, "low", d)?;
            let (high, span) = need(&r.high, "high", d)?;
            if high <= low {
                return Err(here(
                    span,
                    format!("empty range: low = {low}, high = {high} (allowed: low < high)"),
                ));
            }
            Distribution::Uniform { low, high }
        }
        "normal" => {
            present(
                &[
                    ("low", r.low.is_some()),
                    ("high", r.high.is_some()),
                    ("median", r.median.is_some()),
                    ("sigma_ln", r.sigma_ln.is_some()),
                ],
                d,
            )?;
            let (mean, _) = need(&r.mean, "mean", d)?;
            let (std, span) = need(&r.std, "std", d)?;
            if std <= 0.0 {
                return Err(here(span, format!("std = {std} (allowed: > 0)")));
            }
            Distribution::Normal { mean, std }
        }
        "lognormal" => {
            present(
                &[
                    ("low", r.low.is_some()),
                    ("high", r.high.is_some()),
                    ("mean", r.mean.is_some()),
                    ("std", r.std.is_some()),
                ],
                d,
            )?;
            let (median, mspan) = need(&r.median, "median", d)?;
            let (sigma_ln, span) = need(&r.sigma_ln, "sigma_ln", d)?;
            if median <= 0.0 {
                return Err(here(mspan, format!("median = {median} (allowed: > 0)")));
            }
            if sigma_ln <= 0.0 {
                return Err(here(span, format!("sigma_ln = {sigma_ln} (allowed: > 0)")));
            }
            Distribution::LogNormal { median, sigma_ln }
        }
        other => {
            return Err(here(
                r.distribution.span(),
                format!("unknown distribution `{other}` (allowed: uniform, normal, lognormal)"),
            ));
        }
    };
    Ok(RandomAxis { key, distribution })
}

fn keep(k: Option<&KeepFile>, src: &Src) -> Result<(KeepRecordings, Vec<String>, f64), InputError> {
    let all: Vec<String> = METRICS.iter().map(|s| s.to_string()).collect();
    let Some(k) = k else {
        return Ok((KeepRecordings::None, all, DEFAULT_MAX_STORAGE_MB));
    };
    let recordings = match &k.recordings {
        None => KeepRecordings::None,
        Some(r) => {
            let s = r.get_ref().as_str();
            let bad = || {
                src.err(
                    r.span(),
                    "keep.recordings",
                    format!(
                        "`{s}` (allowed: \"all\", \"none\", \"every:N\" with N ≥ 1, \"failed\")"
                    ),
                )
            };
            match s {
                "all" => KeepRecordings::All,
                "none" => KeepRecordings::None,
                "failed" => KeepRecordings::Failed,
                _ => {
                    let n: u64 = s
                        .strip_prefix("every:")
                        .and_then(|n| n.trim().parse().ok())
                        .ok_or_else(bad)?;
                    if n == 0 {
                        return Err(bad());
                    }
                    KeepRecordings::Every(n)
                }
            }
        }
    };
    let metrics = match &k.metrics {
        None => all,
        Some(list) => {
            if list.get_ref().is_empty() {
                return Err(src.err(
                    list.span(),
                    "keep.metrics",
                    "an empty list (allowed: leave `metrics` out for every metric)",
                ));
            }
            let mut out = Vec::new();
            for m in list.get_ref() {
                if !METRICS.contains(&m.get_ref().as_str()) {
                    return Err(src.err(
                        m.span(),
                        "keep.metrics",
                        format!(
                            "unknown metric `{}` (allowed: {})",
                            m.get_ref(),
                            METRICS.join(", ")
                        ),
                    ));
                }
                if !out.contains(m.get_ref()) {
                    out.push(m.get_ref().clone());
                }
            }
            out
        }
    };
    let max = match &k.max_storage_mb {
        None => DEFAULT_MAX_STORAGE_MB,
        Some(m) if m.get_ref().is_finite() && *m.get_ref() > 0.0 => *m.get_ref(),
        Some(m) => {
            return Err(src.err(
                m.span(),
                "keep.max_storage_mb",
                format!("{} is out of range (allowed: > 0)", m.get_ref()),
            ));
        }
    };
    Ok((recordings, metrics, max))
}
