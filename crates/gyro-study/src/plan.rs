//! A study resolved against its scenes and designs: the pure map from a run index to that run's
//! scene (every axis value applied through the scene's keys or the design's overrides), the
//! checks of every axis before any run starts, and the frozen copy of the inputs a sweep's
//! folder keeps so that any node, a retry or a resume builds exactly the same runs.

use crate::draw;
use crate::study::{Distribution, Study, Target};
use gyro_model::error::InputError;
use gyro_sim::{Scene, SceneOverrides};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A scene or design file as the study uses it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Input {
    /// As the study (or the scene) wrote it.
    pub reference: String,
    /// Where it was read from (a path, or `<shipped … NAME>`): errors name it.
    pub label: String,
    pub text: String,
    /// The file a scene's `compass.design` is set to (absolute), for designs.
    #[serde(skip)]
    pub path: Option<PathBuf>,
}

/// A resolved study: the study, its base scenes with each scene's own design, and the study's
/// designs.
#[derive(Clone, Debug)]
pub struct Plan {
    pub study: Study,
    pub scenes: Vec<Input>,
    pub scene_designs: Vec<Input>,
    pub designs: Vec<Input>,
}

/// One run: its index, which base scene and design, and every axis value (grid axes, then
/// random axes, in the study's order).
#[derive(Clone, Debug, PartialEq)]
pub struct RunSpec {
    pub index: u64,
    pub scene: usize,
    pub design: Option<usize>,
    /// Monte Carlo sample number (0 without random axes).
    pub sample: u64,
    pub values: Vec<toml::Value>,
}

fn read_err(file: &str, line: Option<usize>, key: &str, m: impl Into<String>) -> InputError {
    InputError {
        file: file.to_string(),
        line,
        key: key.to_string(),
        message: m.into(),
    }
}

fn resolve(
    reference: &str,
    study_dir: &Path,
    folder: &str,
    shipped: &[(&str, &str)],
) -> Option<(String, String, Option<PathBuf>)> {
    for p in [study_dir.join(reference), PathBuf::from(reference)] {
        if p.is_file() {
            let text = std::fs::read_to_string(&p).ok()?;
            let abs = std::path::absolute(&p).unwrap_or(p.clone());
            return Some((p.display().to_string(), text, Some(abs)));
        }
    }
    let q = study_dir
        .join("..")
        .join(folder)
        .join(format!("{reference}.toml"));
    if q.is_file() {
        let text = std::fs::read_to_string(&q).ok()?;
        return Some((q.display().to_string(), text, std::path::absolute(&q).ok()));
    }
    shipped
        .iter()
        .find(|(n, _)| *n == reference)
        .map(|(n, t)| (format!("<shipped {folder} {n}>"), t.to_string(), None))
}

impl Plan {
    /// Resolves a study: its scenes and designs (paths relative to the study file, then the
    /// shipped library), then checks every axis against them.
    pub fn new(study: Study) -> Result<Plan, InputError> {
        let study_dir = Path::new(&study.file)
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default();
        let mut scenes = Vec::new();
        for (r, line) in &study.scenes {
            let (label, text, _) = resolve(r, &study_dir, "scenes", gyro_sim::library::SCENES)
                .ok_or_else(|| {
                    read_err(
                        &study.file,
                        Some(*line),
                        "scenes",
                        format!(
                            "no scene `{r}`: no such file next to the study or here, and no shipped scene of that name (see `gyrolab scenes`)"
                        ),
                    )
                })?;
            scenes.push(Input {
                reference: r.clone(),
                label,
                text,
                path: None,
            });
        }
        let mut designs = Vec::new();
        for (r, line) in &study.designs {
            let (label, text, path) =
                resolve(r, &study_dir, "designs", gyro_sim::library::DESIGNS).ok_or_else(
                    || {
                        read_err(
                            &study.file,
                            Some(*line),
                            "designs",
                            format!(
                                "no design `{r}`: no such file next to the study or here, and no shipped design of that name (see `gyrolab designs`)"
                            ),
                        )
                    },
                )?;
            designs.push(Input {
                reference: r.clone(),
                label,
                text,
                path: path.or_else(|| Some(PathBuf::from(r))),
            });
        }
        // Each scene's own design, as the scene reads it.
        let mut scene_designs = Vec::new();
        for (s, (_, line)) in scenes.iter().zip(&study.scenes) {
            let dir = Path::new(&s.label)
                .parent()
                .filter(|_| !s.label.starts_with('<'));
            let scene = Scene::from_toml(&s.label, &s.text, dir, &SceneOverrides::default())
                .map_err(|e| {
                    read_err(
                        &study.file,
                        Some(*line),
                        "scenes",
                        format!("the base scene does not load: {e}"),
                    )
                })?;
            let reference = toml::from_str::<toml::Value>(&s.text)
                .ok()
                .and_then(|v| Some(v.get("compass")?.get("design")?.as_str()?.to_string()))
                .unwrap_or_default();
            let path = if scene.design_path.starts_with('<') {
                Some(PathBuf::from(&reference))
            } else {
                std::path::absolute(&scene.design_path).ok()
            };
            scene_designs.push(Input {
                reference,
                label: scene.design_path.clone(),
                text: scene.design.source_text.clone(),
                path,
            });
        }
        let plan = Plan {
            study,
            scenes,
            scene_designs,
            designs,
        };
        plan.check()?;
        Ok(plan)
    }

    /// How many runs.
    pub fn total_runs(&self) -> u64 {
        self.study.total_runs()
    }

    /// The axis keys in the order of [`RunSpec::values`]: grid axes, then random axes.
    pub fn axis_keys(&self) -> Vec<&str> {
        self.study
            .grid
            .iter()
            .map(|a| a.key.name.as_str())
            .chain(self.study.random.iter().map(|a| a.key.name.as_str()))
            .collect()
    }

    /// Run `index`'s scene, design and axis values: the index's digits (slowest first) are the
    /// scene, the design, each grid axis, and the Monte Carlo sample; random values are drawn
    /// from (seed, sample, axis), so every grid point and design sees the same samples (common
    /// random numbers: differences between designs are not sampling noise).
    pub fn run(&self, index: u64) -> RunSpec {
        let dims = self.study.dimensions();
        let mut digits = vec![0u64; dims.len()];
        let mut rest = index;
        for (d, n) in digits.iter_mut().zip(&dims).rev() {
            *d = rest % n;
            rest /= n;
        }
        let g = self.study.grid.len();
        let mut values: Vec<toml::Value> = self
            .study
            .grid
            .iter()
            .enumerate()
            .map(|(k, a)| a.values[digits[2 + k] as usize].clone())
            .collect();
        let sample = digits[2 + g];
        for (k, a) in self.study.random.iter().enumerate() {
            values.push(toml::Value::Float(draw_value(
                &a.distribution,
                self.study.seed,
                sample,
                k as u64,
            )));
        }
        RunSpec {
            index,
            scene: digits[0] as usize,
            design: (!self.designs.is_empty()).then_some(digits[1] as usize),
            sample,
            values,
        }
    }

    /// The design a run uses.
    pub fn design_of(&self, spec: &RunSpec) -> &Input {
        match spec.design {
            Some(d) => &self.designs[d],
            None => &self.scene_designs[spec.scene],
        }
    }

    /// The scene file of a run (the base scene with its design and every axis value set).
    pub fn scene_text(&self, spec: &RunSpec) -> Result<String, String> {
        let keys = self.axis_keys();
        let pairs: Vec<(&str, &toml::Value)> =
            keys.iter().copied().zip(spec.values.iter()).collect();
        self.scene_text_with(spec.scene, self.design_of(spec), &pairs)
    }

    fn scene_text_with(
        &self,
        scene: usize,
        design: &Input,
        values: &[(&str, &toml::Value)],
    ) -> Result<String, String> {
        let mut doc: toml::Value = toml::from_str(&self.scenes[scene].text)
            .map_err(|e| format!("{}: {e}", self.scenes[scene].label))?;
        let design_ref = design
            .path
            .as_ref()
            .map(|p| p.display().to_string())
            .unwrap_or_else(|| design.reference.clone());
        set_path(
            &mut doc,
            &["compass".into(), "design".into()],
            toml::Value::String(design_ref),
        )?;
        for (name, value) in values {
            let key = self
                .study
                .grid
                .iter()
                .map(|a| &a.key)
                .chain(self.study.random.iter().map(|a| &a.key))
                .find(|k| k.name == *name)
                .ok_or_else(|| format!("no axis `{name}`"))?;
            match &key.target {
                Target::Scene(parts) => set_path(&mut doc, parts, (*value).clone())?,
                Target::Design(path) => {
                    let mut parts: Vec<String> = vec!["compass".into(), "design_overrides".into()];
                    parts.push(path.clone());
                    set_flat(&mut doc, &parts, (*value).clone())?
                }
            }
        }
        toml::to_string(&doc).map_err(|e| format!("writing the run's scene: {e}"))
    }

    /// The scene of a run, checked.
    pub fn scene(&self, spec: &RunSpec) -> Result<Scene, String> {
        let text = self.scene_text(spec)?;
        Scene::from_toml(
            &self.scenes[spec.scene].label,
            &text,
            None,
            &SceneOverrides::default(),
        )
        .map_err(|e| e.to_string())
    }

    /// Checks every axis against every scene and design before any run: the key exists (a
    /// design key in every design the study uses; a scene key in the scene file or as an
    /// optional key the scene format knows), and each value (a grid axis's every value, a random
    /// axis's smallest and largest draw) gives a scene that loads, with the other axes at the
    /// base scene's values.
    pub fn check(&self) -> Result<(), InputError> {
        let study = &self.study;
        let err = |line: usize, key: &str, m: String| InputError {
            file: study.file.clone(),
            line: Some(line),
            key: key.to_string(),
            message: m,
        };
        let designs: Vec<&Input> = if self.designs.is_empty() {
            self.scene_designs.iter().collect()
        } else {
            self.designs.iter().collect()
        };
        let mut checks: Vec<(&crate::study::Key, Vec<toml::Value>)> = Vec::new();
        for a in &study.grid {
            checks.push((&a.key, a.values.clone()));
        }
        for (k, a) in study.random.iter().enumerate() {
            let (lo, hi) = draw_extremes(&a.distribution, study.seed, study.samples, k as u64);
            checks.push((&a.key, vec![toml::Value::Float(lo), toml::Value::Float(hi)]));
        }
        for (key, values) in &checks {
            if let Target::Design(path) = &key.target {
                for d in &designs {
                    let doc: toml::Value = toml::from_str(&d.text)
                        .map_err(|e| err(key.line, &key.name, format!("{}: {e}", d.label)))?;
                    if let Err(m) = get_path(&doc, path) {
                        return Err(err(
                            key.line,
                            &key.name,
                            format!("unknown key: design {} has no `{path}`: {m}", d.label),
                        ));
                    }
                }
            }
            for s in 0..self.scenes.len() {
                let ds: Vec<&Input> = if self.designs.is_empty() {
                    vec![&self.scene_designs[s]]
                } else {
                    self.designs.iter().collect()
                };
                for d in ds {
                    for v in values {
                        let text = self
                            .scene_text_with(s, d, &[(key.name.as_str(), v)])
                            .map_err(|m| err(key.line, &key.name, m))?;
                        if let Err(e) = Scene::from_toml(
                            &self.scenes[s].label,
                            &text,
                            None,
                            &SceneOverrides::default(),
                        ) {
                            let unknown = e.message.contains("unknown field");
                            let what = if unknown {
                                format!(
                                    "unknown key: scene {} has no `{}` ({})",
                                    self.scenes[s].label, key.name, e.message
                                )
                            } else {
                                format!(
                                    "value {v} refused by scene {} with design {}: `{}`: {}",
                                    self.scenes[s].label, d.label, e.key, e.message
                                )
                            };
                            return Err(err(key.line, &key.name, what));
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// A random axis's value for a sample.
pub fn draw_value(d: &Distribution, seed: u64, sample: u64, axis: u64) -> f64 {
    match *d {
        Distribution::Uniform { low, high } => {
            low + (high - low) * draw::uniform(seed, sample, axis, 0)
        }
        Distribution::Normal { mean, std } => mean + std * draw::normal(seed, sample, axis),
        Distribution::LogNormal { median, sigma_ln } => {
            median * (sigma_ln * draw::normal(seed, sample, axis)).exp()
        }
    }
}

/// The smallest and largest value a random axis draws over the study's samples (the first
/// million of them: beyond, the draws only fill in).
fn draw_extremes(d: &Distribution, seed: u64, samples: u64, axis: u64) -> (f64, f64) {
    (0..samples.min(1_000_000))
        .map(|s| draw_value(d, seed, s, axis))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        })
}

/// Sets `parts` in a scene document, making missing tables (a scene without `[sea]` may be given
/// a roll period); arrays of tables are addressed by `name` or index. The value takes the type
/// of the value it replaces where that is an integer.
fn set_path(doc: &mut toml::Value, parts: &[String], value: toml::Value) -> Result<(), String> {
    let mut cur = doc;
    for (k, part) in parts.iter().enumerate() {
        let last = k + 1 == parts.len();
        match cur {
            toml::Value::Table(t) => {
                if last {
                    let v = match (t.get(part.as_str()), &value) {
                        (Some(toml::Value::Integer(_)), toml::Value::Float(f))
                            if f.fract() == 0.0 && f.abs() < 9e15 =>
                        {
                            toml::Value::Integer(*f as i64)
                        }
                        _ => value,
                    };
                    t.insert(part.clone(), v);
                    return Ok(());
                }
                cur = t
                    .entry(part.clone())
                    .or_insert_with(|| toml::Value::Table(Default::default()));
            }
            toml::Value::Array(a) => {
                let idx = a
                    .iter()
                    .position(|x| x.get("name").and_then(|n| n.as_str()) == Some(part.as_str()))
                    .or_else(|| part.parse::<usize>().ok().filter(|i| *i < a.len()))
                    .ok_or_else(|| {
                        format!(
                            "no entry `{part}` in `{}` ({} entries; address them by `name` or index from 0)",
                            parts[..k].join("."),
                            a.len()
                        )
                    })?;
                if last {
                    a[idx] = value;
                    return Ok(());
                }
                cur = &mut a[idx];
            }
            _ => {
                return Err(format!(
                    "`{}` is a value, not a table",
                    parts[..k].join(".")
                ));
            }
        }
    }
    Err("empty key".into())
}

/// Sets a key holding a dotted name (`design_overrides."parameters.kappa_n_m"`) under `parts[..n-1]`.
fn set_flat(doc: &mut toml::Value, parts: &[String], value: toml::Value) -> Result<(), String> {
    let (last, head) = parts.split_last().ok_or("empty key")?;
    let mut cur = doc;
    for part in head {
        let toml::Value::Table(t) = cur else {
            return Err(format!("`{part}` is inside a value, not a table"));
        };
        cur = t
            .entry(part.clone())
            .or_insert_with(|| toml::Value::Table(Default::default()));
    }
    let toml::Value::Table(t) = cur else {
        return Err(format!("`{}` is a value, not a table", head.join(".")));
    };
    t.insert(last.clone(), value);
    Ok(())
}

/// Follows a dotted path in a design document (arrays of tables by `name` or index).
fn get_path<'a>(doc: &'a toml::Value, path: &str) -> Result<&'a toml::Value, String> {
    let mut cur = doc;
    for part in path.split('.') {
        cur = match cur {
            toml::Value::Table(t) => t.get(part).ok_or_else(|| {
                format!(
                    "no `{part}` there (present: {})",
                    t.keys().cloned().collect::<Vec<_>>().join(", ")
                )
            })?,
            toml::Value::Array(a) => a
                .iter()
                .find(|x| x.get("name").and_then(|n| n.as_str()) == Some(part))
                .or_else(|| part.parse::<usize>().ok().and_then(|i| a.get(i)))
                .ok_or_else(|| {
                    format!(
                        "no entry `{part}` (entries: {})",
                        a.iter()
                            .filter_map(|x| x.get("name").and_then(|n| n.as_str()))
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                })?,
            _ => return Err(format!("`{part}` is inside a value, not a table")),
        };
    }
    Ok(cur)
}

/// The frozen inputs of a sweep folder: `inputs/manifest.json` and one file per scene and design.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Manifest {
    study_file: String,
    study_name: String,
    total_runs: u64,
    scenes: Vec<Input>,
    scene_designs: Vec<Input>,
    designs: Vec<Input>,
}

/// The inputs folder of a sweep.
pub fn inputs_dir(out: &Path) -> PathBuf {
    out.join("inputs")
}

impl Plan {
    /// Writes the study and every scene and design text into `OUT/inputs/` (a file each, and a
    /// manifest), so that every node and every later resume runs exactly these. If the folder
    /// already holds inputs, they must be the same study and texts.
    pub fn freeze(&self, out: &Path) -> Result<(), String> {
        let dir = inputs_dir(out);
        let manifest = self.manifest();
        let path = dir.join("manifest.json");
        if path.is_file() {
            let old = Plan::load_frozen(out)?;
            // The same study text and the same scene and design texts (not paths: a folder may
            // be resumed from elsewhere).
            let texts = |v: &[Input]| -> Vec<(String, String)> {
                v.iter()
                    .map(|i| (i.reference.clone(), i.text.clone()))
                    .collect()
            };
            if old.study.text != self.study.text
                || texts(&old.scenes) != texts(&self.scenes)
                || texts(&old.scene_designs) != texts(&self.scene_designs)
                || texts(&old.designs) != texts(&self.designs)
            {
                return Err(format!(
                    "{} holds another study ({}, {} runs) or other scene or design texts: resume it with the study it was run with, or choose another --out",
                    out.display(),
                    old.study.file,
                    old.total_runs()
                ));
            }
            return Ok(());
        }
        std::fs::create_dir_all(&dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        crate::table::write_atomically(&dir.join("study.toml"), self.study.text.as_bytes())?;
        for (k, d) in self.designs.iter().enumerate() {
            crate::table::write_atomically(
                &dir.join(format!("design-{k}.toml")),
                d.text.as_bytes(),
            )?;
        }
        for (k, d) in self.scene_designs.iter().enumerate() {
            crate::table::write_atomically(
                &dir.join(format!("scene-{k}-design.toml")),
                d.text.as_bytes(),
            )?;
        }
        let json = serde_json::to_string_pretty(&manifest).map_err(|e| e.to_string())?;
        crate::table::write_atomically(&path, json.as_bytes())
    }

    fn manifest(&self) -> Manifest {
        Manifest {
            study_file: self.study.file.clone(),
            study_name: self.study.name.clone(),
            total_runs: self.total_runs(),
            scenes: self.scenes.clone(),
            scene_designs: self.scene_designs.clone(),
            designs: self.designs.clone(),
        }
    }

    /// The plan a sweep folder was frozen with: the designs are read from its own files, so the
    /// runs never depend on the working directory or on files that changed since.
    pub fn load_frozen(out: &Path) -> Result<Plan, String> {
        let dir = inputs_dir(out);
        let path = dir.join("manifest.json");
        let text = std::fs::read_to_string(&path).map_err(|e| {
            format!(
                "{}: cannot read ({e}): is {} a sweep folder (made by `gyrolab sweep run`)?",
                path.display(),
                out.display()
            )
        })?;
        let m: Manifest = serde_json::from_str(&text)
            .map_err(|e| format!("{}: not a sweep manifest: {e}", path.display()))?;
        let study_text = std::fs::read_to_string(dir.join("study.toml"))
            .map_err(|e| format!("{}: {e}", dir.join("study.toml").display()))?;
        let study = Study::from_toml(&m.study_file, &study_text).map_err(|e| e.to_string())?;
        let abs = std::path::absolute(&dir).unwrap_or(dir.clone());
        let mut designs = m.designs;
        for (k, d) in designs.iter_mut().enumerate() {
            d.path = Some(abs.join(format!("design-{k}.toml")));
        }
        let mut scene_designs = m.scene_designs;
        for (k, d) in scene_designs.iter_mut().enumerate() {
            d.path = Some(abs.join(format!("scene-{k}-design.toml")));
        }
        Ok(Plan {
            study,
            scenes: m.scenes,
            scene_designs,
            designs,
        })
    }
}
