"""`painleve.replay` (a recorded run through the in-process firmware, every
answer compared bit for bit) against `sil-host replay --link in-process`: the
same verdict and document for a recording that replays identically, for a gain
changed in its last bit, and the same refusals for bad input."""

import json
import shutil

import numpy as np
import pytest

import painleve
from conftest import REPO, assert_docs_equal, assert_raises_like_cli, cli


def cli_replay(folder, *args):
    p = cli("replay", [str(folder), "--link", "in-process", *args], check=False)
    return p.returncode, json.loads(p.stdout)


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    """A 2 s hybrid run from x0d, recorded by the CLI (its frames.csv)."""
    out = tmp_path_factory.mktemp("replay") / "rec"
    cli("run", ["--in-process", "--scenario", "scenarios/hybrid-x0d.toml", "--duration", "2", "--no-page"], out)
    return out


def test_a_recording_replays_identically_as_the_cli_says(recording):
    mine = painleve.replay(recording, progress=False)
    code, theirs = cli_replay(recording)
    assert code == 0 and mine.failure is None and mine.exit_code == 0
    assert mine.summary["identical"] is True
    assert mine.summary["periods_replayed"] == mine.summary["periods_recorded"] == 2000
    assert_docs_equal(mine.summary, theirs)


def test_a_gain_changed_in_its_last_bit_diverges_where_the_cli_finds_it(recording):
    kp = float(np.nextafter(np.float32(900.0), np.float32(1e9)))
    with pytest.warns(painleve.PainleveWarning):
        mine = painleve.replay(recording, set={"controller.hybrid.kp": kp}, all=True, progress=False)
    code, theirs = cli_replay(recording, "--set", f"controller.hybrid.kp={kp!r}", "--all")
    assert (code, mine.exit_code) == (1, 1)
    s = mine.summary
    assert s["identical"] is False and s["first_divergence"] is not None
    assert 0 < s["divergent_periods"] <= s["periods_replayed"] == 2000
    assert mine.failure.startswith(f"the replay diverged from the recording at period {s['first_divergence']['period']}")
    # The overrides are given as the CLI's KEY=VALUE text; the rest is the CLI's document.
    assert_docs_equal(s, theirs, ignore={"wall_s", "overrides"})
    with pytest.raises(painleve.PainleveError) as e:
        painleve.replay(recording, set={"controller.hybrid.kp": kp}, strict=True, progress=False)
    assert e.value.exit_code == 1


def test_a_cut_recording_a_missing_folder_and_another_link_are_refused(recording, tmp_path):
    cut = tmp_path / "cut"
    shutil.copytree(recording, cut)
    text = (cut / "frames.csv").read_text()
    (cut / "frames.csv").write_text(text[: len(text) // 2].rsplit("\n", 1)[0] + "\n")
    assert_raises_like_cli(lambda: painleve.replay(cut, progress=False), "replay", [str(cut), "--link", "in-process"])
    missing = tmp_path / "nowhere"
    assert_raises_like_cli(lambda: painleve.replay(missing, progress=False), "replay", [str(missing), "--link", "in-process"])
    with pytest.raises(painleve.PainleveError) as e:
        painleve.replay(recording, link="twin", progress=False)
    assert e.value.exit_code == 2 and "`sil-host replay` replays over the twin link" in str(e.value)


@pytest.mark.parametrize("fmt", ["csv", "mcap"])
def test_a_replays_folder_loads_with_its_answers(recording, tmp_path, fmt):
    # `replay --out` (issue 84): the replayed answers as a run's frames table, the
    # comparison as its summary; `load` names the command and reads the frames.
    out = tmp_path / fmt
    p = cli("replay", [str(recording), "--link", "in-process", "--set", "controller.hybrid.kp=1000", "--all", "--format", fmt], out, check=False)
    assert p.returncode == 1, p.stderr
    r = painleve.load(out)
    assert r.command == "replay" and r.summary["divergent_periods"] == json.loads(p.stdout)["divergent_periods"]
    frames, recorded = r.tables["frames"], painleve.load(recording).tables["frames"]
    assert frames.nrows == recorded.nrows == 2000
    assert np.array_equal(np.asarray(frames["theta1_count"]), np.asarray(recorded["theta1_count"]))
    changed = np.asarray(frames["u1_code"]) != np.asarray(recorded["u1_code"])
    assert 0 < int(changed.sum()) <= r.summary["divergent_periods"]

