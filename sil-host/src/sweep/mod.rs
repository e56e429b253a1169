//! The files of a sweep ([`analyses::sweep`] computes it): its folder
//! ([`store`]: `sweep.json`, the `runs.csv` journal, resume and merge) and its
//! figures ([`figures`]: the `(v_belt, mu)` outcome maps and the per-`mu`
//! indicator slices).

pub mod figures;
pub use experiments::sweep::store;
