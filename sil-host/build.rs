//! Stamps the build with its commit: `SIL_HOST_COMMIT` is `git describe --always
//! --dirty` of the source tree when it was built (`sil-host --version`, the
//! report's stamp), or `unknown` when the source is not a git checkout (an
//! unpacked source archive) or git is missing; and with its optional features,
//! `SIL_HOST_FEATURES` (`board, live, formats, pdf`, or `none`).

use std::{path::Path, process::Command};

fn git(args: &[&str]) -> Option<String> {
    let o = Command::new("git").args(args).output().ok().filter(|o| o.status.success())?;
    Some(String::from_utf8_lossy(&o.stdout).trim().to_string()).filter(|s| !s.is_empty())
}

fn watch(path: &Path) {
    if path.exists() {
        println!("cargo:rerun-if-changed={}", path.display());
    }
}

fn main() {
    let commit = git(&["describe", "--always", "--dirty"]).unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=SIL_HOST_COMMIT={commit}");
    // The optional features built (Cargo.toml `[features]`), for `--version`.
    let built: Vec<&str> = ["board", "live", "formats", "pdf"]
        .into_iter()
        .filter(|f| std::env::var_os(format!("CARGO_FEATURE_{}", f.to_uppercase())).is_some())
        .collect();
    println!("cargo:rustc-env=SIL_HOST_FEATURES={}", if built.is_empty() { "none".to_string() } else { built.join(", ") });
    println!("cargo:rerun-if-changed=build.rs");
    // A build whose git failed (not on PATH, a lock held by another git) said
    // `unknown`: it is built again when PATH changes or the checkout's own files
    // move, found from the manifest's folder, so the stamp never stays stale. Only
    // then: a build that found git is not built again for another PATH (a cargo run
    // from a Python script under pyenv, whose shim puts its own folder first, rebuilt
    // sil-host and every test binary: 200 s of CPU in scripts/test.sh, 2026-11-29).
    if commit == "unknown" {
        println!("cargo:rerun-if-env-changed=PATH");
    }
    if let Ok(manifest) = std::env::var("CARGO_MANIFEST_DIR") {
        let dot_git = Path::new(&manifest).join("../.git");
        for file in ["HEAD", "index", "packed-refs", "refs/heads/main"] {
            watch(&dot_git.join(file));
        }
    }
    // Built again when the commit moves or the index changes (a commit, a checkout,
    // staged edits): a worktree's HEAD and index are its own, the refs are the
    // common folder's (the branch's ref, which a commit moves, and packed-refs).
    if let Some(dir) = git(&["rev-parse", "--git-dir"]) {
        watch(&Path::new(&dir).join("HEAD"));
        watch(&Path::new(&dir).join("index"));
    }
    // And when a tracked file is edited in the working tree (`-dirty` appears or goes
    // without the index moving, issue 68): every tracked file but the prose (`*.md`,
    // `docs/`), whose edits change no output of the build, and `Cargo.lock`, cargo's own
    // (a lock that moves a dependency rebuilds through it; scripts/new_law_test.py adds
    // a law crate and restores the lock, which rebuilt sil-host and every test binary).
    // Paths are the checkout's, from its top level.
    if let Some(top) = git(&["rev-parse", "--show-toplevel"])
        && let Some(files) = git(&["-C", &top, "ls-files"])
    {
        for file in files.lines().filter(|f| !f.ends_with(".md") && !f.starts_with("docs/") && *f != "Cargo.lock") {
            watch(&Path::new(&top).join(file));
        }
    }
    if let Some(common) = git(&["rev-parse", "--git-common-dir"]) {
        watch(&Path::new(&common).join("packed-refs"));
        if let Some(branch) = git(&["symbolic-ref", "-q", "HEAD"]) {
            watch(&Path::new(&common).join(branch));
        }
    }
}
