//! The software-in-the-loop rig: scenarios, sensor models and faults, the
//! plant-side loop, and the transports that reach the firmware (in-process, or
//! iceoryx2 shared memory to the firmware in its own process, or the MCU image
//! over its USART, in QEMU or on a board behind a serial port: processor and
//! hardware in the loop).

pub mod faults;
pub mod firmware_process;
pub mod firmware_side;
pub mod in_process;
pub mod ipc;
pub mod ipc_link;
pub mod pil_link;
pub mod record;
pub mod rig;
pub mod scenario;
pub mod sensors;
pub mod setup;
pub mod summary;
