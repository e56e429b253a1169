//! Real-time set-up of a control loop's thread (CPU pinning, `SCHED_FIFO`,
//! locked memory), for the plant loop and the firmware process of `--realtime`
//! runs; what could not be set up is reported, never fatal.

/// How a real-time control loop was set up by [`prepare_realtime`] (reported in
/// `summary.json`).
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct RealtimeSetup {
    /// The CPU the loop's thread is pinned to; `None` when not pinned.
    pub cpu: Option<usize>,
    /// Its `SCHED_FIFO` priority; `None` under the normal scheduler.
    pub fifo_priority: Option<u8>,
    /// What could not be set up as the scenario asked (the run goes on without it).
    pub warnings: Vec<String>,
    /// The thread's CPUs before pinning, for [`leave_realtime`].
    #[serde(skip)]
    previous_cpus: Vec<usize>,
}

impl RealtimeSetup {
    /// One line for people: `CPU 1, SCHED_FIFO 10`.
    pub fn describe(&self) -> String {
        let cpu = self.cpu.map_or("any CPU".to_string(), |c| format!("CPU {c}"));
        let sched = self.fifo_priority.map_or("normal scheduler".to_string(), |p| format!("SCHED_FIFO {p}"));
        format!("{cpu}, {sched}")
    }
}

/// Undoes [`prepare_realtime`] on the calling thread: the normal scheduler and
/// the CPUs it had before (what the plant does after the run: writing the
/// outputs is no real-time work). Memory stays locked. Never fails.
pub fn leave_realtime(setup: &RealtimeSetup) {
    #[cfg(target_os = "linux")]
    // SAFETY: as in prepare_realtime; the mask and param are owned by this frame.
    unsafe {
        if setup.fifo_priority.is_some() {
            let param = libc::sched_param { sched_priority: 0 };
            libc::sched_setscheduler(0, libc::SCHED_OTHER, &param);
        }
        if setup.cpu.is_some() && !setup.previous_cpus.is_empty() {
            let mut mask: libc::cpu_set_t = std::mem::zeroed();
            for &c in &setup.previous_cpus {
                libc::CPU_SET(c, &mut mask);
            }
            libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mask);
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = setup;
}

/// The CPUs the calling thread may run on (its affinity mask).
#[cfg(target_os = "linux")]
fn allowed_cpus() -> std::io::Result<Vec<usize>> {
    // SAFETY: a zeroed cpu_set_t owned here, of the size passed; pid 0 is the
    // calling thread.
    unsafe {
        let mut mask: libc::cpu_set_t = std::mem::zeroed();
        if libc::sched_getaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mut mask) != 0 {
            return Err(std::io::Error::last_os_error());
        }
        Ok((0..libc::CPU_SETSIZE as usize).filter(|&c| libc::CPU_ISSET(c, &mask)).collect())
    }
}

/// Real-time runs: sets up the calling thread (the control loop) as the
/// scenario's `[rig]` asks: 1 us timer slack instead of the default 50 us (sleeps
/// end when asked), memory locked (no page fault mid-period), pinned to
/// `rig.realtime_cpu` and scheduled `SCHED_FIFO` at `rig.realtime_fifo_priority`.
///
/// Why one CPU for both processes: the plant publishes a frame and blocks for the
/// command, which hands the core straight to the firmware and back, a few
/// microseconds each way; on two CPUs the answer waits for the other core to wake
/// up, which on this virtual machine takes up to milliseconds tens of times a
/// minute. Why `SCHED_FIFO` is safe here: neither loop busy-waits for more than
/// `rig.spin_us` a period, far below the kernel's real-time throttling (95 % of
/// each second); a busy-waiting FIFO loop would be throttled 50 ms every second.
///
/// Never fails: what the kernel refuses (no privilege, no such CPU) is a warning
/// in the result. Linux only; elsewhere it only reports that nothing was set.
pub fn prepare_realtime(rig: &super::scenario::RigSection) -> RealtimeSetup {
    let mut setup = RealtimeSetup::default();
    #[cfg(target_os = "linux")]
    // SAFETY: prctl(PR_SET_TIMERSLACK) takes one integer; mlockall takes flags;
    // sched_{get,set}affinity get a properly sized cpu_set_t owned by this frame;
    // sched_setscheduler gets a valid sched_param. pid 0 is the calling thread.
    unsafe {
        libc::prctl(libc::PR_SET_TIMERSLACK, 1000 as libc::c_ulong, 0 as libc::c_ulong, 0 as libc::c_ulong, 0 as libc::c_ulong);
        if libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) != 0 {
            setup.warnings.push(format!("mlockall: {}", std::io::Error::last_os_error()));
        }
        let pin = rig.realtime_pin().unwrap_or(super::scenario::CpuPin::None);
        match allowed_cpus() {
            Ok(cpus) => setup.previous_cpus = cpus,
            Err(e) => setup.warnings.push(format!("sched_getaffinity: {e}")),
        }
        let cpu = match pin {
            super::scenario::CpuPin::None => None,
            super::scenario::CpuPin::Cpu(c) => Some(c),
            super::scenario::CpuPin::Last => setup.previous_cpus.last().copied(),
        };
        if let Some(c) = cpu {
            let mut mask: libc::cpu_set_t = std::mem::zeroed();
            libc::CPU_SET(c, &mut mask);
            if libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mask) == 0 {
                setup.cpu = Some(c);
            } else {
                setup.warnings.push(format!("cannot pin the control loop to CPU {c}: {}", std::io::Error::last_os_error()));
            }
        }
        let prio = rig.realtime_fifo_priority;
        if prio > 0 {
            let param = libc::sched_param { sched_priority: i32::from(prio) };
            if libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) == 0 {
                setup.fifo_priority = Some(prio);
            } else {
                setup.warnings.push(format!(
                    "SCHED_FIFO priority {prio}: {} (running under the normal scheduler; set rig.realtime_fifo_priority = 0 to silence this)",
                    std::io::Error::last_os_error()
                ));
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = rig;
        setup.warnings.push("real-time set-up (pinning, SCHED_FIFO, memory locking) is Linux-only".into());
    }
    setup
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    fn cpus() -> Vec<usize> {
        allowed_cpus().unwrap()
    }

    #[test]
    fn a_real_time_loop_is_pinned_to_the_last_cpu_and_given_back_its_cpus() {
        // On a thread of its own: the set-up is per thread.
        std::thread::spawn(|| {
            let before = cpus();
            let rig = super::super::scenario::RigSection { realtime_fifo_priority: 0, ..Default::default() };
            let setup = prepare_realtime(&rig);
            assert_eq!(setup.cpu, before.last().copied(), "{:?}", setup.warnings);
            assert_eq!(cpus(), vec![before[before.len() - 1]]);
            assert_eq!(setup.fifo_priority, None);
            leave_realtime(&setup);
            assert_eq!(cpus(), before);
        })
        .join()
        .unwrap();
    }
}
