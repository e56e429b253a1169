//! A failure of the rig's iceoryx2 link, with what was being done.

use crate::services::{Incompatible, ServiceError};

/// A transport failure, with what was being done.
#[derive(Debug, thiserror::Error)]
pub enum IpcError {
    /// iceoryx2 failed.
    #[error("iceoryx2: {0}")]
    Transport(String),
    /// A service another process created lacks what this run needs (bad set-up,
    /// not a fault of the link: the message names the attribute and the value).
    #[error(transparent)]
    Incompatible(#[from] Incompatible),
}

impl From<ServiceError> for IpcError {
    fn from(e: ServiceError) -> Self {
        match e {
            ServiceError::Incompatible(i) => Self::Incompatible(i),
            ServiceError::Other(m) => Self::Transport(m),
        }
    }
}

pub(super) fn err(what: &str, e: impl std::fmt::Debug) -> IpcError {
    IpcError::Transport(format!("{what}: {e:?}"))
}
