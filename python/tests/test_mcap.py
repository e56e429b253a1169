"""``--format mcap`` (issues 44 and 55): ``trace.mcap`` holds what the CSV tables
hold, read back two ways: with the ``mcap`` package's own readers and Google's
protobuf runtime (the file as Foxglove sees it: channels, protobuf schemas and
messages, log times) and with ``painleve.load``. Floats compare to the bit:
the messages' ``double`` fields carry the values' bits."""

import json
import os
import signal
import struct
import subprocess
import time

import numpy as np
import pytest

import painleve
from conftest import REPO, assert_columns_equal, cli, sil_host

mcap_reader = pytest.importorskip("mcap.reader")
mcap_protobuf = pytest.importorskip("mcap_protobuf.decoder")
descriptor_pb2 = pytest.importorskip("google.protobuf.descriptor_pb2")

# A bouncing run from x0a (touchdowns and an impact without collision), so the
# events table has several kinds and resolutions.
ARGS = ["--x0", "a", "--v-belt", "-0.5", "--e-n", "0.2", "--duration", "2"]

SIMULATE_TOPICS = {"/state", "/contact", "/events"}
RUN_TOPICS = {"/state", "/contact", "/torques", "/firmware"}
# What crossed the wire each period (the `frames` table: frame, arm state, command, telemetry; `sil-host replay`).
WIRE_TOPICS = {"/wire/frame", "/wire/arm", "/wire/command", "/wire/telemetry"}
# The arm in Foxglove's own schemas (arm-view: protobuf), beside the tables' channels.
FOXGLOVE = {"/tf": "foxglove.FrameTransforms", "/scene": "foxglove.SceneUpdate", "/log": "foxglove.Log"}


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    root = tmp_path_factory.mktemp("mcap")
    cli("simulate", ARGS + ["--format", "csv"], root / "csv")
    cli("simulate", ARGS + ["--format", "mcap"], root / "mcap")
    return root / "csv", root / "mcap"


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("mcap-run")
    cli("run", ["--in-process", "--duration", "1", "--format", "csv"], root / "csv")
    cli("run", ["--in-process", "--duration", "1", "--format", "mcap"], root / "mcap")
    return root / "csv", root / "mcap"


def by_reader(path):
    """The file through the ``mcap`` package's indexed reader, every message
    decoded by its channel's schema with Google's protobuf runtime: ``{topic:
    [(log time, sequence, {field: value})]}`` of the tables' channels, the
    summary; the arm's channels (Foxglove's schemas, ``FOXGLOVE``) are all there,
    every one of their messages at a log time of the trace."""
    with open(path, "rb") as f:
        reader = mcap_reader.make_reader(f, decoder_factories=[mcap_protobuf.DecoderFactory()])
        summary = reader.get_summary()
        assert summary is not None, "a finished file has its summary"
        out = {}
        foxglove = {}
        for schema, channel, message, decoded in reader.iter_decoded_messages(log_time_order=False):
            assert (channel.message_encoding, schema.encoding) == ("protobuf", "protobuf"), channel.topic
            if channel.topic in FOXGLOVE:
                assert schema.name == FOXGLOVE[channel.topic]
                foxglove.setdefault(channel.topic, []).append(message.log_time)
                continue
            fields = {d.name: getattr(decoded, d.name) for d in decoded.DESCRIPTOR.fields}
            out.setdefault(channel.topic, []).append((message.log_time, message.sequence, fields))
    assert set(foxglove) == set(FOXGLOVE), sorted(foxglove)
    times = {ns for ns, _, _ in out["/state"]}
    assert set(foxglove["/tf"]) <= times and foxglove["/tf"] == foxglove["/scene"]
    return out, summary


def assert_equals_csv(messages, csv_table, topics):
    """Each CSV column is in exactly one of ``topics``' messages (``t`` in all),
    row ``k`` the ``k``-th message; every value equal, floats to the bit."""
    n = csv_table.nrows
    assert n > 1
    for topic in topics:
        assert len(messages[topic]) == n, topic
        assert [seq for _, seq, _ in messages[topic]] == list(range(n)), topic
        t = np.array([m["t"] for _, _, m in messages[topic]])
        assert np.array_equal(t.view(np.int64), csv_table["t"].view(np.int64)), f"{topic}.t"
        # Log time: t in ns of simulated time.
        assert [ns for ns, _, _ in messages[topic]] == [round(x * 1e9) for x in csv_table["t"]], topic
    for col in csv_table.columns:
        if col == "t":
            continue
        holders = [tp for tp in topics if col in messages[tp][0][2]]
        assert len(holders) == 1, f"{col} in {holders}"
        cells = [m[col] for _, _, m in messages[holders[0]]]
        want = csv_table[col]
        if want.dtype.kind == "f":
            got = np.array([np.nan if c is None else c for c in cells], dtype=np.float64)
            assert np.array_equal(got.view(np.int64), want.view(np.int64)), col
        else:
            assert list(cells) == want.tolist(), col
    grouped = {k for tp in topics for k in messages[tp][0][2]}
    assert grouped == set(csv_table.columns), "no column added or lost"


def test_simulate_writes_one_mcap_file_equal_to_its_csv_tables(folders):
    csv_dir, mcap_dir = folders
    assert sorted(p.name for p in mcap_dir.iterdir()) == ["summary.json", "trace.html", "trace.mcap", "trace.pdf", "trace.svg"]
    c = painleve.load(csv_dir)
    messages, summary = by_reader(mcap_dir / "trace.mcap")
    assert set(messages) == SIMULATE_TOPICS
    assert_equals_csv(messages, c.trace, ["/state", "/contact"])
    assert_equals_csv(messages, c.events, ["/events"])
    assert c.events.nrows > 5 and len(set(c.events["kind"])) >= 2
    # Statistics and indexes for Foxglove's seeking: every message counted: two per
    # sample, one per event, and the arm's (a frame and a scene every 10 ms of the 1 ms
    # samples, a log line per event).
    frames = (c.trace.nrows - 1) // 10 + 1
    assert summary.statistics.message_count == 2 * c.trace.nrows + c.events.nrows + 2 * frames + c.events.nrows
    assert summary.statistics.message_end_time == round(c.trace["t"][-1] * 1e9)
    assert len(summary.chunk_indexes) >= 1
    files = json.loads((mcap_dir / "summary.json").read_text())["files"]
    assert [f.rsplit("/", 1)[-1] for f in files] == ["trace.mcap", "trace.svg", "trace.pdf", "trace.html", "summary.json"]


def test_the_protobuf_schemas_describe_every_field_with_its_type_and_unit(folders):
    _, mcap_dir = folders
    with open(mcap_dir / "trace.mcap", "rb") as f:
        summary = mcap_reader.make_reader(f).get_summary()
    fdp = descriptor_pb2.FieldDescriptorProto
    units = {}
    for channel in summary.channels.values():
        schema = summary.schemas[channel.schema_id]
        assert schema.encoding == "protobuf", channel.topic
        if channel.topic in FOXGLOVE:
            # Foxglove's own schemas (checked in tests/e2e/foxglove_view.rs).
            continue
        files = descriptor_pb2.FileDescriptorSet.FromString(schema.data).file
        assert len(files) == 1 and files[0].syntax == "proto3", channel.topic
        (message,) = files[0].message_type
        assert f"{files[0].package}.{message.name}" == schema.name and schema.name.startswith("painleve."), schema.name
        assert message.field[0].name == "t" and [f.number for f in message.field] == list(range(1, len(message.field) + 1))
        for field in message.field:
            assert field.type in (fdp.TYPE_DOUBLE, fdp.TYPE_STRING, fdp.TYPE_BOOL, fdp.TYPE_INT64), (channel.topic, field.name)
        # Each field's meaning and unit, as its comment.
        comments = {tuple(loc.path): loc.leading_comments for loc in files[0].source_code_info.location}
        for k, field in enumerate(message.field):
            assert comments[(4, 0, 2, k)].strip(), (channel.topic, field.name)
            units[(channel.topic, field.name)] = comments[(4, 0, 2, k)]
    assert "rad" in units[("/state", "theta1")] and "m/s" in units[("/contact", "z_n_dot")]


def test_painleve_load_reads_the_mcap_tables_as_the_csv_ones(folders):
    csv_dir, mcap_dir = folders
    m, c = painleve.load(mcap_dir), painleve.load(csv_dir)
    assert m.command == c.command == "simulate"
    assert sorted(m.tables) == sorted(c.tables) == ["events", "trace"]
    for name in ("trace", "events"):
        assert m.tables[name].columns == c.tables[name].columns, name
        for col in c.tables[name].columns:
            x, y = m.tables[name][col], c.tables[name][col]
            assert_columns_equal(x, y, f"{name}.{col}")
            if x.dtype.kind == "f":
                assert np.array_equal(x.view(np.int64), y.view(np.int64)), f"{name}.{col}"


def test_a_runs_mcap_trace_equals_its_csv(runs):
    csv_dir, mcap_dir = runs
    c = painleve.load(csv_dir)
    messages, summary = by_reader(mcap_dir / "trace.mcap")
    assert set(messages) == RUN_TOPICS | WIRE_TOPICS
    assert c.trace.nrows == c.frames.nrows == 1000
    assert_equals_csv(messages, c.trace, ["/state", "/contact", "/torques", "/firmware"])
    assert_equals_csv(messages, c.frames, ["/wire/frame", "/wire/arm", "/wire/command", "/wire/telemetry"])
    # A chunk of the table's rows per 100 periods (count-based, so the bytes are the
    # same on every link), each followed by a chunk of the arm's messages of those
    # periods (/tf and /scene, a frame every 10 ms, and /log when a line was written).
    topics = {c.id: c.topic for c in summary.channels.values()}
    kinds = [sorted(topics[i] for i in c.message_index_offsets) for c in sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)]
    # (One chunk of schemas and channels per table, trace's then frames', before the rows.)
    assert kinds[0] == kinds[1] == [] and len(kinds) == 22, kinds
    assert all(k == sorted(RUN_TOPICS | WIRE_TOPICS) for k in kinds[2::2]), kinds
    assert all(set(k) >= {"/tf", "/scene"} and set(k) <= set(FOXGLOVE) for k in kinds[3::2]), kinds
    m = painleve.load(mcap_dir)
    assert m.command == "run" and list(m.tables) == ["trace", "frames"]
    for name in ("trace", "frames"):
        for col in c.tables[name].columns:
            assert_columns_equal(m.tables[name][col], c.tables[name][col], f"{name}.{col}")


def test_a_cut_mcap_file_gives_its_whole_chunks(runs, tmp_path):
    csv_dir, mcap_dir = runs
    c = painleve.load(csv_dir).trace
    data = (mcap_dir / "trace.mcap").read_bytes()
    seen = set()
    for frac in (0.15, 0.5, 0.8):
        cut = tmp_path / "trace.mcap"
        cut.write_bytes(data[: int(len(data) * frac)])
        tables = painleve.read_mcap(cut)
        t = tables["trace"]
        assert 0 < t.nrows < c.nrows and t.nrows % 100 == 0, (frac, t.nrows)
        seen.add(t.nrows)
        for col in c.columns:
            assert_columns_equal(t[col], c[col][: t.nrows], f"{frac}: trace.{col}")
        # The mcap package's linear reader reads the same messages up to the cut.
        with open(cut, "rb") as f:
            reader = mcap_reader.NonSeekingReader(f)
            n = 0
            try:
                for _, channel, _ in reader.iter_messages(log_time_order=False):
                    n += channel.topic == "/state"
            except Exception:  # the cut record
                pass
        assert n == t.nrows
    assert len(seen) == 3


def record_offsets(data):
    """``[(start, head end, end)]`` of the records of a whole MCAP file (the
    specification's framing: 8 magic bytes, then opcode u8, body length u64 LE,
    body), up to and with the Footer."""
    out, pos = [], 8
    while pos + 9 <= len(data):
        opcode, length = struct.unpack_from("<BQ", data, pos)
        out.append((pos, pos + 9, pos + 9 + length))
        pos += 9 + length
        if opcode == 0x02:
            break
    return out


def test_a_file_cut_at_any_byte_reads_as_its_whole_records(runs, tmp_path):
    # A killed run's file ends anywhere: at a record boundary, inside a record's
    # 9-byte head or inside its body. Cut the whole file there: the reader gives of
    # each table a prefix of the whole table's rows, never an error but "no table"
    # before the table's metadata is whole, more rows for a later cut, and all of
    # them once the cut is past the data (inside the summary or the closing magic).
    _, mcap_dir = runs
    data = (mcap_dir / "trace.mcap").read_bytes()
    full = painleve.read_mcap(mcap_dir / "trace.mcap")["trace"]
    records = record_offsets(data)
    assert len(records) > 24 and records[-1][2] == len(data) - 8
    cuts = set()
    for start, head_end, end in records[:12] + records[-12:]:
        cuts |= {start, start + 1, start + 5, head_end, (head_end + end) // 2}
    cuts |= {len(data) - 4, len(data)}
    cut_file = tmp_path / "trace.mcap.partial"
    last_rows = 0
    for cut in sorted(cuts):
        cut_file.write_bytes(data[:cut])
        try:
            t = painleve.read_mcap(cut_file)["trace"]
        except painleve.PainleveError as e:
            assert "no table" in str(e) and last_rows == 0, f"cut at {cut}: {e}"
            continue
        assert t.nrows >= last_rows, f"cut at {cut}: {t.nrows} rows after {last_rows}"
        last_rows = t.nrows
        for col in full.columns:
            assert_columns_equal(t[col], full[col][: t.nrows], f"cut at {cut}: trace.{col}")
    assert last_rows == full.nrows
    # The end of the last MessageIndex record (opcode 0x07), which follows the last chunk.
    data_end = max(end for start, _, end in records if data[start] == 0x07)
    cut_file.write_bytes(data[:data_end])
    assert painleve.read_mcap(cut_file)["trace"].nrows == full.nrows, "every chunk whole: every row"


# Trace rows per chunk of a streamed run (tables::mcap::STREAM_CHUNK_ROWS): a
# chunk goes out, both tables' waiting rows in it, when the trace has this many.
STREAM_CHUNK_ROWS = 100


def test_a_killed_run_keeps_the_chunks_it_wrote(runs, tmp_path):
    # Issue 80, 9. SIGKILL part way: trace.mcap.partial holds whole chunks, and
    # nothing here depends on when the kill lands (a loaded machine writes fewer
    # chunks by then) nor on how the trace's and the frames' rows share the bytes.
    # What the file guarantees: it reads back; the reader gets every whole chunk
    # (as many messages as the mcap package's linear reader finds before the
    # cut); each table's rows are a prefix of a full run's rows, the same values
    # (lockstep: the same rows every time); the trace's rows are whole chunks.
    csv_dir, _ = runs
    out = tmp_path / "killed"
    argv = [str(sil_host()), "run", "--in-process", "--duration", "600", "--format", "mcap", "--out", str(out), "--json"]
    p = subprocess.Popen(argv, cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    partial = out / "trace.mcap.partial"

    def trace_rows():
        """The trace rows the file holds now, 0 before it is made and before its
        first chunk of rows is whole."""
        try:
            return painleve.read_mcap(partial)["trace"].nrows
        except (FileNotFoundError, painleve.PainleveError, KeyError):
            return 0

    # Killed once it holds a chunk of rows (within milliseconds; the deadline only
    # stops a broken run from hanging the suite).
    deadline = time.monotonic() + 120
    try:
        while p.poll() is None and time.monotonic() < deadline and trace_rows() == 0:
            time.sleep(0.01)
    finally:
        os.kill(p.pid, signal.SIGKILL)
        p.wait()
    assert p.returncode == -signal.SIGKILL, f"the run ended by itself ({p.returncode}) before it was killed"
    tables = painleve.read_mcap(partial)
    t, frames = tables["trace"], tables["frames"]
    assert t.nrows >= STREAM_CHUNK_ROWS, "at least one chunk"
    assert t.nrows % STREAM_CHUNK_ROWS == 0, f"{t.nrows} trace rows: whole chunks only"
    # A full run at least as long as what the killed one wrote (1 s: 1000 periods).
    periods = max(t.nrows, frames.nrows)
    if periods > 1000:
        csv_dir = tmp_path / "full"
        cli("run", ["--in-process", "--duration", str(periods // 1000 + 1), "--format", "csv"], csv_dir)
    full = painleve.load(csv_dir)
    for name, got in (("trace", t), ("frames", frames)):
        whole = full.tables[name]
        assert 0 < got.nrows <= whole.nrows, (name, got.nrows, whole.nrows)
        assert got.columns == whole.columns, name
        for col in whole.columns:
            assert_columns_equal(got[col], whole[col][: got.nrows], f"{name}.{col}: the killed run's rows are the full run's first rows")
    # What else reads it (docs/rig.md "MCAP traces"; issue 66): the mcap package's
    # linear reader in file order gives every message of the whole chunks, then
    # EndOfFile at the cut; with its default log_time_order=True it sorts the whole
    # file first and so gives nothing before EndOfFile; the seeking reader refuses the file.
    from mcap.exceptions import EndOfFile

    def linear(**kw):
        n = {"/state": 0, "/wire/frame": 0}
        with open(partial, "rb") as f:
            with pytest.raises(EndOfFile):
                for _, channel, _ in mcap_reader.NonSeekingReader(f).iter_messages(**kw):
                    if channel.topic in n:
                        n[channel.topic] += 1
        return n

    assert linear(log_time_order=False) == {"/state": t.nrows, "/wire/frame": frames.nrows}, "every whole chunk read"
    assert linear() == {"/state": 0, "/wire/frame": 0}
    seeking = 0
    try:
        with open(partial, "rb") as f:
            seeking = sum(c.topic == "/state" for _, c, _ in mcap_reader.make_reader(f).iter_messages())
    except Exception:  # the footer it starts from is not there
        pass
    assert seeking < t.nrows


def test_the_format_option_lists_mcap_and_an_unknown_one_is_refused():
    from conftest import cli_error

    message, code = cli_error("run", ["--format", "bag"])
    assert code == 2 and "bag" in message and "mcap" in message
    help_text = subprocess.run([str(sil_host()), "simulate", "--help"], capture_output=True, text=True).stdout
    assert "mcap" in help_text and "trace.mcap" in help_text


def test_without_the_mcap_package_load_still_reads_the_trace(folders, monkeypatch):
    # The package reads MCAP with its own (Rust) reader: the `mcap` Python
    # package is needed only by this file's cross-checks.
    import sys

    csv_dir, mcap_dir = folders
    for mod in [m for m in sys.modules if m == "mcap" or m.startswith("mcap.")]:
        monkeypatch.delitem(sys.modules, mod)
    monkeypatch.setitem(sys.modules, "mcap", None)
    m, c = painleve.load(mcap_dir), painleve.load(csv_dir)
    assert m.trace.nrows == c.trace.nrows > 0


def test_a_file_that_is_not_mcap_is_an_error_naming_it(tmp_path):
    bad = tmp_path / "trace.mcap"
    bad.write_text("t,theta1\n0,1\n")
    # A file being read that cannot be: "cannot read", never "cannot write" (issue 66).
    with pytest.raises(painleve.PainleveError, match="^cannot read .*trace.mcap"):
        painleve.read_mcap(bad)


def log_lines(path):
    """The ``/log`` channel's messages (``foxglove.Log``), their text in order."""
    with open(path, "rb") as f:
        reader = mcap_reader.make_reader(f, decoder_factories=[mcap_protobuf.DecoderFactory()])
        return [decoded.message for _, _, _, decoded in reader.iter_decoded_messages(topics=["/log"], log_time_order=False)]


def run_metadata(path):
    """The file's ``painleve.run`` metadata record (``law``), or ``None``."""
    with open(path, "rb") as f:
        for record in mcap_reader.make_reader(f).iter_metadata():
            if record.name == "painleve.run":
                return dict(record.metadata)
    return None


def test_the_log_names_the_law_that_ran(tmp_path):
    # Issue 84: a trace says which law ran, at its first period: the paper's laws
    # by the firmware's controller, a Python callable by its name (a law of one's
    # own: test_impedance_prototype.py, through the command line).
    for controller in ("pid", "hybrid"):
        r = painleve.run(controller=controller, duration=0.05, progress=False)
        path = r.write_mcap(tmp_path / f"{controller}.mcap")
        lines = log_lines(path)
        assert lines[0] == f"control law: {controller}" and lines[1].startswith("start: contact mode "), lines[:3]
        # The same words in summary.json (written by the rig) and the file's metadata.
        assert r.summary["law"] == r.law == controller, (r.summary["law"], r.law)
        assert run_metadata(path) == {"law": controller}, run_metadata(path)

    def my_law(t, sensed):
        return (0.0, 0.0)

    r = painleve.run_controller(my_law, duration=0.05)
    path = r.write_mcap(tmp_path / "mine.mcap")
    lines = log_lines(path)
    assert lines[0] == f"control law: Python {my_law.__qualname__}", lines[:3]
    assert r.summary["law"] == r.law == f"Python {my_law.__qualname__}", r.summary["law"]
    assert run_metadata(path) == {"law": r.law}, run_metadata(path)
    # A simulation runs no law: no record, no words.
    s = painleve.simulate(duration=0.01)
    assert s.law is None and run_metadata(s.write_mcap(tmp_path / "open.mcap")) is None
