"""Long calls release the GIL, report progress and stop cleanly on Ctrl-C."""

import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import pytest

import painleve

LONG_SWEEP = "painleve.sweep(mu=(0.1, 1.0), v_belt=(-1.0, -0.1), v_belt_step=0.001, progress=True)"
SCRIPT = textwrap.dedent(
    """
    import signal, sys, time, resource
    # What a user at a terminal has: Python's own SIGINT handler. A test suite
    # started as a background job (`cmd &` in a script) hands its children SIGINT
    # ignored, and Python keeps a disposition it inherits ignored: without this
    # line the call below would run to its end, deaf to the signal.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    import painleve
    print("started", flush=True)
    t0 = time.monotonic()
    try:
        {call}
    except KeyboardInterrupt:
        stopped = time.monotonic()
        cpu0 = time.process_time()
        time.sleep(1.0)
        print(f"KeyboardInterrupt {{stopped - t0:.3f}} cpu-after {{time.process_time() - cpu0:.3f}}", flush=True)
        sys.exit(0)
    print("finished", flush=True)
    """
)


@pytest.mark.parametrize(
    "call",
    [
        LONG_SWEEP,
        "painleve.poincare(v_step=0.0005, progress=True)",
        "painleve.zmax(all=True, tol=1e-6, duration=120.0, progress=True)",
        "painleve.run(duration=10000.0, progress=True)",
        "painleve.simulate(duration=20000.0, progress=True)",
        "painleve.sensitivity(size='paper', progress=True)",
    ],
)
def test_ctrl_c_stops_a_long_call_promptly(call):
    # Bytes, not text: universal newlines would turn the progress line's \r into \n.
    p = subprocess.Popen([sys.executable, "-c", SCRIPT.format(call=call)], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert p.stdout.readline().strip() == b"started"
    # Each call takes 30 s or more on an idle 2-core machine: it is running.
    time.sleep(1.5)
    sent = time.monotonic()
    p.send_signal(signal.SIGINT)
    try:
        out, err = (x.decode() for x in p.communicate(timeout=60))
    except subprocess.TimeoutExpired:
        # Say where it hung: the last progress line and whether the exception came.
        p.kill()
        out, err = (x.decode(errors="replace") for x in p.communicate())
        last = err.replace("\r", "\n").strip().splitlines()[-3:]
        pytest.fail(f"{call}: still running 60 s after SIGINT; stdout {out!r}; stderr ends {last}")
    elapsed = time.monotonic() - sent
    assert p.returncode == 0, err
    assert out.startswith("KeyboardInterrupt"), (out, err)
    # The work stops within its unit (a run, a trial, a period, a belt speed),
    # then the process is idle: no thread left computing.
    assert elapsed < 1.0 + 10.0, f"{call}: {elapsed:.1f} s from SIGINT to the exception"
    cpu_after = float(out.split()[-1])
    assert cpu_after < 0.2, f"{call}: {cpu_after} s of CPU in the second after the exception: the work goes on"
    if "progress=True" in call:
        assert "\r" in err, "a progress line on stderr"


def test_the_gil_is_released_while_computing():
    """Another Python thread runs while a sweep computes."""
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.01)

    t = threading.Thread(target=count)
    t.start()
    started = time.monotonic()
    painleve.sweep(v_belt_step=0.05, transient=250.0, record=50.0, progress=False)
    ended = time.monotonic()
    stop.set()
    t.join()
    during = [x for x in ticks if started < x < ended]
    assert ended - started > 0.3, "the sweep is long enough to tell"
    assert len(during) > 0.5 * (ended - started) / 0.01 * 0.5, f"{len(during)} ticks in {ended - started:.2f} s"


def test_progress_callback_sees_every_unit_and_can_stop_the_work():
    seen = []
    r = painleve.sweep(mu=(0.3, 0.6), v_belt=(-0.6, -0.3), v_belt_step=0.05, transient=60.0, record=20.0, progress=lambda d, t: seen.append((d, t)))
    n = r["sweep"].nrows
    assert seen and all(t == n for _, t in seen)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)

    class Enough(Exception):
        pass

    def stop(done, total):
        raise Enough(f"{done}/{total}")

    started = time.monotonic()
    with pytest.raises(Enough):
        painleve.sweep(mu=(0.1, 1.0), v_belt=(-1.0, -0.1), progress=stop)
    assert time.monotonic() - started < 15.0


def test_no_signal_handler_is_installed():
    """Python's own SIGINT handler stays in place (the CLI's process-wide handler
    is not installed in the interpreter)."""
    before = signal.getsignal(signal.SIGINT)
    painleve.run(duration=0.5, progress=False)
    assert signal.getsignal(signal.SIGINT) is before
