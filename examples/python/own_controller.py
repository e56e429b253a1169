"""Your own control law against the Painlevé plant, in ten lines (docs/python.md,
"Objects"): a PD law on theta1 plus a force term on f_n, closed through the rig's
sensors (14-bit encoders, noisy 12-bit load cell), zero-order hold and delay.

    pip install ./python && python examples/python/own_controller.py
"""

import painleve

scenario = painleve.Scenario.default().set("timing.duration_s", 2.0)


def my_law(t, y):  # y: painleve.Sensed (SI units, radians)
    u1 = -2.0 * (y.theta1 + 0.2) - 0.1 * y.theta1_dot - 0.05 * (y.f_n - 5.0)
    return u1, 0.0  # motor torques (u1, u2), N m


result = painleve.run_controller(my_law, scenario)
trace = result.trace
print(trace)
print(f"lift-offs: {result.summary['lift_offs']}, final f_n = {trace['f_n'][-1]:.3f} N, modes: {sorted(set(map(str, trace['mode'])))}")
