//! `metaplate experiment list|run|stimuli|report|correct`: the built-in experiments, a session (`experiment_run`),
//! the stimuli (`experiment_stimuli`), the report, settling a trial; the work is `metaplate_experiment`'s.

use std::io::Write;
use std::path::PathBuf;

use clap::{Args, Subcommand};
use metaplate_experiment::listing::list_builtins;
use metaplate_experiment::report::SessionReport;
use metaplate_experiment::settle::correct;
use metaplate_experiment::trials_parquet::write_parquet;

/// Arguments of `metaplate experiment`.
#[derive(Args)]
pub struct ExperimentArgs {
    #[command(subcommand)]
    command: ExperimentCommand,
}

#[derive(Subcommand)]
enum ExperimentCommand {
    /// List the built-in experiments (the paper's four): conditions, repeats, trials, chance.
    List {
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Run one participant's session on the rig (the mock lab of --scene, or --hardware FILE): the plan stored
    /// before the first trial, every trial journalled as it ends, resumed after a crash at the next trial. One
    /// process at a time: a second on a session in use is refused, naming the process that runs it.
    Run(Box<crate::experiment_run::RunArgs>),
    /// How a scan renders experiments' stimuli: each stimulus's predicted peak velocity at its target, null and
    /// other pixels at the drive level, and the suppression (weakest target over strongest null, dB).
    Stimuli(Box<crate::experiment_stimuli::StimuliArgs>),
    /// Report session directories of one experiment: per participant and condition, accuracy with a Wilson 95 %
    /// interval, the exact one-sided binomial p against chance, the confusion matrix, trial times where recorded;
    /// pooled over participants. Trials journalled more than once are listed with the answer counted.
    Report {
        /// Session directories (each holds plan.json and journal.jsonl), one per participant.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Print JSON instead of tables.
        #[arg(long)]
        json: bool,
        /// Write every scored trial as one Parquet file (one row per trial; readable by polars and pyarrow).
        #[arg(long, value_name = "FILE")]
        parquet: Option<PathBuf>,
        /// Write the per-participant accuracy figure (with the chance line) into this directory, PNG and SVG.
        #[arg(long, value_name = "DIR")]
        figures: Option<PathBuf>,
    },
    /// Settle a trial of a session: journal a correction of its answer (what a session whose trial was journalled
    /// twice with different answers needs before it can continue).
    Correct {
        /// The session directory.
        dir: PathBuf,
        /// The trial (its index in the plan, as the refusal names it).
        #[arg(long)]
        trial: u32,
        /// The answer that counts: a response label.
        #[arg(long)]
        response: String,
    },
}

/// Runs `metaplate experiment ...`.
pub fn run(args: &ExperimentArgs) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    match &args.command {
        ExperimentCommand::List { json } => {
            let listing = list_builtins()?;
            if *json {
                writeln!(out, "{}", serde_json::to_string_pretty(&listing)?)?;
            }
            for e in listing.iter().filter(|_| !*json) {
                writeln!(out, "{e}")?;
            }
        }
        ExperimentCommand::Run(args) => crate::experiment_run::run(args)?,
        ExperimentCommand::Stimuli(args) => crate::experiment_stimuli::run(args)?,
        ExperimentCommand::Report { dirs, json, parquet, figures } => {
            let (report, sessions) = SessionReport::read(dirs)?;
            if let Some(path) = parquet {
                write_parquet(path, &sessions)?;
            }
            if let Some(dir) = figures {
                report.write_figure(dir)?;
            }
            if *json {
                writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
            } else {
                report.write_tables(&mut out)?;
            }
        }
        ExperimentCommand::Correct { dir, trial, response } => {
            correct(dir, *trial, response)?;
            writeln!(out, "trial {trial} of {} now counts `{response}`", dir.display())?;
        }
    }
    Ok(())
}
