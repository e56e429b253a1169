//! What a page says it shows: its title, the run's facts (scenario, link,
//! controller, parameters) and the arm's dimensions the view is drawn with.

use rig::scenario::Scenario;
use shared::Params;

/// The description of the run a page shows.
#[derive(Debug, Clone, PartialEq)]
pub struct PageInfo {
    /// The page's title (`SIL run default: hybrid from x0d`).
    pub title: String,
    /// The run's facts as `(name, value with its unit)`, shown under the title in this order.
    pub facts: Vec<(String, String)>,
    /// Length of each link `l`, m.
    pub l: f64,
    /// Height of the base above the belt `H`, m.
    pub h: f64,
    /// Belt speed `v_belt`, m/s (the stripes move at it).
    pub v_belt: f64,
    /// Whether the run is closed loop (a reference `z_t*` and torques to show).
    pub closed_loop: bool,
}

impl PageInfo {
    /// The page of a closed-loop run of `scenario` over `link` (the link's
    /// transport: `in-process`, `iceoryx2`, `twin`, `emulator`, `pil-qemu`,
    /// `pil-serial`): a PIL run over `pil-qemu`, HIL over `pil-serial`, SIL otherwise.
    pub fn closed_loop(scenario: &Scenario, link: &str) -> Self {
        let what = match link {
            "pil-qemu" => "PIL",
            "pil-serial" => "HIL",
            _ => "SIL",
        };
        let p = scenario.plant.params();
        let c = &scenario.controller;
        let references = format!("zₜ* = {} m over {} s, fₙ* = {} N", c.target_z_t, c.move_time_s, c.f_n_ref);
        // A law of one's own is named by the scenario's `[law]` table (a run is refused
        // without it): its name and the parameters the table sets, the rest at the
        // law's declared defaults (summary.json's `firmware_announcement` has them all).
        let (name, controller) = match &scenario.law {
            Some(law) => (law.name.clone(), format!("law `{}` ({}; {references})", law.name, law.params_in_words())),
            None => (c.kind.to_string(), format!("{} ({references})", c.kind)),
        };
        let mut facts = vec![
            ("scenario".to_string(), scenario.name.clone()),
            ("link".to_string(), link.to_string()),
            ("controller".to_string(), controller),
            ("initial condition".to_string(), format!("x0{}", scenario.plant.x0)),
            ("control rate".to_string(), format!("{} Hz", scenario.timing.rate_hz)),
        ];
        facts.extend(plant_facts(&p, &format!("{:?}", scenario.plant.impact_law).to_lowercase(), scenario.plant.e_n));
        Self {
            title: format!("{what} run {}: {name} from x0{}", scenario.name, scenario.plant.x0),
            facts,
            l: p.l,
            h: p.h,
            v_belt: p.v_belt,
            closed_loop: true,
        }
    }

    /// The page of an open-loop simulation (`u = 0`) of the arm `p` from the
    /// initial condition named `x0` with impact law `impact_law` and restitution `e_n`.
    pub fn open_loop(p: &Params<f64>, x0: &str, impact_law: &str, e_n: f64) -> Self {
        let mut facts = vec![
            ("command".to_string(), "simulate (open loop, u = 0)".to_string()),
            ("link".to_string(), "none (the plant alone)".to_string()),
            ("controller".to_string(), "none".to_string()),
            ("initial condition".to_string(), x0.to_string()),
        ];
        facts.extend(plant_facts(p, impact_law, e_n));
        Self { title: format!("open-loop simulation from {x0}"), facts, l: p.l, h: p.h, v_belt: p.v_belt, closed_loop: false }
    }
}

/// The plant's facts every page states.
fn plant_facts(p: &Params<f64>, impact_law: &str, e_n: f64) -> Vec<(String, String)> {
    vec![
        ("μ".to_string(), format!("{}", p.mu)),
        ("belt speed".to_string(), format!("{} m/s", p.v_belt)),
        ("links".to_string(), format!("l = {} m, base H = {} m above the belt", p.l, p.h)),
        ("impacts".to_string(), format!("{impact_law}, eₙ = {e_n}")),
    ]
}

#[cfg(test)]
mod tests {
    use super::PageInfo;
    use rig::{law::LawTable, scenario::Scenario};

    fn controller_fact(info: &PageInfo) -> &str {
        &info.facts.iter().find(|(k, _)| k == "controller").unwrap().1
    }

    /// A law of one's own is named in the title and the facts, with the parameters
    /// its `[law]` table sets, on every link (issue 84: the page said `hybrid`).
    #[test]
    fn a_law_of_ones_own_is_named_with_its_parameters_on_every_link() {
        let mut s = Scenario::default_scenario();
        s.law = Some(LawTable { name: "impedance".into(), params: [("k_t".to_string(), 2500.0), ("d_n".to_string(), 50.0)].into() });
        for link in ["in-process", "iceoryx2", "twin", "emulator", "pil-qemu", "pil-serial"] {
            let info = PageInfo::closed_loop(&s, link);
            assert!(info.title.ends_with(&format!("run {}: impedance from x0d", s.name)), "{link}: {}", info.title);
            let fact = controller_fact(&info);
            assert!(fact.starts_with("law `impedance` (d_n = 50, k_t = 2500, the rest at their defaults; zₜ* = "), "{link}: {fact}");
        }
        s.law = Some(LawTable { name: "pd".into(), params: Default::default() });
        let info = PageInfo::closed_loop(&s, "in-process");
        assert_eq!(info.title, format!("SIL run {}: pd from x0d", s.name));
        assert!(controller_fact(&info).starts_with("law `pd` (every parameter at its default; "), "{}", controller_fact(&info));
    }

    /// The paper's laws keep their title and facts (the golden pages).
    #[test]
    fn the_papers_laws_are_named_by_their_kind() {
        let s = Scenario::default_scenario();
        let info = PageInfo::closed_loop(&s, "pil-qemu");
        assert_eq!(info.title, format!("PIL run {}: hybrid from x0d", s.name));
        assert!(controller_fact(&info).starts_with("hybrid (zₜ* = "), "{}", controller_fact(&info));
    }
}
