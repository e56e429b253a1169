use super::*;
use firmware::ControllerKind;

#[test]
fn bisection_finds_a_known_threshold_of_a_monotone_predicate() {
    let threshold = 0.123_456_7;
    let mut calls = Vec::new();
    let r = bisect_largest(-0.2, 0.2, 1e-4, |x| {
        calls.push(x);
        Ok::<bool, ()>(x <= threshold)
    })
    .unwrap();
    let Bisection::Found { lo, hi, evaluations } = r else { panic!("{r:?}") };
    assert!(lo <= threshold && threshold < hi, "[{lo}, {hi}]");
    assert!(hi - lo <= 1e-4 && hi - lo > 0.5e-4, "halved exactly to the tolerance: {}", hi - lo);
    assert_eq!(evaluations as usize, calls.len());
    assert_eq!(evaluations, max_evaluations(-0.2, 0.2, 1e-4));
    assert_eq!(r.limit(), Some(lo));
    // Threshold on a bisection point: that point is ok, so it is the limit.
    let r = bisect_largest(0.0, 1.0, 0.01, |x| Ok::<bool, ()>(x <= 0.5)).unwrap();
    assert!(matches!(r, Bisection::Found { lo, .. } if lo == 0.5), "{r:?}");
}

#[test]
fn bisection_reports_the_bracket_ends_and_errors() {
    let r = bisect_largest(0.0, 1.0, 0.01, |x| Ok::<bool, ()>(x < -1.0)).unwrap();
    assert_eq!(r, Bisection::LowerFails { lo: 0.0, evaluations: 1 });
    assert_eq!(r.limit(), None);
    let r = bisect_largest(0.0, 1.0, 0.01, |_| Ok::<bool, ()>(true)).unwrap();
    assert_eq!(r, Bisection::UpperReached { hi: 1.0, evaluations: 2 });
    assert_eq!(r.limit(), Some(1.0));
    let e = bisect_largest(0.0, 1.0, 0.01, |x| if x > 0.7 { Err("boom") } else { Ok(true) }).unwrap_err();
    assert_eq!(e, "boom");
}

/// A coarse search on two cases: the trial just below the limit has no lift-off
/// and settles, the one just above lifts off; the ideal hybrid's limit is where
/// `p` vanishes on the belt (paper Table II's end for the elbow-down branch).
#[test]
fn coarse_search_brackets_the_first_lift_off() {
    let base = Scenario::default_scenario();
    let c =
        Criteria { duration_s: 3.0, move_time_s: 2.0, reach_tol_m: 5e-3, settle_tol_m: 1e-3, settle_window_s: 0.5, lift_off_gap_m: 0.0 };
    let tol = 4e-3;
    for setting in [Setting::Ideal, Setting::Sampled] {
        let combo = Combination { controller: ControllerKind::Hybrid, x0: PaperX0::D, setting };
        let bracket = default_bracket(&base, PaperX0::D).unwrap();
        let s = search(&base, combo, bracket, tol, &c, |_| {}).unwrap();
        let Bisection::Found { lo, hi, .. } = s.bisection else { panic!("{:?}", s.bisection) };
        assert!(hi - lo <= tol);
        let (below, _) = trial(&base, combo, lo, &c).unwrap();
        assert!(below.tracked && below.lift_offs == 0 && below.impacts_without_collision == 0, "{below:?}");
        assert_eq!(below.stop, StopReason::Tracked);
        assert!(below.settle_error_m <= 1e-3);
        let (above, _) = trial(&base, combo, hi, &c).unwrap();
        assert!(!above.slides_to_target && above.first_lift_off_s.is_some(), "{above:?}");
        assert_eq!(above.stop, StopReason::LiftOff);
        // The hybrid law tracks every target it slides to: both limits agree.
        assert_eq!(s.z_t_tracking, s.z_t_sliding, "{:?}", s.tracking);
        assert!(!s.limit_trace.is_empty() && s.limit_trace.iter().all(|r| r.mode != "flight"));
        if setting == Setting::Ideal {
            // Where p = 0 on the elbow-down belt with z_r_dot > 0 (`sil-host admissible`).
            let params = shared::Params::<f64>::paper();
            let arm = shared::Arm::new(params);
            let p = |z| crate::admissible::p_on_belt(&arm, z, shared::ElbowBranch::Down, shared::SlipDirection::Positive);
            let end = crate::admissible::positive_intervals(p, bracket.0, bracket.1, 10_000, 1e-10)[0].hi;
            assert!(lo <= end && end < hi + 3e-4, "[{lo}, {hi}] vs p = 0 at {end}");
        }
    }
}

/// The PID from `x0d` never lifts off, but its steady error grows with the target:
/// `Z_t,sliding` (slides to within 5 mm) lies above the tracking limit (within
/// 1 mm), each bound by a trial that says why (not reached, not settled), and the
/// tracking bisection reuses the first one's trials.
#[test]
fn the_pid_s_lift_off_limit_and_tracking_limit_are_apart() {
    let base = Scenario::default_scenario();
    let c =
        Criteria { duration_s: 6.0, move_time_s: 2.0, reach_tol_m: 5e-3, settle_tol_m: 1e-3, settle_window_s: 1.0, lift_off_gap_m: 0.0 };
    let combo = Combination { controller: ControllerKind::Pid, x0: PaperX0::D, setting: Setting::Ideal };
    let bracket = default_bracket(&base, PaperX0::D).unwrap();
    let tol = 4e-3;
    let s = search(&base, combo, bracket, tol, &c, |_| {}).unwrap();
    let (Some(sliding), Some(tracking)) = (s.z_t_sliding, s.z_t_tracking) else { panic!("{s:?}") };
    assert!(tracking + tol < sliding, "tracking {tracking} vs Z_t,sliding {sliding}");
    assert!(s.trials.iter().all(|t| t.lift_offs == 0 && t.impacts_without_collision == 0), "the PID from x0d never lifts off");
    let above_sliding = s.failing_trial(&s.bisection).unwrap();
    assert_eq!(above_sliding.stop, StopReason::NotReached, "{above_sliding:?}");
    assert!(above_sliding.settle_error_m > 5e-3);
    let above_tracking = s.failing_trial(&s.tracking).unwrap();
    assert_eq!(above_tracking.stop, StopReason::NotSettled, "{above_tracking:?}");
    assert!(above_tracking.why_not().unwrap().starts_with("not settled"));
    assert!(s.trial_at(tracking).unwrap().tracked && s.trial_at(sliding).unwrap().slides_to_target);
    // Each target once; at most the two bisections' evaluations.
    let mut targets: Vec<f64> = s.trials.iter().map(|t| t.target_z_t).collect();
    targets.sort_by(f64::total_cmp);
    targets.dedup();
    assert_eq!(targets.len(), s.trials.len());
    assert!(s.trials.len() as u32 <= max_trials(bracket.0, bracket.1, tol));
}
