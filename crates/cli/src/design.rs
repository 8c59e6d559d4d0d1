//! `metaplate design ...`: a metamaterial unit cell's band structure (`metaplate_design`).

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, Subcommand};
use metaplate_core::design::Design;
use metaplate_design::search::{self, DesignResult, SearchSpec, Shard};
use metaplate_design::{BandOptions, MeshOptions, PAPER_WAVELENGTH_FREQS_HZ, band_diagram};

/// Subcommands of `metaplate design`.
#[derive(Subcommand)]
pub enum DesignCommand {
    /// The band diagram of a unit cell along Gamma-X-M-Gamma (finite elements, Bloch conditions): each branch's
    /// phase velocity and wavelength, each mode's plate energy share, the clamped cell's resonator mode, the
    /// homogeneous plate's A0. A table, or JSON with --json; Parquet points with --parquet; the paper's Fig. 2B-D
    /// with --figures.
    Band(BandArgs),
    /// Computes a grid of designs (a search file: the base design, values of the rod's height and diameter, the
    /// lattice constant, the plate's thickness, materials) against objectives (the first branch's phase velocity
    /// under a limit over a band; goals to minimise), each written to OUT/parts as it finishes, then
    /// OUT/results.parquet with the feasible designs and the trade-off front. Killed at any moment, the same
    /// command resumes. `--shard I/N` computes the I-th of N parts (0-based: a Slurm array task id or a Kubernetes
    /// job completion index); `design merge` gathers them.
    Search(SearchArgs),
    /// Gathers the parts of a search's shards into one results file, equal to an unsharded run's.
    Merge(MergeArgs),
}

/// Arguments of `metaplate design search`.
#[derive(Args)]
pub struct SearchArgs {
    /// The search file (TOML; docs/design.md).
    search: PathBuf,
    /// Folder of the results (made when missing; a folder of the same search resumes).
    #[arg(long)]
    out: PathBuf,
    /// Compute only the designs whose index is I modulo N (0 <= I < N).
    #[arg(long, default_value = "0/1")]
    shard: String,
    /// Print one JSON object per finished design on stdout instead of the bar and the front.
    #[arg(long)]
    json: bool,
}

/// Arguments of `metaplate design merge`.
#[derive(Args)]
pub struct MergeArgs {
    /// The search file the shards ran.
    search: PathBuf,
    /// The shards' output folders.
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// The gathered results file (Parquet).
    #[arg(long)]
    out: PathBuf,
}

/// Arguments of `metaplate design band`.
#[derive(Args)]
pub struct BandArgs {
    /// Design: a built-in name (`paper`) or a TOML design file.
    design: String,
    /// Wave vectors along Gamma-X-M-Gamma, both Gammas included (the paper: 90).
    #[arg(long, default_value_t = BandOptions::default().wave_vectors)]
    wave_vectors: usize,
    /// Modes per wave vector.
    #[arg(long, default_value_t = BandOptions::default().modes)]
    modes: usize,
    /// Plate elements along each side of the cell.
    #[arg(long, default_value_t = MeshOptions::default().per_side)]
    per_side: usize,
    /// Plate elements from the rod's footprint to the cell's side.
    #[arg(long, default_value_t = MeshOptions::default().radial)]
    radial: usize,
    /// Beam elements along the rod.
    #[arg(long, default_value_t = MeshOptions::default().rod_elements)]
    rod_elements: usize,
    /// Frequencies at which to report the slow branch's wavelength, Hz (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = PAPER_WAVELENGTH_FREQS_HZ)]
    wavelength_at_hz: Vec<f64>,
    /// Print one JSON object on stdout instead of the table.
    #[arg(long)]
    json: bool,
    /// Also write every branch point as Parquet to this file.
    #[arg(long)]
    parquet: Option<PathBuf>,
    /// Also draw the band diagram, phase velocity and wavelength (PNG and SVG) into this directory.
    #[arg(long)]
    figures: Option<PathBuf>,
}

/// Runs a `metaplate design` command.
pub fn run(command: &DesignCommand) -> anyhow::Result<()> {
    match command {
        DesignCommand::Band(args) => band(args),
        DesignCommand::Search(args) => search(args),
        DesignCommand::Merge(args) => {
            let spec = SearchSpec::load(&args.search)?;
            let results = search::merge(&spec, &args.dirs, &args.out)?;
            print_front(&results);
            Ok(())
        }
    }
}

fn band(args: &BandArgs) -> anyhow::Result<()> {
    let design = Design::resolve(&args.design).with_context(|| format!("loading design {}", args.design))?;
    let options = BandOptions {
        wave_vectors: args.wave_vectors,
        modes: args.modes,
        mesh: MeshOptions { per_side: args.per_side, radial: args.radial, rod_elements: args.rod_elements },
        threads: 0,
    };
    let band = band_diagram(&design, &options, &args.wavelength_at_hz)?;
    if let Some(path) = &args.parquet {
        metaplate_design::write_parquet(path, &band).with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(dir) = &args.figures {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        metaplate_figures::band_structure(dir, "band_structure", &metaplate_figures::design_band(&design, &band))?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&band)?);
    } else {
        print!("{}", band.table_text());
    }
    Ok(())
}

fn search(args: &SearchArgs) -> anyhow::Result<()> {
    let spec = SearchSpec::load(&args.search)?;
    let shard = Shard::parse(&args.shard)?;
    let mut bar = None;
    let outcome = search::run(
        &spec,
        &args.out,
        shard,
        &mut |p| {
            if args.json {
                if let Some(last) = &p.last {
                    println!(
                        "{}",
                        serde_json::json!({"event": "design", "done": p.done, "total": p.total, "result": last})
                    );
                }
                return;
            }
            let bar = bar.get_or_insert_with(|| {
                if p.resumed > 0 {
                    eprintln!("resuming: {} of {} designs already computed", p.resumed, p.total);
                }
                crate::progress::bar(p.total as u64, "designs")
            });
            bar.set_position(p.done as u64);
        },
        &|| false,
    )?;
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    for path in &outcome.recomputed {
        eprintln!("{} could not be read and was computed again", path.display());
    }
    match &outcome.results {
        Some(results) if !args.json => print_front(results),
        Some(_) => {}
        None => eprintln!(
            "shard {}: {} designs computed; gather the shards with `metaplate design merge`",
            args.shard,
            outcome.computed.len()
        ),
    }
    Ok(())
}

/// The count of feasible designs and the trade-off front, one line each.
fn print_front(results: &[DesignResult]) {
    let feasible = results.iter().filter(|r| r.feasible).count();
    println!("{feasible} of {} designs feasible; the trade-off front:", results.len());
    for r in results.iter().filter(|r| r.on_front) {
        let c = &r.candidate;
        println!(
            "  #{}: rod {:.2} x {:.3} mm {}, a {:.1} mm, plate {:.2} mm {}: {:.2} kg/m^2 added, c <= {:.2} m/s, top {:.0} Hz",
            c.index,
            c.rod_height_m * 1e3,
            c.rod_diameter_m * 1e3,
            c.rod_material,
            c.lattice_constant_m * 1e3,
            c.plate_thickness_m * 1e3,
            c.plate_material,
            r.added_mass_kg_m2,
            r.max_phase_velocity_m_s,
            r.top_hz
        );
    }
}
