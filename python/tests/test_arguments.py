"""The Python boundary (issue 42, 2): values checked with Python errors that name
the parameter in the call's terms, partial scenarios merged onto the default,
and the board's keys refused or warned about where there is no board."""

import warnings

import pytest

import painleve


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: painleve.simulate(impact_law="bogus"), "impact_law: expected 'newton', 'poisson' or 'energetic', got str 'bogus'"),
        (lambda: painleve.modes(branch="left"), "branch: expected 'up' or 'down', got str 'left'"),
        (lambda: painleve.sweep(iwc=["plastic", "elastic"], progress=False), "iwc: expected"),
        (lambda: painleve.run(controller="lqr", progress=False), "controller: expected 'pid' or 'hybrid' or None, got str 'lqr'"),
    ],
)
def test_a_choice_not_among_the_choices_is_a_value_error(call, message):
    with pytest.raises(ValueError) as e:
        call()
    assert not isinstance(e.value, painleve.PainleveError), "checked in Python, before any Rust"
    assert str(e.value).startswith(message)


@pytest.mark.parametrize(
    "call, words",
    [
        (lambda: painleve.simulate(duration=-1.0, progress=False), ["duration must be in (0, 1e6] s, got -1"]),
        (lambda: painleve.simulate(sample_dt=0.0, progress=False), ["sample_dt must be in"]),
        (lambda: painleve.simulate(mu=-1.0, progress=False), ["`mu`", ">= 0", "-1"]),
        (lambda: painleve.simulate(e_n=2.0, progress=False), ["`e_n`", "[0, 1]"]),
        (lambda: painleve.modes(theta1_deg=(5, 1)), ["theta1_deg expects MIN,MAX"]),
        (lambda: painleve.zmax(tol=-1.0, progress=False), ["tol -1 m"]),
        (lambda: painleve.simulate(set={"plant.mu": 0.5}, progress=False), ["`plant.mu` is set by mu"]),
    ],
)
def test_a_value_out_of_range_names_the_parameter_without_cli_syntax(call, words):
    with pytest.raises(ValueError) as e:
        call()
    assert isinstance(e.value, painleve.PainleveError) and e.value.exit_code == 2
    text = str(e.value)
    for w in words:
        assert w in text, text
    assert "--" not in text, f"CLI syntax in {text!r}"


def test_a_partial_scenario_dict_is_merged_onto_the_default():
    # Only timing.duration_s changes; plant.mu comes from set=; the rest is the default's.
    r = painleve.run(scenario={"timing": {"duration_s": 0.05}}, set={"plant.mu": 0.5}, progress=False)
    assert r.extras["scenario"]["timing"]["duration_s"] == 0.05
    assert r.extras["scenario"]["plant"]["mu"] == 0.5
    default = painleve.default_scenario()
    assert r.extras["scenario"]["plant"]["v_belt"] == default["plant"]["v_belt"]
    assert len(r.trace["t"]) == 50  # one row per period, 50 periods of 1 ms
    # A Scenario object is taken as it is; a bad key in a dict is named.
    s = painleve.Scenario.default().set("timing.duration_s", 0.02)
    assert len(painleve.run(scenario=s, progress=False).trace["t"]) == 20
    with pytest.raises(painleve.PainleveError) as e:
        painleve.run(scenario={"timing": {"duraton_s": 1.0}}, progress=False)
    assert "timing.duraton_s" in str(e.value)


def test_board_keys_are_refused_or_warned_about_without_a_board():
    with pytest.raises(painleve.PainleveError) as e:
        painleve.run(duration=0.02, set={"board.pwm_max_duty": 4000}, progress=False)
    assert e.value.exit_code == 2 and "board.pwm_max_duty" in str(e.value) and "in-process" in str(e.value)
    with pytest.raises(painleve.PainleveError):
        painleve.zmax(set={"calibration.theta1_zero_count": 100}, progress=False)
    s = painleve.Scenario.default().set("board.pwm_max_duty", 4000).set("timing.duration_s", 0.02)
    with pytest.warns(painleve.PainleveWarning, match=r"\[board\].*ignored"):
        painleve.run(scenario=s, progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        painleve.run(duration=0.02, progress=False)  # the default scenario: no warning


@pytest.mark.parametrize("fn", ["simulate", "poincare"])
def test_an_initial_condition_given_twice_is_refused_as_the_cli_refuses_it(fn):
    # Issue 84: `x0="a"` (the CLI's default) beside `x0_deg` ran in Python, as if
    # x0 were not given, where `sil-host simulate --x0 a --x0-deg ...` is refused.
    with pytest.raises(painleve.PainleveError) as e:
        getattr(painleve, fn)(x0="a", x0_deg=(32, 0, 18.27, 0), progress=False)
    assert e.value.exit_code == 2
    for w in ["x0", "cannot be used with", "x0_deg"]:
        assert w in str(e.value), str(e.value)
    # Not given, x0 is the CLI's "a": the same run as x0="a".
    a = painleve.simulate(duration=0.05, progress=False)
    b = painleve.simulate(x0="a", duration=0.05, progress=False)
    assert a.summary["params"] == b.summary["params"]
    assert (a.trace["theta1"] == b.trace["theta1"]).all()


def test_keywords_reach_the_settings_exactly_without_command_line_text():
    # A double with no short decimal text arrives bit for bit (no text in between).
    mu = 0.1 + 0.2
    r = painleve.simulate(mu=mu, duration=0.01, progress=False)
    assert r.summary["params"]["mu"] == mu and r.summary["params"]["mu"] != 0.3
    # The compiled functions take the arguments given as a dict, laid over clap's
    # defaults: an unknown name, a non-finite number and two names in conflict are
    # refused with the CLI's exit code for bad input, each named.
    from painleve import _painleve

    for given, words in [
        ({"bogus": 1}, ["no parameter `bogus`"]),
        ({"mu": float("nan")}, ["mu", "finite"]),
        ({"x0": "d", "x0_deg": [32, 0, 18.27, 0]}, ["x0", "cannot be used with", "x0_deg"]),
        ({"theta1_deg": "5,x"}, ["theta1_deg", "`5,x`"]),
    ]:
        call = _painleve.modes if "theta1_deg" in given else _painleve.simulate
        with pytest.raises(painleve.PainleveError) as e:
            call(given) if call is _painleve.modes else call(given, None)
        assert e.value.exit_code == 2
        for w in words:
            assert w in str(e.value), str(e.value)
