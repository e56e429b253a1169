"""``painleve.Model`` (issue 55): the arm's model in Python, checked against finite
differences, against its own identities (paper eqs. 1 to 7) and against the
compiled plant (``painleve.Plant``)."""

import math

import numpy as np
import pytest

import painleve

X0D = [math.radians(60.0), 0.0, math.radians(-30.0), 0.0]


@pytest.fixture(scope="module")
def model():
    return painleve.Model()


def states(n=25, seed=3):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        th = rng.uniform(-math.pi, math.pi, 2)
        thd = rng.uniform(-5, 5, 2)
        yield np.array([th[0], thd[0], th[1], thd[1]])


def test_the_parameters_are_the_scenarios_and_keywords_override_them(model):
    p = model.params
    assert p["mu"] == 0.6 and p["v_belt"] == -0.4 and p["l"] > 0 and p["m"] > 0
    m = painleve.Model(mu=0.3, v_belt=0.2)
    assert (m.params["mu"], m.params["v_belt"]) == (0.3, 0.2)
    with pytest.raises(TypeError, match="x0"):
        painleve.Model(x0="d")
    with pytest.raises(painleve.PainleveError):
        painleve.Model(l=-1.0)
    # Issue 69 (5): alpha0 is in radians; Table I's 13.72 (degrees) and 100 are refused, naming it.
    for bad in (13.72, 100.0, -4.0):
        with pytest.raises(painleve.PainleveError) as e:
            painleve.Model(alpha0=bad)
        assert e.value.exit_code == 2 and "alpha0" in str(e.value) and "radians" in str(e.value), str(e.value)
    assert painleve.Model(alpha0=0.2395).params["alpha0"] == 0.2395


def test_inverse_kinematics_inverts_the_tip_on_both_branches(model):
    for s in states():
        theta = np.array([s[0], s[2]])
        z = model.tip(theta)
        # The branch as the inverse kinematics has it: the elbow's side, the sign of
        # theta2 - theta1 taken in (-pi, pi].
        branch = "up" if math.sin(theta[1] - theta[0]) > 0 else "down"
        back = model.inverse_kinematics(z, branch)
        assert np.allclose(model.tip(back), z, atol=1e-12)
        # the same configuration, angles up to 2 pi
        assert np.allclose(np.angle(np.exp(1j * (back - theta))), 0.0, atol=1e-7), (theta, back)
    with pytest.raises(ValueError, match="z ="):
        model.inverse_kinematics([10.0, 0.0])
    with pytest.raises(ValueError, match="branch"):
        model.inverse_kinematics([0.1, 0.0], "sideways")


def test_the_jacobian_and_jdot_qdot_are_the_tips_derivatives(model):
    eps = 1e-6
    for s in states():
        theta, thd = np.array([s[0], s[2]]), np.array([s[1], s[3]])
        J = model.jacobian(theta)
        assert J.shape == (2, 2)
        fd = np.column_stack([(model.tip(theta + eps * e) - model.tip(theta - eps * e)) / (2 * eps) for e in np.eye(2)])
        assert np.allclose(J, fd, atol=1e-8)
        # d/dt (J q_dot) at q_ddot = 0: (J(theta + eps q_dot) - J(theta - eps q_dot)) q_dot / (2 eps)
        fd_jdot = (model.jacobian(theta + eps * thd) - model.jacobian(theta - eps * thd)) @ thd / (2 * eps)
        assert np.allclose(model.jdot_qdot(s), fd_jdot, atol=1e-6 * (1 + np.abs(fd_jdot).max()))


def test_m_q_p_and_b_keep_the_papers_identities(model):
    mu = model.params["mu"]
    for s in states():
        theta = np.array([s[0], s[2]])
        M = model.mass_matrix(theta)
        assert np.allclose(M, M.T) and np.all(np.linalg.eigvalsh(M) > 0)
        J = model.jacobian(theta)
        Q = model.q_matrix(theta)
        assert np.allclose(Q, J @ np.linalg.inv(M) @ J.T, rtol=1e-12, atol=1e-12)  # eq. 3
        for direction, sign in (("positive", 1.0), ("negative", -1.0)):
            p = model.p(theta, direction)
            assert p == pytest.approx(Q[1, 1] - mu * sign * Q[1, 0], rel=1e-12, abs=1e-12)  # eq. 7
            assert model.painleve(theta, direction) == (p < 0)
        # eq. 6: b is the normal component of J M^-1 (u - w - c) + J_dot q_dot
        u = np.array([0.3, -0.2])
        qdd = np.linalg.solve(M, model.generalised_torque(u) - model.bias(s))
        b = (J @ qdd + model.jdot_qdot(s))[1]
        assert model.b(s, u) == pytest.approx(b, rel=1e-9, abs=1e-9)
        assert model.energy(s) == pytest.approx(
            0.5 * np.array([s[1], s[3]]) @ M @ np.array([s[1], s[3]]) + model.energy([s[0], 0.0, s[2], 0.0]), rel=1e-12
        )


def test_the_model_agrees_with_the_compiled_plant(model):
    # The plant's tip and its sliding normal force f_n = -b/p (paper eqs. 5 to 7).
    plant = painleve.Plant(x0="d")
    step = plant.advance(0.001, (0.0, 0.0))
    s = step.state
    assert np.allclose(model.tip([s[0], s[2]]), step.tip, atol=1e-12)
    assert step.mode == "sliding" == model.contact_mode(s)
    z_r_dot = (model.jacobian([s[0], s[2]]) @ [s[1], s[3]])[0] - model.params["v_belt"]
    direction = "positive" if z_r_dot > 0 else "negative"
    f_n = -model.b(s) / model.p([s[0], s[2]], direction)
    assert step.force[1] == pytest.approx(f_n, rel=1e-9)


def test_a_non_finite_input_is_refused_naming_the_argument(model):
    # Issue 66: NaN or infinite angles gave NaN, False or "indeterminate"; the
    # plant refuses such a state, and so does every method of the model, naming
    # the argument and the element.
    bad = (math.nan, math.inf, -math.inf)
    for v in bad:
        text = {math.inf: "inf", -math.inf: "-inf"}.get(v, "nan")
        theta, state = [0.1, v], [0.1, 0.0, 0.2, v]
        for call in (
            lambda: model.tip(theta),
            lambda: model.jacobian(theta),
            lambda: model.mass_matrix(theta),
            lambda: model.q_matrix(theta),
            lambda: model.p(theta),
            lambda: model.painleve(theta),
        ):
            with pytest.raises(ValueError, match=rf"^theta\[1\] = {text}: expected 2 finite numbers \(rad\)"):
                call()
        for call in (
            lambda: model.jdot_qdot(state),
            lambda: model.bias(state),
            lambda: model.b(state),
            lambda: model.contact_mode(state),
            lambda: model.energy(state),
        ):
            with pytest.raises(ValueError, match=rf"^state\[3\] = {text}: "):
                call()
        with pytest.raises(ValueError, match=rf"^torques\[0\] = {text}: .*\(N m\)"):
            model.b([0.1, 0.0, 0.2, 0.0], [v, 0.0])
        with pytest.raises(ValueError, match=r"^torques\[0\]"):
            model.contact_mode([0.1, 0.0, 0.2, 0.0], [v, 0.0])
        with pytest.raises(ValueError, match=r"^torques\[0\]"):
            model.generalised_torque([v, 0.0])
        with pytest.raises(ValueError, match=rf"^z\[0\] = {text}: .*\(m\)"):
            model.inverse_kinematics([v, 0.0])
        with pytest.raises(ValueError, match=r"^v_stick = "):
            model.contact_mode([0.1, 0.0, 0.2, 0.0], v_stick=v)
    with pytest.raises(ValueError, match=r"^v_stick = -1.0"):
        model.contact_mode([0.1, 0.0, 0.2, 0.0], v_stick=-1.0)
    # Finite inputs still answer, and a bad direction is still named.
    assert np.isfinite(model.tip([0.1, 0.2])).all() and isinstance(model.painleve([0.1, 0.2]), bool)
    with pytest.raises(ValueError, match="direction"):
        model.p([0.0, 0.0], "sideways")


def test_a_plants_state_is_settable_and_checked_against_the_contact(model):
    plant = painleve.Plant(x0="d")
    plant.advance(0.01, (0.0, 0.0))
    t = plant.time
    # Lift the arm clear of the belt: in flight, the state and time as set.
    up = model.inverse_kinematics([0.2, 0.0], "down")
    state = [up[0], 0.0, up[1], 0.0]
    plant.state = state
    assert np.array_equal(plant.state, state) and plant.time == t and plant.mode == "flight"
    # reset(state=..., t=...) moves the clock too; the plant then advances from there.
    plant.reset(state=state, t=2.0)
    assert plant.time == 2.0 and plant.advance(0.01).t == pytest.approx(2.01)
    # Below the belt (z_n < -h): refused, the plant unchanged.
    h = model.params["h"]
    low = model.inverse_kinematics([0.05, -h - 0.01], "down")
    before = plant.state.copy()
    with pytest.raises(painleve.PainleveError) as e:
        plant.state = [low[0], 0.0, low[1], 0.0]
    assert e.value.exit_code == 2 and np.array_equal(plant.state, before)
    with pytest.raises(painleve.PainleveError):
        plant.reset(state=[math.nan, 0, 0, 0])
    with pytest.raises(painleve.PainleveError):
        plant.reset(t=-1.0)
    plant.reset()
    assert plant.time == 0.0


def test_a_shape_error_names_the_argument(model):
    # Issue 69 (5): the wrong length or shape names the argument and what it got.
    cases = [
        (lambda: model.mass_matrix([1.0, 2.0, 3.0]), "theta: expected 2 numbers", "a sequence of 3"),
        (lambda: model.mass_matrix(np.zeros((2, 2))), "theta: expected 2 numbers", "an array of shape (2, 2)"),
        (lambda: model.energy(np.zeros(3)), "state: expected 4 numbers", "an array of shape (3,)"),
        (lambda: model.b([0.3, 0.0, -0.5, 0.0], torques=[1.0]), "torques: expected 2 numbers", "a sequence of 1"),
        (lambda: painleve.Plant(state=[1.0, 2.0]), "state: expected 4 numbers", "a sequence of 2"),
    ]
    for call, head, got in cases:
        with pytest.raises(ValueError) as e:
            call()
        assert str(e.value).startswith(head) and got in str(e.value), str(e.value)
    with pytest.raises(TypeError, match="theta: expected 2 numbers"):
        model.tip("ab")
    with pytest.raises(TypeError, match="theta: expected 2 numbers, got an element"):
        model.tip(["a", "b"])
    # The default torques are none: the same b as zero torques given.
    s = [0.3, 0.0, -0.5, 0.0]
    assert model.b(s) == model.b(s, torques=[0.0, 0.0]) == model.b(s, np.zeros(2))
