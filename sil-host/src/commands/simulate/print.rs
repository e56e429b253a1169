//! `sil-host simulate`'s human summary.

use std::io::Write;

use experiments::simulate::summary::Summary;

pub(crate) fn print_human(s: &Summary) {
    let n_events = s.events;
    let ic = &s.initial_condition;
    let mut o = crate::stdout::out();
    let _ = writeln!(
        o,
        "open-loop simulation, u = 0: mu = {}, v_belt = {} m/s, impact law {} (e_n = {}), impact without collision: {}",
        s.params.mu,
        s.params.v_belt,
        s.sim.impact_law.name(),
        s.sim.e_n,
        s.sim.iwc
    );
    let _ = writeln!(
        o,
        "initial condition {} = [{:.2} deg, {:.2} deg/s, {:.2} deg, {:.2} deg/s] (elbow {})",
        ic.name,
        ic.given_deg[0],
        ic.given_deg[1],
        ic.given_deg[2],
        ic.given_deg[3],
        ic.projection.branch.name()
    );
    if ic.projection.projected {
        let _ = writeln!(
            o,
            "  tip was {:.4} mm {} the belt: projected onto it at the same z_t = {:.5} m and elbow branch -> [{:.4} deg, {:.4} deg]",
            ic.projection.height_above_belt.abs() * 1e3,
            if ic.projection.height_above_belt < 0.0 { "inside" } else { "on" },
            ic.projection.tip_given[0],
            ic.used_deg[0],
            ic.used_deg[2]
        );
    }
    let _ = writeln!(
        o,
        "  initial mode: {}{}",
        ic.initial_mode,
        if ic.startup_events.is_empty() { String::new() } else { format!(" (after {} at t = 0)", ic.startup_events.join(", ")) }
    );
    let _ = writeln!(
        o,
        "simulated {:.3} s of {:.3} s in {:.3} s wall ({:.0}x real time)",
        s.simulated_s, s.duration_s, s.wall_s, s.realtime_factor
    );
    let c = &s.counters;
    let _ = writeln!(
        o,
        "events: {n_events} | lift-offs {} ({} at a bounce) | touchdowns {} | impacts without collision {} | stick phases {} | stick-to-slip {} | slip reversals {}",
        s.lift_offs, c.bounces, c.touchdowns, c.impacts_without_collision, c.stick_phases, c.stick_to_slip, c.slip_reversals,
    );
    let _ = writeln!(o, "validity: {}", s.validity);
    let _ = writeln!(o, "energy ledger: {}", s.ledger);
    if !s.validity.is_valid() {
        let _ = writeln!(o, "INVALID: {} (the trajectory violates the model)", s.validity.describe_violations());
    }
    let x = s.final_state;
    let _ = writeln!(
        o,
        "final: mode {}, theta1 = {:.3} deg, theta2 = {:.3} deg, tip = ({:.5}, {:.5}) m",
        s.final_mode,
        x[0].to_degrees(),
        x[2].to_degrees(),
        s.final_tip[0],
        s.final_tip[1]
    );
    if let Some(e) = &s.error {
        let _ = writeln!(o, "FAILED: {e}");
    }
    let _ = writeln!(o, "wrote {}", s.files.join(", "));
}
