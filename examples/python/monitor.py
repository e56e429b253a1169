#!/usr/bin/env python3
"""Live monitor of a Painleve SIL rig: the plant's ground truth over iceoryx2.

Subscribes to `painleve/RIG/ground_truth` (payload `painleve::GroundTruth`,
docs/wire.md), wakes on the event of the same name, and prints (or, with
--plot and matplotlib, plots) the tip's tangential position z_t, the normal
contact force f_n and the contact mode as the run goes. It waits for the rig
to appear (up to --timeout), and stops when the plant is gone (end of the
run), after --count samples, or on Ctrl-C; --csv writes every sample it
received.

    python3 examples/python/monitor.py --rig lab --csv received.csv &
    sil-host run --rig lab --monitors 1

With `--monitors 1` the plant waits for this monitor before period 0 and, in
lockstep, never drops a sample for it (docs/rig.md, "Monitors"). Exit codes:
0 done, 1 no rig within --timeout or a broken service, 2 bad arguments,
130 Ctrl-C or SIGTERM (what was received is still written).
"""

from __future__ import annotations

import argparse
import ctypes
import signal
import sys
import time

import iceoryx2 as iox2

#: `GroundTruth::mode`: the contact mode's code.
MODES = {0: "flight", 1: "sliding", 2: "sticking"}


class GroundTruth(ctypes.Structure):
    """`shared::wire::GroundTruth`: 96 bytes, `#[repr(C)]`, SI units, radians.

    Field order and types must stay those of shared/src/wire.rs (docs/wire.md
    gives the offsets); iceoryx2 checks the type name, the size (96) and the
    alignment (8) when the service is opened.
    """

    _fields_ = [
        ("t", ctypes.c_double),  # sample time t_k, s
        ("seq", ctypes.c_uint32),  # period index k
        ("mode", ctypes.c_uint8),  # 0 flight, 1 sliding, 2 sticking
        ("lift_off", ctypes.c_uint8),  # 1 when the tip is off the belt
        ("reserved", ctypes.c_uint16),  # padding, 0
        ("x", ctypes.c_double * 4),  # [theta1, theta1_dot, theta2, theta2_dot], rad, rad/s
        ("z", ctypes.c_double * 2),  # tip position [z_t, z_n], m
        ("f", ctypes.c_double * 2),  # contact force [f_t, f_n], N
        ("u_applied", ctypes.c_double * 2),  # motor torques applied at t_k, N m
    ]

    @staticmethod
    def type_name() -> str:
        """The iceoryx2 type name of the Rust type (its `type_name` attribute)."""
        return "painleve::GroundTruth"


assert ctypes.sizeof(GroundTruth) == 96 and ctypes.alignment(GroundTruth) == 8

#: Columns of --csv: floats are written with repr(), the shortest text that
#: reads back to the same double (as the rig's trace.csv does), so both
#: compare exactly.
CSV_COLUMNS = ["seq", "t", "z_t", "z_n", "f_t", "f_n", "mode", "lift_off"]


class Stop(Exception):
    """The monitor cannot go on (the message says why); exit code 1."""


def parse_args(argv: list[str]) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rig", required=True, help="the rig's name (`sil-host run --rig NAME`)")
    p.add_argument("--count", type=int, default=0, help="stop after N samples (0: at the end of the run)")
    p.add_argument("--csv", metavar="FILE", help="write every sample received to FILE")
    p.add_argument("--timeout", type=float, default=60.0, help="seconds to wait for the rig to appear (default 60)")
    p.add_argument("--plot", action="store_true", help="plot live with matplotlib (requirements-plot.txt)")
    p.add_argument("--window", type=float, default=2.0, help="--plot: seconds of simulated time shown (default 2)")
    p.add_argument("--quiet", action="store_true", help="print only the closing summary")
    a = p.parse_args(argv)
    if a.count < 0 or not a.timeout > 0 or not a.window > 0:
        p.error("--count must be >= 0, --timeout and --window > 0")
    return a


def open_until(what: str, opener, timeout_s: float, rig: str):
    """Calls `opener()` until the service exists, up to `timeout_s` seconds."""
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            return opener()
        except (iox2.PublishSubscribeOpenError, iox2.EventOpenError) as e:
            if e.args != ("DoesNotExist",):
                raise Stop(f"cannot open {what}: {e!r} (is the rig built from the same sources?)") from e
        if time.monotonic() >= deadline:
            raise Stop(
                f"no rig `{rig}` within {timeout_s:g} s ({what} does not exist): "
                f"start `sil-host run --rig {rig}` (add --monitors 1 to get every sample)"
            )
        time.sleep(0.01)


class Plot:
    """A live figure: z_t, f_n and the contact mode against simulated time."""

    def __init__(self, window_s: float):
        import matplotlib.pyplot as plt  # optional: requirements-plot.txt

        self.plt = plt
        self.window = window_s
        self.t: list[float] = []
        self.series: list[list[float]] = [[], [], []]
        plt.ion()
        self.fig, axes = plt.subplots(3, 1, sharex=True, figsize=(8, 6))
        labels = ["z_t (m)", "f_n (N)", "mode"]
        self.lines = [ax.plot([], [], drawstyle="steps-post" if i == 2 else "default")[0] for i, ax in enumerate(axes)]
        for ax, label in zip(axes, labels):
            ax.set_ylabel(label)
            ax.grid(True)
        axes[2].set_yticks(list(MODES), list(MODES.values()))
        axes[2].set_ylim(-0.5, 2.5)
        axes[2].set_xlabel("t (s)")
        self.axes = axes
        self.last_draw = 0.0

    def add(self, g: GroundTruth) -> None:
        self.t.append(g.t)
        for s, v in zip(self.series, (g.z[0], g.f[1], float(g.mode))):
            s.append(v)

    def draw(self, force: bool = False) -> None:
        now = time.monotonic()
        if not self.t or (not force and now - self.last_draw < 0.05):
            return
        self.last_draw = now
        t0 = self.t[-1] - self.window
        i = next((k for k in range(len(self.t) - 1, -1, -1) if self.t[k] < t0), -1) + 1
        del self.t[:i]
        for s in self.series:
            del s[:i]
        for line, s in zip(self.lines, self.series):
            line.set_data(self.t, s)
        for ax in self.axes[:2]:
            ax.relim()
            ax.autoscale_view()
        self.axes[0].set_xlim(max(t0, 0.0), max(self.t[-1], t0 + self.window))
        self.fig.canvas.draw_idle()
        self.plt.pause(0.001)

    def keep(self) -> None:
        self.draw(force=True)
        self.plt.ioff()
        self.plt.show()


def run(a: argparse.Namespace) -> int:
    iox2.set_log_level_from_env_or(iox2.LogLevel.Error)
    # Python's own SIGINT handling (KeyboardInterrupt), not iceoryx2's.
    node = iox2.NodeBuilder.new().signal_handling_mode(iox2.SignalHandlingMode.Disabled).create(iox2.ServiceType.Ipc)
    name = iox2.ServiceName.new(f"painleve/{a.rig}/ground_truth")
    # Open, never create: the rig makes the services with the attributes it
    # documents (a subscriber buffer of 1024 here; iceoryx2's default is 2).
    service = open_until(
        f"painleve/{a.rig}/ground_truth", lambda: node.service_builder(name).publish_subscribe(GroundTruth).open(), a.timeout, a.rig
    )
    # The plant creates the event after its publisher: subscribing once the event is
    # there connects the subscriber to the publisher at once (docs/rig.md, "Monitors").
    event = open_until(f"the event painleve/{a.rig}/ground_truth", lambda: node.service_builder(name).event().open(), a.timeout, a.rig)
    subscriber = service.subscriber_builder().create()
    listener = event.listener_builder().create()

    out = open(a.csv, "w", encoding="utf-8", newline="") if a.csv else None
    if out:
        out.write(",".join(CSV_COLUMNS) + "\n")
    plot = Plot(a.window) if a.plot else None
    received = missing = 0
    first = last = None
    latest = None
    had_publisher = False
    last_print = 0.0
    interrupted = False
    try:
        while True:
            got = 0
            while not a.count or received < a.count:
                sample = subscriber.receive()
                if sample is None:
                    break
                g = GroundTruth.from_buffer_copy(sample.payload().contents)
                sample.delete()  # hands the slot back to the plant at once
                got += 1
                received += 1
                if last is not None and g.seq > last + 1:
                    missing += g.seq - last - 1
                first = g.seq if first is None else first
                last = g.seq
                latest = g
                if out:
                    out.write(
                        f"{g.seq},{g.t!r},{g.z[0]!r},{g.z[1]!r},{g.f[0]!r},{g.f[1]!r},{MODES.get(g.mode, g.mode)},{g.lift_off}\n"
                    )
                if plot:
                    plot.add(g)
            if a.count and received >= a.count:
                break
            now = time.monotonic()
            if latest is not None and not a.quiet and now - last_print >= 0.1:
                last_print = now
                print(
                    f"t = {latest.t:8.3f} s  z_t = {latest.z[0]:+.5f} m  f_n = {latest.f[1]:8.3f} N  "
                    f"mode = {MODES.get(latest.mode, latest.mode):8s}  received {received}, missing {missing}",
                    flush=True,
                )
            if plot:
                plot.draw()
            if got:
                continue
            publishers = service.dynamic_config.number_of_publishers
            had_publisher = had_publisher or publishers > 0
            if had_publisher and publishers == 0:
                # The plant is gone: what it sent is queued already; take it and stop.
                if subscriber.has_samples():
                    continue
                break
            # Woken by the plant's notification, or every 100 ms to look again.
            try:
                listener.timed_wait(iox2.Duration.from_millis(100))
            except iox2.ListenerWaitError as e:
                # A signal (Ctrl-Z then `fg`) cuts the wait short: look again.
                if e.args != ("InterruptSignal",):
                    raise
    except KeyboardInterrupt:
        interrupted = True
    finally:
        if out:
            out.close()
    span = f", seq {first}..{last}" if first is not None else ""
    print(f"monitor: received {received} samples{span}, missing {missing}", file=sys.stderr)
    if plot and not interrupted:
        plot.keep()
    return 130 if interrupted else 0


def stop_on_sigterm(_signum, _frame) -> None:
    """SIGTERM stops the monitor as Ctrl-C does (what was received is written)."""
    raise KeyboardInterrupt


def main(argv: list[str]) -> int:
    a = parse_args(argv)
    signal.signal(signal.SIGTERM, stop_on_sigterm)
    try:
        return run(a)
    except Stop as e:
        print(f"monitor: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("monitor: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
