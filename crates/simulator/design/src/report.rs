//! A band diagram as text: the summary, then frequency per wave vector and mode.

use std::fmt::Write;

use crate::band::BandDiagram;

impl BandDiagram {
    /// The summary (mass ratio, resonator mode, slow branch) and a table of frequency (Hz) per wave vector and
    /// mode, with the plate's share of each mode's kinetic energy in a second block.
    pub fn table_text(&self) -> String {
        let mut out = String::new();
        let cm = |m: Option<f64>| m.map_or_else(|| "-".to_owned(), |m| format!("{:.2} cm", 100.0 * m));
        // Writing to a String cannot fail.
        let _ = writeln!(
            out,
            "design {}: lattice {:.2} mm, mass ratio {:.2}, {} DOFs",
            self.design,
            1e3 * self.lattice_constant_m,
            self.mass_ratio,
            self.degrees_of_freedom
        );
        match self.resonator_mode {
            Some(m) => {
                let _ = writeln!(
                    out,
                    "clamped-cell resonator mode f_n: {:.1} Hz (plate energy share {:.3})",
                    m.freq_hz, m.plate_energy_share
                );
            }
            None => {
                let _ = writeln!(out, "clamped-cell resonator mode f_n: none (no resonator)");
            }
        }
        let s = &self.slow_branch;
        let _ = writeln!(
            out,
            "slow branch m = {}: top {:.1} Hz (wavelength {}), phase velocity up to {:.2} m/s",
            s.mode,
            s.top_hz,
            cm(s.top_wavelength_m),
            s.max_phase_velocity_m_s
        );
        for w in &s.wavelength_m_at {
            let _ = writeln!(out, "  wavelength at {:.0} Hz: {}", w.freq_hz, cm(w.wavelength_m));
        }
        if let Some(h) = &self.homogenised {
            let _ = writeln!(
                out,
                "homogenised rocking rod (|k| a <= pi/2, {} points, {:.0} to {:.0} Hz): added mass {:.2} x rho h, \
                 stiffness {:.3} x D, rotary inertia {:.3e} kg m^2 per cell, joint resonance {:.1} Hz; frequency \
                 error max {:.2} %, rms {:.2} %",
                h.points,
                h.min_freq_hz,
                h.max_freq_hz,
                h.added_mass_ratio,
                h.rigidity_factor,
                h.rotary_inertia_kg_m2,
                h.resonance_hz,
                100.0 * h.max_relative_error,
                100.0 * h.rms_relative_error
            );
        }
        let _ = writeln!(out);
        let _ = write!(out, "{:>4} {:>8} {:>9} {:>9}", "k#", "pos pi/a", "kx rad/m", "ky rad/m");
        for b in &self.branches {
            let _ = write!(out, " {:>9}", format!("m={} Hz", b.mode));
        }
        let _ = write!(out, " {:>9}", "A0 Hz");
        let _ = writeln!(out);
        for (i, p) in self.path.iter().enumerate() {
            let _ = write!(out, "{:>4} {:>8.3} {:>9.2} {:>9.2}", p.path_index, p.path_position, p.kx_rad_m, p.ky_rad_m);
            for b in &self.branches {
                let _ = write!(out, " {:>9.1}", b.points[i].freq_hz);
            }
            let a0 = self.a0_folded_hz.first().map_or(f64::NAN, |a| a[i]);
            let _ = writeln!(out, " {a0:>9.1}");
        }
        let _ = writeln!(out);
        let _ = writeln!(out, "plate share of kinetic energy per mode (the rest is the resonator's):");
        for (i, p) in self.path.iter().enumerate() {
            let _ = write!(out, "{:>4}", p.path_index);
            for b in &self.branches {
                let _ = write!(out, " {:>6.3}", b.points[i].plate_energy_share);
            }
            let _ = writeln!(out);
        }
        out
    }
}
