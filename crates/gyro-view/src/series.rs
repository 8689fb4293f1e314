//! The time series of a run, full rate, each sent in one `send_columns` call whose scalar column
//! is the recorded `Vec<f64>` handed to arrow without a copy (angles are first turned into
//! degrees, in place).

use std::sync::Arc;

use arrow::array::{ArrayRef, Float64Array};
use rerun::{
    Color, RecordingStream, Scalars, SerializedComponentBatch, SeriesLines, SeriesPoints, TextLog,
};

use crate::fit::{DampedSinusoid, SettlingFit};
use crate::run::{RunData, Series};
use crate::scene::RUN_COLORS;
use crate::{ViewError, sim_time};

/// One plotted quantity: its entity leaf, source channel and field, and whether it is an
/// angle (shown in degrees).
pub(crate) struct Quantity {
    pub entity: &'static str,
    pub field: &'static str,
    pub compass: bool,
    pub angle: bool,
}

/// Everything plotted, in view order; entities live at `<run>/series/<entity>`.
pub(crate) const QUANTITIES: [Quantity; 6] = [
    Quantity {
        entity: "reading_error_deg",
        field: "reading_error_rad",
        compass: true,
        angle: true,
    },
    Quantity {
        entity: "tilt_deg",
        field: "tilt_rad",
        compass: true,
        angle: true,
    },
    Quantity {
        entity: "heading_deg/compass",
        field: "compass_heading_rad",
        compass: true,
        angle: true,
    },
    Quantity {
        entity: "heading_deg/true",
        field: "true_heading_rad",
        compass: true,
        angle: true,
    },
    Quantity {
        entity: "speed_m_per_s",
        field: "speed_m_per_s",
        compass: false,
        angle: false,
    },
    Quantity {
        entity: "roll_deg",
        field: "roll_rad",
        compass: false,
        angle: true,
    },
];

/// The views of [`QUANTITIES`], in order, with the entity prefix (under `<run>/series/`) each shows.
pub(crate) const SERIES_VIEWS: [(&str, &str); 5] = [
    ("reading error (deg)", "reading_error_deg"),
    ("tilt, north end down (deg)", "tilt_deg"),
    ("heading (deg)", "heading_deg"),
    ("speed (m/s)", "speed_m_per_s"),
    ("roll (deg)", "roll_deg"),
];

/// A scalar column straight from a `Vec<f64>` (no copy), one value per row.
fn scalar_column(values: Vec<f64>) -> Result<rerun::SerializedComponentColumn, ViewError> {
    let array: ArrayRef = Arc::new(Float64Array::from(values));
    Ok(
        SerializedComponentBatch::new(array, Scalars::descriptor_scalars())
            .column_of_unit_batches()?,
    )
}

fn send_scalars(
    rec: &RecordingStream,
    entity: &str,
    time_ns: Vec<i64>,
    values: Vec<f64>,
) -> Result<(), ViewError> {
    rec.send_columns(entity, [sim_time(time_ns)], [scalar_column(values)?])?;
    Ok(())
}

fn run_color(run_index: usize, alpha: u8) -> Color {
    let c = RUN_COLORS[run_index % RUN_COLORS.len()];
    Color::from_unmultiplied_rgba(c[0], c[1], c[2], alpha)
}

/// Linear interpolation of `y(t)` on sorted `t` (clamped at the ends).
fn interpolate(t: &[i64], y: &[f64], at: i64) -> Option<f64> {
    let n = t.len().min(y.len());
    if n == 0 {
        return None;
    }
    let i = t[..n].partition_point(|&x| x <= at);
    if i == 0 {
        return Some(y[0]);
    }
    if i >= n {
        return Some(y[n - 1]);
    }
    let (t0, t1) = (t[i - 1] as f64, t[i] as f64);
    let w = if t1 > t0 {
        (at as f64 - t0) / (t1 - t0)
    } else {
        0.0
    };
    Some(y[i - 1] + w * (y[i] - y[i - 1]))
}

/// What was logged for a run's series.
pub(crate) struct SeriesSummary {
    pub samples: usize,
    pub fit: Option<DampedSinusoid>,
}

pub(crate) fn log_series(
    rec: &RecordingStream,
    run: &mut RunData,
    run_index: usize,
    root: &str,
    fit: &dyn SettlingFit,
) -> Result<SeriesSummary, ViewError> {
    let base = format!("{root}/series");
    let fitted = settling_fit(run, fit);
    // Event markers need the reading error in degrees at the event times: keep a copy of the
    // values near events only, before the quantities are taken out of the run.
    let event_marks: Vec<(i64, f64)> = match run.compass.get("reading_error_rad") {
        Some(err) => run
            .events
            .iter()
            .filter_map(|e| {
                Some((
                    e.time_ns,
                    interpolate(&run.compass.time_ns, err, e.time_ns)?.to_degrees(),
                ))
            })
            .collect(),
        None => Vec::new(),
    };
    let samples = run.compass.time_ns.len();
    log_quantities(rec, run, run_index, &base)?;
    if !run.events.is_empty() {
        log_events(rec, run, root, &base, event_marks)?;
    }
    if let Some(f) = &fitted {
        log_fit(rec, run, run_index, &base, f)?;
    }
    Ok(SeriesSummary {
        samples,
        fit: fitted,
    })
}

/// The damped sinusoid fitted to the recorded (SI) reading error, before it is converted for
/// display. Its window: after the last manoeuvre event (the settling that follows it), else all.
fn settling_fit(run: &RunData, fit: &dyn SettlingFit) -> Option<DampedSinusoid> {
    let settle_from_ns = run
        .events
        .iter()
        .map(|e| e.time_ns)
        .max()
        .unwrap_or(i64::MIN);
    let err = run.compass.get("reading_error_rad")?;
    let n = run.compass.time_ns.len().min(err.len());
    let first = run.compass.time_ns[..n].partition_point(|&t| t < settle_from_ns);
    let t_s: Vec<f64> = run.compass.time_ns[first..n]
        .iter()
        .map(|&t| t as f64 * 1e-9)
        .collect();
    fit.fit(&t_s, &err[first..n])
        .filter(DampedSinusoid::is_drawable)
}

/// Every recorded quantity of [`QUANTITIES`] as a line (angles in degrees); the values are
/// moved out of the run, not copied.
fn log_quantities(
    rec: &RecordingStream,
    run: &mut RunData,
    run_index: usize,
    base: &str,
) -> Result<(), ViewError> {
    for q in &QUANTITIES {
        let source: &mut Series = if q.compass {
            &mut run.compass
        } else {
            &mut run.ship
        };
        let Some(mut values) = source.take(q.field) else {
            continue;
        };
        if q.angle || q.field.ends_with("_rad") {
            values.iter_mut().for_each(|v| *v = v.to_degrees());
        }
        let entity = format!("{base}/{}", q.entity);
        let name = match q.entity {
            "heading_deg/compass" => format!("{} compass", run.name),
            "heading_deg/true" => format!("{} true", run.name),
            _ => run.name.clone(),
        };
        let alpha = if q.entity == "heading_deg/true" {
            120
        } else {
            255
        };
        rec.log_static(
            entity.as_str(),
            &SeriesLines::new()
                .with_names([name])
                .with_colors([run_color(run_index, alpha)])
                .with_widths([1.5]),
        )?;
        let len = values.len().min(source.time_ns.len());
        values.truncate(len);
        send_scalars(rec, &entity, source.time_ns[..len].to_vec(), values)?;
    }
    Ok(())
}

/// Manoeuvre events: markers on the reading error, and a text log.
fn log_events(
    rec: &RecordingStream,
    run: &RunData,
    root: &str,
    base: &str,
    event_marks: Vec<(i64, f64)>,
) -> Result<(), ViewError> {
    if !event_marks.is_empty() {
        let entity = format!("{base}/reading_error_deg/events");
        rec.log_static(
            entity.as_str(),
            &SeriesPoints::new()
                .with_names([format!("{} manoeuvres", run.name)])
                .with_markers([rerun::components::MarkerShape::Diamond])
                .with_marker_sizes([5.0])
                .with_colors([Color::from_rgb(250, 250, 250)]),
        )?;
        let (t, v): (Vec<i64>, Vec<f64>) = event_marks.into_iter().unzip();
        send_scalars(rec, &entity, t, v)?;
    }
    let texts: Vec<String> = run
        .events
        .iter()
        .map(|e| {
            let d = if e.description.is_empty() {
                String::new()
            } else {
                format!(": {}", e.description)
            };
            format!("{} {} {}{d}", run.name, e.manoeuvre, e.phase)
        })
        .collect();
    rec.send_columns(
        format!("{root}/events"),
        [sim_time(run.events.iter().map(|e| e.time_ns).collect())],
        TextLog::update_fields()
            .with_many_text(texts)
            .columns_of_unit_batches()?,
    )?;
    Ok(())
}

/// The fitted damped sinusoid and its envelope over the fit's window, at the data's times.
fn log_fit(
    rec: &RecordingStream,
    run: &RunData,
    run_index: usize,
    base: &str,
    f: &DampedSinusoid,
) -> Result<(), ViewError> {
    let (start, end) = ((f.start_s * 1e9) as i64, (f.end_s * 1e9) as i64);
    let times: Vec<i64> = run
        .compass
        .time_ns
        .iter()
        .copied()
        .filter(|&t| t >= start && t <= end)
        .collect();
    let ts = |t: i64| t as f64 * 1e-9;
    let curves: [(&str, Vec<f64>, String); 3] = [
        (
            "fit",
            times.iter().map(|&t| f.value(ts(t)).to_degrees()).collect(),
            format!(
                "{} fit: period {:.0} s, decay {:.3e} /s",
                run.name, f.period_s, f.decay_rate_per_s
            ),
        ),
        (
            "envelope_upper",
            times
                .iter()
                .map(|&t| f.envelope(ts(t)).1.to_degrees())
                .collect(),
            format!("{} envelope", run.name),
        ),
        (
            "envelope_lower",
            times
                .iter()
                .map(|&t| f.envelope(ts(t)).0.to_degrees())
                .collect(),
            format!("{} envelope", run.name),
        ),
    ];
    for (leaf, values, name) in curves {
        let entity = format!("{base}/reading_error_deg/{leaf}");
        rec.log_static(
            entity.as_str(),
            &SeriesLines::new()
                .with_names([name])
                .with_colors([if leaf == "fit" {
                    Color::from_rgb(255, 255, 255)
                } else {
                    run_color(run_index, 150)
                }])
                .with_widths([if leaf == "fit" { 1.0 } else { 0.75 }]),
        )?;
        send_scalars(rec, &entity, times.clone(), values)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_clamps_and_blends() {
        let t = [0, 10, 20];
        let y = [0.0, 1.0, 3.0];
        assert_eq!(interpolate(&t, &y, -5), Some(0.0));
        assert_eq!(interpolate(&t, &y, 15), Some(2.0));
        assert_eq!(interpolate(&t, &y, 99), Some(3.0));
        assert_eq!(interpolate(&[], &[], 0), None);
    }
}
