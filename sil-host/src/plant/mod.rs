//! The plant simulator (stub; being written).

/// Errors of the plant simulator.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// Placeholder.
    #[error("bad input: {0}")]
    BadInput(String),
}

impl SimError {
    /// Whether the error comes from the caller's input (exit code 2).
    pub fn is_bad_input(&self) -> bool {
        matches!(self, Self::BadInput(_))
    }
}
