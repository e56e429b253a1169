//! The board links and tools end to end, one test binary: the board twin in
//! closed loop (`twin`), the flashed image on the emulated board (`emulator`,
//! `emulator_faults`; `emulator_bound`: the control handler's worst case over
//! random scenarios and rates; `dma_faults`: the encoders' acquisition faults over random
//! sequences on both), bring-up over the protocol (`bringup`), and the wiring
//! faults and random scenarios the twin and the image share (`wiring_cases`),
//! the control rate set by configuration on both (`rate`), the reset button at
//! any instant on the flashed image (`reset`).

mod bringup;
mod dma_faults;
mod emulator;
mod emulator_bound;
mod emulator_faults;
mod envelope;
mod fmea;
mod press;
mod rate;
mod reset;
mod twin;
mod wiring_cases;

/// Sends `request` to the flashed image over its USART1 line and ticks the
/// emulated board until the image's reply frame ends (at most 50 ticks), as
/// `sil-host board` would: the image's answer, decoded.
fn ask(
    arm: &mut board_link::free_arm::FreeArm<board_emulator::EmulatedBoard>,
    request: arm_app::bringup::Request,
) -> arm_app::bringup::Reply {
    use firmware::pil::{MAX_FRAME, decode, encode};
    let mut buf = [0u8; MAX_FRAME];
    let frame = encode(&request, &mut buf).unwrap().to_vec();
    let mut got = arm.line(&frame);
    for _ in 0..50 {
        if let Some(end) = got.iter().position(|&b| b == 0) {
            return decode::<arm_app::bringup::Reply>(&mut got[..end]).unwrap();
        }
        arm.tick().unwrap();
        got.extend(arm.line(&[]));
    }
    panic!("no reply to {request:?}")
}
