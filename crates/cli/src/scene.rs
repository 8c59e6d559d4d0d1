//! `metaplate scene list|show`: the built-in scenes, and any scene resolved and checked.

use std::io::Write;

use clap::{Args, Subcommand};
use metaplate_core::scene::Scene;

/// Arguments of `metaplate scene`.
#[derive(Args)]
pub struct SceneArgs {
    #[command(subcommand)]
    command: SceneCommand,
}

#[derive(Subcommand)]
enum SceneCommand {
    /// List the built-in scenes with a one-line description each.
    List,
    /// Print a scene as fully resolved TOML, then a summary as TOML comments (so the output is itself a scene file).
    Show {
        /// A built-in scene's name, or the path of a scene file.
        scene: String,
    },
}

/// Runs `metaplate scene ...`.
pub fn run(args: &SceneArgs) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    match &args.command {
        SceneCommand::List => {
            for name in Scene::builtin_names() {
                let scene = Scene::builtin(name)?;
                writeln!(out, "{name:<14} {}", scene.description)?;
            }
        }
        SceneCommand::Show { scene } => {
            let scene = Scene::resolve(scene)?;
            write!(out, "{}", scene.to_toml_string())?;
            writeln!(out)?;
            for line in summary(&scene) {
                writeln!(out, "# {line}")?;
            }
        }
    }
    Ok(())
}

/// A few lines a person checks first: size, measurable grid, actuators, resonators, cache key.
fn summary(scene: &Scene) -> Vec<String> {
    let (x_min, x_max, y_min, y_max) = scene.plate.outline.bounding_box_m();
    let g = &scene.grid;
    let rods = match scene.resonators.lattice_sites_m(&scene.plate.outline) {
        Ok(sites) if sites.is_empty() => "none".to_owned(),
        Ok(sites) => format!("{} rods every {} mm", sites.len(), scene.resonators.pitch_m * 1e3),
        Err(e) => format!("({e})"),
    };
    let mut lines = vec![
        format!(
            "plate: {} x {} cm, {} mm thick",
            (x_max - x_min) * 100.0,
            (y_max - y_min) * 100.0,
            scene.plate.thickness_m * 1e3
        ),
        format!(
            "grid: {} of {} points measured ({} x {} at {} mm; the rest off the plate or on a support)",
            scene.measured_points().len(),
            g.len(),
            g.nx,
            g.ny,
            g.spacing_m * 1e3
        ),
        format!("actuators: {}; supports: {}; resonators: {rods}", scene.actuators.len(), scene.supports.len()),
        format!("scene id: {}", scene.id().hash),
    ];
    if let Some(design) = &scene.resonators.design {
        // The plate model's view of the rods: what the cell's band structure gave it, and how closely.
        lines.push(match metaplate_plate::design_fit(design) {
            Ok(fit) => format!(
                "rods from design `{}`, homogenised: added mass {:.2} x rho h, stiffness {:.3} x D, rotary inertia \
                 {:.3e} kg m^2 per rod, joint resonance {:.1} Hz (fitted {:.0} to {:.0} Hz, frequency error max \
                 {:.2} %)",
                design.name,
                fit.added_mass_ratio,
                fit.rigidity_factor,
                fit.rotary_inertia_kg_m2,
                fit.resonance_hz,
                fit.min_freq_hz,
                fit.max_freq_hz,
                100.0 * fit.max_relative_error
            ),
            Err(e) => format!("rods from design `{}`: {e}", design.name),
        });
    }
    lines
}
