//! The firmware's process as the link sees it: spawned with the scenario on its
//! standard input, whether it is gone (a spawned process's exit, an attached
//! one's iceoryx2 node), its pid and state (stopped?), and its end when the link
//! drops.

use std::{
    io::Write,
    path::Path,
    process::{Command, Stdio},
    time::{Duration, Instant},
};

use super::{IpcLink, Spawned};
use crate::{
    ipc::{PeerState, Role, peer_state},
    realtime::leave_realtime,
    record::RunError,
    scenario::Scenario,
};

impl IpcLink {
    /// [`Self::firmware_gone`], for a period without an answer. A spawned process
    /// is asked every time (a `waitpid`, microseconds); a firmware started by hand
    /// through iceoryx2's node listing, which reads the node directory and takes
    /// milliseconds, at most every 20 ms of wall time, so a stalled firmware never
    /// costs the plant more than its period per missed period in real time.
    pub(super) fn firmware_gone_checked(&mut self) -> Option<String> {
        if self.spawned.is_none() {
            let now = Instant::now();
            if self.last_peer_check.is_some_and(|t| now - t < Duration::from_millis(20)) {
                return None;
            }
            self.last_peer_check = Some(now);
        }
        self.firmware_gone()
    }

    /// Whether the firmware process is gone, and how.
    pub(super) fn firmware_gone(&mut self) -> Option<String> {
        match &mut self.spawned {
            Some(sp) => match sp.child.try_wait() {
                Ok(Some(status)) => Some(format!("exited ({status})")),
                Ok(None) => None,
                Err(e) => Some(format!("cannot be waited for ({e})")),
            },
            None => match peer_state(Role::Firmware, &self.rig) {
                PeerState::Alive => None,
                PeerState::Dead => Some("died (its iceoryx2 node is dead)".into()),
                PeerState::Absent => Some("is gone (no iceoryx2 node)".into()),
            },
        }
    }

    /// The firmware's process id (spawned, or the attached firmware's node owner).
    pub(super) fn firmware_pid(&self) -> Option<i64> {
        match &self.spawned {
            Some(sp) => Some(i64::from(sp.child.id())),
            None => crate::ipc::live_owner(Role::Firmware, &self.rig),
        }
    }
}

pub(super) fn spawn(exe: &Path, rig: &str, s: &Scenario, realtime: bool) -> Result<Spawned, RunError> {
    let toml = toml::to_string(s).map_err(|e| RunError::Transport(format!("cannot serialise the scenario: {e}")))?;
    let mut cmd = Command::new(exe);
    cmd.args(["firmware", "--rig", rig, "--scenario", "-"]).stdin(Stdio::piped()).stdout(Stdio::null()).stderr(Stdio::inherit());
    if realtime {
        cmd.arg("--realtime");
    }
    let mut child = cmd.spawn().map_err(|e| RunError::Transport(format!("cannot start the firmware process {}: {e}", exe.display())))?;
    let mut stdin = child.stdin.take().ok_or_else(|| RunError::Transport("no stdin to the firmware process".into()))?;
    stdin.write_all(toml.as_bytes()).map_err(|e| RunError::Transport(format!("cannot send the scenario to the firmware process: {e}")))?;
    drop(stdin);
    Ok(Spawned { child })
}

impl Drop for IpcLink {
    fn drop(&mut self) {
        if let Some(setup) = &self.realtime_setup {
            leave_realtime(setup);
        }
        if let Some(sp) = &mut self.spawned {
            if let Ok(None) = sp.child.try_wait() {
                let _ = sp.child.kill();
            }
            let _ = sp.child.wait();
            // A killed firmware could not remove its lock file: the plant does.
            crate::ipc::RigLock::remove_stale(Role::Firmware, &self.rig);
        }
    }
}

/// The state letter of process `pid` (`/proc/PID/stat`'s third field: `R`, `S`,
/// `T` stopped, `t` stopped by a tracer, ...); `None` where there is no procfs.
pub(super) fn process_state(pid: i64) -> Option<char> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name in parentheses may hold spaces: the state follows its ')'.
    stat.rsplit_once(')')?.1.trim_start().chars().next()
}
