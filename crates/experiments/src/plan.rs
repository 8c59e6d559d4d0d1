//! The full trial plan of a session: familiarisation, then conditions x repeats in the file's order, drawn from a
//! seed with `core::rng::SplitMix64` (bit-identical on every platform), and its canonical hash.

use metaplate_core::hash::fnv1a_64;
use metaplate_core::rng::SplitMix64;
use serde::{Deserialize, Serialize};

use crate::file::{Experiment, HASH_PREFIX, OrderMode};

/// Stream of the familiarisation order (see [`SplitMix64::new`]).
const FAMILIARISATION_STREAM: u64 = 0x6661_6d69_6c69; // "famili"
/// Stream of the scored trials' order.
const TRIALS_STREAM: u64 = 0x7472_6961_6c73; // "trials"

/// Which phase a trial belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Phase {
    /// Unscored, unmarked to the participant; removed from the analysis.
    Familiarisation,
    /// Scored.
    Trials,
}

/// One planned trial.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct PlannedTrial {
    /// Position in the plan, from 0.
    pub index: u32,
    /// Familiarisation or scored.
    pub phase: Phase,
    /// Condition: index into the experiment's stimuli.
    pub condition: u32,
    /// The stimulus's id.
    pub stimulus_id: String,
    /// Label of the correct response (never shown to the experimenter).
    pub correct: String,
    /// Which repeat of its condition this is (0-based; 0 in familiarisation).
    pub repeat: u32,
}

/// The plan of one session.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Plan {
    /// The experiment's name.
    pub experiment: String,
    /// [`Experiment::file_hash`] of the file it was drawn from.
    pub file_hash: String,
    /// The seed it was drawn with.
    pub seed: u64,
    /// Every trial, in order.
    pub trials: Vec<PlannedTrial>,
}

impl Plan {
    /// The plan of `experiment` drawn with `seed` (the file's `order.seed` unless the session gives another).
    pub fn new(experiment: &Experiment, seed: u64) -> Self {
        let conditions = experiment.stimuli.len() as u32;
        let mut draws: Vec<(Phase, u32, u32)> = Vec::new();
        if experiment.phases.familiarisation {
            let mut order: Vec<u32> = (0..conditions).collect();
            shuffle(&mut order, &mut SplitMix64::new(seed, FAMILIARISATION_STREAM));
            draws.extend(order.into_iter().map(|c| (Phase::Familiarisation, c, 0)));
        }
        let mut rng = SplitMix64::new(seed, TRIALS_STREAM);
        let repeats = experiment.phases.repeats;
        match experiment.order.mode {
            OrderMode::Full => {
                let mut all: Vec<(u32, u32)> =
                    (0..repeats).flat_map(|r| (0..conditions).map(move |c| (c, r))).collect();
                shuffle(&mut all, &mut rng);
                draws.extend(all.into_iter().map(|(c, r)| (Phase::Trials, c, r)));
            }
            OrderMode::Blocked => {
                for r in 0..repeats {
                    let mut block: Vec<u32> = (0..conditions).collect();
                    shuffle(&mut block, &mut rng);
                    draws.extend(block.into_iter().map(|c| (Phase::Trials, c, r)));
                }
            }
        }
        let trials = draws
            .into_iter()
            .enumerate()
            .map(|(i, (phase, condition, repeat))| {
                let stimulus = &experiment.stimuli[condition as usize];
                PlannedTrial {
                    index: i as u32,
                    phase,
                    condition,
                    stimulus_id: stimulus.id.clone(),
                    correct: stimulus.correct.clone(),
                    repeat,
                }
            })
            .collect();
        Self { experiment: experiment.name.clone(), file_hash: experiment.file_hash(), seed, trials }
    }

    /// The plan's identity: FNV-1a over a canonical text (one line per trial, `index phase condition stimulus
    /// correct repeat`, after the experiment, file hash and seed), so any change of order or content changes it.
    pub fn hash(&self) -> String {
        let mut text = format!("{}\n{}\n{}\n", self.experiment, self.file_hash, self.seed);
        for t in &self.trials {
            let phase = match t.phase {
                Phase::Familiarisation => "familiarisation",
                Phase::Trials => "trials",
            };
            text.push_str(&format!(
                "{} {phase} {} {:?} {:?} {}\n",
                t.index, t.condition, t.stimulus_id, t.correct, t.repeat
            ));
        }
        format!("{HASH_PREFIX}{:016x}", fnv1a_64(text.bytes()))
    }

    /// The number of scored trials.
    pub fn scored(&self) -> usize {
        self.trials.iter().filter(|t| t.phase == Phase::Trials).count()
    }
}

/// Fisher-Yates with `SplitMix64::in_range` (unbiased), last position first.
fn shuffle<T>(items: &mut [T], rng: &mut SplitMix64) {
    for i in (1..items.len()).rev() {
        let j = rng.in_range(0, i as u64) as usize;
        items.swap(i, j);
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;
    use crate::builtin::builtin;

    #[test]
    fn a_plan_is_a_function_of_the_seed_and_covers_every_condition_times_repeats() {
        let e = builtin("pixel-identification").unwrap();
        let a = Plan::new(&e, 7);
        assert_eq!(a, Plan::new(&e, 7));
        assert_eq!(a.hash(), Plan::new(&e, 7).hash());
        let b = Plan::new(&e, 8);
        assert_ne!(a.trials, b.trials);
        assert_ne!(a.hash(), b.hash());
        let mut counts = [0; 5];
        for t in a.trials.iter().filter(|t| t.phase == Phase::Trials) {
            counts[t.condition as usize] += 1;
            assert_eq!(t.correct, e.stimuli[t.condition as usize].correct);
        }
        assert_eq!(counts, [10; 5]);
        let mut fam: Vec<u32> = a.trials[..5].iter().map(|t| t.condition).collect();
        assert!(a.trials[..5].iter().all(|t| t.phase == Phase::Familiarisation));
        fam.sort_unstable();
        assert_eq!(fam, [0, 1, 2, 3, 4]);
        assert_eq!(a.scored(), 50);
        assert!(a.trials.iter().enumerate().all(|(i, t)| t.index as usize == i));
    }

    #[test]
    fn the_plan_is_bit_identical_to_its_recorded_hash() {
        // Pinned: a change of the shuffle, the streams or the canonical text shows here (and breaks resuming
        // sessions recorded before it, which is why it must not happen silently).
        let e = builtin("pixel-identification").unwrap();
        let plan = Plan::new(&e, 1);
        let first: Vec<u32> = plan.trials[..8].iter().map(|t| t.condition).collect();
        assert_eq!(first, PINNED_FIRST);
        assert_eq!(plan.hash(), PINNED_HASH);
    }

    const PINNED_FIRST: [u32; 8] = [0, 1, 4, 2, 3, 1, 1, 3];
    const PINNED_HASH: &str = "fnv1a64:0579c54a87de4906";

    #[test]
    fn blocked_order_holds_each_condition_once_per_block() {
        let mut e = builtin("motion-direction").unwrap();
        e.order.mode = OrderMode::Blocked;
        let plan = Plan::new(&e, 3);
        let scored: Vec<&PlannedTrial> = plan.trials.iter().filter(|t| t.phase == Phase::Trials).collect();
        for (r, block) in scored.chunks(8).enumerate() {
            let mut c: Vec<u32> = block.iter().map(|t| t.condition).collect();
            c.sort_unstable();
            assert_eq!(c, (0..8).collect::<Vec<_>>());
            assert!(block.iter().all(|t| t.repeat == r as u32));
        }
    }
}
