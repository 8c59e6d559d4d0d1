//! One design of a search, judged: its band diagram's first branch against the objectives.

use serde::Serialize;

use crate::band::band_diagram;
use crate::search::spec::{Candidate, Goal, SearchSpec};
use metaplate_core::design::CellResonator;

/// What a search records of one design (one row of its results).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DesignResult {
    /// The design's varied values and index.
    pub candidate: Candidate,
    /// Whether it meets every objective (false too when it could not be computed).
    pub feasible: bool,
    /// Why it is not feasible (empty when it is).
    pub reason: String,
    /// Top of the first branch, Hz (NaN when not computed).
    pub top_hz: f64,
    /// The first branch's highest phase velocity over the objective's band, m/s (NaN when the branch has no point
    /// in that band or the design was not computed).
    pub max_phase_velocity_m_s: f64,
    /// The resonators' free mass per plate area, kg/m^2.
    pub added_mass_kg_m2: f64,
    /// Resonator over cell plate mass.
    pub mass_ratio: f64,
    /// The clamped cell's resonator mode, Hz (NaN when not found).
    pub resonator_mode_hz: f64,
    /// On the trade-off front of the feasible designs (set when results are gathered).
    pub on_front: bool,
}

impl DesignResult {
    /// The value of `goal` (to minimise).
    pub fn goal(&self, goal: Goal) -> f64 {
        match goal {
            Goal::AddedMassKgM2 => self.added_mass_kg_m2,
            Goal::RodHeightM => self.candidate.rod_height_m,
            Goal::MaxPhaseVelocityMS => self.max_phase_velocity_m_s,
            Goal::MassRatio => self.mass_ratio,
        }
    }
}

/// Computes and judges `candidate`. Never fails: a design whose values are out of range or whose eigenproblem fails
/// is recorded as infeasible with the reason, so that a search goes on and a resumed one does not retry it.
pub fn evaluate(spec: &SearchSpec, candidate: &Candidate) -> DesignResult {
    let design = spec.design(candidate);
    let (added_mass_kg_m2, mass_ratio) = match &design.resonator {
        CellResonator::Rod(rod) => (rod.free_mass_kg() / design.lattice_constant_m.powi(2), design.mass_ratio()),
        _ => (0.0, 0.0),
    };
    let mut result = DesignResult {
        candidate: candidate.clone(),
        feasible: false,
        reason: String::new(),
        top_hz: f64::NAN,
        max_phase_velocity_m_s: f64::NAN,
        added_mass_kg_m2,
        mass_ratio,
        resonator_mode_hz: f64::NAN,
        on_front: false,
    };
    if let Err((key, why)) = design.check() {
        result.reason = format!("not a valid design: {key} {why}");
        return result;
    }
    let band = match band_diagram(&design, &spec.band, &[]) {
        Ok(band) => band,
        Err(e) => {
            result.reason = format!("not computed: {e}");
            return result;
        }
    };
    let o = &spec.objectives;
    let Some(first) = band.branches.first() else {
        result.reason = "no branch computed".into();
        return result;
    };
    result.top_hz = first.points.iter().map(|p| p.freq_hz).fold(f64::NEG_INFINITY, f64::max);
    result.resonator_mode_hz = band.resonator_mode_hz.unwrap_or(f64::NAN);
    let in_band = first
        .points
        .iter()
        .filter(|p| p.freq_hz >= o.over_hz[0] && p.freq_hz <= o.over_hz[1])
        .filter_map(|p| p.phase_velocity_m_s);
    result.max_phase_velocity_m_s = in_band.fold(f64::NAN, f64::max);
    let mut reasons = Vec::new();
    if result.top_hz < o.over_hz[1] {
        reasons.push(format!(
            "the first branch tops at {:.0} Hz, below the objective's {} Hz",
            result.top_hz, o.over_hz[1]
        ));
    }
    if let Some(cover) = o.covers_hz
        && result.top_hz < cover[1]
    {
        reasons.push(format!("the first branch tops at {:.0} Hz, short of covering {} Hz", result.top_hz, cover[1]));
    }
    if result.max_phase_velocity_m_s.is_nan() {
        reasons.push(format!("the first branch has no point within {} to {} Hz", o.over_hz[0], o.over_hz[1]));
    } else if result.max_phase_velocity_m_s >= o.max_phase_velocity_m_s {
        reasons.push(format!(
            "phase velocity reaches {:.2} m/s within {} to {} Hz (limit {})",
            result.max_phase_velocity_m_s, o.over_hz[0], o.over_hz[1], o.max_phase_velocity_m_s
        ));
    }
    result.feasible = reasons.is_empty();
    result.reason = reasons.join("; ");
    result
}

/// Marks the trade-off front: the feasible designs no other feasible design beats on every goal (at least as good
/// on all, better on one). Quadratic in the number of feasible designs (a few thousand at most take well under a
/// second).
pub fn mark_front(results: &mut [DesignResult], goals: &[Goal]) {
    let feasible: Vec<usize> = (0..results.len()).filter(|&i| results[i].feasible).collect();
    let values: Vec<Vec<f64>> = feasible.iter().map(|&i| goals.iter().map(|&g| results[i].goal(g)).collect()).collect();
    let dominated =
        |a: &[f64], b: &[f64]| b.iter().zip(a).all(|(vb, va)| vb <= va) && b.iter().zip(a).any(|(vb, va)| vb < va);
    for r in results.iter_mut() {
        r.on_front = false;
    }
    for (k, &i) in feasible.iter().enumerate() {
        results[i].on_front = !values.iter().any(|other| dominated(&values[k], other));
    }
}
