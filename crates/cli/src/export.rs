//! `metaplate export`: a dataset as a universal file (UFF datasets 164, 2411 and 58 or 58b), streamed
//! ([`metaplate_interchange::export`] says what the file holds).

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use metaplate_core::grid::GridSubset;
use metaplate_interchange::{ExportOptions, actuator_sites, default_out, export};
use metaplate_uff::{ByteOrder, Format, Precision};

use crate::progress;

/// Arguments of `metaplate export`.
#[derive(Args)]
pub struct ExportArgs {
    /// Dataset directory.
    #[arg(long)]
    data: PathBuf,
    /// `uff58` (ASCII) or `uff58b` (binary).
    #[arg(long, value_enum)]
    format: UffFormat,
    /// Output file (default: the dataset directory's name with `.uff`, beside it).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Only the points of an evenly spread NXxNY subset of the dataset's grid (for example 7x5).
    #[arg(long)]
    points: Option<GridSubset>,
    /// Also write each frequency response function (type 4, complex) after its impulse response.
    #[arg(long)]
    frequency: bool,
    /// Precision of the values: single (6 significant digits in ASCII, f32 in binary) or double.
    #[arg(long, value_enum, default_value_t = PrecisionArg::Single)]
    precision: PrecisionArg,
    /// Byte order of a binary (uff58b) file.
    #[arg(long, value_enum, default_value_t = ByteOrderArg::Little)]
    byte_order: ByteOrderArg,
    /// A scene file giving the actuators' positions (default: the dataset's built-in scene, when it is one).
    #[arg(long)]
    scene: Option<PathBuf>,
}

/// The file format.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum UffFormat {
    /// Dataset 58, 80-column ASCII.
    Uff58,
    /// Dataset 58b, binary values.
    Uff58b,
}

/// Precision of the values.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PrecisionArg {
    /// Single.
    Single,
    /// Double.
    Double,
}

/// Byte order of binary values.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ByteOrderArg {
    /// Least significant byte first.
    Little,
    /// Most significant byte first.
    Big,
}

/// Runs `metaplate export`.
pub fn run(args: &ExportArgs) -> anyhow::Result<()> {
    let out = match &args.out {
        Some(out) => out.clone(),
        None => default_out(&args.data)?,
    };
    let format = match args.format {
        UffFormat::Uff58 => Format::Ascii,
        UffFormat::Uff58b => Format::Binary {
            byte_order: match args.byte_order {
                ByteOrderArg::Little => ByteOrder::LittleEndian,
                ByteOrderArg::Big => ByteOrder::BigEndian,
            },
        },
    };
    let precision = match args.precision {
        PrecisionArg::Single => Precision::Single,
        PrecisionArg::Double => Precision::Double,
    };
    let options = ExportOptions { format, precision, frequency: args.frequency, points: args.points };
    let actuator_sites = actuator_sites(&args.data, args.scene.as_deref())?;
    let bar = progress::bar(0, "exporting");
    let summary = export(&args.data, &out, &options, &actuator_sites, |p| {
        bar.set_length(p.total);
        bar.set_position(p.done);
    })?;
    bar.finish_and_clear();
    eprintln!(
        "wrote {} ({} records, {:.1} MB in {:.2} s: {:.1} MB/s, {:.0} records/s)",
        out.display(),
        summary.records,
        summary.bytes as f64 / 1e6,
        summary.elapsed_s,
        summary.bytes as f64 / 1e6 / summary.elapsed_s.max(1e-9),
        summary.records as f64 / summary.elapsed_s.max(1e-9),
    );
    Ok(())
}
