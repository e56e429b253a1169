"""The speed of painleve.read_csv / painleve.load against pandas.read_csv, of
painleve.read_arrow against pandas.read_feather, and of painleve.read_mcap
(docs/python.md, "Reading tables"): wall time to read a table the CLI wrote, median of N runs in one
sitting, each reader in turn. The tables: a 300 s open-loop trace (`simulate
--duration 300`: 300 001 rows x 14 columns, 66 MB of CSV, 34 MB of Arrow) and a
62 s closed-loop trace (`run --in-process --duration 62`: 62 000 rows x 21
columns, 17 MB), written by the CLI into a temporary folder first.

    cargo build --release -p sil-host
    python examples/python/read_speed.py [--runs 7] [--sil-host target/release/sil-host]

The tests' pure-Python reference (python/tests/reference_csv.py: the `csv`
module, each cell read by Python) is timed too when it is there.
"""

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import painleve

REPO = Path(__file__).resolve().parents[2]


def median_s(call, runs):
    """Median wall time and median CPU time (this process, all its threads) of ``runs`` calls."""
    wall, cpu = [], []
    for _ in range(runs):
        started, cpu_started = time.perf_counter(), time.process_time()
        call()
        wall.append(time.perf_counter() - started)
        cpu.append(time.process_time() - cpu_started)
    return statistics.median(wall), statistics.median(cpu)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--sil-host", default=str(REPO / "target" / "release" / "sil-host"))
    args = ap.parse_args()
    try:
        import pandas as pd
    except ImportError:
        pd = None
    sys.path.insert(0, str(REPO / "python" / "tests"))
    try:
        from reference_csv import reference_read_csv
    except ImportError:
        reference_read_csv = None
    with tempfile.TemporaryDirectory() as d:
        root = Path(d)
        tables = {
            "simulate --duration 300": (["simulate", "--duration", "300"], root / "sim"),
            "run --in-process --duration 62": (["run", "--in-process", "--duration", "62"], root / "run"),
        }
        for argv, out in tables.values():
            subprocess.run([args.sil_host, *argv, "--out", str(out), "--json"], check=True, capture_output=True, cwd=REPO)
            arrow = Path(str(out) + "-arrow")
            subprocess.run([args.sil_host, *argv, "--format", "arrow", "--out", str(arrow), "--json"], check=True, capture_output=True, cwd=REPO)
            mcap = Path(str(out) + "-mcap")
            subprocess.run([args.sil_host, *argv, "--format", "mcap", "--out", str(mcap), "--json"], check=True, capture_output=True, cwd=REPO)
        print(f"painleve {painleve.__version__}" + (f", pandas {pd.__version__}" if pd else ", no pandas") + f", median of {args.runs} runs")
        for what, (_, out) in tables.items():
            csv = out / "trace.csv"
            t = painleve.read_csv(csv)
            mb = csv.stat().st_size / 1e6
            print(f"\n{what}: trace.csv, {t.nrows} rows x {len(t)} columns, {mb:.1f} MB")
            ours = median_s(lambda: painleve.read_csv(csv), args.runs)
            print(f"  {'':24} {'wall':>7}   {'CPU':>7}")
            print(f"  painleve.read_csv        {ours[0]:7.3f} s {ours[1]:7.3f} s   {mb / ours[0]:4.0f} MB/s")
            w, c = median_s(lambda: painleve.load(out), args.runs)
            print(f"  painleve.load (folder)   {w:7.3f} s {c:7.3f} s")
            if pd is not None:
                w, c = median_s(lambda: pd.read_csv(csv), args.runs)
                print(f"  pandas.read_csv          {w:7.3f} s {c:7.3f} s   {mb / w:4.0f} MB/s   pandas / painleve: wall {w / ours[0]:.2f}, CPU {c / ours[1]:.2f}")
            if reference_read_csv is not None:
                w, c = median_s(lambda: reference_read_csv(csv), max(1, args.runs // 3))
                print(f"  Python csv reference     {w:7.3f} s {c:7.3f} s   reference / painleve: wall {w / ours[0]:.0f}")
            arrow = Path(str(out) + "-arrow") / "trace.arrow"
            ours = median_s(lambda: painleve.read_arrow(arrow), args.runs)
            print(f"  painleve.read_arrow      {ours[0]:7.3f} s {ours[1]:7.3f} s   ({arrow.stat().st_size / 1e6:.1f} MB)")
            if pd is not None:
                w, c = median_s(lambda: pd.read_feather(arrow), args.runs)
                print(f"  pandas.read_feather      {w:7.3f} s {c:7.3f} s   pandas / painleve: wall {w / ours[0]:.2f}, CPU {c / ours[1]:.2f}")
            mcap = Path(str(out) + "-mcap") / "trace.mcap"
            w, c = median_s(lambda: painleve.read_mcap(mcap), args.runs)
            print(f"  painleve.read_mcap       {w:7.3f} s {c:7.3f} s   ({mcap.stat().st_size / 1e6:.1f} MB)")

if __name__ == "__main__":
    main()
