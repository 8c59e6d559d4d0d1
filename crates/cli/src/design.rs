//! `metaplate design ...`: a metamaterial unit cell's band structure (`metaplate_design`).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::Context;
use arrow_array::{ArrayRef, Float64Array, RecordBatch, UInt32Array};
use arrow_schema::{DataType, Field, Schema};
use clap::{Args, Subcommand};
use metaplate_design::{BandDiagram, BandOptions, Design, MeshOptions, PAPER_WAVELENGTH_FREQS_HZ, band_diagram};
use metaplate_figures::{BandFigure, Curve};

/// Subcommands of `metaplate design`.
#[derive(Subcommand)]
pub enum DesignCommand {
    /// The band diagram of a unit cell along Gamma-X-M-Gamma (finite elements, Bloch conditions): each branch's
    /// phase velocity and wavelength, each mode's plate energy share, the clamped cell's resonator mode, the
    /// homogeneous plate's A0. A table, or JSON with --json; Parquet points with --parquet; the paper's Fig. 2B-D
    /// with --figures.
    Band(BandArgs),
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
        write_parquet(path, &band).with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(dir) = &args.figures {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        metaplate_figures::band_structure(dir, "band_structure", &figure(&design, &band))?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&band)?);
    } else {
        print!("{}", band.table_text());
    }
    Ok(())
}

/// One row per branch point: mode, path index and position, wave vector, frequency, phase velocity, wavelength,
/// plate energy share (null phase velocity and wavelength at Gamma).
fn write_parquet(path: &Path, band: &BandDiagram) -> anyhow::Result<()> {
    let points = || band.branches.iter().flat_map(|b| b.points.iter().map(move |p| (b.mode, p)));
    let f64s = |f: &dyn Fn(&metaplate_design::BranchPoint) -> f64| -> ArrayRef {
        Arc::new(Float64Array::from(points().map(|(_, p)| f(p)).collect::<Vec<_>>()))
    };
    let optional = |f: &dyn Fn(&metaplate_design::BranchPoint) -> Option<f64>| -> ArrayRef {
        Arc::new(Float64Array::from(points().map(|(_, p)| f(p)).collect::<Vec<_>>()))
    };
    let u32s = |v: Vec<usize>| -> anyhow::Result<ArrayRef> {
        let v: Result<Vec<u32>, _> = v.into_iter().map(u32::try_from).collect();
        Ok(Arc::new(UInt32Array::from(v?)))
    };
    let position = |i: usize| band.path.get(i).map_or(f64::NAN, |p| p.path_position);
    let schema = Arc::new(Schema::new(vec![
        Field::new("mode", DataType::UInt32, false),
        Field::new("path_index", DataType::UInt32, false),
        Field::new("path_position", DataType::Float64, false),
        Field::new("kx_rad_m", DataType::Float64, false),
        Field::new("ky_rad_m", DataType::Float64, false),
        Field::new("freq_hz", DataType::Float64, false),
        Field::new("phase_velocity_m_s", DataType::Float64, true),
        Field::new("wavelength_m", DataType::Float64, true),
        Field::new("plate_energy_share", DataType::Float64, false),
    ]));
    let columns = vec![
        u32s(points().map(|(m, _)| m).collect())?,
        u32s(points().map(|(_, p)| p.path_index).collect())?,
        f64s(&|p| position(p.path_index)),
        f64s(&|p| p.kx_rad_m),
        f64s(&|p| p.ky_rad_m),
        f64s(&|p| p.freq_hz),
        optional(&|p| p.phase_velocity_m_s),
        optional(&|p| p.wavelength_m),
        f64s(&|p| p.plate_energy_share),
    ];
    let batch = RecordBatch::try_new(schema.clone(), columns)?;
    let props = parquet::file::properties::WriterProperties::builder()
        .set_compression(parquet::basic::Compression::SNAPPY)
        .set_key_value_metadata(Some(vec![parquet::file::metadata::KeyValue::new(
            "metaplate.design".to_owned(),
            band.design.clone(),
        )]))
        .build();
    let mut bytes = Vec::new();
    let mut writer = parquet::arrow::ArrowWriter::try_new(&mut bytes, schema, Some(props))?;
    writer.write(&batch)?;
    writer.close()?;
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().and_then(|n| n.to_str()).context("the Parquet path names no file")?;
    metaplate_store::write_bytes(dir, name, &bytes)?;
    Ok(())
}

/// The paper's Fig. 2B-D: the first five branches with the folded A0 and f_n, up to 1.5 times the top of m = 2 (the
/// slow branch and its partner stay legible; the rod's higher modes are kHz above); c(f) and lambda(f) of m = 1, 2
/// with the analytic A0's.
fn figure(design: &Design, band: &BandDiagram) -> BandFigure {
    let position = |i: usize| band.path[i].path_position;
    let f_max = band.branches.iter().take(2).flat_map(|b| b.points.iter().map(|p| p.freq_hz)).fold(0.0, f64::max);
    let clip_hz = 1.5 * f_max;
    // Curves broken where they leave the plot, so that no line joins across the gap (the figure labels the first).
    let clipped = |label: &str, values: &mut dyn Iterator<Item = (f64, f64)>| -> Vec<Curve> {
        let mut out: Vec<Curve> = Vec::new();
        let mut open = false;
        for (x, f) in values {
            if f <= clip_hz {
                if !open {
                    out.push(Curve { label: label.to_owned(), points: Vec::new() });
                    open = true;
                }
                if let Some(c) = out.last_mut() {
                    c.points.push((x, f));
                }
            } else {
                open = false;
            }
        }
        out
    };
    let branches: Vec<Curve> = band.branches[..band.branches.len().min(5)]
        .iter()
        .map(|b| Curve {
            label: format!("m = {}", b.mode),
            points: b
                .points
                .iter()
                .filter(|p| p.freq_hz <= clip_hz)
                .map(|p| (position(p.path_index), p.freq_hz))
                .collect(),
        })
        .filter(|c| !c.points.is_empty())
        .collect();
    let a0_folded = band
        .a0_folded_hz
        .iter()
        .flat_map(|f| {
            clipped("A0, homogeneous plate (folded)", &mut f.iter().enumerate().map(|(i, &f)| (position(i), f)))
        })
        .collect();
    let per_branch = |value: &dyn Fn(&metaplate_design::BranchPoint) -> Option<f64>| -> Vec<Curve> {
        band.branches
            .iter()
            .take(2)
            .map(|b| Curve {
                label: format!("m = {}", b.mode),
                points: b.points.iter().filter_map(|p| value(p).map(|v| (p.freq_hz, v))).collect(),
            })
            .collect()
    };
    let plate = design.plate;
    let a0_at = |f_hz: f64| {
        let k = plate.a0_wavenumber_rad_m(f_hz);
        (2.0 * std::f64::consts::PI * f_hz / k, 2.0 * std::f64::consts::PI / k)
    };
    let freqs: Vec<f64> = (1..=100).map(|i| f_max * f64::from(i) / 100.0).collect();
    BandFigure {
        title: format!("Band structure of the {} unit cell (up to {clip_hz:.0} Hz)", band.design),
        branches,
        a0_folded,
        resonator_hz: band.resonator_mode_hz,
        phase_velocity: per_branch(&|p| p.phase_velocity_m_s),
        wavelength: per_branch(&|p| p.wavelength_m),
        a0_phase_velocity: Some(Curve {
            label: "A0, homogeneous plate (analytic)".into(),
            points: freqs.iter().map(|&f| (f, a0_at(f).0)).collect(),
        }),
        a0_wavelength: Some(Curve {
            label: "A0, homogeneous plate (analytic)".into(),
            points: freqs.iter().map(|&f| (f, a0_at(f).1)).collect(),
        }),
    }
}
