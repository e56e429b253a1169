//! Tests of the sweep's spec ([`super`]): the paper's grid, balanced shards and
//! their manifests, random initial conditions on the belt.

use super::*;
use proptest::prelude::*;

#[test]
fn the_paper_grid_has_10_by_181_points() {
    let s = SweepSpec::paper();
    assert_eq!((s.mu.len(), s.v_belt.len(), s.n_runs()), (10, 181, 3620));
    assert_eq!(s.mu.values()[2], 0.3);
    assert_eq!(s.v_belt.value(180), -0.1);
    let last = s.run_at(3619);
    assert_eq!((last.i_mu, last.i_v, last.i_ic, last.mu, last.v_belt), (9, 180, 1, 1.0, -0.1));
    assert!(s.validate().is_ok());
}

/// The paper's grid in 16 shards: 113 or 114 runs from `x0a` in every shard
/// (modulo: 226 or 227 in each even shard, none in the odd ones).
#[test]
fn balanced_shards_spread_the_costly_initial_condition() {
    let s = SweepSpec::paper();
    let count = |shard: Shard| shard.indices(&s).into_iter().filter(|&i| s.run_at(i).i_ic == 0).count();
    let balanced: Vec<usize> = (0..16).map(|k| count(Shard::parse(&format!("{k}/16")).unwrap())).collect();
    assert!(balanced.iter().all(|&c| c == 113 || c == 114), "{balanced:?}");
    assert_eq!(balanced.iter().sum::<usize>(), 1810);
    let modulo: Vec<usize> = (0..16).map(|k| count(Shard { k, n: 16, assignment: Assignment::Modulo })).collect();
    assert_eq!((modulo[0], modulo[1]), (227, 0));
}

/// `sweep.json`: the whole sweep is written as before (`{"k":0,"n":1}`), a
/// balanced shard names its assignment, and a shard without one (written before
/// it existed) is read as modulo.
#[test]
fn shard_manifests_old_and_new() {
    assert_eq!(Shard::parse("0/1"), Ok(Shard::ALL));
    assert_eq!(serde_json::to_string(&Shard::ALL).unwrap(), r#"{"k":0,"n":1}"#);
    let b = Shard::parse("3/16").unwrap();
    assert_eq!(serde_json::to_string(&b).unwrap(), r#"{"k":3,"n":16,"assignment":"balanced"}"#);
    assert_eq!(serde_json::from_str::<Shard>(r#"{"k":1,"n":2}"#).unwrap(), Shard { k: 1, n: 2, assignment: Assignment::Modulo });
    for bad in ["2/2", "1/0", "a/3", "3", "-1/4"] {
        assert!(Shard::parse(bad).is_err(), "{bad}");
    }
}

#[test]
fn random_initial_conditions_are_on_the_belt_and_reproducible() {
    let s = SweepSpec { random_ics: 5, ..SweepSpec::paper() };
    let a = s.initial_conditions();
    assert_eq!(a, s.initial_conditions());
    assert_eq!(a.len(), 7);
    let p = Params::<f64>::paper();
    for ic in &a[2..] {
        let z = shared::kinematics::tip_position(p.l, &Vector2::new(ic.x0[0], ic.x0[2]));
        assert!((z[1] + p.h).abs() < 1e-12, "{ic:?}");
    }
    assert_ne!(a[2].x0, a[3].x0);
}

proptest! {
    /// The shards of a sweep partition its runs (every run in exactly one shard,
    /// `indices` ascending), and the balanced assignment gives every shard the same
    /// number of runs to one: overall, of every initial condition (per rule, law and
    /// `e_n`), and of every row (all belt speeds at one rule, law, `e_n`, initial
    /// condition and `mu`).
    #[test]
    fn balanced_shards_partition_the_runs_evenly(
        n_mu in 1usize..6, n_v in 1usize..40, n_e in 1usize..3, ics in 1usize..4, n in 1usize..40,
    ) {
        let s = SweepSpec {
            mu: Axis { start: 0.1, stop: 0.1 * n_mu as f64, step: 0.1 },
            v_belt: Axis { start: -1.0, stop: -1.0 + 0.01 * (n_v - 1) as f64, step: 0.01 },
            e_n: (0..n_e).map(|i| i as f64 * 0.1).collect(),
            impact_laws: vec![ImpactLaw::Newton, ImpactLaw::Poisson],
            paper_ics: vec![],
            random_ics: ics,
            ..SweepSpec::paper()
        };
        let shards: Vec<Shard> = (0..n).map(|k| Shard::parse(&format!("{k}/{n}")).unwrap()).collect();
        let mut owner = vec![usize::MAX; s.n_runs()];
        for shard in &shards {
            let idx = shard.indices(&s);
            prop_assert!(idx.windows(2).all(|w| w[0] < w[1]));
            for i in idx {
                prop_assert_eq!(owner[i], usize::MAX, "run {} in two shards", i);
                prop_assert!(shard.owns(&s, i));
                owner[i] = shard.k;
            }
        }
        prop_assert!(owner.iter().all(|&o| o < n), "every run has a shard");
        // Per-shard counts of the runs selected by `group`, for every group value.
        let spread = |group: &dyn Fn(&RunKey) -> usize| -> usize {
            let mut counts: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
            for (i, &o) in owner.iter().enumerate() {
                counts.entry(group(&s.run_at(i))).or_insert_with(|| vec![0; n])[o] += 1;
            }
            counts.values().map(|c| c.iter().max().unwrap() - c.iter().min().unwrap()).max().unwrap_or(0)
        };
        let law = |k: &RunKey| usize::from(k.impact_law == ImpactLaw::Poisson);
        let e = |k: &RunKey| (k.e_n * 10.0).round() as usize;
        prop_assert!(spread(&|_| 0) <= 1);
        prop_assert!(spread(&|k| (law(k) * 10 + e(k)) * 10 + k.i_ic) <= 1);
        prop_assert!(spread(&|k| ((law(k) * 10 + e(k)) * 10 + k.i_ic) * 10 + k.i_mu) <= 1);
    }

    /// The modulo assignment (folders without `assignment`) is `index mod N`.
    #[test]
    fn modulo_shards_are_index_mod_n(i in 0usize..3620, n in 1usize..40) {
        let s = SweepSpec::paper();
        prop_assert_eq!(Shard { k: 0, n, assignment: Assignment::Modulo }.owner(&s, i), i % n);
    }

    /// Run indices and grid points correspond one to one, for every seed; seed
    /// 0's runs are numbered as the same sweep's with one seed.
    #[test]
    fn run_index_decodes_every_point_once(n_mu in 1usize..5, n_v in 1usize..7, n_e in 1usize..3, ics in 1usize..4, seeds in 1usize..4) {
        let s = SweepSpec {
            mu: Axis { start: 0.1, stop: 0.1 * n_mu as f64, step: 0.1 },
            v_belt: Axis { start: -1.0, stop: -1.0 + 0.1 * (n_v - 1) as f64, step: 0.1 },
            e_n: (0..n_e).map(|i| i as f64 * 0.1).collect(),
            impact_laws: vec![ImpactLaw::Newton, ImpactLaw::Poisson],
            iwc_rules: IwcRule::ALL.to_vec(),
            paper_ics: vec![],
            random_ics: ics,
            seeds,
            jitter: crate::sweep::Jitter { mu: 1e-3, ..Default::default() },
            ..SweepSpec::paper()
        };
        let one = SweepSpec { seeds: 1, ..s.clone() };
        let mut seen = std::collections::HashSet::new();
        for i in 0..s.n_runs() {
            let k = s.run_at(i);
            prop_assert!(seen.insert((k.seed, k.iwc, k.impact_law.name(), k.e_n.to_bits(), k.i_mu, k.i_v, k.i_ic)));
            if k.seed == 0 {
                prop_assert_eq!(k, one.run_at(i));
            }
        }
        prop_assert_eq!(seen.len(), seeds * 2 * 2 * n_e * n_mu * n_v * ics);
        // Every shard of a balanced deal gets each seed's share to one run.
        let shard = Shard::parse("1/3").unwrap();
        let per_seed: Vec<usize> = (0..seeds).map(|q| shard.indices(&s).iter().filter(|&&i| s.run_at(i).seed == q).count()).collect();
        prop_assert!(per_seed.iter().max().unwrap() - per_seed.iter().min().unwrap() <= 1, "{:?}", per_seed);
    }
}
