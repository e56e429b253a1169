"""The cases scripts/cycles.py measures: the default scenario under each term of the
hybrid law and the PID (`named_case`), or random admissible scenarios (`draw_case`)."""

import random

# The hybrid law's friction terms besides the default (`commanded`): every one is
# gated (issue 56), as `controller.friction` names them (firmware::config::FrictionCompensation).
HYBRID_VARIANTS = ("hybrid-estimated", "hybrid-measured", "hybrid-measured_normal", "hybrid-none")


# --random: the terms the cases take in turn, and the ranges they are drawn from.
TERMS = ("hybrid", *HYBRID_VARIANTS, "pid")
# The PIL image's rates (firmware::Config::validate: 100 to 4000 us, 250 Hz to 10 kHz),
# drawn log-uniform as board-link's random_scenarios::log_uniform_period_us.
PERIOD_US = (100, 4000)


def draw_case(seed, i, term, periods):
    """Random admissible scenario `i` of `seed` under `term` (`hybrid`, `hybrid-FRICTION`
    or `pid`), `periods` periods long: the `--set KEY=VALUE`s of `sil-host pil`.

    The ranges are board-link's `random_scenarios::random_admissible` and
    `at_period` (the control handler's bound over random scenarios, issue 56): the
    paper's arm and gains, `plant.x0` the paper's d or u (from a, the hybrid law
    lifts off and the firmware enters its safe state by period 10), `plant.mu` 0.3 to 0.8 and `controller.mu_hat` the same, `plant.v_belt` -1 to
    -0.1 m/s, `controller.f_n_ref` 3 to 10 N, `controller.target_z_t` -0.05 to 0.14 m,
    any sensor seed, the period log-uniform over the image's 100 to 4000 us with the
    command's delay 0.2 ms or half the period when that is shorter; the move takes
    the scenario's 2 s (a move drawn short enough to end within a short run, 0.01 to
    0.4 s, trips the firmware's runaway limits within 20 to 100 periods: the run ends
    in the safe state, measuring little). Every case runs the same number of periods
    (the trace's cost), so its duration in seconds follows from its rate: past 2 s
    (a period past 2 ms at --duration 1) it holds too.

    Drawn from a generator seeded by (`seed`, `i`) alone: case `i` is the same
    whatever `--random N` and `--case` select."""
    r = random.Random(f"scripts/cycles.py {seed} {i}")
    kind, _, friction = term.partition("-")
    # `law`: the scenario's own `[law]` (a law of one's own, issue 70): no
    # controller flag, the same draw of the plant, the references and the rate.
    if kind == "hybrid" and not friction:
        friction = "commanded"
    us = round(PERIOD_US[0] * (PERIOD_US[1] / PERIOD_US[0]) ** r.random())
    duration = periods * us * 1e-6
    mu = round(0.3 + 0.5 * r.random(), 4)
    sets = [
        f"plant.x0={r.choice('du')}",
        f"plant.mu={mu}",
        f"controller.mu_hat={mu}",
        f"plant.v_belt={round(-1.0 + 0.9 * r.random(), 4)}",
        f"controller.f_n_ref={round(3.0 + 7.0 * r.random(), 4)}",
        f"controller.target_z_t={round(-0.05 + 0.19 * r.random(), 4)}",
        f"sensors.seed={r.randrange(1, 1 << 31)}",
        f"timing.rate_hz={1e6 / us!r}",
        f"timing.delta_s={min(0.0002, 0.5 * us * 1e-6):.6f}",
        f"timing.duration_s={duration:.6f}",
    ]
    if friction:
        sets.insert(0, f"controller.friction={friction}")
    argv = [] if kind == "law" else ["--controller", kind]
    for kv in sets:
        argv += ["--set", kv]
    return {"name": f"case {i} ({term}, {us} us)", "index": i, "term": term, "period_us": us, "sets": sets, "argv": argv, "random": True}


def named_case(term, duration):
    """The default scenario (or --scenario's) under `term`, `duration` s; `law`:
    the scenario's own `[law]`."""
    kind, _, friction = term.partition("-")
    if kind == "law":
        return {"name": term, "argv": ["--duration", str(duration)]}
    argv = ["--controller", kind] + (["--set", f"controller.friction={friction}"] if friction else [])
    return {"name": term, "argv": argv + ["--duration", str(duration)]}
