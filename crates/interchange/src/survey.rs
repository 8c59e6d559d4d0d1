//! The import's first pass: what the files hold (units, nodes, every response's header, what is skipped), and the
//! plan drawn from it (the grid, each key's record, the actuators' mapping, the units' conversion).

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use metaplate_core::grid::{GridSpec, SNAP_TOLERANCE_M, snap_to_grid};
use metaplate_store::ScatteredPoints;
use metaplate_uff::{AxisCharacteristics, FunctionType, UffDecoder, UffRecord, Units164};

use crate::error::{InterchangeError, refuse};

mod choose;
use crate::lattice::{self, Frame};
use crate::quantity::{self, Denominator, OrdinateQuantity};
use crate::{IdLines, ImportOptions};
use choose::Chooser;
pub(crate) use choose::wanted_estimator;
pub use choose::{ESTIMATORS, MAX_AXIS_ANGLE_DEG};

/// Bytes read from a file at a time.
const READ_CHUNK: usize = 1 << 20;

/// The function types an import reads; records of every other type are stepped over unread.
pub(crate) const RESPONSE_TYPES: [FunctionType; 2] = [FunctionType::TimeResponse, FunctionType::FrequencyResponse];

/// Spacing given to the grid of a single point, m (a grid needs one; nothing measures it).
pub const ONE_POINT_SPACING_M: f64 = 1e-3;

/// A record an import stepped over, and where.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SkippedRecord {
    /// The file, as given.
    pub file: String,
    /// The record's ordinal in the file, from 1.
    pub record: u64,
    /// The line of its opening delimiter.
    pub line: u64,
    /// What it is: `dataset 2412 (elements)`, `dataset 58, function type 6 (coherence)`.
    pub what: String,
}

/// Which reference degree of freedom an actuator number stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct ActuatorRef {
    /// The dataset's actuator number.
    pub actuator: u16,
    /// The responses' reference node label (any integer: LMS writes -1 for none).
    pub reference_node: i64,
    /// The reference direction (0 scalar, ±1..±6).
    pub direction: i8,
}

/// One response of the files, as the first pass saw it.
pub(crate) struct Seen {
    /// File index and the record's ordinal in it.
    pub(crate) at: (usize, u64),
    /// The line of its opening delimiter.
    pub(crate) line: u64,
    pub(crate) function_type: FunctionType,
    pub(crate) response: i64,
    /// The response direction (0 scalar, ±1..±6).
    pub(crate) response_direction: i8,
    pub(crate) reference: (i64, i8),
    /// The metaplate key of ID line 1, if any.
    pub(crate) key: Option<(u32, u16)>,
    /// The estimator ID line 2 names, if any ([`choose::ESTIMATORS`]).
    pub(crate) estimator: Option<&'static str>,
    pub(crate) ordinate: OrdinateQuantity,
    pub(crate) denominator: Denominator,
    /// Records 9 and 10 as read.
    pub(crate) axes: Box<(AxisCharacteristics, AxisCharacteristics)>,
}

/// What the first pass gathers.
#[derive(Default)]
pub(crate) struct Survey {
    pub(crate) units: Option<Units164>,
    /// Node positions in the file's length unit.
    pub(crate) nodes: HashMap<i64, [f64; 3]>,
    pub(crate) functions: Vec<Seen>,
    /// ID lines of the first response.
    pub(crate) first_ids: Option<[String; 5]>,
    pub(crate) skipped: Vec<SkippedRecord>,
    /// What metaplate's dataset 151 restores, from the first file that has one.
    pub(crate) restored: Option<crate::header::Restored>,
}

/// Decodes each file in turn (responses only), handing every record to `visit` with the file's index, the record's
/// ordinal and the line of its opening delimiter.
pub(crate) fn for_each_record(
    files: &[PathBuf],
    mut visit: impl FnMut(usize, u64, u64, UffRecord) -> Result<(), InterchangeError>,
) -> Result<(), InterchangeError> {
    let mut chunk = vec![0u8; READ_CHUNK];
    for (f, path) in files.iter().enumerate() {
        let mut file = File::open(path)
            .map_err(|source| InterchangeError::File { what: format!("opening {}", path.display()), source })?;
        let mut decoder = UffDecoder::new().only_functions(&RESPONSE_TYPES);
        let mut ordinal = 0u64;
        loop {
            let n = file
                .read(&mut chunk)
                .map_err(|source| InterchangeError::File { what: format!("reading {}", path.display()), source })?;
            if n == 0 {
                decoder.finish();
            } else {
                decoder.push(&chunk[..n]);
            }
            while let Some(record) = decoder.poll() {
                let record = record
                    .map_err(|source| InterchangeError::Malformed { file: path.display().to_string(), source })?;
                ordinal += 1;
                visit(f, ordinal, decoder.opened_line(), record)?;
            }
            if n == 0 {
                break;
            }
        }
    }
    Ok(())
}

/// The specification's name of a function type code.
fn function_type_name(code: u32) -> &'static str {
    match code {
        0 => "general or unknown",
        2 => "auto spectrum",
        3 => "cross spectrum",
        5 => "transmissibility",
        6 => "coherence",
        7 => "auto correlation",
        8 => "cross correlation",
        9 => "power spectral density",
        10 => "energy spectral density",
        11 => "probability density function",
        12 => "spectrum",
        18 => "mode indicator function",
        21 => "partial coherence",
        23 => "eigenvector",
        24 => "shock response spectrum",
        26 => "multiple coherence",
        27 => "order function",
        _ => "not a response",
    }
}

/// What a dataset number holds, for the list of skipped records.
fn dataset_name(number: u32) -> &'static str {
    match number {
        15 => "nodes, single precision",
        18 => "coordinate systems",
        55 => "data at nodes (mode shapes)",
        82 => "trace lines",
        151 => "header",
        1858 => "qualifiers",
        2400 => "model header",
        2412 => "elements",
        2414 => "analysis data",
        2420 => "coordinate systems",
        2467 => "groups",
        _ => "not read",
    }
}

/// `FILE record N (dataset 58 from line L)`: a response record, for messages.
pub(crate) fn record_at(files: &[PathBuf], seen: &Seen) -> String {
    format!("{} record {} (dataset 58 from line {})", files[seen.at.0].display(), seen.at.1, seen.line)
}

/// The first pass: units, nodes, every response's header, and what is skipped.
pub(crate) fn survey(files: &[PathBuf], options: &ImportOptions) -> Result<Survey, InterchangeError> {
    let mut survey = Survey::default();
    for_each_record(files, |f, ordinal, line, record| {
        match record {
            UffRecord::Units(units) => {
                if survey.units.as_ref().is_some_and(|u| *u != units) {
                    refuse!(
                        "{} record {ordinal} (dataset 164 from line {line}) gives other units than an earlier dataset \
                         164: one set of units is accepted across the files",
                        files[f].display()
                    );
                }
                survey.units = Some(units);
            }
            UffRecord::Nodes(nodes) => {
                for node in nodes.nodes {
                    survey.nodes.insert(i64::from(node.label), node.position_m);
                }
            }
            UffRecord::Function(function) => {
                let h = &function.header;
                if survey.first_ids.is_none() {
                    survey.first_ids = Some(h.id_lines.clone());
                }
                survey.functions.push(Seen {
                    at: (f, ordinal),
                    line,
                    function_type: h.function_type,
                    response: h.response.node,
                    response_direction: h.response.direction,
                    reference: (h.reference.node, h.reference.direction),
                    key: IdLines::parse_key(&h.id_lines[0]),
                    estimator: choose::estimator(&h.id_lines[1]),
                    // Placeholders until dataset 164 is known (it may come after the responses).
                    ordinate: OrdinateQuantity::Other { name: String::new() },
                    denominator: Denominator::Unused,
                    axes: Box::new((h.ordinate.clone(), h.denominator.clone())),
                });
            }
            UffRecord::Header(header) => match crate::header::restored(&header) {
                Some(restored) => match &survey.restored {
                    Some(earlier) if *earlier != restored => refuse!(
                        "{} record {ordinal} (dataset 151 from line {line}): metaplate's header of another dataset \
                         (unit {:?}, calibration {}) than an earlier file's (unit {:?}, calibration {}); the files of \
                         one export are accepted together",
                        files[f].display(),
                        restored.unit,
                        restored.calibration.as_deref().unwrap_or("none"),
                        earlier.unit,
                        earlier.calibration.as_deref().unwrap_or("none")
                    ),
                    _ => survey.restored = Some(restored),
                },
                None => survey.skipped.push(SkippedRecord {
                    file: files[f].display().to_string(),
                    record: ordinal,
                    line,
                    what: format!("dataset 151 ({})", dataset_name(151)),
                }),
            },
            UffRecord::Other(other) => {
                let what = match other.function_type {
                    Some(code) => format!("dataset 58, function type {code} ({})", function_type_name(code)),
                    None => format!("dataset {} ({})", other.dataset_number, dataset_name(other.dataset_number)),
                };
                survey.skipped.push(SkippedRecord {
                    file: files[f].display().to_string(),
                    record: ordinal,
                    line,
                    what,
                });
            }
        }
        Ok(())
    })?;
    for seen in &mut survey.functions {
        let (ordinate, denominator) = &*seen.axes;
        seen.ordinate = quantity::ordinate(ordinate, survey.units.as_ref());
        let per_newton = matches!(seen.ordinate, OrdinateQuantity::Motion { per_newton: true, .. });
        seen.denominator = quantity::denominator(denominator, survey.units.as_ref(), per_newton);
        if let OrdinateQuantity::Other { name } = &seen.ordinate
            && !options.accept_unknown_quantity
        {
            refuse!(
                "{}, line {}, record 9 (ordinate data characteristics): the ordinate is {name}; metaplate imports \
                 velocity, and acceleration or displacement converted to it (data types 11, 12, 8, or 0 or 1 with a \
                 units label such as m/s, m/s², g, mm); --accept-unknown-quantity imports it as declared unknown",
                record_at(files, seen),
                seen.line + 10
            );
        }
    }
    Ok(survey)
}

/// What the second pass imports.
pub(crate) struct Plan {
    pub(crate) grid: GridSpec,
    /// (file index, record ordinal) of the function imported for each key.
    pub(crate) by_at: HashMap<(usize, u64), (u32, u16)>,
    pub(crate) grid_from: String,
    pub(crate) actuators: Vec<ActuatorRef>,
    /// Node -> position in the grid's frame, m (the responses'; every node's with the metaplate grid).
    pub(crate) placed: HashMap<i64, (f64, f64)>,
    /// The fitted lattice's (or the scattered points' plane's) frame, to place other nodes (the references) in it.
    pub(crate) frame: Option<Frame>,
    /// The points' positions when they lie on no lattice.
    pub(crate) scattered: Option<ScatteredPoints>,
    /// Responses not chosen where a key had several of its kind (another estimator, another direction).
    pub(crate) not_chosen: Vec<SkippedRecord>,
    /// The estimator chosen where a key had FRFs of several, if any key had.
    pub(crate) estimator: Option<&'static str>,
    /// The response direction chosen where a key had responses in several, if any key had.
    pub(crate) response_direction: Option<i8>,
}

/// The grid, the actuators and each key's function: one per key, the time response, else the FRF; of several of
/// one kind, as [`Chooser`] chooses (`estimator`: the one [`choose::wanted_estimator`] resolved).
pub(crate) fn plan(
    files: &[PathBuf],
    survey: &Survey,
    first_ids: &[String; 5],
    options: &ImportOptions,
    estimator: Option<&'static str>,
    positions_m: &HashMap<i64, [f64; 3]>,
) -> Result<Plan, InterchangeError> {
    // Nodes off the plane z = const are an import's original positions exported again: placed again as on their
    // first import (the ID lines' grid is in that import's frame, which the nodes are not).
    let z: Vec<f64> = survey.functions.iter().filter_map(|s| positions_m.get(&s.response)).map(|p| p[2]).collect();
    let flat = z.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b)) - z.iter().fold(f64::INFINITY, |a, &b| a.min(b))
        <= SNAP_TOLERANCE_M
        || z.is_empty();
    let metaplate_grid = IdLines::parse_grid(&first_ids[1]).filter(|_| !options.grid_from_nodes && flat);
    let Placement { grid, keys, grid_from, actuators, placed, frame, scattered } = match metaplate_grid {
        Some(grid) if survey.functions.iter().all(|s| s.key.is_some()) => {
            let keys: Vec<(u32, u16)> = survey.functions.iter().filter_map(|s| s.key).collect();
            let mut actuators = BTreeSet::new();
            for (seen, key) in survey.functions.iter().zip(&keys) {
                actuators.insert(ActuatorRef {
                    actuator: key.1,
                    reference_node: seen.reference.0,
                    direction: seen.reference.1,
                });
            }
            Placement {
                grid,
                keys,
                grid_from: "metaplate ID lines".to_owned(),
                actuators: actuators.into_iter().collect(),
                placed: positions_m.iter().map(|(&label, p)| (label, (p[0], p[1]))).collect(),
                frame: None,
                scattered: None,
            }
        }
        _ => keys_from_nodes(files, survey, positions_m)?,
    };
    let mut groups: BTreeMap<(u32, u16), Vec<usize>> = BTreeMap::new();
    for (i, key) in keys.iter().enumerate() {
        groups.entry(*key).or_default().push(i);
    }
    let rank = |i: usize| match survey.functions[i].function_type {
        FunctionType::TimeResponse => 0,
        _ => 1,
    };
    // The plane's normal: the fitted one, else z (points in a plane z = const, or on metaplate's grid).
    let normal = frame.as_ref().map_or([0.0, 0.0, 1.0], |f| f.normal);
    let mut chooser = Chooser::new(files, survey, estimator, normal);
    let mut by_at = HashMap::new();
    for (key, candidates) in &groups {
        let best = candidates.iter().map(|&i| rank(i)).min().unwrap_or(0);
        let pool: Vec<usize> = candidates.iter().copied().filter(|&i| rank(i) == best).collect();
        let pool = chooser.by_estimator(*key, pool)?;
        let pool = chooser.by_direction(*key, pool)?;
        if let [first, second, ..] = pool[..] {
            refuse!(
                "point {} actuator {} has two responses of one type: {} and {} (one response per response node, \
                 reference node and direction, and estimator is accepted)",
                key.0,
                key.1,
                record_at(files, &survey.functions[first]),
                record_at(files, &survey.functions[second])
            );
        }
        if let Some(&i) = pool.first() {
            by_at.insert(survey.functions[i].at, *key);
        }
    }
    let (not_chosen, estimator, response_direction) = chooser.finish();
    Ok(Plan { grid, by_at, grid_from, actuators, placed, frame, scattered, not_chosen, estimator, response_direction })
}

/// The grid placed from the response nodes' positions (m), each function's key, and the actuators: the distinct
/// (reference node, direction) pairs of the responses, numbered from 0 in ascending order.
fn keys_from_nodes(
    files: &[PathBuf],
    survey: &Survey,
    positions_m: &HashMap<i64, [f64; 3]>,
) -> Result<Placement, InterchangeError> {
    let responses: BTreeSet<i64> = survey.functions.iter().map(|s| s.response).collect();
    let references: BTreeSet<(i64, i8)> = survey.functions.iter().map(|s| s.reference).collect();
    if references.len() > usize::from(u16::MAX) + 1 {
        refuse!("{} reference degrees of freedom: more actuators than a dataset numbers (65536)", references.len());
    }
    let mut labels = Vec::with_capacity(responses.len());
    let mut positions = Vec::with_capacity(responses.len());
    for &label in &responses {
        let Some(p) = positions_m.get(&label) else {
            let Some(seen) = survey.functions.iter().find(|s| s.response == label) else { continue };
            refuse!(
                "{}, line {}, record 6 (DOF identification), response node: node {label} has no position: no dataset \
                 2411 lists it; give the positions with --nodes FILE (CSV columns node,x_m,y_m and optionally z_m)",
                record_at(files, seen),
                seen.line + 7
            )
        };
        labels.push(label);
        positions.push(*p);
    }
    let Placed { grid, indices, grid_from, in_plane: placed, frame, scattered } = place(&positions)?;
    let placed: HashMap<i64, (f64, f64)> = labels.iter().copied().zip(placed).collect();
    let point_of: HashMap<i64, u32> =
        labels.iter().zip(&indices).map(|(&label, &i)| (label, u32::try_from(i).unwrap_or(u32::MAX))).collect();
    let actuators: Vec<ActuatorRef> = references
        .iter()
        .enumerate()
        .map(|(a, &(reference_node, direction))| ActuatorRef {
            actuator: u16::try_from(a).unwrap_or(u16::MAX),
            reference_node,
            direction,
        })
        .collect();
    let actuator_of: HashMap<(i64, i8), u16> =
        actuators.iter().map(|a| ((a.reference_node, a.direction), a.actuator)).collect();
    let keys = survey
        .functions
        .iter()
        .map(|s| (point_of.get(&s.response).copied().unwrap_or(0), actuator_of.get(&s.reference).copied().unwrap_or(0)))
        .collect();
    Ok(Placement { grid, keys, grid_from, actuators, placed, frame, scattered })
}

/// Where the response points go: the grid, each point's flat index in it and in-plane position (m), where the
/// grid came from, the frame of a fit in 3-D, and the positions of points on no lattice.
struct Placed {
    grid: GridSpec,
    indices: Vec<usize>,
    grid_from: String,
    in_plane: Vec<(f64, f64)>,
    frame: Option<Frame>,
    scattered: Option<ScatteredPoints>,
}

/// The grid of the response points (m, 3-D): one point; else points in a plane of constant z on an axis-aligned
/// grid as they are ([`snap_to_grid`]); else the lattice of their plane ([`crate::lattice::fit`]); else scattered
/// points ([`scattered`]).
fn place(points: &[[f64; 3]]) -> Result<Placed, InterchangeError> {
    let flat: Vec<(f64, f64)> = points.iter().map(|p| (p[0], p[1])).collect();
    if points.windows(2).all(|w| w[0] == w[1]) {
        let (x, y) = flat.first().copied().unwrap_or_default();
        let grid = GridSpec { nx: 1, ny: 1, spacing_m: ONE_POINT_SPACING_M, origin_x_m: x, origin_y_m: y };
        let (indices, grid_from) = (vec![0; points.len()], "one point".to_owned());
        return Ok(Placed { grid, indices, grid_from, in_plane: flat, frame: None, scattered: None });
    }
    let z_range = points.iter().map(|p| p[2]).fold(f64::NEG_INFINITY, f64::max)
        - points.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
    let in_xy = z_range <= SNAP_TOLERANCE_M;
    let snap_error = if in_xy {
        match snap_to_grid(&flat) {
            Ok((grid, indices)) => {
                let grid_from = "nodes".to_owned();
                return Ok(Placed { grid, indices, grid_from, in_plane: flat, frame: None, scattered: None });
            }
            Err(e) => e.to_string(),
        }
    } else {
        format!("they span {:.4} mm in z", z_range * 1e3)
    };
    match lattice::fit(points) {
        Ok(lattice) => Ok(Placed {
            grid_from: lattice.describe(),
            grid: lattice.grid,
            indices: lattice.indices,
            in_plane: lattice.in_plane_m,
            frame: Some(lattice.frame),
            scattered: None,
        }),
        Err(why) => scattered(points, in_xy, &format!("not a grid as they are ({snap_error}) nor a lattice ({why})")),
    }
}

/// Points on no lattice (a scan mesh) kept where they are: in the plane z = const as given (`in_xy`), else in
/// their least-squares plane ([`lattice::plane`]: through their centroid, u along the projection of x). Their grid
/// is their index ([`metaplate_store::DatasetMeta::with_scattered`]), spaced by the median nearest-neighbour
/// distance.
///
/// # Errors
/// [`InterchangeError::Refused`] for more points than [`lattice::MAX_LATTICE_POINTS`] or two at one position in
/// the plane (no analysis can tell them apart).
fn scattered(points: &[[f64; 3]], in_xy: bool, not_lattice: &str) -> Result<Placed, InterchangeError> {
    let n = points.len();
    if n > lattice::MAX_LATTICE_POINTS {
        refuse!(
            "the {n} response nodes are {not_lattice}; scattered points are kept up to {} points",
            lattice::MAX_LATTICE_POINTS
        );
    }
    let (frame, plane_rms_m) = lattice::plane(points);
    let in_plane: Vec<(f64, f64)> = if in_xy {
        points.iter().map(|p| (p[0], p[1])).collect()
    } else {
        points.iter().map(|&p| frame.place(p)).collect()
    };
    let nearest = metaplate_core::points::nearest_neighbours(&in_plane);
    if let Some(i) = nearest.iter().position(|n| n.distance_m <= 0.0) {
        refuse!(
            "response nodes {i} and another of the {n} (in label order) lie at one position in their plane: \
             distinct positions are accepted"
        );
    }
    let Some(spacing_m) = metaplate_core::points::median_distance_m(&nearest) else {
        refuse!("the {n} response nodes have no spacing: scattered points are at least two distinct positions")
    };
    let frame_text = if in_xy {
        "the plane z = const of the nodes, x and y as given".to_owned()
    } else {
        let c = frame.centroid_m;
        let [u, nn] = [frame.u, frame.normal].map(|a| a.map(|v| (v * 1e3).round() / 1e3 + 0.0));
        format!(
            "the nodes' least-squares plane (normal ({:.3}, {:.3}, {:.3}), points {:.3} µm rms off it): origin at \
             their centroid ({:.6}, {:.6}, {:.6}) m, x along ({:.3}, {:.3}, {:.3})",
            nn[0],
            nn[1],
            nn[2],
            plane_rms_m * 1e6,
            c[0],
            c[1],
            c[2],
            u[0],
            u[1],
            u[2]
        )
    };
    let grid_from = format!(
        "scattered points: the {n} response nodes are {not_lattice}; kept at their positions in {frame_text}, \
         {:.4} mm apart (median nearest neighbour)",
        spacing_m * 1e3
    );
    let grid = GridSpec { nx: n, ny: 1, spacing_m, origin_x_m: 0.0, origin_y_m: 0.0 };
    let scattered = ScatteredPoints { positions_m: in_plane.clone(), frame: frame_text };
    let frame = (!in_xy).then_some(frame);
    Ok(Placed { grid, indices: (0..n).collect(), grid_from, in_plane, frame, scattered: Some(scattered) })
}

/// Where the responses go: the grid, each function's key, where the grid came from, the actuators.
struct Placement {
    grid: GridSpec,
    keys: Vec<(u32, u16)>,
    grid_from: String,
    actuators: Vec<ActuatorRef>,
    /// Response node -> position in the grid's frame, m.
    placed: HashMap<i64, (f64, f64)>,
    /// The fitted lattice's frame, if the points were fitted in 3-D.
    frame: Option<Frame>,
    /// The points' positions when they lie on no lattice.
    scattered: Option<ScatteredPoints>,
}

/// Node positions from a CSV file: a header naming the columns `node`, `x_m`, `y_m` and optionally `z_m` (in any
/// order, other columns ignored), then one node per line; metres.
///
/// # Errors
/// An unreadable file; [`InterchangeError::Refused`] naming the line and column of what is not a node label or a
/// finite number, a missing column, or a node listed twice.
pub fn read_nodes_csv(path: &Path) -> Result<HashMap<i64, [f64; 3]>, InterchangeError> {
    let text = std::fs::read_to_string(path)
        .map_err(|source| InterchangeError::File { what: format!("reading {}", path.display()), source })?;
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    let Some((_, header)) = lines.next() else {
        refuse!("{}: empty; expected a header node,x_m,y_m[,z_m]", path.display())
    };
    let names: Vec<String> = header.split(',').map(|c| c.trim().to_ascii_lowercase()).collect();
    let column = |name: &str| names.iter().position(|c| c == name);
    let (Some(node), Some(x), Some(y)) = (column("node"), column("x_m"), column("y_m")) else {
        refuse!(
            "{} line 1: the header {header:?} lacks a column node, x_m or y_m (accepted: node,x_m,y_m[,z_m])",
            path.display()
        )
    };
    let z = column("z_m");
    let mut nodes = HashMap::new();
    for (i, line) in lines {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let cell = |c: usize, name: &str| -> Result<&str, InterchangeError> {
            match cells.get(c) {
                Some(v) => Ok(v),
                None => refuse!("{} line {}: no column {name}", path.display(), i + 1),
            }
        };
        let number = |c: usize, name: &str| -> Result<f64, InterchangeError> {
            let v = cell(c, name)?;
            match v.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                _ => {
                    refuse!("{} line {}, column {name}: {v:?} is not a finite number of metres", path.display(), i + 1)
                }
            }
        };
        let label = cell(node, "node")?;
        let Ok(label) = label.parse::<i64>() else {
            refuse!("{} line {}, column node: {label:?} is not a node label (an integer)", path.display(), i + 1)
        };
        let position = [
            number(x, "x_m")?,
            number(y, "y_m")?,
            match z {
                Some(z) => number(z, "z_m")?,
                None => 0.0,
            },
        ];
        if nodes.insert(label, position).is_some() {
            refuse!("{} line {}: node {label} is listed twice", path.display(), i + 1);
        }
    }
    Ok(nodes)
}
