//! The one table of symbols every figure's text is written with: the paper's
//! symbols in Unicode (θ̇₁, μ, zₜ, fₙ), in place of the code names the CSV
//! columns and the command line use (`theta1_dot`, `mu`, `z_t`, `f_n`).
//!
//! Every glyph here is in DejaVu Sans, the font the figures are laid out with and
//! their PDFs embed ([`super::font`]); a test checks it. Unicode has no subscript
//! b, so the belt's speed `v_belt` is written in words ("belt speed").
//!
//! Sources: the symbols of docs/model.md and of the paper (Marchese et al., ECC
//! 2019: θ₁, θ₂, μ, zₜ, zₙ, fₙ, eₙ, p, b).

/// The shoulder angle `theta1`.
pub const THETA1: &str = "θ₁";
/// The elbow angle `theta2`.
pub const THETA2: &str = "θ₂";
/// The shoulder's angular velocity `theta1_dot` (a combining dot above θ).
pub const THETA1_DOT: &str = "θ\u{307}₁";
/// The elbow's angular velocity `theta2_dot`.
pub const THETA2_DOT: &str = "θ\u{307}₂";
/// The tip's slip velocity relative to the belt `z_r_dot` (ż, the precomposed z
/// with a dot above, and a subscript r).
pub const Z_R_DOT: &str = "żᵣ";
/// The tip's normal velocity `z_n_dot`.
pub const Z_N_DOT: &str = "żₙ";
/// The coefficient of friction `mu`.
pub const MU: &str = "μ";
/// The controller's estimate of the coefficient of friction `mu_hat`.
pub const MU_HAT: &str = "μ\u{302}";
/// The tip's tangential coordinate along the belt `z_t`.
pub const Z_T: &str = "zₜ";
/// Its target `z_t*`.
pub const Z_T_REF: &str = "zₜ*";
/// The tip's normal coordinate `z_n` (the belt at `-H`).
pub const Z_N: &str = "zₙ";
/// The normal contact force `f_n`.
pub const F_N: &str = "fₙ";
/// The normal restitution coefficient `e_n`.
pub const E_N: &str = "eₙ";
/// The largest target slid to with no lift-off, `Z_t,sliding`.
pub const Z_T_SLIDING: &str = "Zₜ,sliding";
/// The belt's speed `v_belt`, in words (Unicode has no subscript b).
pub const BELT_SPEED: &str = "belt speed";
/// The joint torques `u1`, `u2`.
pub const TAU: [&str; 2] = ["τ₁", "τ₂"];

/// The code names [`prose`] replaces, each with its symbol.
const CODE_NAMES: [(&str, &str); 14] = [
    ("theta1_dot", THETA1_DOT),
    ("theta2_dot", THETA2_DOT),
    ("theta1", THETA1),
    ("theta2", THETA2),
    ("mu_hat", MU_HAT),
    ("mu", MU),
    ("e_n", E_N),
    ("z_t", Z_T),
    ("Z_t", "Zₜ"),
    ("z_n", Z_N),
    ("f_n", F_N),
    ("z_r_dot", Z_R_DOT),
    ("v_belt", BELT_SPEED),
    ("um", "µm"),
];

/// `text` with each code name standing as a word (`mu_hat`, `e_n`, `theta1_dot`,
/// `um`) replaced by its symbol (μ̂, eₙ, θ̇₁, µm), for labels that come from the
/// analyses' own names (a sensitivity study's choices).
pub fn prose(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 8);
    let mut word = String::new();
    let flush = |word: &mut String, out: &mut String| {
        out.push_str(CODE_NAMES.iter().find(|(code, _)| *code == word.as_str()).map_or(word.as_str(), |(_, sym)| sym));
        word.clear();
    };
    for c in text.chars() {
        if c.is_ascii_alphanumeric() || c == '_' {
            word.push(c);
        } else {
            flush(&mut word, &mut out);
            out.push(c);
        }
    }
    flush(&mut word, &mut out);
    out
}

/// An axis description: `symbol (unit)`, e.g. `θ̇₁ (rad/s)`; the unit `-` for a
/// number without one.
pub fn axis(symbol: &str, unit: &str) -> String {
    format!("{symbol} ({unit})")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every symbol's glyphs are in the figures' font (no tofu in a figure or its PDF).
    #[test]
    fn every_symbol_is_in_the_figures_font() {
        use plotters::prelude::IntoFont;
        super::super::font::register();
        let all = [
            THETA1,
            THETA2,
            THETA1_DOT,
            THETA2_DOT,
            Z_R_DOT,
            Z_N_DOT,
            MU,
            MU_HAT,
            Z_T,
            Z_T_REF,
            Z_N,
            F_N,
            E_N,
            Z_T_SLIDING,
            BELT_SPEED,
            TAU[0],
            TAU[1],
        ];
        let face = ab_glyph::FontRef::try_from_slice(super::super::font::bytes()).unwrap();
        for s in all {
            for c in s.chars() {
                assert_ne!(ab_glyph::Font::glyph_id(&face, c).0, 0, "{c:?} of {s:?} is not in DejaVu Sans");
            }
            assert!(("sans-serif", 18.0).into_font().box_size(s).is_ok());
        }
        assert_eq!(axis(THETA1_DOT, "rad/s"), "θ\u{307}₁ (rad/s)");
        for (_, sym) in CODE_NAMES {
            for c in sym.chars() {
                assert_ne!(ab_glyph::Font::glyph_id(&face, c).0, 0, "{c:?} of {sym:?} is not in DejaVu Sans");
            }
        }
    }

    /// Code names become symbols where they stand as words, and only there.
    #[test]
    fn prose_replaces_whole_code_names() {
        assert_eq!(prose("mu_hat mismatch"), "μ\u{302} mismatch");
        assert_eq!(prose("newton, e_n = 0.2*"), "newton, eₙ = 0.2*");
        assert_eq!(prose("gap > 1 um"), "gap > 1 µm");
        assert_eq!(prose("Z_t,sliding at mu = 0.6"), "Zₜ,sliding at μ = 0.6");
        assert_eq!(prose("mumble, summit, e_nx"), "mumble, summit, e_nx");
    }
}
