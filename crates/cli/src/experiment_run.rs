//! `metaplate experiment run`: one participant's session of a behavioural experiment on the rig.
//!
//! Before the first trial the full plan is drawn (`--seed`, default the file's `order.seed`), hashed and stored
//! (`journal::Session::start`: a resume needs the same plan and experiment file, unless `--force`), and every
//! stimulus is rendered once through the calibration (`play::prepare`: pixels snapped to the scan's points, refused
//! off the plate, in a gap or when a drive would clip), its drive hash recorded with each trial. Each trial plays
//! its stimulus on the rig (the onset measured on the loopback), takes a response and is journalled (fsync'd) as it
//! ends. A session killed at any moment resumes at the next trial with the same plan.
//!
//! Timing: a stimulus starts one impulse-response length into its drive (the lead the inverse filter needs to build
//! it) and the drive lasts one more after it (the plate's ring-down): the drive is `2 x IR + stimulus` long. Times
//! in the journal are on the rig's clock (virtual on the mock lab, where the console's waits for the experimenter
//! are added to it): `scheduled_onset_s` and `measured_onset_s` are
//! the clock at the play's start plus the playback's scheduled and loopback-measured onsets.
//!
//! Responses:
//! - `--participant sim[:opts]`: the simulated participant (`metaplate_experiment::participant`) answers from the
//!   predicted peak velocities at the pixels: the stimulus's target pixels against the others, with the odd pattern
//!   of an odd-one-out stimulus rendered alone (the others null) for that prediction. It plays each presentation
//!   once and takes its model's response time on the rig's clock.
//! - any other id: the experimenter's console on the terminal (stderr), line-based: the trial number and the
//!   response options only (never the answer); a response key then Enter; `r` repeat the stimulus, `u` undo the
//!   last answer (an undo entry; that trial is asked again), `v` void the trial (re-queued at the end), `p` pause.
//!   An `until-response` experiment replays the stimulus every `repeat_pause_s` until an entry. End of input stops
//!   the session (resumable).
//!
//! A hardware file's keypad answers too: a key press is that key's entry (letters and digits).
//!
//! Not done here: the masking noise (a warning says so).

use std::collections::BTreeMap;
use std::io::BufRead;
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::Duration;

use anyhow::{Context, bail};
use clap::Args;
use metaplate_control::target::Waveform;
use metaplate_core::audio::AudioConfig;
use metaplate_core::hash::fnv1a_64;
use metaplate_core::rig::{Rig, Wiring};
use metaplate_experiment::file::{HASH_PREFIX, Presentation};
use metaplate_experiment::{
    Entry, Experiment, FieldAtPixels, Plan, PlannedTrial, Session, SessionRecord, SimParticipant, Stimulus,
    TrialRecord, builtin,
};
use metaplate_keypad::{HidInput, KeyAction, Keypad};
use metaplate_recipes::drive::DRIVE_PEAK_FS;
use metaplate_store::Dataset;
use serde_json::json;

use crate::focus::{PixelSpec, RenderOptions, TargetSpec};
use crate::play::{self, Pattern};
use crate::run::Source;

/// Console keys of the experimenter's actions (response keys must differ from them).
const REPEAT_KEY: &str = "r";
const UNDO_KEY: &str = "u";
const VOID_KEY: &str = "v";
const PAUSE_KEY: &str = "p";
/// How long the keypad's thread waits for a report before looking again, s.
const KEYPAD_POLL_S: f64 = 0.2;

/// Arguments of `metaplate experiment run`.
#[derive(Args)]
pub struct RunArgs {
    /// A built-in experiment (`metaplate experiment list`) or an experiment file.
    experiment: String,
    /// The participant: an id (`P01`: the experimenter's console answers), or `sim[:opts]`, the simulated
    /// participant (`sim:seed=3`; options: seed, threshold_m_s, level_slope_db, contrast_50_db,
    /// contrast_slope_db, lapse).
    #[arg(long)]
    participant: String,
    /// Scan dataset directory (impulse responses in m/s per full-scale drive, measured through the calibration).
    #[arg(long)]
    data: PathBuf,
    /// Calibration dataset the scan was measured through: the drives go through its Kirkeby filters.
    #[arg(long)]
    calibration: PathBuf,
    /// Session directory: plan.json and journal.jsonl. An existing session there is resumed.
    #[arg(long)]
    out: PathBuf,
    /// Where to play: --scene (mock lab) or --hardware FILE.
    #[command(flatten)]
    source: Source,
    /// Seed of the plan (the trial order) and of the stimuli's noise. Default: the file's `order.seed`.
    #[arg(long)]
    seed: Option<u64>,
    /// Playback level relative to full scale (each stimulus's drives are peak-normalised to 1, then scaled).
    #[arg(long, default_value_t = DRIVE_PEAK_FS)]
    level: f64,
    /// Resume even though the plan, the experiment file or the participant differ from the stored session's (the
    /// stored plan is kept, and the forcing journalled).
    #[arg(long)]
    force: bool,
    /// Print one JSON object per trial on stdout (and one at the end).
    #[arg(long)]
    json: bool,
    /// Mock lab only: where the plate's Green's functions are cached.
    #[command(flatten)]
    cache: crate::cache::CacheArgs,
}

/// How stimuli are driven: through the calibration in `calibration`, at `level` (full scale 1).
pub(crate) struct DriveOptions {
    pub calibration: PathBuf,
    pub level: f64,
}

/// A stimulus rendered and checked, ready to play.
pub(crate) struct Prepared {
    pub pattern: Pattern,
    /// `fnv1a64:` over the drive samples' bits and the level.
    pub drive_hash: String,
    /// What the simulated participant feels (m/s), `None` for a human participant.
    pub field: Option<FieldAtPixels>,
}

/// Who answers.
enum Responder {
    Sim(SimParticipant),
    Console(Receiver<String>),
}

/// How a trial ended.
enum Outcome {
    /// Journalled (answered, voided or an answer undone): go on.
    Next,
    /// The console's input ended: stop, resumable.
    Stopped,
}

/// Runs `metaplate experiment run`.
pub fn run(args: &RunArgs) -> anyhow::Result<()> {
    let experiment = builtin::resolve(&args.experiment)?;
    let participant = args.participant.trim();
    if participant.is_empty() {
        bail!("--participant must not be empty");
    }
    let is_sim = participant == "sim" || participant.starts_with("sim:");
    let sim = if is_sim { Some(SimParticipant::parse(participant)?) } else { None };
    if sim.is_none() {
        for r in &experiment.responses {
            if [REPEAT_KEY, UNDO_KEY, VOID_KEY, PAUSE_KEY].contains(&r.key.as_str()) {
                bail!(
                    "the response `{}` uses the key `{}`, which the console keeps for repeat (r), undo (u), void (v) \
                     and pause (p)",
                    r.label,
                    r.key
                );
            }
        }
    }
    let dataset = Dataset::open(&args.data).with_context(|| format!("opening dataset {}", args.data.display()))?;
    let plan = Plan::new(&experiment, args.seed.unwrap_or(experiment.order.seed));
    let stored = SessionRecord::read(&args.out).ok();
    if let Some(stored) = &stored
        && stored.header.participant != participant
        && !args.force
    {
        bail!(
            "{} holds the session of participant `{}`, not `{participant}` (--force to continue it anyway)",
            args.out.display(),
            stored.header.participant
        );
    }
    // The stimuli's noise is drawn from the plan's seed: a resumed session's (forced, the stored plan's) plays the
    // drives its first trials played.
    let seed = stored.as_ref().map_or(plan.seed, |s| s.header.plan.seed);
    let play::OpenedSource { mut rig, lab, keypad, .. } =
        play::rig_for(&dataset, &args.source, None, args.cache.dir())?;
    // Every stimulus rendered once, before the session is started or resumed: a refusal comes now, with nothing
    // written.
    let mut prepared: BTreeMap<String, Prepared> = BTreeMap::new();
    for stimulus in &experiment.stimuli {
        let drive = DriveOptions { calibration: args.calibration.clone(), level: args.level };
        let p = prepare_stimulus(&dataset, &drive, &experiment, stimulus, seed, &rig.wiring, sim.is_some())
            .with_context(|| format!("preparing the stimulus `{}`", stimulus.id))?;
        prepared.insert(stimulus.id.clone(), p);
    }
    if let Some(m) = &experiment.masking {
        // The interface must open the masking pair too: asked now, so that a refusal comes with nothing written.
        let channels = prepared.values().map(|p| p.pattern.playback.channels()).max().unwrap_or(0);
        rig.audio
            .configure(&AudioConfig { channels, ..rig.wiring.audio_config() })
            .with_context(|| format!("opening the masking outputs {} and {}", m.channels[0], m.channels[1]))?;
        eprintln!(
            "masking: pink noise on outputs {} and {} at {} dB FS RMS while each stimulus plays",
            m.channels[0], m.channels[1], m.level_dbfs
        );
    }
    let mut session = Session::start(&args.out, &experiment, participant, plan, args.force)
        .with_context(|| format!("starting the session in {}", args.out.display()))?;
    // A forced resume keeps the stored plan: it may name stimuli the given file lacks.
    if let Some(t) = session.header().plan.trials.iter().find(|t| !prepared.contains_key(&t.stimulus_id)) {
        bail!("the stored plan plays `{}`, which the experiment file does not have", t.stimulus_id);
    }

    let mut responder = match sim {
        Some(s) => Responder::Sim(s),
        None => Responder::Console(console_input(keypad)),
    };
    let mut answered = answered_stack(&SessionRecord::read(&args.out)?.entries);
    let total = session.header().plan.trials.len();
    let header = session.header();
    eprintln!(
        "{} for `{participant}`: plan {} ({total} trials, seed {}), session {}",
        header.experiment,
        header.plan_hash,
        header.plan.seed,
        args.out.display()
    );
    let mut stopped = false;
    while let Some(trial) = session.next_trial().cloned() {
        let done = session.progress().results.iter().filter(|r| r.is_some()).count();
        let stimulus = prepared.get(&trial.stimulus_id).context("internal: stimulus not prepared")?;
        let ctx = TrialContext {
            number: done + 1,
            total,
            experiment: &experiment,
            json: args.json,
            on_mock_lab: lab.is_some(),
        };
        let outcome = match &mut responder {
            Responder::Sim(sim) => sim_trial(&mut session, &mut rig, &trial, stimulus, sim, &ctx)?,
            Responder::Console(lines) => {
                console_trial(&mut session, &mut rig, &trial, stimulus, lines, &mut answered, &ctx)?
            }
        };
        match outcome {
            Outcome::Next => {}
            Outcome::Stopped => {
                stopped = true;
                break;
            }
        }
    }
    let answered_now = session.progress().results.iter().filter(|r| r.is_some()).count();
    if args.json {
        let event = if stopped { "stopped" } else { "finished" };
        println!("{}", json!({"event": event, "dir": args.out, "answered": answered_now, "trials": total}));
    }
    if stopped {
        eprintln!("stopped with {answered_now} of {total} trials answered; the same command resumes at the next trial");
    } else {
        eprintln!(
            "session complete: {total} trials journalled in {}; `metaplate experiment report {}` reports it",
            args.out.display(),
            args.out.display()
        );
    }
    Ok(())
}

/// Renders `stimulus` (noise drawn from `seed`) through the calibration and prepares it for `rig`; for a simulated
/// participant also the field it feels.
pub(crate) fn prepare_stimulus(
    dataset: &Dataset,
    drive: &DriveOptions,
    experiment: &Experiment,
    stimulus: &Stimulus,
    seed: u64,
    wiring: &Wiring,
    for_sim: bool,
) -> anyhow::Result<Prepared> {
    let lead_s = dataset.ir_len() as f64 / dataset.sample_rate_hz();
    let options = RenderOptions { pad_s: Some(lead_s + stimulus.duration_s()), ..RenderOptions::default() };
    let pixels = stimulus.waveforms(experiment, seed)?;
    let mut specs = Vec::with_capacity(pixels.len());
    for pw in &pixels {
        let pixel = &experiment.pixels[pw.pixel];
        // One waveform per pixel: the experiment file refuses a stimulus that would need several (a sine played
        // more than once).
        let waveform = &pw.waveform;
        specs.push(PixelSpec {
            x_m: pixel.x_m,
            y_m: pixel.y_m,
            target: TargetSpec::Waveform(waveform.delayed(lead_s)),
            label: format!("{}: {}", pixel.name, waveform_kind(waveform)),
        });
    }
    let mut pattern = play::prepare(dataset, &specs, &drive.calibration, &options, wiring, drive.level)?;
    if let Some(m) = &experiment.masking {
        // Each stimulus its own masker, the same on every run of the plan's seed.
        let noise_seed = seed ^ fnv1a_64(stimulus.id.bytes());
        let ears = m.render(pattern.playback.frames(), wiring.audio_sample_rate_hz, noise_seed)?;
        for (channel, noise) in m.channels.iter().zip(&ears) {
            pattern.playback.add_output(u32::from(*channel), noise)?;
        }
    }
    // Two pixels on one measured point would be asked to do two things at once: the scan is too coarse for the
    // experiment's pixels.
    let name = |k: usize| experiment.pixels[pixels[k].pixel].name.as_str();
    for (i, a) in pattern.pixels.iter().enumerate() {
        if let Some(j) = pattern.pixels[..i].iter().position(|b| b.point_index == a.point_index) {
            bail!(
                "the pixels `{}` and `{}` snap to the same measured point ({}): the scan is too coarse for this \
                 experiment's pixels",
                name(j),
                name(i),
                a.point_index
            );
        }
    }
    let bytes = pattern.rendered.signals.iter().flatten().flat_map(|v| v.to_bits().to_le_bytes());
    let drive_hash = format!("{HASH_PREFIX}{:016x}", fnv1a_64(bytes.chain(drive.level.to_bits().to_le_bytes())));
    let field = if for_sim {
        // The answer is about the target pixels: predict them alone against silence elsewhere (for a stimulus
        // whose other pixels are null already, that is the stimulus itself).
        let alone = specs
            .iter()
            .zip(&pixels)
            .map(|(s, pw)| {
                let target = if pw.target { s.target.clone() } else { TargetSpec::Waveform(Waveform::Null) };
                PixelSpec { target, ..s.clone() }
            })
            .collect::<Vec<_>>();
        let peaks_m_s: Vec<f64> = if alone.iter().zip(&specs).all(|(a, s)| a.target == s.target) {
            pattern.pixels.iter().map(|p| p.predicted_peak_mm_s * 1e-3).collect()
        } else {
            let probe = play::prepare(dataset, &alone, &drive.calibration, &options, wiring, drive.level)?;
            probe.pixels.iter().map(|p| p.predicted_peak_mm_s * 1e-3).collect()
        };
        let pick = |target: bool| -> Vec<f64> {
            pixels.iter().zip(&peaks_m_s).filter(|(pw, _)| pw.target == target).map(|(_, v)| *v).collect()
        };
        Some(FieldAtPixels { target_peak_m_s: pick(true), other_peak_m_s: pick(false) })
    } else {
        None
    };
    Ok(Prepared { pattern, drive_hash, field })
}

/// The kind of a waveform, for reports.
fn waveform_kind(w: &Waveform) -> &'static str {
    match w {
        Waveform::Impulse { .. } | Waveform::Impulses { .. } => "impulses",
        Waveform::Noise { .. } | Waveform::NoiseBursts { .. } => "noise-bursts",
        Waveform::Sine { .. } => "sine",
        Waveform::WaveletTrain { .. } => "wavelets",
        Waveform::Null => "null",
    }
}

/// What every trial needs besides its stimulus.
struct TrialContext<'a> {
    /// 1-based position among the trials (answered so far + 1).
    number: usize,
    total: usize,
    experiment: &'a Experiment,
    json: bool,
    /// The rig's clock is the mock lab's virtual clock: the console's waits are added to it, so that a rehearsal's
    /// trial times are the experimenter's.
    on_mock_lab: bool,
}

/// One play on the rig: (scheduled, measured) onset, s on the rig's clock.
fn play_once(rig: &mut Rig, stimulus: &Prepared) -> anyhow::Result<(f64, f64)> {
    let t0 = rig.clock.now_s();
    let played = stimulus.pattern.play(rig)?;
    if played.underruns > 0 || played.gap {
        eprintln!("warning: {} audio underrun(s), recording gap: {}", played.underruns, played.gap);
    }
    Ok((t0 + played.scheduled_onset_s, t0 + played.measured_onset_s))
}

fn sim_trial(
    session: &mut Session,
    rig: &mut Rig,
    trial: &PlannedTrial,
    stimulus: &Prepared,
    sim: &SimParticipant,
    ctx: &TrialContext,
) -> anyhow::Result<Outcome> {
    eprintln!("trial {} of {}", ctx.number, ctx.total);
    let (scheduled, measured) = play_once(rig, stimulus)?;
    let field = stimulus.field.as_ref().context("internal: no predicted field for the simulated participant")?;
    let labels = session.header().labels.clone();
    let response = sim.answer(trial.index, &trial.correct, &labels, field)?.to_owned();
    let explored = ctx.experiment.presentation == Presentation::UntilResponse;
    let trial_time_s = sim.response_time_s(trial.index, explored);
    let entered_s = measured + trial_time_s;
    rig.clock.sleep_s((entered_s - rig.clock.now_s()).max(0.0));
    let record = TrialRecord {
        trial: trial.index,
        stimulus_id: trial.stimulus_id.clone(),
        drive_hash: stimulus.drive_hash.clone(),
        scheduled_onset_s: scheduled,
        measured_onset_s: Some(measured),
        repeats_requested: 0,
        response,
        response_entered_s: entered_s,
        trial_time_s,
    };
    journal_trial(session, record, ctx)?;
    Ok(Outcome::Next)
}

/// Appends a trial's record and prints its event.
fn journal_trial(session: &mut Session, record: TrialRecord, ctx: &TrialContext) -> anyhow::Result<()> {
    session.append(&Entry::Trial(record.clone()))?;
    if ctx.json {
        println!(
            "{}",
            json!({"event": "trial", "trial": record.trial, "number": ctx.number, "of": ctx.total,
                "response": record.response, "drive_hash": record.drive_hash,
                "scheduled_onset_s": record.scheduled_onset_s, "measured_onset_s": record.measured_onset_s,
                "repeats_requested": record.repeats_requested, "trial_time_s": record.trial_time_s})
        );
    }
    Ok(())
}

/// The trials answered and not since undone or voided, in the order they were answered: what `u` undoes.
fn answered_stack(entries: &[Entry]) -> Vec<u32> {
    let mut stack: Vec<u32> = Vec::new();
    for e in entries {
        match e {
            Entry::Trial(r) => stack.push(r.trial),
            Entry::Undo { trial, .. } | Entry::Void { trial, .. } => stack.retain(|t| t != trial),
            Entry::Correction { .. } | Entry::Forced { .. } => {}
        }
    }
    stack
}

/// The console's entries: standard input's lines, and the keypad's key presses (one character each), read on
/// threads (so that a stimulus can repeat while the console waits).
fn console_input(keypad: Option<Keypad<Box<dyn HidInput>>>) -> Receiver<String> {
    let (tx, rx) = std::sync::mpsc::channel();
    if let Some(keypad) = keypad {
        eprintln!("the keypad answers too: its keys are the console's");
        let tx = tx.clone();
        std::thread::spawn(move || forward_keypad_keys(keypad, |entry| tx.send(entry).is_ok()));
    }
    std::thread::spawn(move || {
        for line in std::io::stdin().lock().lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    rx
}

/// Hands each key pressed on `keypad` (a key down with a character: letters and digits) to `send` as a console
/// entry of that one character; ignores releases and keys without a character, reopens a device that asks for it
/// (a second later), and returns when `send` says the console is gone (returns false).
fn forward_keypad_keys<H: HidInput>(mut keypad: Keypad<H>, send: impl Fn(String) -> bool) {
    loop {
        match keypad.next_event(KEYPAD_POLL_S) {
            Ok(Some(event)) if event.action == KeyAction::Down => {
                if let Some(c) = event.key.character()
                    && !send(c.to_string())
                {
                    return;
                }
            }
            Ok(_) => {}
            Err(e) if e.suggests_reopen() => {
                eprintln!("keypad: {e}; reopening");
                std::thread::sleep(Duration::from_secs(1));
                let _ = keypad.reopen();
            }
            Err(e) => eprintln!("keypad: {e}"),
        }
    }
}

fn console_trial(
    session: &mut Session,
    rig: &mut Rig,
    trial: &PlannedTrial,
    stimulus: &Prepared,
    lines: &Receiver<String>,
    answered: &mut Vec<u32>,
    ctx: &TrialContext,
) -> anyhow::Result<Outcome> {
    let e = ctx.experiment;
    let options: Vec<String> = e.responses.iter().map(|r| format!("{} {}", r.key, r.label)).collect();
    // Blind: the trial number and the options, never the stimulus or the answer.
    eprintln!(
        "trial {} of {}: {}   ({REPEAT_KEY} repeat, {UNDO_KEY} undo last, {VOID_KEY} void, {PAUSE_KEY} pause)",
        ctx.number,
        ctx.total,
        options.join("  ")
    );
    let (scheduled, first_onset) = play_once(rig, stimulus)?;
    let mut repeats = 0u32;
    let until_response = e.presentation == Presentation::UntilResponse;
    let replay_every = Duration::from_secs_f64(e.repeat_pause_s.max(0.0) + stimulus.pattern.playback.duration_s);
    loop {
        let waiting = std::time::Instant::now();
        let line = if until_response {
            match lines.recv_timeout(replay_every) {
                Ok(line) => line,
                Err(RecvTimeoutError::Timeout) => {
                    play_once(rig, stimulus)?;
                    continue;
                }
                Err(RecvTimeoutError::Disconnected) => return Ok(Outcome::Stopped),
            }
        } else {
            match lines.recv() {
                Ok(line) => line,
                Err(_) => return Ok(Outcome::Stopped),
            }
        };
        if ctx.on_mock_lab {
            rig.clock.sleep_s(waiting.elapsed().as_secs_f64());
        }
        let key = line.trim();
        let now_s = rig.clock.now_s();
        if let Some(option) = e.responses.iter().find(|r| r.key == key) {
            let record = TrialRecord {
                trial: trial.index,
                stimulus_id: trial.stimulus_id.clone(),
                drive_hash: stimulus.drive_hash.clone(),
                scheduled_onset_s: scheduled,
                measured_onset_s: Some(first_onset),
                repeats_requested: repeats,
                response: option.label.clone(),
                response_entered_s: now_s,
                trial_time_s: now_s - first_onset,
            };
            journal_trial(session, record, ctx)?;
            answered.push(trial.index);
            return Ok(Outcome::Next);
        }
        match key {
            "" => {}
            REPEAT_KEY => {
                rig.clock.sleep_s(e.repeat_pause_s);
                play_once(rig, stimulus)?;
                repeats += 1;
            }
            UNDO_KEY => {
                let Some(last) = answered.pop() else {
                    eprintln!("nothing to undo");
                    continue;
                };
                session.append(&Entry::Undo { trial: last, entered_s: now_s })?;
                eprintln!("the last answer is undone: that trial is asked again");
                if ctx.json {
                    println!("{}", json!({"event": "undo", "trial": last}));
                }
                return Ok(Outcome::Next);
            }
            VOID_KEY => {
                session.append(&Entry::Void {
                    trial: trial.index,
                    reason: "voided at the console".into(),
                    entered_s: now_s,
                })?;
                eprintln!("trial {} of {} void: it is asked again at the end", ctx.number, ctx.total);
                if ctx.json {
                    println!("{}", json!({"event": "void", "trial": trial.index}));
                }
                return Ok(Outcome::Next);
            }
            PAUSE_KEY => {
                eprintln!("paused: Enter to go on");
                if lines.recv().is_err() {
                    return Ok(Outcome::Stopped);
                }
            }
            other => eprintln!(
                "`{other}` is not a key here: {}, or {REPEAT_KEY} {UNDO_KEY} {VOID_KEY} {PAUSE_KEY}",
                options.join(", ")
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use std::sync::Arc;

    use metaplate_core::clock::VirtualClock;
    use metaplate_keypad::{ReportPrefix, ScriptStep, ScriptedHid, TransportError};

    use super::*;

    #[test]
    fn the_keypads_key_presses_are_console_entries() {
        // Boot keyboard reports (modifiers, reserved, six key slots): `2` (usage 0x1f) down and up, a shift alone,
        // `u` (0x18), an unplugged pad (reopened), `r` (0x15), then `z` (0x1d) an hour later, which finds the
        // console gone.
        let key = |usage: u8| [0, 0, usage, 0, 0, 0, 0, 0];
        let script = vec![
            ScriptStep::boot_report(0.5, key(0x1f)),
            ScriptStep::boot_report(0.1, key(0)),
            ScriptStep::boot_report(0.2, [0x02, 0, 0, 0, 0, 0, 0, 0]),
            ScriptStep::boot_report(0.2, [0; 8]),
            ScriptStep::boot_report(0.3, key(0x18)),
            ScriptStep::boot_report(0.1, key(0)),
            ScriptStep::Fail(TransportError::Disconnected("unplugged".into())),
            ScriptStep::boot_report(0.3, key(0x15)),
            ScriptStep::boot_report(0.1, key(0)),
            ScriptStep::boot_report(3600.0, key(0x1d)),
        ];
        let clock = Arc::new(VirtualClock::new());
        let keypad = Keypad::new(ScriptedHid::new(&clock, script), clock, ReportPrefix::None);
        // A channel without a buffer: the last key's hand-over waits for the console, which is gone by then.
        let (tx, rx) = std::sync::mpsc::sync_channel::<String>(0);
        let forwarder = std::thread::spawn(move || forward_keypad_keys(keypad, |entry| tx.send(entry).is_ok()));
        let entries: Vec<String> = (0..3).map(|_| rx.recv_timeout(Duration::from_secs(10)).unwrap()).collect();
        assert_eq!(entries, ["2", "u", "r"]);
        drop(rx);
        forwarder.join().unwrap();
    }
}
