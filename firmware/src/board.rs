//! Hardware behind traits (the way smoltcp and embassy keep logic testable):
//! where frames come from and commands go is the board's business; what the
//! firmware does with them is [`handle`], one function shared by every image
//! (the arm image's timer interrupt, the PIL image's serial loop) and the host.
//!
//! A board turns what happens to it into [`Event`]s: a sensor frame at the
//! control tick, a new configuration (PIL), an operator's reset (the arm's
//! enable button), a dead peer, the end of a run. [`handle`] steps the
//! firmware on a frame and gives the board an [`Outcome`] to act on: the
//! command to write (torques, or the safe state's zero torque and disabled
//! drivers), a configuration accepted or rejected.

use shared::{
    time::Instant,
    wire::{ActuatorCommand, SensorFrame},
};

use crate::{
    config::Config, config::ConfigError, control_law::ControlLaw, controller::Firmware, controller::SafeReason, tick_clock::TickClock,
};

/// What happened at a board: the input of [`handle`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Event {
    /// The sensor frame of a period (sampled at its tick, `frame.t_us`).
    Frame(SensorFrame),
    /// A new configuration: the firmware starts afresh with it (PIL's `Configure`).
    Configure(Config),
    /// The operator leaves the safe state (a button, a command): [`Firmware::reset`].
    Reset,
    /// The peer that sends frames is gone (the board saw it die): latch
    /// [`SafeReason::PeerLost`] and answer frame `seq` with zero torque.
    PeerLost {
        /// The sequence number the safe command answers.
        seq: u32,
    },
    /// The board missed `periods` control ticks: it woke to frames it never
    /// answered (a stall) and dropped them as stale, to answer only the newest,
    /// which comes next as [`Event::Frame`]. Counted as overruns
    /// ([`Firmware::missed_periods`]).
    Missed {
        /// Control periods missed.
        periods: u32,
    },
    /// The run is over: [`run`] returns.
    End,
}

/// What [`handle`] asks the board to do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outcome {
    /// Write this command (it carries the safe state in its status word: a
    /// board disables its drivers then).
    Command(ActuatorCommand),
    /// The configuration of an [`Event::Configure`] is in force.
    Configured,
    /// The configuration of an [`Event::Configure`] is invalid; the firmware,
    /// if any, is unchanged.
    Rejected(ConfigError),
    /// A frame arrived before any configuration: nothing to step.
    NotConfigured {
        /// The frame's sequence number.
        seq: u32,
    },
    /// The firmware left the safe state ([`Event::Reset`]).
    Reset,
    /// Missed periods were counted ([`Event::Missed`]); nothing to write.
    Missed {
        /// Control periods missed.
        periods: u32,
    },
    /// The run ended ([`Event::End`]).
    Ended,
}

/// A board: the source of events and the sink of outcomes.
pub trait Board {
    /// Why the board failed (a dead peer, a broken link).
    type Error;
    /// Blocks until the next event.
    ///
    /// # Errors
    /// The board's error (peer gone, link broken).
    fn next_event(&mut self) -> Result<Event, Self::Error>;
    /// When the step of the frame just received starts, on the clock of
    /// [`SensorFrame::t_us`] (the frame's sample time plus whatever delayed the
    /// start).
    fn now(&self) -> Instant;
    /// Acts on an outcome; `firmware` is the state after it (telemetry), with
    /// whichever law it runs.
    ///
    /// # Errors
    /// The board's error.
    fn apply<L: ControlLaw>(&mut self, outcome: &Outcome, firmware: Option<&Firmware<L>>) -> Result<(), Self::Error>;
}

/// One event: steps, reconfigures, resets or latches the safe state, then has
/// the board apply the outcome, which it also returns.
///
/// `firmware` is `None` until a configuration arrives (PIL); boards with a
/// built-in configuration pass `Some` from the start.
///
/// # Errors
/// The board's error from [`Board::apply`].
pub fn handle<L: ControlLaw, B: Board, C: TickClock>(
    firmware: &mut Option<Firmware<L>>,
    event: Event,
    board: &mut B,
    clock: &C,
) -> Result<Outcome, B::Error> {
    let outcome = match (event, firmware.as_mut()) {
        (Event::Frame(frame), Some(fw)) => Outcome::Command(fw.step(board.now(), &frame, clock)),
        (Event::Frame(frame), None) => Outcome::NotConfigured { seq: frame.seq },
        (Event::Configure(cfg), _) => match Firmware::with_law(cfg) {
            Ok(fw) => {
                *firmware = Some(fw);
                Outcome::Configured
            }
            Err(e) => Outcome::Rejected(e),
        },
        (Event::Reset, fw) => {
            if let Some(fw) = fw {
                fw.reset();
            }
            Outcome::Reset
        }
        (Event::PeerLost { seq }, fw) => match fw {
            Some(fw) => {
                fw.enter_safe_state(SafeReason::PeerLost);
                Outcome::Command(fw.safe_command(seq, board.now()))
            }
            None => Outcome::NotConfigured { seq },
        },
        (Event::Missed { periods }, fw) => {
            if let Some(fw) = fw {
                fw.missed_periods(periods);
            }
            Outcome::Missed { periods }
        }
        (Event::End, _) => Outcome::Ended,
    };
    board.apply(&outcome, firmware.as_ref())?;
    Ok(outcome)
}

/// Handles events until [`Event::End`].
///
/// # Errors
/// The board's first error.
pub fn run<L: ControlLaw, B: Board, C: TickClock>(firmware: &mut Option<Firmware<L>>, board: &mut B, clock: &C) -> Result<(), B::Error> {
    loop {
        let event = board.next_event()?;
        if handle(firmware, event, board, clock)? == Outcome::Ended {
            return Ok(());
        }
    }
}

/// A clock that never advances (tests, replay on the host): every step takes 0 ticks.
#[derive(Debug, Clone, Copy, Default)]
pub struct FrozenClock;

impl TickClock for FrozenClock {
    fn ticks(&self) -> u32 {
        0
    }
    fn ticks_per_second(&self) -> u32 {
        1_000_000
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shared::wire::status;

    /// A board that plays a script of events and records the outcomes.
    struct Script {
        events: std::vec::IntoIter<Event>,
        outcomes: Vec<Outcome>,
        now: Instant,
    }

    impl Board for Script {
        type Error = &'static str;
        fn next_event(&mut self) -> Result<Event, Self::Error> {
            let e = self.events.next().ok_or("script exhausted")?;
            if let Event::Frame(f) = e {
                self.now = f.sampled_at();
            }
            Ok(e)
        }
        fn now(&self) -> Instant {
            self.now
        }
        fn apply<L: ControlLaw>(&mut self, outcome: &Outcome, _: Option<&Firmware<L>>) -> Result<(), Self::Error> {
            self.outcomes.push(*outcome);
            Ok(())
        }
    }

    fn frame(seq: u32) -> SensorFrame {
        // The tip of x0d near the belt, at rest: a frame the firmware trusts.
        SensorFrame { t_us: seq as u64 * 1000, seq, theta1_count: 15_860, elbow_count: 15_290, ..SensorFrame::default() }
    }

    #[test]
    fn run_configures_steps_resets_and_ends_in_script_order() {
        let bad = Config { period: shared::Period::from_us(10).unwrap(), ..Config::default() };
        let events = vec![
            Event::Frame(frame(0)),
            Event::Configure(bad),
            Event::Configure(Config::default()),
            Event::Frame(frame(1)),
            Event::PeerLost { seq: 2 },
            Event::Frame(frame(3)),
            Event::Reset,
            Event::End,
        ];
        let mut board = Script { events: events.into_iter(), outcomes: Vec::new(), now: Instant::from_us(0) };
        let mut fw: Option<Firmware<crate::PaperLaws>> = None;
        run(&mut fw, &mut board, &FrozenClock).unwrap();
        let o = &board.outcomes;
        assert_eq!(o.len(), 8);
        assert_eq!(o[0], Outcome::NotConfigured { seq: 0 });
        assert!(matches!(o[1], Outcome::Rejected(_)), "{:?}", o[1]);
        assert_eq!(o[2], Outcome::Configured);
        let Outcome::Command(c1) = o[3] else { panic!("{:?}", o[3]) };
        assert_eq!((c1.seq, c1.status & status::SAFE_STATE), (1, 0));
        // The lost peer latches the safe state: zero torque for that frame and the next.
        for (i, seq) in [(4, 2), (5, 3)] {
            let Outcome::Command(c) = o[i] else { panic!("{:?}", o[i]) };
            assert_eq!(c.seq, seq);
            assert_eq!((c.u1_code, c.u2_code), (0, 0));
            assert_eq!(SafeReason::from_status(c.status), Some(SafeReason::PeerLost));
        }
        assert_eq!(o[6], Outcome::Reset);
        assert_eq!(fw.as_ref().unwrap().safe_state(), None, "reset leaves the safe state");
        assert_eq!(o[7], Outcome::Ended);
    }

    /// Missed ticks count as overruns and consecutive misses: fewer than the limit
    /// and a step on time clears the streak; the limit latches the safe state.
    #[test]
    fn missed_periods_count_as_overruns_and_latch_at_the_limit() {
        let limit = Config::default().deadline_miss_limit;
        let events = vec![
            Event::Frame(frame(0)),
            Event::Missed { periods: u32::from(limit) - 1 },
            Event::Frame(frame(u32::from(limit))),
            Event::Missed { periods: 500 },
            Event::Frame(frame(u32::from(limit) + 501)),
            Event::End,
        ];
        let mut board = Script { events: events.into_iter(), outcomes: Vec::new(), now: Instant::from_us(0) };
        let mut fw = Some(Firmware::new(Config::default()).unwrap());
        run(&mut fw, &mut board, &FrozenClock).unwrap();
        let o = &board.outcomes;
        let Outcome::Command(c) = o[2] else { panic!("{:?}", o[2]) };
        assert_eq!((c.overruns, c.status & status::SAFE_STATE), (u32::from(limit) - 1, 0), "below the limit: counted, not safe");
        let Outcome::Command(c) = o[4] else { panic!("{:?}", o[4]) };
        assert_eq!(c.overruns, u32::from(limit) - 1 + 500);
        assert_eq!(SafeReason::from_status(c.status), Some(SafeReason::DeadlineMisses));
        assert_eq!((c.u1_code, c.u2_code), (0, 0));
    }

    #[test]
    fn a_board_error_stops_the_loop() {
        let mut board =
            Script { events: vec![Event::Configure(Config::default())].into_iter(), outcomes: Vec::new(), now: Instant::from_us(0) };
        assert_eq!(run(&mut None::<Firmware<crate::PaperLaws>>, &mut board, &FrozenClock), Err("script exhausted"));
    }
}
