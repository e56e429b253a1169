//! What an experiment computed and wrote ([`Done`]): its typed result, its
//! files, and why it stopped early; `--strict` on top.

/// What a command computed and wrote: its typed result, the files it wrote, and
/// why it stopped early when it did (everything up to then is written). Each
/// command's `execute` returns one, its `run` prints it; `sil-host report` calls
/// the `execute`s directly.
#[derive(Debug)]
pub struct Done<T> {
    /// The command's result (its JSON document's type, or the analysis result).
    pub result: T,
    /// The files written, in the order the command lists them.
    pub files: Vec<std::path::PathBuf>,
    /// Why the command stopped early or part of it failed; `None` when it finished.
    pub failure: Option<crate::error::Error>,
}

impl<T> Done<T> {
    /// A finished command.
    pub fn ok(result: T, files: Vec<std::path::PathBuf>) -> Self {
        Self { result, files, failure: None }
    }

    /// With `strict`, a command that finished but whose results have violations
    /// (`validity`, summed over its runs) fails with [`crate::error::Error::Invalid`]
    /// (exit 1); an earlier failure is kept.
    pub fn strict(mut self, strict: bool, validity: &plant::Validity) -> Self {
        if strict && self.failure.is_none() && !validity.is_valid() {
            self.failure = Some(crate::error::Error::Invalid(validity.describe_violations()));
        }
        self
    }

    /// The command's outcome: `Err` with the failure, if any.
    ///
    /// # Errors
    /// The failure.
    pub fn into_result(self) -> Result<(), crate::error::Error> {
        self.failure.map_or(Ok(()), Err)
    }
}

#[cfg(test)]
mod strict_tests {
    use super::Done;

    /// `--strict` turns a violation into exit 1, keeps an earlier failure, and
    /// leaves clean results and non-strict runs alone.
    #[test]
    fn strict_fails_only_on_violations() {
        let cone = plant::Validity { cone_violations: 2, ..plant::Validity::default() };
        let rules = plant::Validity { zeno_stops: 5, newton_fallbacks: 1, ..plant::Validity::default() };
        let e = Done::ok((), vec![]).strict(true, &cone).into_result().unwrap_err();
        assert_eq!(e.exit_code(), 1);
        assert!(e.to_string().contains("2 friction-cone violations"), "{e}");
        assert!(Done::ok((), vec![]).strict(false, &cone).into_result().is_ok());
        assert!(Done::ok((), vec![]).strict(true, &rules).into_result().is_ok(), "fallbacks and Zeno stops are not violations");
        let earlier = Done { result: (), files: vec![], failure: Some(crate::error::Error::bad_input("x")) };
        assert_eq!(earlier.strict(true, &cone).into_result().unwrap_err().exit_code(), 2);
    }
}
