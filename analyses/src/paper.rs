//! What the paper prints, for side-by-side tables: Marchese, Coraggio, Hogan,
//! di Bernardo (ECC 2019), as restated in docs/model.md "What the paper reports"
//! (the specification's MODEL.md). These numbers are never used to tune the model;
//! `sil-host report` and docs/results.md put ours next to them and say why they
//! differ.

use firmware::ControllerKind;
use plant::initial::PaperX0;

/// `mu` of Table II.
pub const TABLE_II_MU: f64 = 0.6;

/// Table II, experiment 2: the `z_t` range (m) on the belt with `p > 0`, elbow up,
/// `[from, to)`, at `mu = 0.6` with `z_r_dot > 0`.
pub const TABLE_II_ELBOW_UP_M: [f64; 2] = [-0.184, 0.183];

/// Table II: the same range, elbow down.
pub const TABLE_II_ELBOW_DOWN_M: [f64; 2] = [-0.184, 0.168];

/// Fig. 3, experiment 3: the critical `mu` (bouncing only for `mu >= mu_c`, on the
/// paper's grid of `mu` in steps of 0.1), for every `v_belt`.
pub const CRITICAL_MU: f64 = 0.4;

/// Fig. 3: persistent bouncing at `mu = 0.6` from `x0a` for `v_belt` in this
/// range, m/s.
pub const BOUNCING_X0A_MU06_M_S: [f64; 2] = [-0.575, -0.3];

/// Fig. 3: whether the open loop from `x0d` bounces anywhere (it does not).
pub const X0D_BOUNCES: bool = false;

/// Experiments 5 and 6: `Z_t,sliding`, m, as printed. `Some(None)`: the paper found
/// no gains that avoid lift-off (the PID from `x0u`); `None`: the paper prints no value.
pub fn z_t_sliding(controller: ControllerKind, x0: PaperX0) -> Option<Option<f64>> {
    match (controller, x0) {
        (ControllerKind::Pid, PaperX0::D) => Some(Some(0.0375)),
        (ControllerKind::Pid, PaperX0::U) => Some(None),
        (ControllerKind::Hybrid, PaperX0::D) => Some(Some(0.148)),
        (ControllerKind::Hybrid, PaperX0::U) => Some(Some(0.163)),
        _ => None,
    }
}

/// Fig. 9, experiment 7: whether the hybrid closed loop bounces persistently at any
/// `v_belt` in `[-1, -0.1]` m/s (it does not).
pub const CLOSED_LOOP_BOUNCES: bool = false;

/// The paper's definition of `Z_t,sliding`, quoted.
pub const Z_T_SLIDING_DEFINITION: &str = "the largest value of z_t such that no lift-off occurs";

/// In words, for summaries: the paper's `Z_t,sliding` per case.
pub const Z_T_SLIDING_SUMMARY: &str = "the paper (docs/model.md \"What the paper reports\"): Z_t,sliding = 0.0375 m for the PID from x0d (no gains found that avoid lift-off from x0u), 0.148 m for the hybrid law from x0d and 0.163 m from x0u; it does not say how long a run lasts or how closely the target must be reached";

#[cfg(test)]
mod tests {
    use super::*;

    /// The numbers here are docs/model.md's "What the paper reports", printed as the
    /// paper prints them: the two stay in step.
    #[test]
    fn every_number_is_the_one_docs_model_md_restates() {
        let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/model.md")).unwrap();
        let section = doc.split("## What the paper reports").nth(1).expect("docs/model.md has the section");
        let mut numbers = vec![
            TABLE_II_MU,
            TABLE_II_ELBOW_UP_M[0],
            TABLE_II_ELBOW_UP_M[1],
            TABLE_II_ELBOW_DOWN_M[0],
            TABLE_II_ELBOW_DOWN_M[1],
            CRITICAL_MU,
            BOUNCING_X0A_MU06_M_S[0],
            BOUNCING_X0A_MU06_M_S[1],
        ];
        for controller in [ControllerKind::Pid, ControllerKind::Hybrid] {
            for x0 in [PaperX0::D, PaperX0::U] {
                let v = z_t_sliding(controller, x0).unwrap_or_else(|| panic!("{controller:?} {x0:?} has a printed value"));
                numbers.extend(v);
            }
        }
        for x in numbers {
            assert!(section.contains(&format!("{x}")), "{x} is not in docs/model.md's section");
        }
        assert_eq!(z_t_sliding(ControllerKind::Pid, PaperX0::U), Some(None));
        assert!(section.contains("no gains were found that avoid lift-off"));
        let prose = section.replace('`', "").split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(prose.contains(Z_T_SLIDING_DEFINITION), "the quoted definition");
        assert_eq!(section.contains("from `x0d` none"), !X0D_BOUNCES);
        assert!(section.contains("no persistent bouncing for any `v_belt`") != CLOSED_LOOP_BOUNCES);
    }
}
