"""Issue 80, 8: the package writes its files as ``sil-host`` writes its outputs
(sil-host/src/output.rs, tests/e2e/binary.rs
``run_writes_no_trace_through_a_link_planted_in_its_folder``): never through a
symbolic link planted at the output name (the link is replaced by the file, its
target left as it was, a dangling link's target not made), whole or not at all
(a temporary file in the same folder renamed into place: a write that fails part
way leaves the previous file, or nothing, at the name, and no temporary file).

Every method that writes a file is covered: ``Result.write_page``, and
``Result.write_mcap`` of a run in memory (the Rust writer) and of a loaded folder
(a copy of its ``trace.mcap``)."""

import os
import subprocess
import sys
import textwrap

import pytest

import painleve

from conftest import cli


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """``{name: (result, write(result, path))}``: each way the package writes a file."""
    mcap_dir = tmp_path_factory.mktemp("loaded") / "mcap"
    cli("run", ["--in-process", "--duration", "0.2", "--format", "mcap"], mcap_dir)
    sim = painleve.simulate(x0="a", duration=0.5, progress=False)
    run = painleve.run(duration=0.2, progress=False)
    return {
        "write_page": (sim, lambda r, p: r.write_page(p)),
        "write_mcap simulate": (sim, lambda r, p: r.write_mcap(p)),
        "write_mcap run": (run, lambda r, p: r.write_mcap(p)),
        "write_mcap loaded": (painleve.load(mcap_dir), lambda r, p: r.write_mcap(p)),
    }


WAYS = ["write_page", "write_mcap simulate", "write_mcap run", "write_mcap loaded"]


def _expected(results, way, tmp_path):
    """The bytes ``way`` writes at a plain path (no link there)."""
    r, write = results[way]
    plain = tmp_path / "plain" / "out"
    plain.parent.mkdir()
    return write(r, plain).read_bytes()


def _leftovers(folder):
    """Temporary files (``.NAME.XXXXXX.partial``) left in ``folder``."""
    return sorted(n for n in os.listdir(folder) if n.endswith(".partial"))


@pytest.mark.parametrize("way", WAYS)
def test_a_link_planted_at_the_output_name_is_replaced_and_its_target_kept(results, way, tmp_path):
    r, write = results[way]
    expected = _expected(results, way, tmp_path)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    victim = tmp_path / "victim.txt"
    victim.write_bytes(b"keep")
    # A link to an existing file, at a name given as a file and at the name a folder gets.
    for name in ("given.out", "trace.html" if way == "write_page" else "trace.mcap"):
        planted = out_dir / name
        planted.symlink_to(victim)
        written = write(r, planted if name == "given.out" else out_dir)
        assert written == planted
        assert victim.read_bytes() == b"keep", f"{way}: written through the link at {name}"
        assert not planted.is_symlink() and planted.is_file(), f"{way}: the link at {name} is replaced by a file"
        assert planted.read_bytes() == expected, way
    # A dangling link: nothing is made at its target.
    absent = tmp_path / "absent"
    dangling = out_dir / "dangling.out"
    dangling.symlink_to(absent)
    write(r, dangling)
    assert not absent.exists(), f"{way}: a file made through a dangling link"
    assert not dangling.is_symlink() and dangling.read_bytes() == expected
    # A link at the temporary name the CLI uses is not followed either (the
    # package's temporary names are its own: the link is left alone).
    cli_partial = out_dir / ".again.out.partial"
    cli_partial.symlink_to(victim)
    write(r, out_dir / "again.out")
    assert victim.read_bytes() == b"keep" and (out_dir / "again.out").read_bytes() == expected
    assert _leftovers(out_dir) == [".again.out.partial"] and cli_partial.is_symlink()


@pytest.mark.parametrize("way", WAYS)
def test_a_write_that_cannot_start_leaves_the_name_as_it_was(results, way, tmp_path):
    r, write = results[way]
    # A missing folder: FileNotFoundError naming the file, nothing made.
    missing = tmp_path / "no" / "such" / "folder" / "f.out"
    with pytest.raises(FileNotFoundError, match="no/such/folder/f.out"):
        write(r, missing)
    assert not (tmp_path / "no").exists()
    # A folder at the name a folder gets (out/trace.*): refused, the folder kept, nothing left.
    out_dir = tmp_path / "out"
    (out_dir / ("trace.html" if way == "write_page" else "trace.mcap")).mkdir(parents=True)
    with pytest.raises(IsADirectoryError):
        write(r, out_dir)
    assert _leftovers(out_dir) == []


# A write that fails part way, as a full disk would: the child process may write
# files of at most 4 KiB (RLIMIT_FSIZE; root too), so every file here fails
# mid-write with EFBIG ("File too large") once its first 4 KiB are out.
_MID_WRITE = textwrap.dedent(
    """
    import resource, signal, sys
    import painleve
    way, folder, out = sys.argv[1:4]
    if way == "write_mcap loaded":
        r = painleve.load(folder)
    elif way == "write_mcap run":
        r = painleve.run(duration=0.2, progress=False)
    else:
        r = painleve.simulate(x0="a", duration=0.5, progress=False)
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (4096, resource.RLIM_INFINITY))
    try:
        (r.write_page if way == "write_page" else r.write_mcap)(out)
    except OSError as e:
        print(type(e).__name__, e)
        sys.exit(3)
    """
)


@pytest.mark.parametrize("way", WAYS)
def test_a_write_that_fails_part_way_leaves_no_partial_file(results, way, tmp_path):
    r, write = results[way]
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    loaded_dir = results["write_mcap loaded"][0].path
    for before in (b"the previous file", None):
        out = out_dir / ("kept.out" if before else "new.out")
        if before is not None:
            out.write_bytes(before)
        p = subprocess.run(
            [sys.executable, "-c", _MID_WRITE, way, str(loaded_dir), str(out)], capture_output=True, text=True, timeout=300
        )
        assert p.returncode == 3, f"{way}: exit {p.returncode}\n{p.stdout}\n{p.stderr}"
        if before is None:
            assert not out.exists(), f"{way}: a partial file at the output name"
        else:
            assert out.read_bytes() == before, f"{way}: the previous file was overwritten"
        assert _leftovers(out_dir) == [], f"{way}: temporary files left"
        assert "File too large" in p.stdout and str(out) in p.stdout, f"the error names the file: {p.stdout}"
    # The same write without the limit succeeds (the limit, not the write, failed above).
    assert write(r, out_dir / "new.out").stat().st_size > 4096
