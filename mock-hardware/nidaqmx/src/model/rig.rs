//! The stand-in's side of the lab link ([`crate::lab`]): a timed input task reads the stand-in rig, and on-demand
//! output writes are told to it.

use std::time::Instant;

use super::{NiError, ReadOutcome, Samples, StandIn, Task, codes, err, overwritten};
use crate::lab::{LabLink, Reply};

/// The stand-in rig cannot be reached, or refused: the device went away, as NI reports it.
pub(super) fn lab_gone(detail: &str) -> NiError {
    err(
        codes::DEVICE_CANNOT_BE_ACCESSED,
        "Device cannot be accessed.\nPossible causes:\nDevice is no longer present in the system.",
        detail,
    )
}

impl StandIn {
    /// Connects a timed input task that starts running to the stand-in rig, when there is one.
    pub(super) fn open_lab(&mut self, handle: u64) -> Result<(), NiError> {
        let Some(socket) = self.lab_socket.clone().or_else(crate::lab::socket_beside_library) else { return Ok(()) };
        let task = self.task(handle)?;
        let (Some(timing), false) = (task.timing, task.ai.is_empty()) else { return Ok(()) };
        let inputs: Vec<u8> = task.ai.iter().map(|c| c.index).collect();
        let link = LabLink::start(&socket, timing.rate_hz, &inputs).map_err(|detail| lab_gone(&detail))?;
        self.labs.insert(handle, link);
        Ok(())
    }

    /// Tells the stand-in rig, when there is one, the voltages `device`'s `ao0` and `ao1` now hold (its galvo
    /// mirrors follow them).
    pub(super) fn forward_outputs(&mut self, device: &str) -> Result<(), NiError> {
        let Some(socket) = self.lab_socket.clone().or_else(crate::lab::socket_beside_library) else { return Ok(()) };
        let mut link = match self.outputs_link.take() {
            Some(link) => link,
            None => LabLink::outputs(&socket).map_err(|detail| lab_gone(&detail))?,
        };
        let held = |index: u8| self.held_v.get(&(device.to_owned(), index)).copied().unwrap_or(0.0);
        let (x_v, y_v) = (held(0), held(1));
        link.set_outputs(x_v, y_v).map_err(|detail| lab_gone(&detail))?;
        self.outputs_link = Some(link);
        Ok(())
    }

    /// One attempt of a read of a task that reads the stand-in rig: `num` samples per channel (-1: what this clock
    /// says was acquired, `acquired` in all) into `out`, grouped by `fill_mode`.
    ///
    /// # Errors
    /// -200279 when the rig's buffer overflowed; -201003 when the rig cannot be reached (the acquisition is then
    /// over) or refuses; as the read's own checks.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn read_from_lab(
        &mut self,
        task: &Task,
        handle: u64,
        acquired: u64,
        num: i32,
        fill_mode: u32,
        out: &mut [f64],
        now: Instant,
    ) -> Result<ReadOutcome, NiError> {
        let Some(link) = self.labs.get_mut(&handle) else { return Ok(ReadOutcome::Wait(None)) };
        // The rig paces its samples (and reports its own overflows); "all available" is what this clock says
        // was acquired.
        let want = if num < 0 { acquired.saturating_sub(task.read_pos) } else { u64::from(num.unsigned_abs()) };
        let reply = match link.read(task.read_pos, want) {
            Ok(reply) => reply,
            Err(e) => {
                // The connection may be out of step (a reply half read): the acquisition is over.
                self.labs.remove(&handle);
                return Err(lab_gone(&format!("the stand-in rig: {e}")));
            }
        };
        match reply {
            Reply::Wait { ms } => Ok(ReadOutcome::Wait(Some(now + std::time::Duration::from_millis(ms)))),
            Reply::Data(values) if values.len() as u64 == want * task.ai.len() as u64 => {
                self.fill(task, handle, Samples::Rig(&values), want, fill_mode, out)
            }
            Reply::Overrun => Err(overwritten(&task.name)),
            Reply::Error(text) => Err(lab_gone(&format!("the stand-in rig: {text}"))),
            Reply::Data(values) => Err(lab_gone(&format!(
                "the stand-in rig sent {} values for {want} samples of {} inputs",
                values.len(),
                task.ai.len()
            ))),
            Reply::Ok => Err(lab_gone("the stand-in rig answered ok to a read")),
        }
    }
}
