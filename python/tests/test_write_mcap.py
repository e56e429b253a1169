"""Issue 69 (2): a run's result writes its Foxglove file. ``Result.write_mcap`` gives
the bytes ``sil-host ... --format mcap`` writes as ``trace.mcap`` for the same run
(the tables' channels and the arm's ``/tf``, ``/scene`` and ``/log``), for
``simulate`` (over random open-loop runs, not only the default) and ``run``; a
``run_controller`` result's file reads back as its own table; a loaded folder
copies its file; what holds no run says so."""

import random

import numpy as np
import pytest

import painleve

from conftest import cli


def _same_file(tmp_path, r, argv, command):
    cli(command, [*argv, "--format", "mcap"], tmp_path / "cli")
    written = r.write_mcap(tmp_path)
    assert written == tmp_path / "trace.mcap"
    expected = (tmp_path / "cli" / "trace.mcap").read_bytes()
    got = written.read_bytes()
    assert len(got) == len(expected) and got == expected, f"{len(got)} bytes written, the CLI's file has {len(expected)}"
    return written


def test_a_simulates_mcap_is_the_clis_byte_for_byte(tmp_path):
    # The 10 s bounce from x0a: 10 001 samples in several 1 MiB chunks, 60 events among them.
    r = painleve.simulate(x0="a", progress=False)
    written = _same_file(tmp_path, r, ["--x0", "a"], "simulate")
    tables = dict(painleve.read_mcap(written))
    assert int((tables["events"]["kind"] == "touchdown").sum()) == int((r.events["kind"] == "touchdown").sum()) >= 20
    np.testing.assert_array_equal(tables["trace"]["z_t"], r.trace["z_t"])


def _random_case(seed):
    g = random.Random(seed)
    kwargs = {
        "x0": g.choice(["a", "d", "u"]),
        "mu": round(g.uniform(0.2, 0.8), 3),
        "v_belt": round(g.uniform(-1.0, 1.0), 3),
        "e_n": g.choice([0.0, 0.2, 0.5]),
        "duration": round(g.uniform(1.0, 4.0), 2),
        "sample_dt": g.choice([1e-3, 5e-4, 2e-3]),
    }
    argv = [a for k, v in kwargs.items() for a in (f"--{k.replace('_', '-')}", str(v))]
    return kwargs, argv


@pytest.mark.parametrize("seed", range(4))
def test_random_open_loop_runs_write_the_clis_file(tmp_path, seed):
    kwargs, argv = _random_case(6900 + seed)
    r = painleve.simulate(progress=False, **kwargs)
    _same_file(tmp_path, r, argv, "simulate")


def test_a_runs_mcap_is_the_clis_byte_for_byte(tmp_path):
    r = painleve.run(duration=1.0, progress=False)
    written = _same_file(tmp_path, r, ["--in-process", "--duration", "1"], "run")
    trace = dict(painleve.read_mcap(written))["trace"]
    assert len(trace["t"]) == r.trace.nrows == 1000


def test_a_python_controllers_run_writes_its_records(tmp_path):
    r = painleve.run_controller(lambda t, sensed: (0.1, -0.05), duration=0.2)
    written = r.write_mcap(tmp_path / "mine.mcap")
    trace = dict(painleve.read_mcap(written))["trace"]
    assert list(trace) == list(r.trace.columns)
    for column in trace:
        np.testing.assert_array_equal(trace[column], r.trace[column])


def test_a_loaded_folder_copies_its_file_or_says_why_not(tmp_path):
    cli("simulate", ["--x0", "a", "--duration", "1", "--format", "mcap"], tmp_path / "mcap")
    copied = painleve.load(tmp_path / "mcap").write_mcap(tmp_path / "copy.mcap")
    assert copied.read_bytes() == (tmp_path / "mcap" / "trace.mcap").read_bytes()
    cli("simulate", ["--x0", "a", "--duration", "1"], tmp_path / "csv")
    with pytest.raises(ValueError, match="no trace.mcap"):
        painleve.load(tmp_path / "csv").write_mcap(tmp_path / "x.mcap")
    with pytest.raises(ValueError, match="no run"):
        painleve.admissible().write_mcap(tmp_path / "y.mcap")


@pytest.mark.parametrize("fmt", ["csv", "arrow"])
def test_a_loaded_runs_csv_or_arrow_folder_writes_the_clis_mcap(tmp_path, fmt):
    # Issue 84: a run's tables and summary hold every row the file needs: the same
    # bytes as `--format mcap` of the same run, the law's /log and metadata included.
    args = ["--in-process", "--duration", "1.5", "--scenario", "scenarios/pid-x0u.toml", "--no-page"]
    cli("run", [*args, "--format", fmt], tmp_path / fmt)
    cli("run", [*args, "--format", "mcap"], tmp_path / "mcap")
    written = painleve.load(tmp_path / fmt).write_mcap(tmp_path / "from-folder.mcap")
    assert written.read_bytes() == (tmp_path / "mcap" / "trace.mcap").read_bytes()


def test_an_unwritable_path_is_an_os_error(tmp_path):
    r = painleve.simulate(x0="a", duration=0.1, progress=False)
    with pytest.raises(OSError):
        r.write_mcap(tmp_path / "no" / "such" / "folder" / "t.mcap")


def test_a_runs_frames_are_the_clis_frames_csv(tmp_path):
    # The wire record `sil-host replay` reads: every frame and answer, to the bit.
    cli("run", ["--in-process", "--duration", "0.5"], tmp_path / "cli")
    r = painleve.run(duration=0.5, progress=False)
    loaded = painleve.load(tmp_path / "cli")
    assert list(loaded.tables) == ["trace", "frames"] and list(r.tables) == ["trace", "frames"]
    assert r.frames.columns == loaded.frames.columns and r.frames.nrows == 500
    for column in r.frames.columns:
        a, b = np.asarray(r.frames[column]), np.asarray(loaded.frames[column])
        if a.dtype.kind == "f":
            assert np.array_equal(a.view(np.int64), b.view(np.int64)), column
        else:
            assert a.tolist() == b.tolist(), column
