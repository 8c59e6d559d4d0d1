//! The stand-in rig: the mock lab behind the real instruments' own links, for `metaplate lab serve`.
//!
//! [`StandInRig::start`] serves one [`MockLab`] in a folder, and writes `hardware.toml` there naming:
//! - the vibrometer: the lab's Polytec controller on a pseudo-terminal (the `polytec` backend);
//! - the aim: two Zaber stages moving the head ([`stages`]), on a second pseudo-terminal (`zaber`); the lab puts the
//!   beam where the stages are;
//! - the DAQ: NI-DAQmx (`nidaqmx`), through a copy of the stand-in library (`libnidaqmx_standin.so`) placed beside
//!   the rig's socket, so that its analog inputs read the lab's vibrometer output and loopback ([`daq_link`]);
//! - the audio interface: ALSA's stock `file` PCM writing into a FIFO the lab reads (`alsa`), with no ALSA
//!   configuration to install ([`playback`]).
//!
//! Every byte then runs through the real backends (serialport, zaber, the NI-DAQmx loader, libasound); only the
//! devices are simulated. Time: the DAQ acquires in real time, or `speed` times faster ([`ServeOptions::speed`]);
//! the stages move in real time.

mod daq_link;
mod playback;
mod stages;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use metaplate_mock_ldv::PtyServer;

use crate::{LabError, MockLab};

/// The FIFO the audio interface's `file` PCM writes into, in the rig's folder.
pub const PLAYBACK_FIFO: &str = "play.fifo";
/// The hardware file the rig writes in its folder.
pub const HARDWARE_FILE: &str = "hardware.toml";
/// The ALSA configuration the rig writes when its scene clocks the interface at another rate (`setup.
/// audio_device_rate_hz`): the stock configuration and the PCM [`RATE_PCM`], ALSA's `file` PCM behind a `plug`
/// fixed at that rate.
pub const ALSA_CONFIG: &str = "asound.conf";
/// The PCM [`ALSA_CONFIG`] defines.
pub const RATE_PCM: &str = "metaplate_rig";

/// How the rig serves.
#[derive(Debug, Clone, PartialEq)]
pub struct ServeOptions {
    /// How many times faster than real time the DAQ acquires (1: real time, as a device). Above 1 a rehearsal runs
    /// quicker; valid range 0.1 to 100.
    pub speed: f64,
    /// The stand-in NI-DAQmx library to copy into the folder (built by `cargo build -p metaplate-mock-nidaqmx`).
    pub nidaqmx_library: PathBuf,
    /// The `plate` the hardware file names (a built-in scene's name, or a scene file's absolute path).
    pub plate: String,
    /// What aims the beam.
    pub aim: RigAim,
}

/// What aims the stand-in rig's beam.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RigAim {
    /// Two Zaber stages carrying the head ([`stages`]).
    #[default]
    Stages,
    /// The lab's galvo mirrors on the stand-in NI-DAQmx's `ao0` and `ao1`, through a fit that `metaplate aim
    /// teach --hardware` writes (`galvo-fit.toml` in the folder); the beam lands where the mirrors' geometry, unknown
    /// to the host, puts it. The plate's response is taken at the prepared point nearest the beam (the fit's error,
    /// under a millimetre, is not rendered: the rig prepares no neighbours for the slope).
    Galvo,
}

impl std::str::FromStr for RigAim {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        match text {
            "stages" => Ok(RigAim::Stages),
            "galvo" => Ok(RigAim::Galvo),
            other => Err(format!("{other:?}: `stages` (Zaber) or `galvo` (mirrors on NI outputs)")),
        }
    }
}

/// The galvo fit file a [`RigAim::Galvo`] rig's hardware file names.
pub const GALVO_FIT: &str = "galvo-fit.toml";

impl ServeOptions {
    /// Options for serving scene `scene` (a built-in name, or a scene file, named by its absolute path) at `speed`,
    /// with the stand-in library at `nidaqmx_library` (`None`: `nidaqmx_standin::library_file_name()` beside the
    /// running program).
    ///
    /// # Errors
    /// [`LabError::Serve`] when the running program's path cannot be found.
    pub fn new(
        scene: &str,
        speed: f64,
        nidaqmx_library: Option<PathBuf>,
        aim: RigAim,
    ) -> Result<ServeOptions, LabError> {
        let nidaqmx_library = match nidaqmx_library {
            Some(path) => path,
            None => std::env::current_exe()
                .map_err(|e| LabError::Serve { what: format!("finding the running program: {e}") })?
                .with_file_name(nidaqmx_standin::library_file_name()),
        };
        let file = std::fs::canonicalize(scene).ok().filter(|path| path.is_file());
        let plate = file.map_or_else(|| scene.to_owned(), |path| path.display().to_string());
        Ok(ServeOptions { speed, nidaqmx_library, plate, aim })
    }
}

/// How long an acquisition waits for its first playback before it runs without one.
const WAIT_FOR_PLAYBACK: Duration = Duration::from_secs(2);

/// How far behind the wall clock (scaled by the speed) samples are handed out: a playback that arrives meanwhile is
/// scheduled first.
const LAG: Duration = Duration::from_millis(50);

/// When the current acquisition started, on the wall clock and on the lab's.
#[derive(Debug, Clone, Copy)]
struct Acquisition {
    /// Which connection holds it.
    connection: u64,
    /// Which acquisition of the rig's it is (from 1).
    generation: u64,
    wall_t0: Instant,
    virtual_t0_s: f64,
    rate_hz: f64,
}

/// What the DAQ link and the playback reader share: the speed, the running acquisition, whether a playback is
/// arriving, which acquisition last had one scheduled, and until when it sounds.
#[derive(Debug)]
struct Timing {
    speed: f64,
    acquisition: Mutex<Option<Acquisition>>,
    /// Bytes of a playback are arriving that the lab has not scheduled yet: no sample is handed out meanwhile.
    receiving: AtomicBool,
    /// The generation of the acquisition that last had a playback scheduled during it (0: none).
    played_generation: AtomicU64,
    /// The last scheduled playback: its acquisition's generation, and when it stops sounding, lab time.
    sounding: Mutex<(u64, f64)>,
}

impl Timing {
    fn new(speed: f64) -> Timing {
        Timing {
            speed,
            acquisition: Mutex::new(None),
            receiving: false.into(),
            played_generation: 0.into(),
            sounding: Mutex::new((0, f64::NEG_INFINITY)),
        }
    }

    fn acquisition(&self) -> Option<Acquisition> {
        self.acquisition.lock().ok().and_then(|a| *a)
    }

    /// Whether acquisition `a` has had its first playback scheduled.
    fn played(&self, a: &Acquisition) -> bool {
        self.played_generation.load(Ordering::Acquire) == a.generation
    }

    /// When a playback arriving at wall instant `wall` starts sounding, lab time, before the interface's latency,
    /// and the generation of the acquisition it arrives in (0: none). The acquisition's first playback, while the
    /// acquisition still waits for it (nothing after the lab's time now handed out): the lab's time now. A later
    /// one, or once the acquisition has stopped waiting: its arrival on the acquisition's clock, never before what
    /// was handed out. A playback that arrives while the one before it still sounds, in the same acquisition,
    /// continues it. With no acquisition: the lab's time.
    fn arrival_s(&self, lab_now_s: f64, wall: Instant) -> (f64, u64) {
        let Some(a) = self.acquisition() else { return (lab_now_s, 0) };
        let waited = wall.saturating_duration_since(a.wall_t0);
        // Still waiting for a first playback, with the lag to spare: nothing after the lab's time has been handed out.
        // Later, samples up to the wall clock less the lag may have been: the wall clock then says when.
        let arrival_s = if !self.played(&a) && waited + LAG < WAIT_FOR_PLAYBACK {
            lab_now_s
        } else {
            (a.virtual_t0_s + waited.as_secs_f64() * self.speed).max(lab_now_s)
        };
        let (generation, until_s) = self.sounding.lock().map(|s| *s).unwrap_or((0, f64::NEG_INFINITY));
        let start_s = if generation == a.generation && arrival_s < until_s { until_s } else { arrival_s };
        (start_s, a.generation)
    }

    /// A playback of acquisition `generation` that sounds until `until_s` (lab time) is about to be scheduled:
    /// recorded first, so that an acquisition that starts meanwhile starts after it.
    fn will_sound(&self, generation: u64, until_s: f64) {
        if let Ok(mut sounding) = self.sounding.lock() {
            *sounding = (generation, sounding.1.max(until_s));
        }
    }

    /// A playback of acquisition `generation` was scheduled.
    fn scheduled(&self, generation: u64) {
        if self.acquisition().is_some_and(|a| a.generation == generation) {
            self.played_generation.store(generation, Ordering::Release);
        }
    }

    /// When the last scheduled playback stops sounding, lab time.
    fn sounding_until_s(&self) -> f64 {
        self.sounding.lock().map_or(f64::NEG_INFINITY, |s| s.1)
    }
}

/// A running stand-in rig. Dropping it stops the threads that serve it (an acquisition's connection ends when its
/// host hangs up) and removes what it put in its folder.
pub struct StandInRig {
    dir: PathBuf,
    stop: Arc<AtomicBool>,
    threads: Vec<JoinHandle<()>>,
    // Held for their threads: the pseudo-terminals live as long as the servers.
    ldv: PtyServer,
    /// The Zaber stages' server, when they aim.
    stages: Option<PtyServer>,
    lab: MockLab,
}

impl std::fmt::Debug for StandInRig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StandInRig").field("dir", &self.dir).finish_non_exhaustive()
    }
}

impl StandInRig {
    /// Serves `lab` from `dir` (created if missing): the pseudo-terminals, the FIFO, the socket and the library,
    /// and `dir/hardware.toml` naming them.
    ///
    /// # Errors
    /// [`LabError::InvalidOption`] for a speed out of range; [`LabError::Serve`] when the folder, the FIFO, the
    /// socket, the library's copy or the hardware file cannot be made (a rig already serving there included);
    /// [`LabError::Pty`] when a pseudo-terminal cannot be opened.
    pub fn start(lab: MockLab, dir: &Path, options: &ServeOptions) -> Result<StandInRig, LabError> {
        if !(options.speed.is_finite() && (0.1..=100.0).contains(&options.speed)) {
            return Err(LabError::InvalidOption { name: "speed", reason: format!("{} (0.1 to 100)", options.speed) });
        }
        std::fs::create_dir_all(dir)
            .map_err(|e| LabError::Serve { what: format!("creating {}: {e}", dir.display()) })?;
        let timing = Arc::new(Timing::new(options.speed));
        // From here on, a failure drops the rig: its threads stop and its files go.
        let mut rig = StandInRig {
            dir: dir.to_path_buf(),
            stop: Arc::new(AtomicBool::new(false)),
            threads: Vec::new(),
            ldv: PtyServer::spawn(Arc::clone(&lab.ldv))?,
            stages: None,
            lab,
        };
        // The socket first: binding it fails while another rig serves this folder, before anything of that rig's is
        // touched (its library, mapped by its hosts, above all).
        let socket = dir.join(nidaqmx_standin::lab::SOCKET_NAME);
        rig.threads.push(daq_link::serve(&rig.lab, &socket, Arc::clone(&timing), Arc::clone(&rig.stop))?);
        let library = std::fs::read(&options.nidaqmx_library).map_err(|e| LabError::Serve {
            what: format!(
                "reading the stand-in NI-DAQmx library {} (build it with `cargo build -p metaplate-mock-nidaqmx`): {e}",
                options.nidaqmx_library.display()
            ),
        })?;
        write_durably(dir, &nidaqmx_standin::library_file_name(), &library)?;
        rig.threads.push(playback::serve(&rig.lab, &dir.join(PLAYBACK_FIFO), timing, Arc::clone(&rig.stop))?);
        let aim_section = match options.aim {
            RigAim::Stages => {
                let (server, bridge, section) = stages::serve(&rig.lab, Arc::clone(&rig.stop))?;
                rig.stages = Some(server);
                rig.threads.push(bridge);
                section
            }
            RigAim::Galvo => format!(
                "# The lab's galvo mirrors on the stand-in's outputs; teach the fit with `metaplate aim teach \
                 --hardware`.\n[aim]\nbackend = \"galvo\"\nfit = \"{GALVO_FIT}\"\nsettle_ms = 2.0\n\n[aim.outputs]\n\
                 backend = \"nidaqmx\"\ndevice = \"Dev1\"\nx_channel = \"ao0\"\ny_channel = \"ao1\"\n\
                 library = \"{}\"\n",
                nidaqmx_standin::library_file_name()
            ),
        };
        if let Some(rate_hz) = rig.lab.scene().setup.audio_device_rate_hz {
            let fifo = dir.join(PLAYBACK_FIFO);
            let config = format!(
                "# The stand-in rig's interface, clocked at {rate_hz} Hz whatever the host asks (its scene's \
                 setup.audio_device_rate_hz).\n</usr/share/alsa/alsa.conf>\npcm.{RATE_PCM} {{\n type plug\n slave {{\n  \
                 pcm {{ type file slave.pcm null file {:?} format \"raw\" }}\n  rate {}\n }}\n}}\n",
                fifo.display().to_string(),
                rate_hz.round()
            );
            write_durably(dir, ALSA_CONFIG, config.as_bytes())?;
        }
        // Last, and whole: a host that sees the file finds the rig serving.
        write_durably(dir, HARDWARE_FILE, hardware_file(&rig, options, &aim_section).as_bytes())?;
        Ok(rig)
    }

    /// The folder served.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The hardware file naming the rig's instruments.
    pub fn hardware_path(&self) -> PathBuf {
        self.dir.join(HARDWARE_FILE)
    }

    /// The ALSA configuration the host must be run with (`ALSA_CONFIG_PATH`), when the rig wrote one
    /// ([`ALSA_CONFIG`]).
    pub fn alsa_config(&self) -> Option<PathBuf> {
        Some(self.dir.join(ALSA_CONFIG)).filter(|path| path.exists())
    }

    /// What the rig serves and how to use it, for a person.
    pub fn summary(&self) -> String {
        let hardware = self.hardware_path();
        let env = self.alsa_config().map(|c| format!("ALSA_CONFIG_PATH={} ", c.display())).unwrap_or_default();
        let aim = match self.stages_port_path() {
            Some(port) => format!("stages (Zaber) on {}", port.display()),
            None => format!(
                "galvo mirrors on NI-DAQmx Dev1/ao0:1 (teach: metaplate aim teach --hardware {})",
                hardware.display()
            ),
        };
        format!(
            "stand-in rig serving from {}: vibrometer (Polytec) on {}, {aim}\n\
             try: {env}metaplate check --hardware {}\n\
             Ctrl-C stops it",
            self.dir.display(),
            self.ldv.path().display(),
            hardware.display()
        )
    }

    /// The vibrometer controller's pseudo-terminal.
    pub fn ldv_port_path(&self) -> &Path {
        self.ldv.path()
    }

    /// The stages' pseudo-terminal, when they aim.
    pub fn stages_port_path(&self) -> Option<&Path> {
        self.stages.as_ref().map(PtyServer::path)
    }
}

impl Drop for StandInRig {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        for thread in self.threads.drain(..) {
            let _ = thread.join();
        }
        // What names the rig goes first, then what serves it; the library copy too, so that nothing loads it
        // without its rig.
        let library = nidaqmx_standin::library_file_name();
        for name in [HARDWARE_FILE, ALSA_CONFIG, PLAYBACK_FIFO, nidaqmx_standin::lab::SOCKET_NAME, &library] {
            let _ = std::fs::remove_file(self.dir.join(name));
        }
    }
}

/// Writes `bytes` as `dir/name` whole and durably (the store's write: a temporary file, fsync'd, renamed over it;
/// a host that has the old file mapped keeps it).
///
/// # Errors
/// [`LabError::Serve`] with the store's reason.
fn write_durably(dir: &Path, name: &str, bytes: &[u8]) -> Result<(), LabError> {
    metaplate_store::write_bytes(dir, name, bytes).map_err(|e| LabError::Serve { what: e.to_string() })
}

/// How long a serving thread sleeps when it has nothing to do.
const IDLE_POLL: Duration = Duration::from_millis(1);

/// `dir/hardware.toml`: the rig's instruments, its wiring, and the plate.
fn hardware_file(rig: &StandInRig, options: &ServeOptions, aim: &str) -> String {
    let lab = &rig.lab;
    let w = lab.wiring();
    let list = |v: &[u32]| v.iter().map(u32::to_string).collect::<Vec<_>>().join(", ");
    let fifo = rig.dir.join(PLAYBACK_FIFO);
    let (pcm, pcm_comment) = match lab.scene().setup.audio_device_rate_hz {
        Some(_) => (
            RATE_PCM.to_owned(),
            format!("# Defined in {ALSA_CONFIG}: run with ALSA_CONFIG_PATH={}.\n", rig.dir.join(ALSA_CONFIG).display()),
        ),
        None => (format!("file:'{}',raw", fifo.display()), String::new()),
    };
    format!(
        "# The stand-in rig `metaplate lab serve` is serving from this folder: the mock lab of scene {scene:?} behind\n\
         # the real instruments' links. Valid while it serves.\n\n\
         plate = {plate:?}\n\n\
         # The lab's Polytec controller on a pseudo-terminal.\n\
         [ldv]\nbackend = \"polytec\"\nport = {ldv:?}\n\n\
         # NI-DAQmx through the stand-in library beside the rig's socket: its inputs read the lab.\n\
         [daq]\nbackend = \"nidaqmx\"\ndevice = \"Dev1\"\nlibrary = {library:?}\nterminal = \"rse\"\n\n\
         # ALSA's stock `file` PCM, writing into the FIFO the lab plays from.\n{pcm_comment}\
         [audio]\nbackend = \"alsa\"\ndevice = {pcm:?}\nsample_rate_hz = {rate:?}\nchannels = {channels}\n\n\
         {aim}\n\
         [wiring]\nactuator_channels = [{actuators}]\nloopback_channel = {loopback}\nvelocity_input = {velocity}\n\
         loopback_input = {loopback_input}\ndaq_range_v = {range:?}\ndaq_sample_rate_hz = {daq_rate:?}\n\
         loopback_volts_per_full_scale = {lv:?}\n",
        scene = lab.scene().name,
        plate = options.plate,
        ldv = rig.ldv_port_path().display().to_string(),
        library = nidaqmx_standin::library_file_name(),
        pcm = pcm,
        rate = w.audio_sample_rate_hz,
        channels = w.audio_channels,
        actuators = list(&w.actuator_channels),
        loopback = w.loopback_channel,
        velocity = w.velocity_input,
        loopback_input = w.loopback_input,
        range = w.daq_range_v,
        daq_rate = w.daq_sample_rate_hz,
        lv = w.loopback_volts_per_full_scale,
    )
}
