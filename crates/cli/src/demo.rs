//! `metaplate demo`: the main job, on the built-in simulated plates, with no hardware and no arguments
//! (`metaplate_evaluation::demo` says what it does). It prints the paper-against-suite table (DESIGN.md section 6)
//! and writes `DIR/summary.json` and `DIR/report.html`; progress goes to stderr.

use std::path::PathBuf;

use clap::Args;
use indicatif::ProgressBar;
use metaplate_core::grid::GridSubset;
use metaplate_evaluation::Progress;
use metaplate_evaluation::demo::{DemoRequest, run_demo};
use metaplate_recipes::{Event, Observer};

use crate::cache::CacheArgs;
use crate::progress;

/// Arguments of `metaplate demo`.
#[derive(Args)]
pub struct DemoArgs {
    /// Output directory (created; an earlier demo's results in it are replaced).
    #[arg(long, default_value = "metaplate-demo")]
    out: PathBuf,
    /// The paper's full 49 x 25 grid and protocol (5 x 3 s sweeps) instead of a 25 x 13 grid and the quick protocol.
    #[arg(long)]
    full: bool,
    /// Seed of the simulated lab (noise, speckle, actuator spread) and of the recipes' choices.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    cache: CacheArgs,
    /// Scan grid NXxNY (a subset of the plate's grid), for tests.
    #[arg(long, hide = true, conflicts_with = "full")]
    grid: Option<String>,
}

/// Runs the demo.
pub fn run(args: &DemoArgs) -> anyhow::Result<()> {
    let cache_dir = args.cache.dir();
    let request = DemoRequest {
        out: &args.out,
        full: args.full,
        grid: args.grid.as_deref().map(str::parse::<GridSubset>).transpose()?,
        seed: args.seed,
        cache_dir: cache_dir.as_deref(),
    };
    let summary = run_demo(&request, &mut Bars { label: String::new(), spinner: None, bar: None })?;
    print!("{}", summary.table_text());
    println!(
        "\nwrote {} and the datasets, figures and patterns under {}",
        args.out.join("summary.json").display(),
        args.out.display()
    );
    println!("the report (open it in a browser): {}", args.out.join("report.html").display());
    Ok(())
}

/// A spinner per step on stderr, and a progress bar for a recipe's points once it starts.
struct Bars {
    label: String,
    spinner: Option<ProgressBar>,
    bar: Option<ProgressBar>,
}

impl Progress for Bars {
    fn begin(&mut self, label: &str) {
        label.clone_into(&mut self.label);
        self.spinner = Some(progress::spinner(label.to_owned()));
    }

    fn end(&mut self) {
        for bar in [self.spinner.take(), self.bar.take()].into_iter().flatten() {
            bar.finish_and_clear();
        }
    }
}

impl Observer for Bars {
    fn event(&mut self, event: &Event) {
        match event {
            Event::Started { total, done, .. } => {
                if let Some(spinner) = self.spinner.take() {
                    spinner.finish_and_clear();
                }
                let bar = progress::bar(*total as u64, &self.label);
                bar.set_position(*done as u64);
                self.bar = Some(bar);
            }
            Event::Committed { done, snr_db, clock_s, .. } => {
                if let Some(bar) = &self.bar {
                    bar.set_position(*done as u64);
                    let snr = snr_db.map_or_else(String::new, |s| format!(", SNR {s:.0} dB"));
                    bar.set_message(format!("{} ({:.2} h simulated{snr})", self.label, clock_s / 3600.0));
                }
            }
            Event::Stopped { .. } | Event::Finished { .. } => self.end(),
            _ => {}
        }
    }
}
