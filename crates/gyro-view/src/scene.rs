//! The 3-D part of a run: each body's shape (static, in its own frame), its pose at every kept
//! sample (one `send_columns` per body), the rotor's spin marker, the North–West–Up axes, true
//! and indicated North, and the apparent vertical.

use std::collections::BTreeMap;

use gyro_mcap::contract::{compass_state, ship_state, tf};
use gyro_model::Shape;
use rerun::{
    Arrows3D, Boxes3D, Color, Cylinders3D, Ellipsoids3D, FillMode, LineStrips3D, Mesh3D,
    RecordingStream, TimeColumn, Transform3D,
};

use crate::math::{self, Quat, TiltExaggeration};
use crate::run::{BodyInfo, EARTH_FRAME, PotsInfo, RunData, TankInfo, Track};
use crate::{ViewError, ViewOptions, decimate, sim_time};

/// Colours of bodies by depth in the chain.
const BODY_COLORS: [[u8; 3]; 7] = [
    [150, 160, 175], // ship
    [214, 160, 60],  // first gimbal: brass
    [90, 150, 220],  // spider / float
    [110, 190, 120], // vertical ring
    [200, 110, 170], // case
    [230, 90, 70],   // rotor
    [180, 180, 90],
];

/// Run tints, mixed into body colours for the second and later runs so overlays tell apart.
pub(crate) const RUN_COLORS: [[u8; 3]; 6] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
];

fn body_color(depth: usize, run_index: usize) -> Color {
    let c = BODY_COLORS[depth.min(BODY_COLORS.len() - 1)];
    if run_index == 0 {
        return Color::from_rgb(c[0], c[1], c[2]);
    }
    let t = RUN_COLORS[run_index % RUN_COLORS.len()];
    let mix = |a: u8, b: u8| ((u16::from(a) + u16::from(b)) / 2) as u8;
    Color::from_unmultiplied_rgba(mix(c[0], t[0]), mix(c[1], t[1]), mix(c[2], t[2]), 200)
}

/// A length that sizes the overlays: the largest extent of the drawn bodies (not the hull).
fn instrument_scale_m(bodies: &BTreeMap<String, BodyInfo>) -> f64 {
    let s = bodies
        .values()
        .map(|b| match b.shape {
            Shape::Ring { radius_m, .. } | Shape::Disc { radius_m, .. } => radius_m,
            Shape::Sphere { radius_m } => radius_m,
            Shape::Box { size_m } => 0.5 * size_m.iter().fold(0.0_f64, |a, &b| a.max(b)),
            Shape::Hull { .. } | Shape::None => 0.0,
        })
        .filter(|v| v.is_finite())
        .fold(0.0_f64, f64::max);
    if s > 0.0 { s } else { 0.1 }
}

fn f32x3(v: [f64; 3]) -> [f32; 3] {
    [v[0] as f32, v[1] as f32, v[2] as f32]
}

fn quat_f32(q: Quat) -> rerun::Quaternion {
    rerun::Quaternion::from_xyzw([q[0] as f32, q[1] as f32, q[2] as f32, q[3] as f32])
}

/// A ring about z of mean radius `r`: a band of height `w` and radial thickness `t`, as a mesh
/// with its own vertices (and normals) per face so it shades as a solid.
fn ring_mesh(r: f64, w: f64, t: f64, color: Color) -> Mesh3D {
    const N: usize = 72;
    let (ro, ri, h) = (
        (r + 0.5 * t) as f32,
        (r - 0.5 * t).max(0.0) as f32,
        (0.5 * w) as f32,
    );
    let mut pos: Vec<[f32; 3]> = Vec::with_capacity(8 * (N + 1));
    let mut nrm: Vec<[f32; 3]> = Vec::with_capacity(8 * (N + 1));
    let mut tri: Vec<[u32; 3]> = Vec::with_capacity(8 * N);
    // Each face: (radius a, z a, radius b, z b, normal kind).
    let faces: [(f32, f32, f32, f32, u8); 4] = [
        (ro, -h, ro, h, 0),  // outer
        (ri, h, ri, -h, 1),  // inner
        (ri, h, ro, h, 2),   // top
        (ro, -h, ri, -h, 3), // bottom
    ];
    for (ra, za, rb, zb, kind) in faces {
        let base = pos.len() as u32;
        for i in 0..=N {
            let phi = std::f32::consts::TAU * i as f32 / N as f32;
            let (s, c) = phi.sin_cos();
            let n = match kind {
                0 => [c, s, 0.0],
                1 => [-c, -s, 0.0],
                2 => [0.0, 0.0, 1.0],
                _ => [0.0, 0.0, -1.0],
            };
            pos.push([ra * c, ra * s, za]);
            pos.push([rb * c, rb * s, zb]);
            nrm.push(n);
            nrm.push(n);
        }
        for i in 0..N as u32 {
            let (a, b, c, d) = (
                base + 2 * i,
                base + 2 * i + 1,
                base + 2 * i + 2,
                base + 2 * i + 3,
            );
            tri.push([a, c, b]);
            tri.push([b, c, d]);
        }
    }
    Mesh3D::new(pos)
        .with_vertex_normals(nrm)
        .with_triangle_indices(tri)
        .with_albedo_factor(color.0)
}

/// A hull outline (deck with a bow, narrower keel, frames between) of length `l`, beam `b`,
/// depth `d`, deck at `z_deck`; the bow points along +x.
fn hull_outline(l: f64, b: f64, d: f64, z_deck: f64) -> Vec<Vec<[f32; 3]>> {
    let outline = |half_beam: f64, z: f64, shorten: f64| -> Vec<[f32; 3]> {
        let (xs, xb, xt) = (-0.5 * l + shorten, 0.5 * l - 1.2 * b, 0.5 * l - shorten);
        vec![
            f32x3([xs, half_beam, z]),
            f32x3([xb, half_beam, z]),
            f32x3([xt, 0.0, z]),
            f32x3([xb, -half_beam, z]),
            f32x3([xs, -half_beam, z]),
            f32x3([xs, half_beam, z]),
        ]
    };
    let deck = outline(0.5 * b, z_deck, 0.0);
    let keel = outline(0.25 * b, z_deck - d, 0.08 * l);
    let mut strips = vec![deck.clone(), keel.clone()];
    for i in 0..5 {
        strips.push(vec![deck[i], keel[i]]);
    }
    strips
}

/// Logs the static geometry of one body at `entity` (in the body's frame).
fn log_shape(
    rec: &RecordingStream,
    entity: &str,
    name: &str,
    info: &BodyInfo,
    color: Color,
) -> Result<(), ViewError> {
    match info.shape {
        Shape::Ring { radius_m, width_m } => {
            let t = (0.35 * width_m).max(0.04 * radius_m);
            rec.log_static(
                format!("{entity}/shape"),
                &ring_mesh(radius_m, width_m, t, color),
            )?;
        }
        Shape::Disc {
            radius_m,
            thickness_m,
        } => {
            let axis = info.rotor.map_or([0.0, 0.0, 1.0], |r| r.0);
            let q = math::rotation_between([0.0, 0.0, 1.0], axis);
            rec.log_static(
                format!("{entity}/shape"),
                &Cylinders3D::from_lengths_and_radii([thickness_m as f32], [radius_m as f32])
                    .with_quaternions([quat_f32(q)])
                    .with_colors([color])
                    .with_fill_mode(FillMode::Solid),
            )?;
        }
        Shape::Box { size_m } => {
            rec.log_static(
                format!("{entity}/shape"),
                &Boxes3D::from_half_sizes([f32x3(size_m.map(|s| 0.5 * s))])
                    .with_colors([color])
                    .with_labels([name]),
            )?;
        }
        Shape::Sphere { radius_m } => {
            rec.log_static(
                format!("{entity}/shape"),
                &Ellipsoids3D::from_radii([radius_m as f32])
                    .with_colors([color])
                    .with_fill_mode(FillMode::MajorWireframe)
                    .with_line_radii([(0.012 * radius_m) as f32]),
            )?;
        }
        Shape::Hull { size_m } => {
            let [l, b, d] = size_m;
            rec.log_static(
                format!("{entity}/shape"),
                &LineStrips3D::new(hull_outline(l, b, d, 0.0))
                    .with_colors([color])
                    .with_labels([name]),
            )?;
        }
        Shape::None => {}
    }
    Ok(())
}

/// The rotor's spin marker: a bar across the disc face and a block at the rim, at
/// `<rotor>/spin_marker`, turned a twelfth of a turn (in the spin's sense) per displayed sample —
/// a display rate, not the true spin, which no output rate could sample; plus the spin axis.
fn log_spin_marker(
    rec: &RecordingStream,
    entity: &str,
    info: &BodyInfo,
    time: &TimeColumn,
    n: usize,
) -> Result<(), ViewError> {
    let Some((axis, sign)) = info.rotor else {
        return Ok(());
    };
    let (r, half_t) = match info.shape {
        Shape::Disc {
            radius_m,
            thickness_m,
        } => (radius_m, 0.5 * thickness_m),
        Shape::Ring { radius_m, width_m } => (radius_m, 0.5 * width_m),
        Shape::Sphere { radius_m } => (radius_m, 0.0),
        _ => (0.05, 0.0),
    };
    let helper = if axis[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let p = {
        let c = [
            axis[1] * helper[2] - axis[2] * helper[1],
            axis[2] * helper[0] - axis[0] * helper[2],
            axis[0] * helper[1] - axis[1] * helper[0],
        ];
        let n = math::norm(c);
        [c[0] / n, c[1] / n, c[2] / n]
    };
    let lift = half_t + 0.01 * r;
    let at = |along_p: f64| -> [f32; 3] {
        f32x3([
            p[0] * along_p + axis[0] * lift,
            p[1] * along_p + axis[1] * lift,
            p[2] * along_p + axis[2] * lift,
        ])
    };
    let marker = format!("{entity}/spin_marker");
    rec.log_static(
        format!("{marker}/bar"),
        &LineStrips3D::new([vec![at(-0.9 * r), at(0.9 * r)]])
            .with_colors([Color::from_rgb(255, 255, 255)])
            .with_radii([(0.03 * r) as f32]),
    )?;
    rec.log_static(
        format!("{marker}/tab"),
        &Boxes3D::from_centers_and_half_sizes([at(0.9 * r)], [[(0.08 * r) as f32; 3]])
            .with_colors([Color::from_rgb(255, 230, 0)])
            .with_fill_mode(FillMode::Solid),
    )?;
    let step = sign * std::f64::consts::TAU / 12.0;
    let quats = (0..n).map(|k| quat_f32(math::axis_angle(axis, step * (k % 12) as f64)));
    rec.send_columns(
        marker,
        [time.clone()],
        Transform3D::update_fields()
            .with_many_quaternion(quats)
            .columns_of_unit_batches()?,
    )?;
    rec.log_static(
        format!("{entity}/spin_axis"),
        &Arrows3D::from_vectors([f32x3(axis.map(|a| sign * 1.7 * r * a))])
            .with_colors([Color::from_rgb(255, 230, 0)])
            .with_labels(["spin (marker turns at a display rate)"]),
    )?;
    Ok(())
}

/// Communicating pots on their carrier, at `<carrier>/pots/<name>`: the tube and the pots'
/// outlines (static), and each pot's liquid column, c ± u high, from the recorded level.
fn log_pots(
    rec: &RecordingStream,
    entity: &str,
    name: &str,
    pots: &PotsInfo,
    run: &RunData,
    opts: &ViewOptions,
) -> Result<(), ViewError> {
    let root = format!("{entity}/pots/{}", crate::run::entity_name(name));
    let a = pots.axis;
    let c = pots.rest_level_m;
    let along = |p: [f64; 3], d: f64| [p[0] + d * a[0], p[1] + d * a[1], p[2] + d * a[2]];
    let upright = quat_f32(math::rotation_between([0.0, 0.0, 1.0], a));
    let mercury = Color::from_rgb(205, 208, 216);
    rec.log_static(
        format!("{root}/tube"),
        &LineStrips3D::new([pots
            .tube_path_m
            .iter()
            .map(|p| f32x3(*p))
            .collect::<Vec<_>>()])
        .with_colors([mercury])
        .with_radii([(0.3 * pots.radius_m) as f32]),
    )?;
    // The pots themselves: 2c high, open at the top.
    rec.log_static(
        format!("{root}/outline"),
        &Cylinders3D::from_lengths_and_radii(
            [(2.0 * c) as f32; 2],
            [(1.15 * pots.radius_m) as f32; 2],
        )
        .with_centers([
            f32x3(along(pots.first_base_m, c)),
            f32x3(along(pots.second_base_m, c)),
        ])
        .with_quaternions([upright, upright])
        .with_colors([Color::from_rgb(120, 120, 130)])
        .with_fill_mode(FillMode::MajorWireframe),
    )?;
    let Some(level) = run.compass.get(&pots.level_field) else {
        return Ok(());
    };
    let kept = decimate(&run.compass.time_ns, opts);
    let time = sim_time(kept.iter().map(|&k| run.compass.time_ns[k]).collect());
    for (pot, base, sign) in [
        ("first", pots.first_base_m, 1.0),
        ("second", pots.second_base_m, -1.0),
    ] {
        let column = format!("{root}/{pot}");
        rec.log_static(
            format!("{column}/liquid"),
            &Cylinders3D::from_lengths_and_radii([1.0_f32], [pots.radius_m as f32])
                .with_colors([mercury])
                .with_fill_mode(FillMode::Solid),
        )?;
        let height = |k: usize| (c + sign * level[k]).max(0.0);
        rec.send_columns(
            column.as_str(),
            [time.clone()],
            Transform3D::update_fields()
                .with_many_translation(kept.iter().map(|&k| f32x3(along(base, 0.5 * height(k)))))
                .with_many_quaternion(kept.iter().map(|_| upright))
                .with_many_scale(kept.iter().map(|&k| [1.0, 1.0, height(k) as f32]))
                .columns_of_unit_batches()?,
        )?;
    }
    Ok(())
}

/// A liquid tank on its carrier, at `<carrier>/tank/<name>`: each compartment's outline, 2c
/// high (static), and its oil column, c + h high, from the recorded levels.
fn log_tank(
    rec: &RecordingStream,
    entity: &str,
    name: &str,
    tank: &TankInfo,
    run: &RunData,
    opts: &ViewOptions,
) -> Result<(), ViewError> {
    let root = format!("{entity}/tank/{}", crate::run::entity_name(name));
    let c = tank.rest_depth_m;
    let floor = tank.floor_height_m;
    let oil = Color::from_rgb(196, 150, 60);
    let n = tank.compartments.len();
    rec.log_static(
        format!("{root}/outline"),
        &Cylinders3D::from_lengths_and_radii(
            vec![(2.0 * c) as f32; n],
            tank.compartments.iter().map(|k| k.radius_m as f32),
        )
        .with_centers(
            tank.compartments
                .iter()
                .map(|k| f32x3([k.centroid_m[0], k.centroid_m[1], floor + c])),
        )
        .with_colors([Color::from_rgb(120, 120, 130)])
        .with_fill_mode(FillMode::MajorWireframe),
    )?;
    let kept = decimate(&run.compass.time_ns, opts);
    let time = sim_time(kept.iter().map(|&k| run.compass.time_ns[k]).collect());
    for (i, comp) in tank.compartments.iter().enumerate() {
        let fields: Option<Vec<&[f64]>> = comp
            .level_fields
            .iter()
            .map(|f| run.compass.get(f))
            .collect();
        let Some(fields) = fields else {
            continue;
        };
        let column = format!("{root}/compartment_{}", i + 1);
        rec.log_static(
            format!("{column}/oil"),
            &Cylinders3D::from_lengths_and_radii([1.0_f32], [comp.radius_m as f32])
                .with_colors([oil])
                .with_fill_mode(FillMode::Solid),
        )?;
        let height = |k: usize| {
            let h: f64 = fields
                .iter()
                .zip(&comp.level_coefficients)
                .map(|(f, a)| a * f[k])
                .sum();
            (c + h).max(0.0)
        };
        let (x, y) = (comp.centroid_m[0], comp.centroid_m[1]);
        rec.send_columns(
            column.as_str(),
            [time.clone()],
            Transform3D::update_fields()
                .with_many_translation(kept.iter().map(|&k| f32x3([x, y, floor + 0.5 * height(k)])))
                .with_many_scale(kept.iter().map(|&k| [1.0, 1.0, height(k) as f32]))
                .columns_of_unit_batches()?,
        )?;
    }
    Ok(())
}

/// Springs between bodies, at `<earth>/springs/<name>`, and linkages' rods, at
/// `<earth>/linkages/<name>`: a line between the two attachment points at every pose shown, each
/// point carried to the earth frame through its body's shown poses (so a tilt exaggeration
/// moves the line with the bodies).
fn log_springs_and_linkages(
    rec: &RecordingStream,
    run: &RunData,
    shown: &[Shown],
    earth: &str,
    scale_m: f64,
) -> Result<(), ViewError> {
    let index: BTreeMap<&str, usize> = run
        .tracks
        .iter()
        .enumerate()
        .map(|(i, (name, _))| (name.as_str(), i))
        .collect();
    // A body-frame point in the earth frame at time t; frames without a track hang from it.
    let in_earth = |body: &str, t: i64, p: [f64; 3]| -> Option<[f64; 3]> {
        let (mut name, mut x) = (body, p);
        for _ in 0..64 {
            let Some(&i) = index.get(name) else {
                return Some(x);
            };
            let s = &shown[i];
            if s.time_ns.is_empty() {
                return None;
            }
            let k = at_or_before(&s.time_ns, t);
            let q = s.rotation[k].xyzw().map(f64::from);
            let r = math::rotate(q, x);
            let tr = s.translation[k];
            x = [0, 1, 2].map(|j| r[j] + f64::from(tr[j]));
            name = run.tracks[i].1.parent.as_str();
        }
        None
    };
    // Springs gold and thin, linkages' rods steel grey and thicker.
    let kinds = [
        ("springs", Color::from_rgb(200, 170, 60), 0.004),
        ("linkages", Color::from_rgb(150, 160, 175), 0.006),
    ];
    for (body, info) in &run.bodies {
        let lines = kinds.iter().zip([&info.springs, &info.linkages]);
        for ((kind, color, radius), (name, spring)) in
            lines.flat_map(|(k, list)| list.iter().map(move |l| (k, l)))
        {
            let Some(&i) = index.get(body.as_str()) else {
                continue;
            };
            let times = shown[i].time_ns.clone();
            let strips: Option<Vec<Vec<[f32; 3]>>> = times
                .iter()
                .map(|&t| {
                    let a = in_earth(body, t, spring.point_m)?;
                    let b = in_earth(&spring.other_body, t, spring.other_point_m)?;
                    Some(vec![f32x3(a), f32x3(b)])
                })
                .collect();
            let Some(strips) = strips else {
                continue;
            };
            let entity = format!("{earth}/{kind}/{}", crate::run::entity_name(name));
            rec.send_columns(
                entity.as_str(),
                [sim_time(times)],
                LineStrips3D::update_fields()
                    .with_strips(strips)
                    .columns_of_unit_batches()?,
            )?;
            rec.log_static(
                entity,
                &LineStrips3D::update_fields()
                    .with_colors([*color])
                    .with_radii([(radius * scale_m) as f32])
                    .with_labels([name.as_str()]),
            )?;
        }
    }
    Ok(())
}

/// Frame name → entity path, and frame name → depth below the earth frame.
type FramePaths = (BTreeMap<String, String>, BTreeMap<String, usize>);

/// Entity path of every frame under `root` (= the earth frame), following the parent chain;
/// frames whose parent is unknown hang from the earth frame.
fn frame_paths(run: &RunData, root: &str) -> Result<FramePaths, ViewError> {
    let index: BTreeMap<&str, usize> = run
        .tracks
        .iter()
        .enumerate()
        .map(|(i, (name, _))| (name.as_str(), i))
        .collect();
    let mut paths = BTreeMap::new();
    let mut depths = BTreeMap::new();
    for (name, _) in &run.tracks {
        let mut chain = vec![name.as_str()];
        let mut cur = name.as_str();
        while let Some(&i) = index.get(cur) {
            let parent = run.tracks[i].1.parent.as_str();
            if parent == EARTH_FRAME || !index.contains_key(parent) {
                break;
            }
            if chain.contains(&parent) {
                return Err(ViewError::Poses {
                    path: run.path.clone(),
                    detail: format!("frame {name:?}: its parent chain loops through {parent:?}"),
                });
            }
            chain.push(parent);
            cur = parent;
        }
        let mut path = root.to_owned();
        for f in chain.iter().rev() {
            path.push('/');
            path.push_str(&crate::run::entity_name(f));
        }
        depths.insert(name.clone(), chain.len() - 1);
        paths.insert(name.clone(), path);
    }
    Ok((paths, depths))
}

/// Poses of one frame at its kept samples, as logged (relative to the parent entity).
struct Shown {
    time_ns: Vec<i64>,
    translation: Vec<[f32; 3]>,
    rotation: Vec<rerun::Quaternion>,
}

/// Index of the latest `times[i] <= t` (or 0).
fn at_or_before(times: &[i64], t: i64) -> usize {
    times.partition_point(|&x| x <= t).saturating_sub(1)
}

/// Decimates every track and, with a tilt exaggeration, recomputes each frame's rotation in its
/// parent from the exaggerated earth-frame rotations of both.
fn shown_poses(run: &RunData, opts: &ViewOptions, depths: &BTreeMap<String, usize>) -> Vec<Shown> {
    let exaggeration = TiltExaggeration::new(opts.tilt_exaggeration);
    let kept: Vec<Vec<usize>> = run
        .tracks
        .iter()
        .map(|(_, t)| decimate(&t.time_ns, opts))
        .collect();
    let index: BTreeMap<&str, usize> = run
        .tracks
        .iter()
        .enumerate()
        .map(|(i, (name, _))| (name.as_str(), i))
        .collect();
    // Earth-frame rotations (recorded and shown) at the kept samples, parents first.
    let mut order: Vec<usize> = (0..run.tracks.len()).collect();
    order.sort_by_key(|&i| depths.get(&run.tracks[i].0).copied().unwrap_or(0));
    let n = run.tracks.len();
    let mut raw: Vec<Vec<Quat>> = vec![Vec::new(); n];
    let mut shown: Vec<Vec<Quat>> = vec![Vec::new(); n];
    let mut kept_times: Vec<Vec<i64>> = vec![Vec::new(); n];
    for &i in &order {
        let track: &Track = &run.tracks[i].1;
        kept_times[i] = kept[i].iter().map(|&k| track.time_ns[k]).collect();
        if exaggeration.is_identity() {
            continue;
        }
        let parent = index.get(track.parent.as_str()).copied();
        let mut r = Vec::with_capacity(kept[i].len());
        for &k in &kept[i] {
            let rel = math::normalize(track.rotation_xyzw[k]);
            let p = match parent {
                Some(p) if !raw[p].is_empty() => {
                    raw[p][at_or_before(&kept_times[p], track.time_ns[k])]
                }
                _ => math::IDENTITY,
            };
            r.push(math::mul(p, rel));
        }
        let up_axis = r.first().map_or([0.0, 0.0, 1.0], |q| {
            math::nearest_axis(math::rotate(math::conj(*q), [0.0, 0.0, 1.0]))
        });
        shown[i] = r.iter().map(|q| exaggeration.apply(*q, up_axis)).collect();
        raw[i] = r;
    }
    (0..n)
        .map(|i| {
            let track = &run.tracks[i].1;
            let parent = index.get(track.parent.as_str()).copied();
            let rotation = kept[i]
                .iter()
                .enumerate()
                .map(|(j, &k)| {
                    if exaggeration.is_identity() {
                        return quat_f32(math::normalize(track.rotation_xyzw[k]));
                    }
                    let p = match parent {
                        Some(p) if !shown[p].is_empty() => {
                            shown[p][at_or_before(&kept_times[p], track.time_ns[k])]
                        }
                        _ => math::IDENTITY,
                    };
                    quat_f32(math::normalize(math::mul(math::conj(p), shown[i][j])))
                })
                .collect();
            Shown {
                time_ns: kept_times[i].clone(),
                translation: kept[i]
                    .iter()
                    .map(|&k| f32x3(track.translation_m[k]))
                    .collect(),
                rotation,
            }
        })
        .collect()
}

/// Counts of what was logged for a run's 3-D scene.
pub(crate) struct SceneSummary {
    pub bodies: Vec<String>,
    pub poses_per_frame: usize,
}

pub(crate) fn log_scene(
    rec: &RecordingStream,
    run: &RunData,
    run_index: usize,
    root: &str,
    opts: &ViewOptions,
) -> Result<SceneSummary, ViewError> {
    let earth = format!("{root}/{EARTH_FRAME}");
    let (paths, depths) = frame_paths(run, &earth)?;
    let shown = shown_poses(run, opts, &depths);
    let mut poses_per_frame = 0;
    let mut hull_drawn = false;
    for ((name, _), s) in run.tracks.iter().zip(&shown) {
        let Some(path) = paths.get(name) else {
            continue;
        };
        poses_per_frame = poses_per_frame.max(s.time_ns.len());
        let time = sim_time(s.time_ns.clone());
        rec.send_columns(
            path.as_str(),
            [time.clone()],
            Transform3D::update_fields()
                .with_many_translation(s.translation.iter().copied())
                .with_many_quaternion(s.rotation.iter().copied())
                .columns_of_unit_batches()?,
        )?;
        let depth = depths.get(name).copied().unwrap_or(0);
        if let Some(info) = run.bodies.get(name) {
            log_shape(rec, path, name, info, body_color(depth, run_index))?;
            log_spin_marker(rec, path, info, &time, s.time_ns.len())?;
            for (pots_name, pots) in &info.pots {
                log_pots(rec, path, pots_name, pots, run, opts)?;
            }
            for (tank_name, tank) in &info.tanks {
                log_tank(rec, path, tank_name, tank, run, opts)?;
            }
            hull_drawn |= matches!(info.shape, Shape::Hull { .. });
        }
    }
    // The ship: its own hull if a body gives one, else a schematic outline around the instrument.
    let scale = instrument_scale_m(&run.bodies);
    if !hull_drawn && let Some(ship) = paths.get(tf::SHIP_FRAME) {
        rec.log_static(
            format!("{ship}/hull_outline"),
            &LineStrips3D::new(hull_outline(
                4.5 * scale,
                1.8 * scale,
                0.8 * scale,
                -1.3 * scale,
            ))
            .with_colors([body_color(0, run_index)])
            .with_labels(["ship (schematic, not to scale)"]),
        )?;
    }
    log_springs_and_linkages(rec, run, &shown, &earth, scale)?;
    log_overlays(rec, run, run_index, root, opts, 2.2 * scale)?;
    let mut bodies: Vec<String> = run.tracks.iter().map(|(n, _)| n.clone()).collect();
    bodies.sort();
    Ok(SceneSummary {
        bodies,
        poses_per_frame,
    })
}

/// North–West–Up axes and true North (static); indicated North and the apparent vertical at
/// the kept samples.
fn log_overlays(
    rec: &RecordingStream,
    run: &RunData,
    run_index: usize,
    root: &str,
    opts: &ViewOptions,
    len_m: f64,
) -> Result<(), ViewError> {
    let l = len_m as f32;
    let base = format!("{root}/overlay");
    if run_index == 0 {
        rec.log_static(
            format!("{base}/axes_nwu"),
            &Arrows3D::from_vectors([
                [0.6 * l, 0.0, 0.0],
                [0.0, 0.6 * l, 0.0],
                [0.0, 0.0, 0.6 * l],
            ])
            .with_colors([
                Color::from_rgb(230, 60, 60),
                Color::from_rgb(60, 200, 60),
                Color::from_rgb(70, 110, 240),
            ])
            .with_labels(["N", "W", "Up"]),
        )?;
    }
    rec.log_static(
        format!("{base}/true_north"),
        &Arrows3D::from_vectors([[l, 0.0, 0.0]])
            .with_colors([Color::from_rgb(230, 60, 60)])
            .with_labels(["true North"]),
    )?;
    let exaggeration = TiltExaggeration::new(opts.tilt_exaggeration);
    let tint = RUN_COLORS[run_index % RUN_COLORS.len()];
    let kept = decimate(&run.compass.time_ns, opts);
    if let Some(err) = run.compass.get(compass_state::READING_ERROR_RAD) {
        let label = if (opts.error_exaggeration - 1.0).abs() < 1e-12 {
            format!("{}: indicated North", run.name)
        } else {
            format!(
                "{}: indicated North (error ×{})",
                run.name, opts.error_exaggeration
            )
        };
        let vectors = kept.iter().map(|&k| {
            let e = opts.error_exaggeration * err.get(k).copied().unwrap_or(0.0);
            [l * 1.1 * e.cos() as f32, l * 1.1 * e.sin() as f32, 0.0]
        });
        let entity = format!("{base}/indicated_north");
        rec.send_columns(
            entity.as_str(),
            [sim_time(
                kept.iter().map(|&k| run.compass.time_ns[k]).collect(),
            )],
            Arrows3D::update_fields()
                .with_vectors(vectors)
                .columns_of_unit_batches()?,
        )?;
        rec.log_static(
            entity,
            &Arrows3D::update_fields()
                .with_origins([[0.0_f32, 0.0, 0.002 * l]])
                .with_colors([Color::from_rgb(tint[0], tint[1], tint[2])])
                .with_labels([label]),
        )?;
    }
    let kept = decimate(&run.ship.time_ns, opts);
    if let (Some(gn), Some(gw), Some(gu)) = (
        run.ship.get(ship_state::GRAVITY_NORTH_M_PER_S2),
        run.ship.get(ship_state::GRAVITY_WEST_M_PER_S2),
        run.ship.get(ship_state::GRAVITY_UP_M_PER_S2),
    ) {
        let vectors = kept.iter().map(|&k| {
            let g = |c: &[f64]| c.get(k).copied().unwrap_or(0.0);
            let up = [-g(gn), -g(gw), -g(gu)];
            let v = exaggeration.vector(up);
            let n = math::norm(v);
            if n > 0.0 && n.is_finite() {
                f32x3([v[0] / n * len_m, v[1] / n * len_m, v[2] / n * len_m])
            } else {
                [0.0, 0.0, l]
            }
        });
        let entity = format!("{base}/apparent_vertical");
        rec.send_columns(
            entity.as_str(),
            [sim_time(
                kept.iter().map(|&k| run.ship.time_ns[k]).collect(),
            )],
            Arrows3D::update_fields()
                .with_vectors(vectors)
                .columns_of_unit_batches()?,
        )?;
        let label = if exaggeration.is_identity() {
            format!("{}: apparent vertical", run.name)
        } else {
            format!(
                "{}: apparent vertical (tilt ×{})",
                run.name, opts.tilt_exaggeration
            )
        };
        rec.log_static(
            entity,
            &Arrows3D::update_fields()
                .with_colors([Color::from_rgb(240, 240, 240)])
                .with_labels([label]),
        )?;
    }
    Ok(())
}
