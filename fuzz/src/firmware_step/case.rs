//! A case of the target: the configuration and a script of steps (each frame's
//! counts, flags, sequence and time moves, start and clock), resets and lost peers.

use super::knobs::Knobs;

/// Most operations in one case.
pub const MAX_OPS: usize = 48;

/// The counts of a frame.
#[derive(Debug, Clone)]
pub enum Counts {
    /// The arm near the belt: the tip moves by `dz_t * 10 um` along it, sits
    /// `dz_n * 20 um` above it, presses with `10 + f_n * 0.05` N; the belt at -0.4 m/s plus `belt / 8` mm/s
    /// (its changes within the belt check's 40 mm/s a period).
    Plausible {
        /// Tangential move, 10 um.
        dz_t: i8,
        /// Height above the belt, 20 um.
        dz_n: i8,
        /// Tangential force beyond `-mu f_n`, 20 mN.
        f_t: i8,
        /// Normal force beyond 10 N, 50 mN.
        f_n: i8,
        /// Belt speed beyond -0.4 m/s, mm/s.
        belt: i8,
    },
    /// Random counts within their ranges (encoders modulo `2^bits`).
    InRange {
        /// Base encoder.
        theta1: u16,
        /// Elbow encoder.
        elbow: u16,
        /// Load cell `f_t`.
        f_t: i16,
        /// Load cell `f_n`.
        f_n: i16,
        /// Belt speed, mm/s.
        belt: i16,
    },
    /// Arbitrary bits.
    Raw {
        /// Base encoder.
        theta1: u16,
        /// Elbow encoder.
        elbow: u16,
        /// Load cell `f_t`.
        f_t: i16,
        /// Load cell `f_n`.
        f_n: i16,
        /// Belt speed, mm/s.
        belt: i16,
    },
    /// Each field at an edge: indices into [`EDGE_U16`] and [`EDGE_I16`].
    Edge {
        /// Base encoder.
        theta1: u8,
        /// Elbow encoder.
        elbow: u8,
        /// Load cell `f_t`.
        f_t: u8,
        /// Load cell `f_n`.
        f_n: u8,
        /// Belt speed.
        belt: u8,
    },
}

/// Edge values of the encoder counts (the ends of the 10- to 16-bit ranges).
pub const EDGE_U16: [u16; 12] = [0, 1, 1023, 1024, 4095, 4096, 16383, 16384, 32767, 32768, 65534, 65535];
/// Edge values of the signed codes (load cell ends, belt limits, `i16` ends).
pub const EDGE_I16: [i16; 14] = [0, 1, -1, 2047, 2048, -2048, -2049, 5000, 5001, -5000, -5001, i16::MAX, i16::MIN, i16::MIN + 1];

/// How a frame's sequence number follows the previous frame's.
#[derive(Debug, Clone)]
pub enum SeqMove {
    /// `+1`.
    Next,
    /// The same again.
    Same,
    /// Back by this much (wrapping).
    Back(u32),
    /// Forward by this much (wrapping): a gap.
    Skip(u32),
    /// This number.
    Set(u32),
    /// `u32::MAX - n`.
    NearWrap(u8),
}

/// How a frame's `t_us` follows the previous frame's.
#[derive(Debug, Clone)]
pub enum TimeMove {
    /// `+Ts`.
    Period,
    /// Back by this much (saturating).
    Back(u64),
    /// Forward by this much (saturating).
    Forward(u64),
    /// This stamp.
    Set(u64),
    /// `u64::MAX - n`.
    NearMax(u16),
}

/// When the step starts (`now_us`), from the frame's `t_us`.
#[derive(Debug, Clone)]
pub enum Start {
    /// `t_us + d` (on time while `d < Ts`).
    Delay(u32),
    /// `t_us - e` (saturating): before the frame was sampled.
    Early(u64),
    /// Any time.
    At(u64),
    /// `u64::MAX - n`.
    NearMax(u16),
}

/// The step's own clock: reads `start`, then `start + elapsed` (wrapping), at `tps` ticks/s.
#[derive(Debug, Clone)]
pub struct Clock {
    /// First reading.
    pub start: u32,
    /// Ticks between the two readings.
    pub elapsed: u32,
    /// Ticks per second (0 included).
    pub tps: u32,
}

/// One operation of a case.
#[derive(Debug, Clone)]
pub enum Op {
    /// One step.
    Step {
        /// Counts.
        counts: Counts,
        /// Frame flags.
        flags: u16,
        /// Sequence number.
        seq: SeqMove,
        /// Stamp.
        t: TimeMove,
        /// Start of the step.
        start: Start,
        /// The step's clock.
        clock: Clock,
    },
    /// `Firmware::reset`.
    Reset,
    /// `Firmware::enter_safe_state(PeerLost)` and the safe command for `seq`.
    PeerLost {
        /// The sequence number answered.
        seq: u32,
        /// Its `now_us`.
        now_us: u64,
    },
}

/// One case.
#[derive(Debug, Clone)]
pub struct Case {
    /// The configuration.
    pub knobs: Knobs,
    /// Where the tip starts along the belt for plausible frames, as a fraction of 0.3 m.
    pub z_t0: f32,
    /// Elbow up for plausible frames.
    pub elbow_up: bool,
    /// Plausible frames read the load cell at full scale (the tip driven into
    /// the belt: the firmware's overload limit, `firmware::runaway`).
    pub pressed: bool,
    /// The first frame's sequence number.
    pub seq0: u32,
    /// The first frame's stamp `t_us`.
    pub t0: u64,
    /// The script.
    pub ops: Vec<Op>,
}
