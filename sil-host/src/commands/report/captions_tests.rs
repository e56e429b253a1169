//! Tests of the figures' captions ([`super`]).

use super::*;

fn caption(what: &str) -> Caption {
    Caption { what: what.into(), parameters: "mu = 0.6".into(), paper: Some("Fig. 3".into()) }
}

#[test]
fn figures_are_numbered_in_the_order_shown_with_their_caption_below() {
    let mut figures = Figures::new("figures/");
    let mut md = String::new();
    figures.show(&mut md, "modes/modes.svg", &caption("Contact modes: the map"));
    figures.show(&mut md, "sweep/map_newton_e0.2.svg", &caption("The outcome [per run]"));
    assert!(
        md.contains(
            "![Figure 1: Contact modes](figures/modes/modes.svg)\n\n**Figure 1.** Contact modes: the map. μ = 0.6. In the paper: Fig. 3.\n"
        ),
        "{md}"
    );
    assert!(md.contains("![Figure 2: The outcome per run](figures/sweep/map_newton_e0.2.svg)"), "{md}");
    assert!(md.find("Figure 1.").unwrap() < md.find("Figure 2.").unwrap());
    assert_eq!(figures.shown(), ["modes/modes.svg", "sweep/map_newton_e0.2.svg"]);
    // On the report's own page each caption links its PDF.
    let mut md = String::new();
    let mut figures = Figures::new("").with_pdf();
    figures.show(&mut md, "modes/modes.svg", &caption("Contact modes: the map"));
    assert!(md.contains("In the paper: Fig. 3. [PDF](modes/modes.pdf)\n"), "{md}");
}

#[test]
fn side_by_side_figures_share_one_number() {
    let mut figures = Figures::new("");
    let mut md = String::new();
    figures.show(&mut md, "a/one.svg", &caption("One"));
    let columns = vec![("left".to_string(), vec!["l/map.svg".to_string()]), ("right".to_string(), vec!["r/map.svg".to_string()])];
    figures.show_side_by_side(&mut md, &columns, &caption("Both"));
    figures.show(&mut md, "a/three.svg", &caption("Three"));
    assert!(md.contains("| ![Figure 2, left: Both](l/map.svg) | ![Figure 2, right: Both](r/map.svg) |"), "{md}");
    assert!(md.contains("**Figure 2.** Both.") && md.contains("**Figure 3.** Three."), "{md}");
    assert_eq!(figures.shown().len(), 4);
}

/// Captions and alt text use the figures' symbols, not the code names.
#[test]
fn captions_are_written_in_the_papers_symbols() {
    let c = Caption {
        what: "The indicator max theta1_dot against v_belt".into(),
        parameters: "z_t* = 0.1 m, f_n* = 10 N, e_n = 0.2, mu_hat = 0.66".into(),
        paper: Some("Fig. 9".into()),
    };
    assert_eq!(
        c.text(),
        "The indicator max θ\u{307}₁ against belt speed. zₜ* = 0.1 m, fₙ* = 10 N, eₙ = 0.2, μ\u{302} = 0.66. In the paper: Fig. 9."
    );
    assert_eq!(alt("The (theta1, theta1_dot) grid: modes"), "The (θ₁, θ\u{307}₁) grid");
}

#[test]
fn a_caption_without_a_counterpart_says_so() {
    let c = Caption { what: "A run".into(), parameters: String::new(), paper: None };
    assert_eq!(c.text(), "A run. No counterpart in the paper.");
}
