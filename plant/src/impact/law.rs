//! The scenario's choices for an impact ([`super`] documentation): the impact law
//! ([`ImpactLaw`]: Newton, Poisson, energetic) and what the impact without
//! collision leaves behind ([`IwcRule`]).

/// The impact law, a first-class scenario parameter (`plant.impact_law`) and
/// command-line option (`--impact-law newton|poisson|energetic`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum ImpactLaw {
    /// Restitution of the normal velocity (`e` is Newton's coefficient `e_n`);
    /// falls back to [`ImpactLaw::Energetic`] where it would create energy.
    Newton,
    /// Restitution of the normal impulse via Darboux-Keller (`e` is Poisson's
    /// coefficient); falls back to [`ImpactLaw::Energetic`] where it would create energy.
    Poisson,
    /// Stronge's energetic restitution via Darboux-Keller (`e` is the energetic
    /// coefficient `e_*`): never creates energy.
    Energetic,
}

impl ImpactLaw {
    /// Every law, in documentation order.
    pub const ALL: [ImpactLaw; 3] = [Self::Newton, Self::Poisson, Self::Energetic];

    /// Lower-case name (`newton`, `poisson`, `energetic`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Newton => "newton",
            Self::Poisson => "poisson",
            Self::Energetic => "energetic",
        }
    }
}

impl std::fmt::Display for ImpactLaw {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// What the impact without collision leaves behind (scenario `plant.iwc`,
/// command-line `--iwc restitution|plastic`; module documentation).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum IwcRule {
    /// The impact law's restitution acts on the compression the tangential impact
    /// creates: the tip leaves the belt (`v_n = -e v_n,min > 0` for Newton), as the
    /// paper's "z_n_dot turns from zero to positive" describes.
    #[default]
    Restitution,
    /// The tip is left stuck tangentially with `v_n = 0` (Newton's law applied to the
    /// zero approach velocity; Moreau-Jean time-steppers).
    Plastic,
}

impl IwcRule {
    /// Both rules.
    pub const ALL: [IwcRule; 2] = [Self::Restitution, Self::Plastic];

    /// Lower-case name (`restitution`, `plastic`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Restitution => "restitution",
            Self::Plastic => "plastic",
        }
    }
}

impl std::fmt::Display for IwcRule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
