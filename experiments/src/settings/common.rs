//! The arguments several commands share: the output folder and `--json`
//! ([`OutputArgs`]), `--strict` ([`StrictArgs`]), and a closed-loop run's scenario
//! with its overrides ([`ScenarioArgs`]).

use std::path::PathBuf;

/// Options shared by every command's output.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct OutputArgs {
    /// Folder for the files the command writes (created if missing).
    #[cfg_attr(feature = "clap", arg(long, default_value = "out", value_name = "DIR"))]
    pub out: PathBuf,
    /// Print one JSON document on stdout instead of the human summary.
    #[cfg_attr(feature = "clap", arg(long))]
    pub json: bool,
}

/// `--live [ADDR]` and `--live-rate`: a run shown live in Foxglove (`run`,
/// `pil`, `simulate`; `arm-view::LiveTable`).
#[derive(Debug, Clone, Copy)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct LiveArgs {
    /// Serve the run live to the Foxglove app over the Foxglove WebSocket
    /// protocol on ADDR (default 127.0.0.1:8765, the app's default; port 0: any
    /// free port), while it runs: the channels of trace.mcap, the arm in 3D
    /// (/tf, /scene), the plots' channels and the log (/log), with the same
    /// bytes. In Foxglove: Open connection > Foxglove WebSocket >
    /// ws://127.0.0.1:8765, and the layout docs/foxglove/layout.json. The run
    /// is paced by --live-rate; its files do not depend on the viewer, and a
    /// viewer that stopped reading is dropped 1 s after the run's end. An ADDR
    /// other than 127.0.0.1 or ::1 serves the run to the network (a warning).
    #[cfg_attr(feature = "clap", arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:8765"))]
    pub live: Option<std::net::SocketAddr>,
    /// With --live: simulated seconds per wall-clock second (1: real time; 0.1:
    /// ten times slower, to follow a bounce), in (0, 1000]. A `--realtime` run
    /// is paced by its own clock and takes only 1.
    #[cfg_attr(feature = "clap", arg(long, value_name = "RATE", default_value_t = 1.0, requires = "live"))]
    pub live_rate: f64,
    /// With --live: wait at most S seconds, in [0, 3600], for a viewer to
    /// subscribe before the run starts (then 0.5 s for its other
    /// subscriptions), so that it sees the run from its first period; 0: start
    /// at once. The run starts anyway when no viewer comes.
    #[cfg_attr(feature = "clap", arg(long, value_name = "S", default_value_t = 0.0, requires = "live"))]
    pub live_wait: f64,
    /// With --live: messages queued for each viewer, in [16, 1000000] (the Foxglove
    /// SDK's backlog): a viewer further behind loses the oldest messages of the
    /// tables and the arm, never the run's pace; raise it for a slow network.
    #[cfg_attr(feature = "clap", arg(long, value_name = "N", default_value_t = 1024, requires = "live"))]
    pub live_backlog: usize,
}

impl LiveArgs {
    /// The live view asked for: its address, rate, wait (s) and backlog (messages).
    ///
    /// # Errors
    /// A message when the rate is not in (0, 1000], the wait not in [0, 3600] or
    /// the backlog not in [16, 1000000].
    pub fn checked(&self) -> Result<Option<(std::net::SocketAddr, f64, f64, usize)>, String> {
        if !(16..=1_000_000).contains(&self.live_backlog) {
            return Err(format!("--live-backlog {}: expected messages per viewer in [16, 1000000]", self.live_backlog));
        }
        if !(self.live_rate > 0.0 && self.live_rate <= 1000.0) {
            return Err(format!("--live-rate {}: expected simulated seconds per second in (0, 1000]", self.live_rate));
        }
        if !(0.0..=3600.0).contains(&self.live_wait) {
            return Err(format!("--live-wait {}: expected seconds in [0, 3600]", self.live_wait));
        }
        Ok(self.live.map(|a| (a, self.live_rate, self.live_wait, self.live_backlog)))
    }
}

/// `--strict`, on every command that simulates.
#[derive(Debug, Clone, Copy)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct StrictArgs {
    /// Exit 1 if any result violates the model (an energy-creating impact, a
    /// friction-cone violation, an integrator failure); everything is still written
    /// and the violations are listed. Without it they are reported, and exit is 0.
    #[cfg_attr(feature = "clap", arg(long))]
    pub strict: bool,
}

/// The scenario of a run and its command-line overrides.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[cfg_attr(feature = "clap", derive(serde::Serialize, serde::Deserialize))]
pub struct ScenarioArgs {
    /// Scenario file (TOML, see scenarios/), `-` for standard input; default: the
    /// embedded default scenario (hybrid from x0d, mu 0.6, v_belt -0.4 m/s, f_n* 10 N,
    /// z_t* 0.10 m over 2 s, 10 s, 1 kHz).
    #[cfg_attr(feature = "clap", arg(long, value_name = "FILE.toml"))]
    pub scenario: Option<PathBuf>,
    /// Override the controller.
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice::option"))]
    pub controller: Option<firmware::ControllerKind>,
    /// Override the initial condition.
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice::option"))]
    pub x0: Option<plant::initial::PaperX0>,
    /// Override the tangential target z_t*, m.
    #[cfg_attr(feature = "clap", arg(long))]
    pub target_zt: Option<f64>,
    /// Override the run length, s.
    #[cfg_attr(feature = "clap", arg(long))]
    pub duration: Option<f64>,
    /// Override the sensor-noise seed.
    #[cfg_attr(feature = "clap", arg(long))]
    pub seed: Option<u64>,
    /// Override the impact-without-collision rule (scenario `plant.iwc`):
    /// `restitution` (the tip is thrown off the belt) or `plastic` (left stuck, v_n = 0).
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::choice::option"))]
    pub iwc: Option<plant::impact::IwcRule>,
    /// Change one scenario key, e.g. `--set plant.m=0.24 --set controller.pid.kp=[150,0]`
    /// (repeatable). KEY is the scenario file's dotted key path (docs/rig.md), VALUE a
    /// TOML value (a bare word such as `pid` is a string). Applied to the file before
    /// it is read, so a bad key or value is an error naming it (exit 2). A key also
    /// set by a flag here (`--x0` and `plant.x0`, ...) is refused.
    #[cfg_attr(feature = "clap", arg(long = "set", value_name = "KEY=VALUE", allow_hyphen_values = true))]
    #[cfg_attr(feature = "clap", serde(with = "super::values::text"))]
    pub set: Vec<rig::overrides::Override>,
}
