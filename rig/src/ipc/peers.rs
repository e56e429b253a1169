//! Each process's iceoryx2 node and what node monitoring says about its peer:
//! node names by role and rig, rig names, whether the peer runs, died or is
//! absent, and whether a rig is already in use in a role.

use iceoryx2::{node::NodeView, prelude::*};

use super::error::{IpcError, err};

/// Which end of the link a process is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// The plant (`sil-host run`).
    Plant,
    /// The firmware (`sil-host firmware`).
    Firmware,
}

impl Role {
    /// The node name of this role in rig `rig`.
    pub fn node_name(self, rig: &str) -> String {
        match self {
            Self::Plant => format!("painleve-plant-{rig}"),
            Self::Firmware => format!("painleve-firmware-{rig}"),
        }
    }
}

/// The default rig name of a plant process.
pub fn default_rig_name() -> String {
    format!("painleve-{}", std::process::id())
}

/// Checks a rig name: letters, digits, `-` and `_`, 1 to 40 characters.
///
/// # Errors
/// A message naming the bad name.
pub fn check_rig_name(rig: &str) -> Result<(), String> {
    let ok = !rig.is_empty() && rig.len() <= 40 && rig.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
    if ok { Ok(()) } else { Err(format!("rig name {rig:?}: use 1 to 40 letters, digits, '-' or '_'")) }
}

/// The rig reports its own errors; iceoryx2's warnings (no config file: defaults
/// used) are noise here.
fn quiet() {
    set_log_level(LogLevel::Error);
}

/// A process's iceoryx2 node, after removing the stale resources of dead nodes.
///
/// # Errors
/// [`IpcError`] when the node cannot be created.
pub fn node(role: Role, rig: &str) -> Result<Node<ipc::Service>, IpcError> {
    quiet();
    let name = NodeName::new(&role.node_name(rig)).map_err(|e| err("node name", e))?;
    let node = NodeBuilder::new()
        .name(&name)
        // The rig handles SIGINT/SIGTERM itself (it writes what it recorded).
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(|e| match foreign_iceoryx2_files() {
            // iceoryx2 keeps one folder per machine; another user's run made it,
            // and it only says "InternalError" (issue 52, 4).
            Some(why) => IpcError::Transport(format!("create node: {e:?}: {why}")),
            None => err("create node", e),
        })?;
    // A killed run leaves its node's resources behind: clean them so that they
    // never block this run's services.
    let _ = node.try_cleanup_dead_nodes();
    Ok(node)
}

/// Why this user cannot make iceoryx2 nodes, if another user's files are in the
/// way: iceoryx2's root folder (`/tmp/iceoryx2/`) and its subfolders are one
/// per machine, made by whoever ran first, so a second user's node fails.
fn foreign_iceoryx2_files() -> Option<String> {
    let root = std::path::PathBuf::from(String::from_utf8_lossy(Config::global_config().global.root_path().as_bytes()).into_owned());
    foreign_files_in(&root)
}

/// The message naming the first of `root` and its entries that is another
/// user's, if any.
fn foreign_files_in(root: &std::path::Path) -> Option<String> {
    use std::os::unix::fs::MetadataExt;
    let root = root.to_path_buf();
    let me = crate::private_files::euid();
    let mut places = vec![root.clone()];
    if let Ok(entries) = std::fs::read_dir(&root) {
        places.extend(entries.flatten().map(|e| e.path()));
    }
    places.into_iter().find_map(|p| {
        let m = std::fs::symlink_metadata(&p).ok()?;
        (m.uid() != me).then(|| {
            format!(
                "another user's iceoryx2 files are in the way: {} belongs to uid {} (you are uid {me}); iceoryx2 keeps one \
                 folder per machine, so run as that user, or remove {} when no rig runs",
                p.display(),
                m.uid(),
                root.display()
            )
        })
    })
}

/// What iceoryx2's node monitoring says about the peer of a rig.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PeerState {
    /// Its process runs.
    Alive,
    /// Its process died without cleaning up (killed).
    Dead,
    /// No node of that name (never started, or exited cleanly).
    Absent,
}

/// The process id of a live node `role` of rig `rig` other than this process's,
/// if there is one: the rig is then in use in that role (issue 15: one plant and
/// one firmware per rig). Two processes starting within the same instant can both
/// see it free; a rig name per run (the default) avoids that.
pub fn live_owner(role: Role, rig: &str) -> Option<i64> {
    quiet();
    let wanted = role.node_name(rig);
    let me = i64::from(std::process::id());
    let mut owner = None;
    let _ = Node::<ipc::Service>::list(Config::global_config(), |node| {
        if let NodeState::Alive(v) = &node
            && v.details().as_ref().is_some_and(|d| d.name().as_str() == wanted)
        {
            let pid = v.id().pid::<ipc::Service>().map_or(-1, |p| i64::from(p.value()));
            if pid != me {
                owner = Some(pid);
                return CallbackProgression::Stop;
            }
        }
        CallbackProgression::Continue
    });
    owner
}

/// The state of the node `role` of rig `rig`.
pub fn peer_state(role: Role, rig: &str) -> PeerState {
    quiet();
    let wanted = role.node_name(rig);
    let mut state = PeerState::Absent;
    let _ = Node::<ipc::Service>::list(Config::global_config(), |node| {
        let (details, found) = match &node {
            NodeState::Alive(v) => (v.details(), PeerState::Alive),
            NodeState::Dead(v) => (v.details(), PeerState::Dead),
            _ => return CallbackProgression::Continue,
        };
        if details.as_ref().is_some_and(|d| d.name().as_str() == wanted) {
            // An alive node of the name wins over a dead one of an earlier run.
            if found == PeerState::Alive || state == PeerState::Absent {
                state = found;
            }
        }
        CallbackProgression::Continue
    });
    state
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 52, 4: a second user's run failed with "create node: InternalError";
    /// another user's iceoryx2 folder is now named, with its owner.
    #[test]
    fn another_users_iceoryx2_files_are_named() {
        let root = tempfile::tempdir().unwrap();
        std::fs::create_dir(root.path().join("nodes")).unwrap();
        assert_eq!(foreign_files_in(root.path()), None, "all ours");
        if crate::private_files::euid() != 0 {
            eprintln!("skipped the other user's case: needs root to chown to nobody");
            return;
        }
        std::os::unix::fs::chown(root.path().join("nodes"), Some(65534), Some(65534)).unwrap();
        let why = foreign_files_in(root.path()).unwrap();
        assert!(why.contains("another user's iceoryx2 files") && why.contains("uid 65534") && why.contains("nodes"), "{why}");
    }
}
