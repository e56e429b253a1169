//! `sil-host board-twin --pty`: the board twin, or the emulated `arm` image,
//! with the arm hanging free, serving the bring-up protocol on a
//! pseudo-terminal, and the operator's commands on standard input (the belt,
//! weights on the load cell).

use std::{sync::Arc, time::Duration};

use board_link::{
    bringup_line::{self, Pty},
    free_arm::{ArmBoard, FreeArm},
};
use board_twin::{BusFaults, FlashModel};
use rig::setup::firmware_config;

use crate::{
    cli::{BoardTwinArgs, FlashArg},
    error::CliError,
};
use experiments::scenario::load_scenario;

/// `sil-host board-twin --pty`.
///
/// # Errors
/// [`CliError`]: a bad scenario or board description (exit 2), a pseudo-terminal
/// that does not open, a plant failure.
pub fn twin(args: &BoardTwinArgs) -> Result<(), CliError> {
    let s = load_scenario(&args.scenario)?;
    if let Some(t) = args.serve_for
        && !(t.is_finite() && t > 0.0)
    {
        return Err(CliError::bad_input(format!("--serve-for {t}: must be a positive number of seconds")));
    }
    let flash = if args.flash == FlashArg::Erased {
        FlashModel::erased()
    } else {
        FlashModel::brought_up(&s.calibration.arm_calibration(), firmware_config(&s))
            .map_err(|e| CliError::bad_input(format!("the settings record: {}", e.describe())))?
    };
    if args.flash == FlashArg::Corrupt {
        // One bit of the record's frame: its CRC-32C no longer matches.
        flash.bytes().borrow_mut()[12] ^= 0x10;
    }
    // A board's compiled-in configuration has the runaway limits on, always: a
    // scenario that turns them off puts that in the saved record only (`--flash
    // saved`), which the board refuses at reset, the drivers locked out.
    let mut s = s;
    s.controller.runaway_limits = true;
    if args.emulated {
        let elf = args.elf.clone().unwrap_or_else(board_link::emulator_link::default_image);
        let arm = FreeArm::emulated(&s, s.board, &flash, &elf).map_err(|e| CliError::bad_input(e.to_string()))?;
        serve_arm(args, arm, "emulated arm image")
    } else {
        let arm = FreeArm::with_flash(&s, s.board, &s.calibration, flash).map_err(|e| CliError::bad_input(e.to_string()))?;
        serve_arm(args, arm, "board twin")
    }
}

/// What the twin's operator does, from a line of its standard input.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Operator {
    /// Hangs the load `[f_t, f_n]`, N, on the load cell (`weight AXIS NEWTONS`, `weight off`).
    Weight([f64; 2]),
    /// Presses the reset button (`reset`).
    Reset,
    /// Raises the belt to the tip (`belt up`) or lowers it below the hanging
    /// tip (`belt down`).
    Belt(bool),
}

/// A line of the twin's standard input: `weight AXIS NEWTONS`, `weight off`,
/// `reset`, `belt up` or `belt down`.
fn operator_command(line: &str) -> Result<Operator, String> {
    match line.split_whitespace().collect::<Vec<_>>()[..] {
        ["reset"] => Ok(Operator::Reset),
        ["belt", "up"] => Ok(Operator::Belt(true)),
        ["belt", "down"] => Ok(Operator::Belt(false)),
        _ => weight_command(line).map(Operator::Weight),
    }
}

/// `weight AXIS NEWTONS` or `weight off`: the load `[f_t, f_n]` it hangs, N.
fn weight_command(line: &str) -> Result<[f64; 2], String> {
    let words: Vec<&str> = line.split_whitespace().collect();
    let usage = || format!("`{line}`: expected `weight normal|tangential NEWTONS`, `weight off`, `reset`, `belt up` or `belt down`");
    match words[..] {
        ["weight", "off"] => Ok([0.0; 2]),
        ["weight", axis, n] => {
            let n: f64 = n.parse().map_err(|_| usage())?;
            if !(n.is_finite() && n.abs() <= 25.0) {
                return Err(format!("`{line}`: the load cell takes at most 25 N"));
            }
            match axis {
                "normal" => Ok([0.0, n]),
                "tangential" => Ok([n, 0.0]),
                _ => Err(usage()),
            }
        }
        _ => Err(usage()),
    }
}

/// Announces the port and the pose, then serves `arm` until stopped.
fn serve_arm<B: ArmBoard>(args: &BoardTwinArgs, mut arm: FreeArm<B>, what: &str) -> Result<(), CliError> {
    if args.fault_line {
        arm.set_faults(BusFaults { driver_fault: true, ..BusFaults::default() });
    }
    let mut pty = Pty::open().map_err(CliError::bad_input)?;
    let pose = arm.pose_counts();
    let pose_deg = pose.map(|c| {
        let d = f64::from(c) * 360.0 / 16384.0;
        if d > 180.0 { d - 360.0 } else { d }
    });
    let flash_name = format!("{:?}", args.flash).to_lowercase();
    if args.json {
        outln!("{}", serde_json::json!({ "port": pty.path, "pose_deg": pose_deg, "pose_counts": pose, "flash": flash_name }));
    } else {
        outln!(
            "{what} on {}: the arm hangs at theta1 {:.6} deg, elbow {:.6} deg (counts {:?}: the jig's pose); flash {flash_name}{}",
            pty.path.display(),
            pose_deg[0],
            pose_deg[1],
            pose,
            if args.fault_line { "; fault line asserted" } else { "" }
        );
    }
    if crate::stdout::failed() {
        // Nobody can read the port's name: nothing to serve (exit 141 or 1, crate::stdout).
        return Ok(());
    }
    // The operator, from standard input (one a line): a weight on the load
    // cell (`weight normal 4.905`, `weight tangential -2`, `weight off`), the
    // reset button (`reset`), or the belt's lift (`belt up`, `belt down`).
    let load = arm.load();
    let reset = arm.reset_button();
    let belt = arm.belt_lift();
    std::thread::spawn(move || {
        for line in std::io::stdin().lines().map_while(Result::ok) {
            match operator_command(&line) {
                Ok(Operator::Weight(w)) => {
                    *load.lock().unwrap_or_else(std::sync::PoisonError::into_inner) = w;
                    eprintln!("load cell: f_t {} N, f_n {} N hung", w[0], w[1]);
                }
                Ok(Operator::Reset) => {
                    reset.store(true, std::sync::atomic::Ordering::Relaxed);
                    eprintln!("reset: the board restarts from its flash");
                }
                Ok(Operator::Belt(up)) => {
                    belt.store(up, std::sync::atomic::Ordering::Relaxed);
                    eprintln!(
                        "{}",
                        if up {
                            "belt up: the tip on the running belt at the scenario's initial pose, held there while the drivers are off"
                        } else {
                            "belt down: below the hanging tip"
                        }
                    );
                }
                Err(e) => eprintln!("{e}"),
            }
        }
    });
    // Until Ctrl-C or SIGTERM, or --serve-for's time (which sets the same flag,
    // without a signal: the exit code stays 0).
    let stop = crate::cancel::stop_flag();
    if let Some(t) = args.serve_for {
        let stop = Arc::clone(&stop);
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_secs_f64(t));
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
        });
    }
    bringup_line::serve(&mut arm, &mut pty.master, &stop).map_err(CliError::Board)?;
    if crate::cancel::exit_code().is_some() {
        // Ctrl-C or SIGTERM (not --serve-for's end): 130 or 143.
        return Err(CliError::interrupted(format!("{what} stopped")));
    }
    Ok(())
}
