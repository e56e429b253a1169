//! What a debug probe and the host's serial line see of the emulated board
//! ([`EmulatedBoard`]): the image's monitor block read from RAM, the bytes on
//! USART1 both ways, defmt's RTT up-channel, and the stack's high-water mark.

use arm_app::monitor::{MONITOR_BYTES, MONITOR_MAGIC, Monitor};
use rsemu::core::{space::MemAttrs, value::Width};
use shared::wire::{ActuatorCommand, FirmwareTelemetry};

use super::EmulatedBoard;
use crate::{checks::peek, device::RegisterModel, usart1::Usart1};

impl EmulatedBoard {
    /// The image's monitor block after the last tick (`None` before its first),
    /// as the last run left it.
    pub fn monitor(&self) -> Option<Monitor> {
        self.monitor
    }

    /// Reads the monitor block from RAM, as a debug probe does.
    pub(super) fn read_monitor(&self) -> Option<Monitor> {
        let space = self.m.machine.space("mem")?;
        let mut b = [0u8; MONITOR_BYTES];
        for (i, chunk) in b.chunks_exact_mut(4).enumerate() {
            let w = space.read(u64::from(self.image.monitor) + 4 * i as u64, Width::U32, MemAttrs::DEBUG).ok()? as u32;
            chunk.copy_from_slice(&w.to_le_bytes());
        }
        let u32_at = |o: usize| u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]);
        let f32_at = |o: usize| f32::from_bits(u32_at(o));
        let i16_at = |o: usize| i16::from_le_bytes([b[o], b[o + 1]]);
        if u32_at(0) != MONITOR_MAGIC {
            return None;
        }
        Some(Monitor {
            magic: u32_at(0),
            version: u32_at(4),
            ticks: u32_at(8),
            drivers_enabled: u32_at(12),
            command: ActuatorCommand {
                t_sent_us: u64::from(u32_at(16)) | (u64::from(u32_at(20)) << 32),
                seq: u32_at(24),
                u1_code: i16_at(28),
                u2_code: i16_at(30),
                status: u32_at(32),
                step_ticks: u32_at(36),
                overruns: u32_at(40),
                reserved: u32_at(44),
            },
            telemetry: FirmwareTelemetry {
                seq: u32_at(48),
                status: u32_at(52),
                z_t_ref: f32_at(56),
                f_n_ref: f32_at(60),
                q: [f32_at(64), f32_at(68)],
                qd: [f32_at(72), f32_at(76)],
                f: [f32_at(80), f32_at(84)],
                u_raw: [f32_at(88), f32_at(92)],
            },
        })
    }

    /// Bytes to the image's USART1 (the host's side of the bring-up line).
    pub fn send(&self, bytes: &[u8]) {
        if let Some(w) = self.m.hub.window("usart1") {
            w.with(|m| {
                if let Some(u) = as_usart(m) {
                    u.rx.extend(bytes.iter().copied());
                    let _ = u.deliver();
                }
            });
        }
    }

    /// Bytes the image sent on USART1 since the last call.
    pub fn take_sent(&self) -> Vec<u8> {
        self.m
            .hub
            .window("usart1")
            .map(|w| w.with(|m| as_usart(m).map(|u| std::mem::take(&mut u.tx)).unwrap_or_default()))
            .unwrap_or_default()
    }

    /// The defmt frames the image wrote to RTT so far (probe-rs's view), taken.
    pub fn take_rtt(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.rtt)
    }

    /// Copies defmt's RTT up-channel 0 out of RAM and frees it, as probe-rs does.
    pub(super) fn drain_rtt(&mut self) {
        let Some(cb) = self.image.rtt else { return };
        let Some(space) = self.m.machine.space("mem") else { return };
        let rd32 = |a: u32| space.read(u64::from(a), Width::U32, MemAttrs::DEBUG).map(|v| v as u32).unwrap_or(0);
        // SEGGER RTT: a 16-byte id, two counts, then the up buffers (24 bytes each).
        let up = cb + 24;
        let (buf, size, wr, rd) = (rd32(up + 4), rd32(up + 8), rd32(up + 12), rd32(up + 16));
        if size == 0 || wr >= size || rd >= size {
            return;
        }
        let mut r = rd;
        while r != wr {
            self.rtt.push(space.read(u64::from(buf + r), Width::U8, MemAttrs::DEBUG).unwrap_or(0) as u8);
            r = (r + 1) % size;
        }
        let _ = space.write(u64::from(up + 16), Width::U32, u64::from(wr), MemAttrs::DEBUG);
    }

    /// The stack's high-water mark, bytes: from the stack's top down to the
    /// lowest word no longer holding the image's paint (`0xC0FFEE11`).
    pub fn stack_high_water_bytes(&self) -> u32 {
        const PAINT: u32 = 0xC0FF_EE11;
        let (low, top) = self.image.stack;
        let mut p = low;
        while p < top && peek(&self.m.machine, p) == PAINT {
            p += 4;
        }
        top - p
    }
}

fn as_usart(m: &mut dyn RegisterModel) -> Option<&mut Usart1> {
    (m as &mut dyn std::any::Any).downcast_mut()
}
