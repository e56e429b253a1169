//! The MCU image computes what the host library computes: in a PIL run of the
//! default scenario (the `pil` image in QEMU), every command the image sends is
//! compared with `Firmware::step` on the host for the same frame at the same
//! start time. This replaces the replay image's test (the replay image is gone:
//! the PIL image covers it with frames from a live plant). Needs `qemu-system-arm`.

use crate::common;

use firmware::{Firmware, board::FrozenClock};
use rig::{
    Exchange, FirmwareLink,
    pil_link::{PilLink, PilOptions},
    record::RunError,
    run_loop,
    scenario::Scenario,
    setup::firmware_config,
};
use shared::wire::{GroundTruth, SensorFrame, status};

/// One period: (seq, image codes, host codes, image status, host status).
type Pair = (u32, [i16; 2], [i16; 2], u32, u32);

/// A link that forwards to the image and steps the host library beside it.
struct Compare {
    image: PilLink,
    host: Firmware<firmware::PaperLaws>,
    pairs: Vec<Pair>,
}

impl FirmwareLink for Compare {
    fn transport(&self) -> &'static str {
        "compare"
    }
    fn exchange(&mut self, frame: &SensorFrame, truth: &GroundTruth) -> Result<Exchange, RunError> {
        let answer = self.image.exchange(frame, truth)?;
        // The image's step starts at the frame's sample time (no injected delay).
        let host = self.host.step(frame.sampled_at(), frame, &FrozenClock);
        if let Exchange::Answered { command, .. } = &answer {
            self.pairs.push((command.seq, [command.u1_code, command.u2_code], [host.u1_code, host.u2_code], command.status, host.status));
        }
        Ok(answer)
    }
    fn finish(&mut self, last_seq: u32) {
        self.image.finish(last_seq);
    }
}

#[test]
fn the_pil_image_sends_the_commands_of_the_host_library() {
    let mut s = Scenario::default_scenario();
    s.timing.duration_s = 2.5; // the move (2 s) and the hold after it
    let setup = rig::RunSetup::new(s.clone()).unwrap();
    let image = PilLink::start(&setup, &PilOptions::new(common::qemu_image("pil")), None).unwrap();
    let mut link = Compare { image, host: Firmware::new(firmware_config(&s)).unwrap(), pairs: Vec::new() };
    let (records, err) = run_loop(&setup, &mut link, &mut ());
    assert!(err.is_none(), "{err:?}");
    assert_eq!(link.pairs.len(), records.len());
    assert_eq!(link.pairs.len(), 2500);
    let mut identical = 0;
    for &(seq, img, host, img_status, host_status) in &link.pairs {
        // The deadline bit depends on each side's clock; everything else is the step's.
        let mask = !status::DEADLINE_MISS;
        assert_eq!(img_status & mask, host_status & mask, "seq {seq}: status");
        assert_eq!(img_status & status::SAFE_STATE, 0, "seq {seq}: never safe");
        // Same f32 code on both sides (shared trig); acos/atan2/sqrt come from the
        // platform's libm on the host and the `libm` crate on the image.
        let d = (img[0] - host[0]).abs().max((img[1] - host[1]).abs());
        assert!(d <= 4, "seq {seq}: image {img:?} vs host {host:?}");
        identical += usize::from(d == 0);
    }
    assert!(identical * 100 >= link.pairs.len() * 99, "{identical} of {} identical", link.pairs.len());
}
