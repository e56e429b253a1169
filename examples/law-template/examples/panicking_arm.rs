//! The `arm` image of a law that panics on purpose (issue 70: the firmware's
//! protection around a law's own failure): the impedance law until period 500,
//! then a panic in the control interrupt. On the MCU nothing unwinds: the panic
//! handler disables the motor drivers at once, logs the panic and traps; the
//! independent watchdog resets the MCU within 5 periods and the image comes back
//! with the drivers off until the enable button. `tests/e2e/law_template.rs`
//! runs it on the emulated board.
//!
//!     cargo build -p law-template --profile mcu --target thumbv7em-none-eabihf --example panicking_arm
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    println!("`panicking_arm` is a Cortex-M4F image: build it with --target thumbv7em-none-eabihf (its doc comment)");
}

#[cfg(target_os = "none")]
mod law {
    use firmware::{Config, ControlLaw, Declares, LawContext, LawInput, LawOutput, LawSpec, law::LawError};
    use law_template::Impedance;

    /// The impedance law until period 500, then a panic.
    #[derive(Debug, Clone, Copy, Default)]
    pub struct Panicking {
        law: Impedance,
        periods: u32,
    }

    impl ControlLaw for Panicking {
        const SPEC: LawSpec = LawSpec { name: "panicking", ..Impedance::SPEC };

        fn fresh(cfg: &Config) -> Self {
            Self { law: Impedance::fresh(cfg), periods: 0 }
        }

        fn declares(cfg: &Config) -> Declares {
            Impedance::declares(cfg)
        }

        fn step(&mut self, ctx: &LawContext<'_>, input: &LawInput) -> Result<LawOutput, LawError> {
            self.periods += 1;
            if self.periods > 500 {
                panic!("a law that panics on purpose");
            }
            self.law.step(ctx, input)
        }
    }
}

#[cfg(target_os = "none")]
board_stm32f405::arm_image!(law::Panicking);
