//! The images' bodies, generic over the control law (issue 70): an image's
//! binary is its entry point and its law ([`crate::pil_image!`],
//! [`crate::arm_image!`]), so a law of one's own gets the same images as the
//! paper's laws from its own crate (`examples/law-template/`).

pub mod arm;
pub mod pil;

/// Re-exported for the image macros: the entry point's and the interrupts'
/// attributes, and the firmware.
pub use cortex_m_rt::entry;
pub use firmware;
pub use stm32f4::stm32f405::interrupt;

/// The PIL image of control law `$law` (a `firmware::ControlLaw`): the law's
/// declaration as the symbol `PAINLEVE_LAW_SPEC` (`firmware::law_spec_symbol!`,
/// which the host reads from the ELF to bind a scenario's `[law]` table) and
/// the entry point, which runs [`pil::run`]. Use it at the top level of a
/// binary built for `thumbv7em-none-eabihf`.
#[macro_export]
macro_rules! pil_image {
    ($law:ty) => {
        $crate::images::firmware::law_spec_symbol!($law);

        #[$crate::images::entry]
        fn main() -> ! {
            // Referenced, so the linker keeps the declaration for the host.
            core::hint::black_box(&PAINLEVE_LAW_SPEC);
            $crate::images::pil::run::<$law>()
        }
    };
}

/// The arm image of control law `$law` (a `firmware::ControlLaw`): the law's
/// declaration as the symbol `PAINLEVE_LAW_SPEC`, the application's statics
/// (`ARM`, `APP`: [`arm::AppCell`], [`arm::AppSlot`]), the four interrupt
/// handlers (TIM2, DMA2 stream 0, USART1 and the control step on CAN2_TX's
/// vector) and the entry point, which runs [`arm::run`]. Use it at the top
/// level of a binary built for `thumbv7em-none-eabihf`; `$law` by a path that
/// resolves there (`firmware::PaperLaws`, `my_crate::MyLaw`).
#[macro_export]
macro_rules! arm_image {
    ($law:ty) => {
        $crate::images::firmware::law_spec_symbol!($law);

        use $crate::images::interrupt;

        static ARM: $crate::images::arm::AppCell<$law> = $crate::images::arm::app_cell();
        #[unsafe(link_section = ".uninit.APP")]
        static mut APP: $crate::images::arm::AppSlot<$law> = $crate::images::arm::AppSlot::uninit();

        #[interrupt]
        fn TIM2() {
            $crate::images::arm::on_tim2();
        }

        #[interrupt]
        fn DMA2_STREAM0() {
            $crate::images::arm::on_dma2_stream0();
        }

        #[interrupt]
        fn USART1() {
            $crate::images::arm::on_usart1();
        }

        /// The control step (`acquisition::CONTROL_INTERRUPT`).
        #[interrupt]
        fn CAN2_TX() {
            // SAFETY: this is the control interrupt.
            unsafe { $crate::images::arm::on_control(&ARM) };
        }

        #[$crate::images::entry]
        fn main() -> ! {
            // Referenced, so the linker keeps the declaration for the host.
            core::hint::black_box(&PAINLEVE_LAW_SPEC);
            // SAFETY: once, from the entry point, with the image's statics.
            unsafe { $crate::images::arm::run::<$law>(&ARM, &raw mut APP) }
        }
    };
}
