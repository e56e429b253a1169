//! The run's events as the page marks them (issue 69): every plant event
//! (touchdown, impact without collision, lift-off, singular point, ...) and the
//! firmware's entry into its safe state, at its exact time, with the contact
//! impulse of an impact. They are instants, so they fall between the frames and
//! the plots' samples; the page draws them on their own: ticks on every plot's
//! time axis, the normal impulses as stems on the force plot, a flash of the
//! contact in the frame after an impact, the events since the previous frame in
//! the readout, and a list (one `li` per event, `data-kind`, `data-t`) that a
//! click moves the cursor to.

use serde_json::{Value, json};

/// At most this many events are kept (the first ones): a page of a long
/// chattering run stays small; the page says how many were left out.
pub const MAX_EVENTS: usize = 20_000;

/// The name of the firmware's safe-state entry among the page's event kinds.
pub const SAFE_STATE: &str = "safe_state";

/// One event as the page takes it.
#[derive(Debug, Clone, PartialEq)]
pub struct PageEvent {
    /// Time, s.
    pub t: f64,
    /// Its kind, as `events.csv` names it (`touchdown`, `lift_off`,
    /// `impact_without_collision`, ...; [`SAFE_STATE`] for the firmware's).
    pub kind: &'static str,
    /// The contact impulse `[P_t, P_n]` of an impact, N s (zero otherwise).
    pub impulse: [f64; 2],
}

impl From<&plant::PlantEvent> for PageEvent {
    fn from(e: &plant::PlantEvent) -> Self {
        Self { t: e.t, kind: e.kind.name(), impulse: e.impulse }
    }
}

/// The events gathered for a page, in time order, at most [`MAX_EVENTS`].
#[derive(Debug, Clone, Default)]
pub struct Events {
    kept: Vec<PageEvent>,
    left_out: u64,
}

impl Events {
    /// Adds the next event (in time order).
    pub fn push(&mut self, e: PageEvent) {
        if self.kept.len() < MAX_EVENTS {
            self.kept.push(e);
        } else {
            self.left_out += 1;
        }
    }

    /// How many events the run had (kept and left out).
    pub fn count(&self) -> u64 {
        self.kept.len() as u64 + self.left_out
    }

    /// The page's JSON: `{t: [s], kind: [index into kinds], kinds: [names],
    /// p_t: [N s], p_n: [N s], left_out}` (times as f64: two events a
    /// microsecond apart at 100 s stay apart).
    pub fn json(&self) -> Value {
        let mut kinds: Vec<&'static str> = Vec::new();
        let kind: Vec<usize> = self
            .kept
            .iter()
            .map(|e| {
                kinds.iter().position(|k| *k == e.kind).unwrap_or_else(|| {
                    kinds.push(e.kind);
                    kinds.len() - 1
                })
            })
            .collect();
        json!({
            "t": self.kept.iter().map(|e| e.t).collect::<Vec<_>>(),
            "kind": kind,
            "kinds": kinds,
            "p_t": self.kept.iter().map(|e| e.impulse[0] as f32).collect::<Vec<_>>(),
            "p_n": self.kept.iter().map(|e| e.impulse[1] as f32).collect::<Vec<_>>(),
            "left_out": self.left_out,
        })
    }

    /// What the page says about its events.
    pub fn note(&self) -> String {
        let mut counts: Vec<(&str, u64)> = Vec::new();
        for e in &self.kept {
            match counts.iter_mut().find(|(k, _)| *k == e.kind) {
                Some((_, n)) => *n += 1,
                None => counts.push((e.kind, 1)),
            }
        }
        let listed = counts.iter().map(|(k, n)| format!("{n} {k}")).collect::<Vec<_>>().join(", ");
        let base = "Events: each at its exact time, between the frames and the plots' samples: a tick on every plot's \
                    time axis, the normal impulse Pₙ of an impact as a stem on the force plot (its own axis, in N s on \
                    the right), a ring around the tip in the frame after an impact, the events since the previous frame in \
                    the readout, and the list under the plots (a click moves the cursor there).";
        match (self.kept.len(), self.left_out) {
            (0, _) => format!("{base} This run has none."),
            (_, 0) => format!("{base} This run has {} ({listed}).", self.kept.len()),
            (n, left) => {
                format!("{base} The first {n} are shown ({listed}); {left} later ones are left out (the events table has them all).")
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_are_kept_in_order_up_to_the_cap_and_the_rest_counted() {
        let mut ev = Events::default();
        for k in 0..MAX_EVENTS + 3 {
            ev.push(PageEvent { t: k as f64, kind: if k % 2 == 0 { "touchdown" } else { "lift_off" }, impulse: [0.0, k as f64] });
        }
        assert_eq!(ev.count(), (MAX_EVENTS + 3) as u64);
        let j = ev.json();
        assert_eq!(j["t"].as_array().unwrap().len(), MAX_EVENTS);
        assert_eq!(j["left_out"], 3);
        assert_eq!(j["kinds"], json!(["touchdown", "lift_off"]));
        assert_eq!(j["kind"][0], 0);
        assert_eq!(j["kind"][1], 1);
        assert!(ev.note().contains("3 later ones are left out"), "{}", ev.note());
        assert!(ev.note().contains("10000 touchdown, 10000 lift_off"), "{}", ev.note());
    }

    #[test]
    fn a_run_without_events_says_so() {
        assert!(Events::default().note().ends_with("This run has none."));
    }
}
