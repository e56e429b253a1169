//! Which of the rig's five links a closed-loop run goes over, named once and
//! opened in one place (in the manner of copper-rs, whose configuration names a
//! run's sources and sinks and whose runtime opens them, in simulation or on
//! the hardware alike): `run` and `pil` say which link they want as a
//! [`LinkSpec`], and [`LinkSpec::open`] makes it.

use std::path::PathBuf;

#[cfg(feature = "board")]
use board_link::{EmulatorLink, TwinLink};
use rig::{
    FirmwareLink,
    in_process::InProcessLink,
    ipc::MonitorPolicy,
    ipc_link::IpcLink,
    pil_link::{LogSink, PilLink, PilOptions},
    setup::RunSetup,
};

use crate::error::CliError;

/// A closed-loop run's link and what opening it takes.
pub enum LinkSpec {
    /// The firmware step linked into the plant's process (`run --in-process`).
    InProcess,
    /// The firmware in its own process over iceoryx2 shared memory (`run`, the
    /// default): rig `rig`; the firmware process spawned from this executable,
    /// or attached to (`--attach`, started by hand); lockstep or `--realtime`;
    /// the monitors the plant waits for.
    Iceoryx2 {
        /// The rig's name (its iceoryx2 services).
        rig: String,
        /// Attach to a firmware process started by hand instead of spawning one.
        attach: bool,
        /// Real time (the wall clock paces the periods) rather than lockstep.
        realtime: bool,
        /// The monitors the plant waits for, and how.
        monitors: MonitorPolicy,
    },
    /// The `arm` application on the board twin's bus-level models (`run --link twin`).
    Twin,
    /// The flashed `arm` ELF at `elf` on the emulated reference board (`run --link emulator`).
    Emulator {
        /// The image.
        elf: PathBuf,
    },
    /// The MCU image in QEMU or on a board behind a serial port (`pil`): the
    /// target and its options, and where the image's log lines go as they come.
    Pil {
        /// The target and the link's options.
        options: PilOptions,
        /// The image's defmt lines as they are decoded (QEMU only).
        on_log: Option<LogSink>,
    },
}

/// An open link of one of the five kinds (each boxed: they differ in size by
/// hundreds of bytes, and the loop calls them through `dyn FirmwareLink` anyway), kept whole so that a command can read
/// what its kind measured after the run (iceoryx2's timings, the twin's notices,
/// the PIL image's counts and log).
pub enum OpenLink {
    /// [`LinkSpec::InProcess`].
    InProcess(Box<InProcessLink>),
    /// [`LinkSpec::Iceoryx2`].
    Iceoryx2(Box<IpcLink>),
    /// [`LinkSpec::Twin`] (the feature `board`).
    #[cfg(feature = "board")]
    Twin(Box<TwinLink>),
    /// [`LinkSpec::Emulator`] (the feature `board`).
    #[cfg(feature = "board")]
    Emulator(Box<EmulatorLink>),
    /// [`LinkSpec::Pil`].
    Pil(Box<PilLink>),
}

impl LinkSpec {
    /// Opens the link for run `setup`: makes the firmware's side ready and, for
    /// the links that handshake, checks its announcement against the scenario.
    ///
    /// # Errors
    /// [`CliError`]: the rig's own failures to start (`RunError`: exit 2 where the
    /// input is at fault, such as another user's rig or a firmware that
    /// announces another configuration, else 1); the twin's and the emulated
    /// board's refusals as bad input (exit 2), such as runaway limits turned off
    /// or a missing image; QEMU that cannot start or a board that does not answer;
    /// the twin and the emulated board in a build without the feature `board`
    /// ([`crate::features::missing`], exit 2).
    pub fn open(self, setup: &RunSetup) -> Result<OpenLink, CliError> {
        Ok(match self {
            Self::InProcess => OpenLink::InProcess(Box::new(InProcessLink::new(setup).map_err(CliError::from)?)),
            Self::Iceoryx2 { rig, attach, realtime, monitors } => {
                let exe = if attach {
                    None
                } else {
                    Some(
                        std::env::current_exe()
                            .map_err(|e| CliError::bad_input(format!("cannot find this executable to spawn the firmware: {e}")))?,
                    )
                };
                OpenLink::Iceoryx2(Box::new(IpcLink::connect(setup, &rig, exe.as_deref(), realtime, &monitors).map_err(CliError::from)?))
            }
            #[cfg(feature = "board")]
            Self::Twin => OpenLink::Twin(Box::new(TwinLink::new(setup).map_err(|e| CliError::bad_input(e.to_string()))?)),
            #[cfg(feature = "board")]
            Self::Emulator { elf } => {
                let link = EmulatorLink::new(setup, &elf).map_err(|e| CliError::bad_input(e.to_string()))?;
                // Which bytes run (issue 84: a copied binary silently ran the build tree's image).
                eprintln!("emulator: loaded {}", link.loaded);
                OpenLink::Emulator(Box::new(link))
            }
            #[cfg(not(feature = "board"))]
            Self::Twin => return Err(crate::features::missing("board", "--link twin")),
            #[cfg(not(feature = "board"))]
            Self::Emulator { .. } => return Err(crate::features::missing("board", "--link emulator")),
            Self::Pil { options, on_log } => OpenLink::Pil(Box::new(PilLink::start(setup, &options, on_log).map_err(CliError::from)?)),
        })
    }
}

impl OpenLink {
    /// The link, as the period loop drives it.
    pub fn link(&mut self) -> &mut dyn FirmwareLink {
        match self {
            Self::InProcess(l) => l.as_mut(),
            Self::Iceoryx2(l) => l.as_mut(),
            #[cfg(feature = "board")]
            Self::Twin(l) => l.as_mut(),
            #[cfg(feature = "board")]
            Self::Emulator(l) => l.as_mut(),
            Self::Pil(l) => l.as_mut(),
        }
    }
}
