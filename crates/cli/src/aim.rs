//! `metaplate aim teach`: jog the galvo mirrors' beam onto marks with the keyboard, then write the fit (the keys,
//! the teaching and the fit are `metaplate_aim::galvo`'s; this reads keys and prints).

use std::io::{IsTerminal as _, Read as _, Write as _};
use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use metaplate_aim::galvo::teach::{KeyDecoder, Teach, parse_mark_mm, parse_marks_mm};
use metaplate_aim::galvo::{FitModel, file};
use metaplate_core::aim::MirrorOutputs;
use metaplate_lab::mirrors::{MirrorGeometry, MockMirrors};

#[derive(Subcommand)]
pub enum AimCommand {
    /// Jog the beam onto marks (arrows move, +/- change the step 1 mV to 1 V, Enter records, q finishes) and
    /// write the galvo fit; stdin that is not a terminal is read as the same key bytes.
    Teach(TeachArgs),
}

#[derive(Args)]
pub struct TeachArgs {
    /// The hardware file: its `[aim]` (backend "galvo") names the mirrors' outputs and the fit file to write.
    #[arg(long, required_unless_present = "scene", conflicts_with = "scene")]
    hardware: Option<PathBuf>,
    /// Teach the mock lab's mirrors of this scene (built-in name or file) instead; prints where the beam lands.
    #[arg(long)]
    scene: Option<String>,
    /// A mark's plate coordinates in mm, `X,Y`; repeat, in teaching order.
    #[arg(long = "mark-mm", value_name = "X,Y", allow_hyphen_values = true, value_parser = parse_mark_mm)]
    marks: Vec<(f64, f64)>,
    /// A file of marks, one `X, Y` in mm per line (`#` comments), taught after any --mark-mm.
    #[arg(long, value_name = "FILE")]
    marks_file: Option<PathBuf>,
    /// The map: projective (at least 4 marks) or polynomial2 (at least 6).
    #[arg(long, default_value = "projective", value_parser = str::parse::<FitModel>)]
    model: FitModel,
    /// Where to write the fit (default: the hardware file's `aim.fit`; required with --scene).
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
}

pub fn run(command: &AimCommand) -> anyhow::Result<()> {
    let AimCommand::Teach(args) = command;
    let mut marks = args.marks.clone();
    if let Some(path) = &args.marks_file {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        marks.extend(parse_marks_mm(&text, &path.display().to_string())?);
    }
    let (mut outputs, fit_path, mock): (Box<dyn MirrorOutputs>, PathBuf, Option<MockMirrors>) = match &args.hardware {
        Some(path) => {
            let hardware = metaplate_drivers::HardwareFile::load(path)?;
            let (outputs, fit) = metaplate_drivers::open_galvo_outputs(&hardware)?;
            (outputs, args.out.clone().unwrap_or(fit), None)
        }
        None => {
            let name = args.scene.as_deref().unwrap_or_default();
            let scene = metaplate_core::scene::Scene::resolve(name).with_context(|| format!("loading scene {name}"))?;
            let Some(out) = args.out.clone() else { bail!("--scene needs --out FILE: where to write the fit") };
            let mirrors = MockMirrors::new(MirrorGeometry::seeded(scene.seed));
            (Box::new(mirrors.clone()), out, Some(mirrors))
        }
    };
    let mut teach = Teach::new(marks, outputs.limit_v())?;
    teach.start(outputs.as_mut())?;
    let raw = std::io::stdin().is_terminal().then(raw_mode).transpose()?;
    let mut out = std::io::stdout();
    // In raw mode a newline does not return the carriage: every line ends with both.
    let mut say = |line: String| write!(out, "{line}\r\n").and_then(|()| out.flush());
    let beam = |m: &Option<MockMirrors>| {
        m.as_ref()
            .and_then(MockMirrors::beam_m)
            .map_or(String::new(), |(x, y)| format!("; beam at ({:.2}, {:.2}) mm", x * 1e3, y * 1e3))
    };
    if let Some(prompt) = teach.prompt() {
        say(format!("{prompt}: jog onto it, Enter records, q finishes{}", beam(&mock)))?;
    }
    let mut decoder = KeyDecoder::new();
    let mut byte = [0u8; 1];
    while !teach.is_finished() && std::io::stdin().read(&mut byte)? == 1 {
        let Some(key) = decoder.push(byte[0]) else { continue };
        let event = teach.press(key, outputs.as_mut())?;
        if let Some(message) = teach.message(&event) {
            say(format!("{message}{}", beam(&mock)))?;
        }
    }
    drop(raw);
    let fit = teach.fit(args.model)?;
    file::write(&fit_path, &fit)?;
    println!("wrote {}: {}", fit_path.display(), fit.summary());
    Ok(())
}

/// The terminal in raw mode (keys arrive one by one, unechoed) until the guard drops.
fn raw_mode() -> anyhow::Result<RawMode> {
    use rustix::termios::{OptionalActions, tcgetattr, tcsetattr};
    let saved = tcgetattr(std::io::stdin()).context("reading the terminal's mode")?;
    let mut raw = saved.clone();
    raw.make_raw();
    tcsetattr(std::io::stdin(), OptionalActions::Now, &raw).context("setting the terminal to raw mode")?;
    Ok(RawMode(saved))
}

struct RawMode(rustix::termios::Termios);

impl Drop for RawMode {
    fn drop(&mut self) {
        // Restoring can only fail if stdin stopped being a terminal; nothing is left to restore then.
        let _ = rustix::termios::tcsetattr(std::io::stdin(), rustix::termios::OptionalActions::Now, &self.0);
    }
}
