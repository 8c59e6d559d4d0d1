//! The plate-to-volts map of a pair of galvanometer mirrors, fitted from taught points.
//!
//! Two models ([`FitModel`]):
//! - **projective** (a homography, 8 parameters, at least 4 points): what a flat plate seen through the mirrors is
//!   to first order (offset, scale, rotation, shear and the keystone of a head that is not square to the plate).
//!   Fitted by the normalised direct linear transform, solved by SVD (never normal equations).
//! - **polynomial2** (each voltage a 2nd-order polynomial of x and y, 12 parameters, at least 6 points): for
//!   mirrors whose small non-linearity matters more than the keystone. Least squares by SVD on normalised
//!   coordinates.
//!
//! Valid range: the fit interpolates within the taught marks' bounding rectangle; outside it, it extrapolates (and
//! the aimer still refuses any point needing more than the outputs' range). Coordinates must be finite; the marks
//! must be distinct and not all on one line (for exactly 4 projective marks, no 3 on one line).

use faer::Mat;

use crate::GalvoError;

/// Below this ratio of a singular value to the largest, the taught points do not pin the map down (degenerate).
/// Normalised coordinates are O(1), so a well-spread set of marks is many orders of magnitude above it.
const RANK_TOLERANCE: f64 = 1e-9;

/// Two taught points closer than this fraction of the set's extent count as the same point.
const DUPLICATE_FRACTION: f64 = 1e-6;

/// Newton iterations inverting the map (volts to plate) for the residual; the maps are smooth and the start
/// point is within a residual of the answer, so a few iterations reach rounding.
const NEWTON_ITERATIONS: usize = 8;

/// Which map the fit is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FitModel {
    /// A homography (8 parameters, at least 4 points).
    Projective,
    /// A 2nd-order polynomial per axis (12 parameters, at least 6 points).
    Polynomial2,
}

impl FitModel {
    /// The fewest taught points that determine the model.
    pub fn min_points(self) -> usize {
        match self {
            FitModel::Projective => 4,
            FitModel::Polynomial2 => 6,
        }
    }

    /// The model's name in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            FitModel::Projective => "projective",
            FitModel::Polynomial2 => "polynomial2",
        }
    }
}

impl std::str::FromStr for FitModel {
    type Err = String;

    /// `projective` or `polynomial2`.
    fn from_str(name: &str) -> Result<FitModel, String> {
        [FitModel::Projective, FitModel::Polynomial2]
            .into_iter()
            .find(|m| m.name() == name)
            .ok_or_else(|| format!("\"{name}\": projective or polynomial2"))
    }
}

/// One taught point: a mark on the plate and the mirror voltages that put the beam on it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaughtPoint {
    /// The mark on the plate, m.
    pub x_m: f64,
    /// The mark on the plate, m.
    pub y_m: f64,
    /// The X mirror's voltage, V.
    pub x_v: f64,
    /// The Y mirror's voltage, V.
    pub y_v: f64,
}

/// How far the fit puts the taught voltages from their marks, measured on the plate, mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Residual {
    /// Root mean square over the taught points, mm.
    pub rms_mm: f64,
    /// The largest, mm.
    pub max_mm: f64,
    /// Which taught point has the largest.
    pub worst_point: usize,
}

/// A similarity that takes a point set to centroid 0 and mean distance sqrt(2) from it (Hartley's normalisation):
/// `n = scale * (p - centre)`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Normalisation {
    centre: (f64, f64),
    scale: f64,
}

impl Normalisation {
    fn of(points: &[(f64, f64)]) -> Normalisation {
        let n = points.len() as f64;
        let cx = points.iter().map(|p| p.0).sum::<f64>() / n;
        let cy = points.iter().map(|p| p.1).sum::<f64>() / n;
        let mean = points.iter().map(|p| (p.0 - cx).hypot(p.1 - cy)).sum::<f64>() / n;
        // A set of one repeated point has mean 0: the duplicate check refuses it before the scale is used.
        let scale = if mean > 0.0 { std::f64::consts::SQRT_2 / mean } else { 1.0 };
        Normalisation { centre: (cx, cy), scale }
    }

    fn apply(&self, p: (f64, f64)) -> (f64, f64) {
        (self.scale * (p.0 - self.centre.0), self.scale * (p.1 - self.centre.1))
    }

    /// The 3 x 3 matrix of the map, row-major.
    fn matrix(&self) -> [f64; 9] {
        let s = self.scale;
        [s, 0.0, -s * self.centre.0, 0.0, s, -s * self.centre.1, 0.0, 0.0, 1.0]
    }

    /// The 3 x 3 matrix of the inverse map, row-major.
    fn inverse_matrix(&self) -> [f64; 9] {
        let s = self.scale;
        [1.0 / s, 0.0, self.centre.0, 0.0, 1.0 / s, self.centre.1, 0.0, 0.0, 1.0]
    }
}

/// The fitted map's parameters.
#[derive(Debug, Clone, PartialEq)]
enum Map {
    /// `[x_v, y_v, 1] ~ h * [x_m, y_m, 1]`, row-major, scaled so that the taught points have `w > 0`.
    Projective([f64; 9]),
    /// `x_v = cx . f(n)`, `y_v = cy . f(n)` with `n` the normalised plate point and `f = [1, x, y, x², xy, y²]`.
    Polynomial2 { norm: Normalisation, cx: [f64; 6], cy: [f64; 6] },
}

/// The plate-to-volts map fitted from taught points, with its residual.
#[derive(Debug, Clone, PartialEq)]
pub struct GalvoFit {
    model: FitModel,
    points: Vec<TaughtPoint>,
    map: Map,
    residual: Residual,
}

impl GalvoFit {
    /// Fits `model` to `points`.
    ///
    /// # Errors
    /// [`GalvoError::TooFewPoints`]; [`GalvoError::InvalidPoint`] for a non-finite coordinate;
    /// [`GalvoError::Duplicate`] for two points on one spot of the plate or at one pair of voltages;
    /// [`GalvoError::Collinear`] for marks on one line (any 3 of exactly 4 projective marks);
    /// [`GalvoError::Degenerate`] for any other set that does not determine the map (6 marks on a conic for the
    /// polynomial, voltages inconsistent with a projective map).
    pub fn fit(model: FitModel, points: &[TaughtPoint]) -> Result<GalvoFit, GalvoError> {
        check_points(model, points)?;
        let plate: Vec<(f64, f64)> = points.iter().map(|p| (p.x_m, p.y_m)).collect();
        let volts: Vec<(f64, f64)> = points.iter().map(|p| (p.x_v, p.y_v)).collect();
        let map = match model {
            FitModel::Projective => Map::Projective(fit_homography(&plate, &volts)?),
            FitModel::Polynomial2 => fit_polynomial2(&plate, &volts)?,
        };
        let mut fit = GalvoFit {
            model,
            points: points.to_vec(),
            map,
            residual: Residual { rms_mm: 0.0, max_mm: 0.0, worst_point: 0 },
        };
        fit.residual = fit.residual_of_points()?;
        Ok(fit)
    }

    /// Which model this is.
    pub fn model(&self) -> FitModel {
        self.model
    }

    /// The taught points it was fitted from.
    pub fn points(&self) -> &[TaughtPoint] {
        &self.points
    }

    /// The residual over the taught points, on the plate, mm.
    pub fn residual(&self) -> Residual {
        self.residual
    }

    /// One line for a person: the model, the points and the residual.
    pub fn summary(&self) -> String {
        let r = self.residual;
        format!(
            "{} fit of {} marks: residual rms {:.3} mm, max {:.3} mm (mark {})",
            self.model.name(),
            self.points.len(),
            r.rms_mm,
            r.max_mm,
            r.worst_point
        )
    }

    /// The taught marks' bounding rectangle, m: `((x_min, y_min), (x_max, y_max))`, where the fit interpolates.
    pub fn taught_bounds_m(&self) -> ((f64, f64), (f64, f64)) {
        let fold =
            |f: fn(f64, f64) -> f64, init: f64, get: fn(&TaughtPoint) -> f64| self.points.iter().map(get).fold(init, f);
        (
            (fold(f64::min, f64::INFINITY, |p| p.x_m), fold(f64::min, f64::INFINITY, |p| p.y_m)),
            (fold(f64::max, f64::NEG_INFINITY, |p| p.x_m), fold(f64::max, f64::NEG_INFINITY, |p| p.y_m)),
        )
    }

    /// The mirror voltages that put the beam on (`x_m`, `y_m`), V; `None` where the projective map has no finite
    /// image (the point is beyond the map's horizon, on the far side from the taught marks) or for a non-finite
    /// point.
    pub fn volts_at(&self, x_m: f64, y_m: f64) -> Option<(f64, f64)> {
        if !x_m.is_finite() || !y_m.is_finite() {
            return None;
        }
        let v = match &self.map {
            Map::Projective(h) => {
                let w = h[6] * x_m + h[7] * y_m + h[8];
                // The taught points all have w > 0; a point with w <= 0 is not on the plate as the mirrors see it.
                if w <= f64::EPSILON * (h[6].abs() + h[7].abs() + h[8].abs()) {
                    return None;
                }
                ((h[0] * x_m + h[1] * y_m + h[2]) / w, (h[3] * x_m + h[4] * y_m + h[5]) / w)
            }
            Map::Polynomial2 { norm, cx, cy } => {
                let f = features(norm.apply((x_m, y_m)));
                (dot6(cx, &f), dot6(cy, &f))
            }
        };
        (v.0.is_finite() && v.1.is_finite()).then_some(v)
    }

    /// The map's Jacobian at (`x_m`, `y_m`): `[[dxv/dx, dxv/dy], [dyv/dx, dyv/dy]]`, V per m.
    fn jacobian(&self, x_m: f64, y_m: f64) -> Option<[[f64; 2]; 2]> {
        match &self.map {
            Map::Projective(h) => {
                let w = h[6] * x_m + h[7] * y_m + h[8];
                let (u, v) = self.volts_at(x_m, y_m)?;
                Some([[(h[0] - u * h[6]) / w, (h[1] - u * h[7]) / w], [(h[3] - v * h[6]) / w, (h[4] - v * h[7]) / w]])
            }
            Map::Polynomial2 { norm, cx, cy } => {
                let (x, y) = norm.apply((x_m, y_m));
                let s = norm.scale;
                let d = |c: &[f64; 6]| [s * (c[1] + 2.0 * c[3] * x + c[4] * y), s * (c[2] + c[4] * x + 2.0 * c[5] * y)];
                Some([d(cx), d(cy)])
            }
        }
    }

    /// Where on the plate the fit says the voltages (`x_v`, `y_v`) put the beam, m, by Newton's method from the
    /// plate point `start_m`; `None` if it does not converge (a singular Jacobian on the way).
    pub fn plate_at(&self, x_v: f64, y_v: f64, start_m: (f64, f64)) -> Option<(f64, f64)> {
        let mut q = start_m;
        for _ in 0..NEWTON_ITERATIONS {
            let (u, v) = self.volts_at(q.0, q.1)?;
            let [[a, b], [c, d]] = self.jacobian(q.0, q.1)?;
            let det = a * d - b * c;
            if det == 0.0 || !det.is_finite() {
                return None;
            }
            let (ru, rv) = (u - x_v, v - y_v);
            q = (q.0 - (d * ru - b * rv) / det, q.1 - (-c * ru + a * rv) / det);
        }
        (q.0.is_finite() && q.1.is_finite()).then_some(q)
    }

    /// The residual of the taught points: for each, how far from its mark the fit puts its taught voltages.
    fn residual_of_points(&self) -> Result<Residual, GalvoError> {
        let mut sum_sq = 0.0;
        let mut worst = (0, 0.0);
        for (i, p) in self.points.iter().enumerate() {
            let (x, y) = self.plate_at(p.x_v, p.y_v, (p.x_m, p.y_m)).ok_or_else(|| GalvoError::Degenerate {
                detail: format!("the fitted map cannot be inverted at taught point {i}"),
            })?;
            let d_mm = (x - p.x_m).hypot(y - p.y_m) * 1e3;
            sum_sq += d_mm * d_mm;
            if d_mm > worst.1 {
                worst = (i, d_mm);
            }
        }
        Ok(Residual { rms_mm: (sum_sq / self.points.len() as f64).sqrt(), max_mm: worst.1, worst_point: worst.0 })
    }
}

/// Refuses too few, non-finite, duplicated or collinear points.
fn check_points(model: FitModel, points: &[TaughtPoint]) -> Result<(), GalvoError> {
    if points.len() < model.min_points() {
        return Err(GalvoError::TooFewPoints { model: model.name(), needed: model.min_points(), got: points.len() });
    }
    for (index, p) in points.iter().enumerate() {
        if ![p.x_m, p.y_m, p.x_v, p.y_v].iter().all(|v| v.is_finite()) {
            return Err(GalvoError::InvalidPoint { index, detail: format!("{p:?}: not finite") });
        }
    }
    let plate: Vec<(f64, f64)> = points.iter().map(|p| (p.x_m, p.y_m)).collect();
    let volts: Vec<(f64, f64)> = points.iter().map(|p| (p.x_v, p.y_v)).collect();
    for (side, set) in [("plate", &plate), ("volts", &volts)] {
        check_duplicates(side, set)?;
        check_collinear(side, set, model == FitModel::Projective && set.len() == 4)?;
    }
    Ok(())
}

fn check_duplicates(side: &'static str, set: &[(f64, f64)]) -> Result<(), GalvoError> {
    let extent = set.iter().flat_map(|a| set.iter().map(move |b| (a.0 - b.0).hypot(a.1 - b.1))).fold(0.0, f64::max);
    for (i, a) in set.iter().enumerate() {
        for (j, b) in set.iter().enumerate().skip(i + 1) {
            if (a.0 - b.0).hypot(a.1 - b.1) <= DUPLICATE_FRACTION * extent {
                return Err(GalvoError::Duplicate { side, first: i, second: j });
            }
        }
    }
    Ok(())
}

/// All points on one line (a 2 x 2 scatter of rank 1), or with `any_three`, any 3 of them.
fn check_collinear(side: &'static str, set: &[(f64, f64)], any_three: bool) -> Result<(), GalvoError> {
    let norm = Normalisation::of(set);
    let n: Vec<(f64, f64)> = set.iter().map(|&p| norm.apply(p)).collect();
    let (sxx, syy, sxy) = n.iter().fold((0.0, 0.0, 0.0), |(a, b, c), p| (a + p.0 * p.0, b + p.1 * p.1, c + p.0 * p.1));
    // The smaller eigenvalue of the scatter over the larger: 0 when all points are on one line.
    let half_trace = (sxx + syy) / 2.0;
    let gap = (((sxx - syy) / 2.0).powi(2) + sxy * sxy).sqrt();
    if (half_trace - gap) <= RANK_TOLERANCE * (half_trace + gap) {
        return Err(GalvoError::Collinear { side, points: (0..set.len()).collect() });
    }
    if any_three {
        for i in 0..n.len() {
            for j in i + 1..n.len() {
                for k in j + 1..n.len() {
                    let (a, b, c) = (n[i], n[j], n[k]);
                    let cross = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
                    if cross.abs() <= 1e3 * RANK_TOLERANCE {
                        return Err(GalvoError::Collinear { side, points: vec![i, j, k] });
                    }
                }
            }
        }
    }
    Ok(())
}

/// The homography taking `plate` to `volts` by the normalised DLT: the null vector of the 2n x 9 system (padded
/// with zero rows to at least 9, so the SVD's V is square), from its smallest singular value.
fn fit_homography(plate: &[(f64, f64)], volts: &[(f64, f64)]) -> Result<[f64; 9], GalvoError> {
    let np = Normalisation::of(plate);
    let nv = Normalisation::of(volts);
    let rows = (2 * plate.len()).max(9);
    let mut a = Mat::<f64>::zeros(rows, 9);
    for (i, (&p, &v)) in plate.iter().zip(volts).enumerate() {
        let (x, y) = np.apply(p);
        let (u, w) = nv.apply(v);
        let r0 = [-x, -y, -1.0, 0.0, 0.0, 0.0, u * x, u * y, u];
        let r1 = [0.0, 0.0, 0.0, -x, -y, -1.0, w * x, w * y, w];
        for c in 0..9 {
            a[(2 * i, c)] = r0[c];
            a[(2 * i + 1, c)] = r1[c];
        }
    }
    let svd = a.svd().map_err(|e| GalvoError::Degenerate { detail: format!("the SVD did not converge: {e:?}") })?;
    let s: Vec<f64> = (0..9).map(|k| svd.S()[k]).collect();
    let mut order: Vec<usize> = (0..9).collect();
    order.sort_by(|&i, &j| s[i].total_cmp(&s[j]));
    let (smallest, second, largest) = (order[0], order[1], order[8]);
    // A second (near) null vector: the points leave a family of maps open.
    if s[second] <= RANK_TOLERANCE * s[largest] {
        return Err(GalvoError::Degenerate {
            detail: "the taught points leave the projective map undetermined (more than one map fits them)".into(),
        });
    }
    let hn: [f64; 9] = std::array::from_fn(|k| svd.V()[(k, smallest)]);
    // h = Tv^-1 * hn * Tp
    let mut h = mul3(&mul3(&nv.inverse_matrix(), &hn), &np.matrix());
    // Sign so that the taught points have w > 0; they must all be on one side of the horizon.
    let w = |h: &[f64; 9], p: &(f64, f64)| h[6] * p.0 + h[7] * p.1 + h[8];
    if plate.first().is_some_and(|p| w(&h, p) < 0.0) {
        h.iter_mut().for_each(|v| *v = -*v);
    }
    let norm = h.iter().map(|v| v * v).sum::<f64>().sqrt();
    h.iter_mut().for_each(|v| *v /= norm);
    if let Some(i) = plate.iter().position(|p| w(&h, p) <= 0.0) {
        return Err(GalvoError::Degenerate {
            detail: format!("taught point {i} falls beyond the fitted map's horizon: the points are inconsistent"),
        });
    }
    Ok(h)
}

/// Least squares of a 2nd-order polynomial per axis over the normalised plate points, by thin SVD.
fn fit_polynomial2(plate: &[(f64, f64)], volts: &[(f64, f64)]) -> Result<Map, GalvoError> {
    let norm = Normalisation::of(plate);
    let mut a = Mat::<f64>::zeros(plate.len(), 6);
    for (i, &p) in plate.iter().enumerate() {
        for (c, v) in features(norm.apply(p)).into_iter().enumerate() {
            a[(i, c)] = v;
        }
    }
    let svd =
        a.thin_svd().map_err(|e| GalvoError::Degenerate { detail: format!("the SVD did not converge: {e:?}") })?;
    let s: Vec<f64> = (0..6).map(|k| svd.S()[k]).collect();
    let largest = s.iter().copied().fold(0.0, f64::max);
    if s.iter().any(|&v| v <= RANK_TOLERANCE * largest) {
        return Err(GalvoError::Degenerate {
            detail: "the taught marks lie on one conic: they leave the polynomial map undetermined; add marks \
                     spread over the plate"
                .into(),
        });
    }
    // x = V diag(1/s) U^T b, for each axis.
    let solve = |b: &dyn Fn(usize) -> f64| -> [f64; 6] {
        let utb: Vec<f64> =
            (0..6).map(|k| (0..plate.len()).map(|i| svd.U()[(i, k)] * b(i)).sum::<f64>() / s[k]).collect();
        std::array::from_fn(|r| (0..6).map(|k| svd.V()[(r, k)] * utb[k]).sum())
    };
    let cx = solve(&|i| volts[i].0);
    let cy = solve(&|i| volts[i].1);
    Ok(Map::Polynomial2 { norm, cx, cy })
}

fn features((x, y): (f64, f64)) -> [f64; 6] {
    [1.0, x, y, x * x, x * y, y * y]
}

fn dot6(c: &[f64; 6], f: &[f64; 6]) -> f64 {
    c.iter().zip(f).map(|(a, b)| a * b).sum()
}

/// The product of two 3 x 3 row-major matrices.
fn mul3(a: &[f64; 9], b: &[f64; 9]) -> [f64; 9] {
    std::array::from_fn(|k| {
        let (r, c) = (k / 3, k % 3);
        (0..3).map(|m| a[3 * r + m] * b[3 * m + c]).sum()
    })
}
