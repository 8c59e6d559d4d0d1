//! Shared domain types of metaplate.
//!
//! The vocabulary every other crate speaks: measurement grids, scenes (one TOML file describing a whole simulated
//! lab), the capability traits a recipe sees, the [`Rig`](rig::Rig) that holds them and how it is wired, clocks, the
//! seeded generator and hashes. It depends on nothing else in the workspace, and everything else may depend on it.
//!
//! # Modules
//!
//! - [`grid`]: [`GridSpec`](grid::GridSpec), a uniform rectangular grid of measurement points;
//!   [`GridSubset`](grid::GridSubset), the one parser of a command line's `NXxNY` subset; and
//!   [`snap_to_grid`](grid::snap_to_grid), positions from an untrusted file snapped to the regular grid they lie on
//!   (typed refusals, proptested).
//! - [`scene`]: [`Scene`](scene::Scene), a whole simulated lab (plate, supports, resonators, actuators and their
//!   voice coils, grid, vibrometer, DAQ, audio interface, fault schedule, seed) read from one TOML file; the
//!   built-in scenes are in `crates/foundation/core/scenes/`. A user's file is checked key by key, and every
//!   problem is a [`SceneError`](scene::SceneError) naming the file, line and key path, never a panic.
//!   - [`Imperfection`](scene::Imperfection): every imperfection the mock lab models (LDV noise, speckle, dropouts,
//!     quantisation, clipping, clock drift, latency, nonlinearity, actuator spread, the beam's aiming error
//!     `ldv.aim_error_rms_m`, faults), each switched off on the same plate by
//!     [`Scene::without`](scene::Scene::without) / [`Scene::with_only`](scene::Scene::with_only), for error budgets
//!     (`daq.bits = 0`: an ideal converter; `daq.clipping = false`: no clipping).
//!   - [`SetupSpec`](scene::SetupSpec): the optional `[setup]` table of bench mistakes (swapped actuator cables, no
//!     loopback, the audio interface at another rate, the free disk space) for `metaplate check` to catch.
//! - [`toml_locate`]: the one home of located TOML errors. [`DocIndex`](toml_locate::DocIndex) maps a byte offset
//!   to file, line, column and dotted key path, with hints for unit mistakes (the unit is in each key's name); scene
//!   files and `metaplate-experiment`'s experiment files both report through it.
//! - The capability traits, in SI units, behind which a recipe sees its instruments and never a transport:
//!   [`Vibrometer`](vibrometer::Vibrometer), [`Aim`](aim::Aim) (what puts the beam on a point: mirrors, stages,
//!   the mock lab), [`Daq`](daq::Daq) and [`AudioOut`](audio::AudioOut). Each error says
//!   what the caller can do next (retry, reconnect or reopen, stop).
//! - [`rig`]: [`Rig`](rig::Rig) (the instruments, the clock they share, and their [`Wiring`](rig::Wiring))
//!   and [`Rig::play_and_record`](rig::Rig::play_and_record), the one play-and-record: start the DAQ, play, read to a
//!   length, stop; no retries (retrying is the caller's policy).
//! - [`clock`]: [`Clock`](clock::Clock), with [`RealClock`](clock::RealClock) for the lab and
//!   [`VirtualClock`](clock::VirtualClock) for the mock lab, which jumps forward instead of sleeping. Everything that
//!   waits asks a `Clock`, never the operating system.
//! - [`error_chain`]: [`message`](error_chain::message), an error and its causes as one line, each cause once.
//! - [`hash`]: [`fnv1a_64`](hash::fnv1a_64), the stable non-cryptographic hash of cache keys and scene identities.
//! - [`rng`]: [`SplitMix64`](rng::SplitMix64) and [`mix64`](rng::mix64), the one seeded generator of the library
//!   code.
//!
//! # Invariants
//!
//! - [`Scene::id`](scene::Scene::id) is the one scene identity: an FNV-1a hash of the scene's canonical form
//!   ([`Scene::canonical_text`](scene::Scene::canonical_text): the resolved values, keys sorted, floats as their
//!   bits), so a change of formatting, key order or float spelling in the TOML file cannot break a resume or a
//!   cache. An optional key at its default is not written, so adding one changes no existing scene's identity.
//! - [`Scene::physics_hash`](scene::Scene::physics_hash) is the same over what the plate's response alone depends
//!   on (not the voice coils, which act on the drive, nor the instruments, faults or setup): the key of the
//!   Green's-function cache, shared by scenes that differ only in their instruments or setup.
//! - Seeded draws are bit-identical on every platform and with every dependency version: library code draws from
//!   [`rng`] only.

pub mod aim;
pub mod audio;
pub mod clock;
pub mod daq;
pub mod design;
pub mod error_chain;
pub mod grid;
pub mod hash;
pub mod points;
pub mod rig;
pub mod rng;
pub mod scene;
pub mod toml_locate;
pub mod vibrometer;
