//! The shipped library of scenes and designs. The files live in `scenes/` and `designs/` at the
//! repository root and are also compiled into the program, so `gyrolab run harbour-50n` works
//! from any directory. A path always wins over a shipped name.

use gyro_model::InputError;
use std::path::{Path, PathBuf};

macro_rules! shipped {
    ($folder:literal; $($name:literal),* $(,)?) => {
        &[$(($name, include_str!(concat!("../../../", $folder, "/", $name, ".toml")))),*]
    };
}

/// Shipped designs: (name, TOML text).
pub const DESIGNS: &[(&str, &str)] = shipped!("designs"; "foucault-gyroscope", "anschutz-1906", "sperry-1911", "slough", "sperry-twin-1918",
    "anschutz-three-gyro-1912");

/// Shipped scenes: (name, TOML text).
pub const SCENES: &[(&str, &str)] = shipped!("scenes";
    "harbour-0n", "harbour-30n", "harbour-50n", "harbour-70n",
    "run-north-30kn", "speed-change-20kn", "turn-90", "turn-180", "zigzag-45",
    "rolling-cardinal", "rolling-intercardinal",
    "foucault-azimuth-45n", "foucault-latitude-45n",
    "sperry-harbour-0n", "sperry-harbour-35n", "sperry-harbour-60n",
    "sperry-run-north-30kn", "sperry-speed-change-20kn", "sperry-turn-90", "sperry-turn-180",
    "sperry-zigzag-45", "sperry-rolling-cardinal", "sperry-rolling-intercardinal",
    "slough-harbour-0n", "slough-harbour-35n", "slough-harbour-60n",
    "slough-run-north-30kn", "slough-speed-change-20kn", "slough-turn-90", "slough-turn-180",
    "slough-zigzag-45", "slough-rolling-cardinal", "slough-rolling-intercardinal",
    "twin-harbour-0n", "twin-harbour-35n", "twin-harbour-60n",
    "twin-run-north-30kn", "twin-speed-change-20kn", "twin-turn-90", "twin-turn-180",
    "twin-zigzag-45", "twin-rolling-cardinal", "twin-rolling-intercardinal",
    "three-gyro-harbour-0n", "three-gyro-harbour-35n", "three-gyro-harbour-50n",
    "three-gyro-run-north-30kn", "three-gyro-speed-change-20kn", "three-gyro-turn-90",
    "three-gyro-turn-180", "three-gyro-zigzag-45", "three-gyro-rolling-cardinal",
    "three-gyro-rolling-intercardinal", "three-gyro-hermione", "three-gyro-damping-adjustment",
);

/// One-line description of a TOML file (its `description` key).
pub fn describe(text: &str) -> String {
    toml::from_str::<toml::Table>(text)
        .ok()
        .and_then(|t| {
            t.get("description")
                .and_then(|d| d.as_str())
                .map(str::to_string)
        })
        .unwrap_or_default()
}

fn read(
    reference: &str,
    dir: Option<&Path>,
    folder: &str,
    shipped: &[(&str, &str)],
    what: &str,
) -> Result<(String, String, Option<PathBuf>), InputError> {
    if let Some(p) = crate::scene::resolve_path(reference, dir, folder) {
        let text = std::fs::read_to_string(&p).map_err(|e| InputError {
            file: p.display().to_string(),
            line: None,
            key: "(file)".into(),
            message: format!("cannot read: {e}"),
        })?;
        let parent = p.parent().map(Path::to_path_buf);
        return Ok((p.display().to_string(), text, parent));
    }
    if let Some((name, text)) = shipped.iter().find(|(n, _)| *n == reference) {
        return Ok((format!("<shipped {what} {name}>"), text.to_string(), None));
    }
    Err(InputError {
        file: reference.to_string(),
        line: None,
        key: "(file)".into(),
        message: format!(
            "no such file, and no shipped {what} of that name (shipped: {})",
            shipped
                .iter()
                .map(|(n, _)| *n)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    })
}

/// Reads a scene by path or shipped name: (label for errors, text, directory for relative refs).
pub(crate) fn read_scene(reference: &str) -> Result<(String, String, Option<PathBuf>), InputError> {
    read(reference, None, "scenes", SCENES, "scene")
}

/// Reads a design by path (relative to the scene's folder, or `../designs/NAME.toml` from it, or
/// `designs/NAME.toml` here) or shipped name.
pub(crate) fn read_design(
    reference: &str,
    scene_dir: Option<&Path>,
) -> Result<(String, String), InputError> {
    read(reference, scene_dir, "designs", DESIGNS, "design").map(|(l, t, _)| (l, t))
}
