//! Opening the rig a hardware file names, each instrument through its backend.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use metaplate_core::aim::{Aim, MirrorOutputs, NoAimer};
use metaplate_core::clock::{Clock, RealClock};
use metaplate_core::rig::Rig;
use metaplate_core::scene::Scene;
use metaplate_keypad::{HidInput, Keypad};

use crate::aim::{AimSection, MirrorOutputsSection};
use crate::backends::{self, Capability};
use crate::file::{AudioSection, DaqSection, HardwareError, HardwareFile, KeypadSection, LdvSection};

/// Why a rig is opened, which sets how far opening goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OpenPurpose {
    /// `metaplate check`: every instrument is tried whatever became of the others (one attempt names every fault;
    /// stages may home even when another instrument failed), the vibrometer connected and the galvo fit held to
    /// its residual limit.
    Check,
    /// A measurement (calibrate, scan): the vibrometer connected and the galvo fit held to its limit; opening stops
    /// at the first instrument that fails, before anything after it moves.
    Measure,
    /// Playing stimuli (play, experiments), which neither reads the vibrometer nor aims: it is opened without being
    /// connected, the fit is not held to its limit, and opening stops at the first failure.
    Play,
}

/// What a hardware file opens: the rig the recipes drive, and the keypad beside it (not a capability of [`Rig`]:
/// no recipe reads it yet).
pub struct OpenedRig {
    /// The LDV, the DAQ and the audio interface on the real clock, with the file's wiring.
    pub rig: Rig,
    /// The response keypad, when the file has a `[keypad]`.
    pub keypad: Option<Keypad<Box<dyn HidInput>>>,
}

impl std::fmt::Debug for OpenedRig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OpenedRig").field("keypad", &self.keypad.is_some()).finish_non_exhaustive()
    }
}

/// The plate the hardware file at `path` names (its scene, validated) and the rig and keypad it opens
/// ([`open_rig`]): the wiring must name one channel per actuator of the plate, which is checked before anything
/// is opened.
///
/// # Errors
/// [`HardwareError::File`] and the others of [`open_rig`]; [`HardwareError::Scene`] for the plate's scene;
/// [`HardwareError::Plate`] when the wiring does not fit it.
pub fn open_plate_rig(path: &Path, purpose: OpenPurpose) -> Result<(Scene, OpenedRig), HardwareError> {
    let file = HardwareFile::load(path)?;
    let scene = Scene::resolve(&file.plate)?;
    scene.validate()?;
    let actuators = file.wiring.actuator_channels.len();
    if actuators != scene.actuators.len() {
        let reason = format!(
            "wiring.actuator_channels lists {actuators} actuators, the plate `{}` has {}",
            file.plate,
            scene.actuators.len()
        );
        return Err(HardwareError::Plate { path: path.to_path_buf(), reason });
    }
    Ok((scene, open_rig(&file, purpose)?))
}

/// Opens every instrument `file` names, in the order LDV, DAQ, audio interface (configured once at the file's
/// rate and channel count, so that a missing card is found now rather than at the first point), keypad, aim; on
/// the real clock, as far as `purpose` asks ([`OpenPurpose`]: for a check, each is tried whatever became of the
/// others, so that one attempt names every fault).
///
/// # Errors
/// [`HardwareError::NotInThisBuild`] for the first backend this build lacks (the galvo mirrors' outputs too),
/// before anything is opened; [`HardwareError::Devices`] naming each instrument that could not be opened
/// ([`HardwareError::failed_instruments`]; the first only, unless for a check).
pub fn open_rig(file: &HardwareFile, purpose: OpenPurpose) -> Result<OpenedRig, HardwareError> {
    let mut named = file.backends();
    if let Some(AimSection::Galvo(galvo)) = &file.aim {
        match &galvo.outputs {
            MirrorOutputsSection::Nidaqmx(_) => named.push((Capability::Daq, "nidaqmx")),
        }
    }
    for (capability, name) in named {
        if let Some(backend) = backends::find(capability, name)
            && let Some(reason) = backend.missing_reason()
        {
            return Err(HardwareError::NotInThisBuild {
                path: file.path.clone(),
                key: format!("{}.backend", capability.section()),
                backend: backend.name,
                reason,
            });
        }
    }
    let clock: Arc<dyn Clock> = Arc::new(RealClock::new());
    // After a failure, a measurement or a playback opens nothing more (the stages would home for nothing).
    let every = purpose == OpenPurpose::Check;
    let measuring = purpose != OpenPurpose::Play;
    fn kept<T>(
        failures: &mut Vec<HardwareError>,
        every: bool,
        open: impl FnOnce() -> Result<T, HardwareError>,
    ) -> Option<T> {
        if !every && !failures.is_empty() {
            return None;
        }
        open().map_err(|e| failures.push(e)).ok()
    }
    let mut failures = Vec::new();
    let vibrometer = kept(&mut failures, every, || open_ldv(&file.ldv, measuring));
    let daq = kept(&mut failures, every, || open_daq(&file.daq, &file.path));
    let audio = kept(&mut failures, every, || open_audio(&file.audio));
    let keypad =
        kept(&mut failures, every, || file.keypad.as_ref().map(|keypad| open_keypad(keypad, &clock)).transpose());
    let aim = kept(&mut failures, every, || open_aim(file, &clock, measuring));
    match (vibrometer, daq, audio, keypad, aim) {
        (Some(vibrometer), Some(daq), Some(audio), Some(keypad), Some(aim)) => {
            Ok(OpenedRig { rig: Rig { vibrometer, aim, daq, audio, clock, wiring: file.wiring() }, keypad })
        }
        // A backend missing from this build is the build's error, not an instrument's.
        _ => match failures.iter().position(|e| matches!(e, HardwareError::NotInThisBuild { .. })) {
            Some(at) => Err(failures.swap_remove(at)),
            None => Err(HardwareError::Devices { failures }),
        },
    }
}

/// The error of an instrument that could not be opened.
fn device(capability: Capability, backend: &'static str, name: &str, detail: impl ToString) -> HardwareError {
    HardwareError::Device { device: capability.noun(), backend, name: name.to_string(), detail: detail.to_string() }
}

/// Reports a backend missing from this build as a device error; unreachable after `open_rig`'s check, and kept
/// so that every match below stays exhaustive whatever the features.
#[allow(dead_code)] // Used only in builds without some backend.
fn not_built(capability: Capability, backend: &'static str, name: &str) -> HardwareError {
    device(capability, backend, name, "this build of metaplate lacks the backend")
}

/// The vibrometer; `connect`: a Polytec controller is connected now (identity, the decoder asked for, its
/// ranges), so that one that does not answer, or lacks the decoder, is named when the rig opens.
fn open_ldv(
    section: &LdvSection,
    connect: bool,
) -> Result<Box<dyn metaplate_core::vibrometer::Vibrometer + Send>, HardwareError> {
    match section {
        LdvSection::Polytec(polytec) => {
            let name = polytec.port.display().to_string();
            #[cfg(feature = "serial")]
            {
                use metaplate_ldv::{PolytecDriver, RetryPolicy, SerialPortLine};
                let error = |e: &dyn std::fmt::Display| device(Capability::Vibrometer, "polytec", &name, e);
                let config = polytec.config().map_err(|e| error(&e))?;
                let line = SerialPortLine::open(polytec.selector()).map_err(|e| error(&e))?;
                let mut driver = PolytecDriver::new(line, RetryPolicy::default(), config).map_err(|e| error(&e))?;
                if connect {
                    driver.decoder().map_err(|e| error(&e))?;
                }
                Ok(Box::new(driver))
            }
            #[cfg(not(feature = "serial"))]
            {
                let _ = connect;
                Err(not_built(Capability::Vibrometer, "polytec", &name))
            }
        }
        LdvSection::Analog(analog) => {
            let ldv =
                metaplate_ldv::AnalogVibrometer::new(analog.identity(), &analog.range, analog.output_full_scale_v)
                    .map_err(|e| device(Capability::Vibrometer, "analog", &analog.model, e))?;
            Ok(Box::new(ldv))
        }
    }
}

fn open_daq(section: &DaqSection, file_path: &Path) -> Result<Box<dyn metaplate_core::daq::Daq + Send>, HardwareError> {
    match section {
        DaqSection::LabjackU6(u6) => {
            let serial = &u6.serial;
            #[cfg(feature = "labjack-u6")]
            {
                use metaplate_daq::{U6Driver, UsbTransport};
                let error = |e: &dyn std::fmt::Display| device(Capability::Daq, "labjack-u6", serial, e);
                let transport = UsbTransport::open(u6.selector()).map_err(|e| error(&e))?;
                let driver = U6Driver::open(transport, u6.settings()).map_err(|e| error(&e))?;
                // The transport matched the USB serial descriptor when the U6 has one; ConfigU6's is the truth.
                if &metaplate_core::daq::Daq::identity(&driver).serial != serial {
                    let found = &metaplate_core::daq::Daq::identity(&driver).serial;
                    return Err(error(&format!("the U6 found reports serial number {found}")));
                }
                Ok(Box::new(driver))
            }
            #[cfg(not(feature = "labjack-u6"))]
            Err(not_built(Capability::Daq, "labjack-u6", serial))
        }
        DaqSection::Nidaqmx(ni) => {
            #[cfg(feature = "nidaqmx")]
            {
                let settings = ni.settings(file_path).map_err(|(key, reason)| HardwareError::File {
                    path: file_path.to_path_buf(),
                    key,
                    reason,
                })?;
                let daq = metaplate_daq::NiDaqmx::open(&settings)
                    .map_err(|e| device(Capability::Daq, "nidaqmx", &ni.device, e))?;
                Ok(Box::new(daq))
            }
            #[cfg(not(feature = "nidaqmx"))]
            {
                let _ = file_path;
                Err(not_built(Capability::Daq, "nidaqmx", &ni.device))
            }
        }
        DaqSection::Alsa(alsa) => {
            // Opened when the recipe configures it (rate, inputs), as ALSA opens a stream.
            #[cfg(all(feature = "alsa", target_os = "linux"))]
            {
                let daq = metaplate_audio::AlsaCaptureDaq::new(&alsa.device, alsa.full_scale_v);
                Ok(Box::new(match &alsa.channel_map {
                    Some(map) => daq.expect_channel_map(map.clone()),
                    None => daq,
                }))
            }
            #[cfg(not(all(feature = "alsa", target_os = "linux")))]
            Err(not_built(Capability::Daq, "alsa", &alsa.device))
        }
    }
}

fn open_audio(section: &AudioSection) -> Result<Box<dyn metaplate_core::audio::AudioOut + Send>, HardwareError> {
    match section {
        AudioSection::Alsa(alsa) => {
            #[cfg(all(feature = "alsa", target_os = "linux"))]
            {
                use metaplate_audio::{AlsaSink, AudioDriver};
                use metaplate_core::audio::{AudioConfig, AudioOut};
                let mut audio = AudioDriver::new(AlsaSink::new(&alsa.device));
                audio
                    .configure(&AudioConfig { sample_rate_hz: alsa.sample_rate_hz, channels: alsa.channels })
                    .map_err(|e| device(Capability::Audio, "alsa", &alsa.device, e))?;
                Ok(Box::new(audio))
            }
            #[cfg(not(all(feature = "alsa", target_os = "linux")))]
            Err(not_built(Capability::Audio, "alsa", &alsa.device))
        }
    }
}

fn open_keypad(section: &KeypadSection, clock: &Arc<dyn Clock>) -> Result<Keypad<Box<dyn HidInput>>, HardwareError> {
    match section {
        KeypadSection::Hidraw(hid) => {
            #[cfg(all(feature = "hidraw", target_os = "linux"))]
            {
                use metaplate_keypad::{HidapiInput, HidapiSelector, ReportPrefix};
                let error = |e: &dyn std::fmt::Display| device(Capability::Keypad, "hidraw", &hid.usb, e);
                let ids = crate::file::UsbIds::parse(&hid.usb).map_err(|e| error(&e))?;
                let selector =
                    HidapiSelector { vendor_id: ids.vendor_id, product_id: ids.product_id, serial: ids.serial };
                let input: Box<dyn HidInput> = Box::new(HidapiInput::open(selector).map_err(|e| error(&e))?);
                let prefix = hid.report_id.map_or(ReportPrefix::None, ReportPrefix::ReportId);
                Ok(Keypad::new(input, Arc::clone(clock), prefix))
            }
            #[cfg(not(all(feature = "hidraw", target_os = "linux")))]
            {
                let _ = clock;
                Err(not_built(Capability::Keypad, "hidraw", &hid.usb))
            }
        }
    }
}

/// The galvo mirrors' outputs the `[aim]` section of `file` names, opened, and the fit file it names (what
/// `metaplate aim teach` drives and writes).
///
/// # Errors
/// [`HardwareError::File`] when there is no galvo `[aim]`; [`HardwareError::NotInThisBuild`] for outputs this
/// build lacks; [`HardwareError::Device`] when they cannot be opened.
pub fn open_galvo_outputs(file: &HardwareFile) -> Result<(Box<dyn MirrorOutputs>, PathBuf), HardwareError> {
    match &file.aim {
        Some(AimSection::Galvo(galvo)) => Ok((open_mirror_outputs(file, &galvo.outputs)?, galvo.fit.clone())),
        Some(AimSection::Zaber(_)) => Err(HardwareError::File {
            path: file.path.clone(),
            key: "aim.backend".into(),
            reason: "\"zaber\": stages move in mm from their own travel and need no taught fit (teaching is for \
                     galvo mirrors)"
                .into(),
        }),
        None => Err(HardwareError::File {
            path: file.path.clone(),
            key: "aim".into(),
            reason: "missing: teaching needs an [aim] section with backend = \"galvo\"".into(),
        }),
    }
}

/// The aimer `[aim]` names, or [`NoAimer`] naming the section to add: the galvo fit is read and checked now
/// (held to `max_residual_mm` when `hold_fit`), the outputs opened.
fn open_aim(file: &HardwareFile, clock: &Arc<dyn Clock>, hold_fit: bool) -> Result<Box<dyn Aim + Send>, HardwareError> {
    if let Some(AimSection::Zaber(zaber)) = &file.aim {
        use crate::zaber::OpenFailure;
        return zaber.open().map_err(|failure| match failure {
            OpenFailure::Key(key, reason) => HardwareError::File { path: file.path.clone(), key, reason },
            OpenFailure::Device(detail) => device(Capability::Aim, "zaber", &zaber.port.display().to_string(), detail),
            OpenFailure::NotBuilt => not_built(Capability::Aim, "zaber", &zaber.port.display().to_string()),
        });
    }
    let Some(AimSection::Galvo(galvo)) = &file.aim else {
        return Ok(Box::new(NoAimer {
            detail: format!(
                "{} has no [aim] section: add one (`backend = \"galvo\"`, see the user guide) to put the beam on \
                 points",
                file.path.display()
            ),
        }));
    };
    let fit = metaplate_aim::galvo::file::read(&galvo.fit).map_err(|e| HardwareError::File {
        path: file.path.clone(),
        key: "aim.fit".into(),
        reason: e.to_string(),
    })?;
    let residual = fit.residual();
    if hold_fit && residual.max_mm > galvo.max_residual_mm {
        let detail = format!(
            "the taught fit's residual, {:.3} mm at mark {}, is over aim.max_residual_mm = {} mm: teach the marks \
             again (`metaplate aim teach`)",
            residual.max_mm, residual.worst_point, galvo.max_residual_mm
        );
        return Err(device(Capability::Aim, "galvo", &galvo.fit.display().to_string(), detail));
    }
    let outputs = open_mirror_outputs(file, &galvo.outputs)?;
    let settings = metaplate_aim::galvo::GalvoSettings { settle_s: galvo.settle_ms * 1e-3 };
    let aimer = metaplate_aim::galvo::GalvoAimer::new(fit, outputs, Arc::clone(clock), settings)
        .map_err(|e| device(Capability::Aim, "galvo", &galvo.fit.display().to_string(), e))?;
    Ok(Box::new(aimer))
}

/// The mirrors' outputs of `[aim.outputs]`, opened.
fn open_mirror_outputs(
    file: &HardwareFile,
    section: &MirrorOutputsSection,
) -> Result<Box<dyn MirrorOutputs>, HardwareError> {
    match section {
        MirrorOutputsSection::Nidaqmx(ni) => {
            #[cfg(feature = "nidaqmx")]
            {
                let _ = file;
                let outputs = metaplate_daq::NiMirrorOutputs::open(
                    &ni.device,
                    &ni.x_channel,
                    &ni.y_channel,
                    ni.limit_v,
                    ni.library.clone(),
                )
                .map_err(|e| device(Capability::Aim, "galvo", &ni.device, e))?;
                Ok(Box::new(outputs))
            }
            #[cfg(not(feature = "nidaqmx"))]
            {
                let _ = ni;
                let reason = backends::find(Capability::Daq, "nidaqmx")
                    .and_then(|b| b.missing_reason())
                    .unwrap_or_else(|| "this build lacks NI-DAQmx".into());
                Err(HardwareError::NotInThisBuild {
                    path: file.path.clone(),
                    key: "aim.outputs.backend".into(),
                    backend: "nidaqmx",
                    reason,
                })
            }
        }
    }
}
