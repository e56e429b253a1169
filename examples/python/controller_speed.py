"""The speed of painleve.run_controller (docs/python.md, "Objects"): control
periods per second, the trace's rows over the wall time of the whole call, median
of 5 runs of the default scenario (10 s at 1 kHz: 10 000 periods), with a trivial
Python controller, the PD law of own_controller.py, and painleve.run (the
firmware linked in) for comparison.

    python examples/python/controller_speed.py
"""

import statistics
import time

import painleve

scenario = painleve.Scenario.default()


def zero(t, y):
    return 0.0, 0.0


def pd(t, y):
    return -2.0 * (y.theta1 + 0.2) - 0.1 * y.theta1_dot - 0.05 * (y.f_n - 5.0), 0.0


def periods_per_s(call, runs=5):
    rates = []
    for _ in range(runs):
        started = time.perf_counter()
        result = call()
        rates.append(result.trace.nrows / (time.perf_counter() - started))
    return statistics.median(rates)


print(f"trivial Python controller: {periods_per_s(lambda: painleve.run_controller(zero, scenario)):9.0f} periods/s")
print(f"PD law in Python:          {periods_per_s(lambda: painleve.run_controller(pd, scenario)):9.0f} periods/s")
print(f"painleve.run (firmware):   {periods_per_s(lambda: painleve.run(progress=False)):9.0f} periods/s")
