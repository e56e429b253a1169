//! End-to-end tests live in `tests/tests/`; this crate has no library code (its
//! binary `sil-host-e2e` is the `sil-host` command line, for process-level tests).
