"""A short fuzzing run of the CSV and YAML loaders (issue 7, item 7).

Whatever bytes a data set's files hold, loading either succeeds or raises ``DataError``; never
another exception (which the command line would show as a traceback). Three fuzzers, bounded
to a few hundred examples each (well under 30 s together):

* arbitrary bytes as a table, and as ``meta.yaml``;
* mutations of a valid data set (byte flips, insertions, deletions, and splices of tokens
  that broke or could break the loaders: ``nan``, ``1e999``, separators, quotes, NUL, BOMs,
  YAML tags, impossible dates, deep nesting, huge integers);
* YAML documents built from arbitrary nested values for every ``meta.yaml`` key.

``IMBENCH_FUZZ_EXAMPLES`` sets the examples per fuzzer for a longer session.

Crashes this found, now fixed in ``benchmark/core/tables.py`` and ``benchmark/problems/timedomain/data.py`` (the
``@example`` lines keep them as regressions): ``ValueError`` for a YAML date that does not
exist (``2001-02-30``), ``RecursionError`` for deeply nested YAML, ``OverflowError`` for a
400-digit integer as ``sample_time``/``inertia``, ``IsADirectoryError`` for a folder named
``stop.csv``; non-finite ``inf`` accepted as ``sample_time``/``inertia`` and
``pole_pairs: 10**400`` accepted (crashes later); overflow to ``inf`` in the Clarke
transform of huge phase values accepted as data.
"""

from __future__ import annotations

import os
import tempfile
import warnings
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from benchmark.core.errors import DataError
from benchmark.core.meta_file import read_meta
from benchmark.core.tables import read_table
from benchmark.problems.timedomain.data import load_startup_dataset

pytestmark = pytest.mark.filterwarnings("ignore::benchmark.core.errors.DataWarning")

#: examples per fuzzer; a longer session: IMBENCH_FUZZ_EXAMPLES=20000 python -m pytest tests/core/test_fuzz.py
FUZZ = settings(
    max_examples=int(os.environ.get("IMBENCH_FUZZ_EXAMPLES", "250")),
    deadline=None,
    suppress_health_check=list(HealthCheck),
)

GOOD_META = b"kind: startup\npole_pairs: 1\nsample_time: 0.001\ninput_hold: zoh\nsupply_frequency: 50.0\n"
GOOD_STARTUP = b"t,v_alpha,v_beta,i_alpha,i_beta,speed\n" + b"".join(
    f"{k * 0.001},{300 * (k % 7 - 3)},{-200 + k},{0.5 * k},{-0.25 * k},{k * 1.5}\n".encode()
    for k in range(25)
)
GOOD_STOP = b"t,speed\n" + b"".join(f"{k * 0.001},{100 - 3 * k}\n".encode() for k in range(30))

TOKENS = [
    b"nan",
    b"inf",
    b"-inf",
    b"1e999",
    b"-1e-400",
    b"9" * 400,
    b",",
    b";",
    b"\t",
    b"\n",
    b"\r",
    b"\r\n",
    b"\x00",
    b"\xef\xbb\xbf",
    b"\xff\xfe",
    b'"',
    b"'",
    b" ",
    b"",
    b"!!binary",
    b"!!python/object:os.system",
    b"2001-02-30",
    b"[" * 200,
    b"{",
    b"- ",
    b": ",
    b"? ",
    b"&a ",
    b"*a",
    b"<<: ",
    b"---\n",
    b"...\n",
    b"%YAML 1.1\n",
    b"0x1F",
    b"1_000",
    b"1,5",
    b"\xc3\x28",
    b"\xe2\x80\xa8",
    b"t",
    b"speed",
    b"v_r,v_s,v_t",
    b"pole_pairs: ",
    b"sample_time: ",
    b".inf",
    b"-.nan",
    b"~",
    b"true",
    b"1e308",
]


@st.composite
def mutated(draw, data: bytes):
    b = bytearray(data)
    for _ in range(draw(st.integers(1, 8))):
        op = draw(st.integers(0, 4))
        pos = draw(st.integers(0, len(b)))
        if op == 0 and pos < len(b):
            b[pos] = draw(st.integers(0, 255))
        elif op == 1:
            b[pos:pos] = draw(st.binary(min_size=1, max_size=4))
        elif op == 2:
            del b[pos : pos + draw(st.integers(1, 40))]
        elif op == 3:
            b[pos:pos] = draw(st.sampled_from(TOKENS))
        else:  # splice a line of the file elsewhere (reordered, repeated rows)
            lines = bytes(b).split(b"\n")
            k = draw(st.integers(0, len(lines) - 1))
            lines.insert(draw(st.integers(0, len(lines))), lines[k])
            b = bytearray(b"\n".join(lines))
    return bytes(b)


def _load(files: dict[str, bytes]):
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        for name, data in files.items():
            (folder / name).write_bytes(data)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                load_startup_dataset(folder)
            except DataError:
                pass


@FUZZ
@given(st.binary(max_size=400))
@example(b"t,speed\n0,1\n")
@example(b"\xef\xbb\xbft,speed\n0,1\n0.001,2\n")
@example(b'"t,speed\n0,1\n')
@example(b"t;speed\n0,5;1,5\n0,6;2.5\n")
def test_arbitrary_bytes_as_a_table(data):
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "table.csv"
        path.write_bytes(data)
        try:
            read_table(path, [("t", "speed")], optional=("v",))
        except DataError:
            pass


@FUZZ
@given(st.binary(max_size=300))
@example(b"sample_time: 2001-02-30\npole_pairs: 1\n")
@example(b"[" * 5000)
@example(b"pole_pairs: 1\nsample_time: " + b"9" * 400 + b"\n")
@example(b"? [a]\n: 1\n")
@example(b"!!binary 'a'")
def test_arbitrary_bytes_as_meta_yaml(data):
    with tempfile.TemporaryDirectory() as d:
        (Path(d) / "meta.yaml").write_bytes(data)
        try:
            read_meta(Path(d), {"pole_pairs": int, "sample_time": float})
        except DataError:
            pass


@FUZZ
@given(mutated(GOOD_META), mutated(GOOD_STARTUP), st.one_of(st.none(), mutated(GOOD_STOP)))
@example(GOOD_META + b"inertia: " + b"9" * 400 + b"\n", GOOD_STARTUP, None)
@example(GOOD_META.replace(b"0.001", b"1e400"), GOOD_STARTUP, None)
@example(GOOD_META.replace(b"pole_pairs: 1", b"pole_pairs: " + b"9" * 400), GOOD_STARTUP, None)
@example(GOOD_META, b"t,v_r,v_s,v_t,i_r,i_s,speed\n0,1e308,-1e308,-1e308,1,1,1\n0.001,1,1,1,1,1,1\n", None)
@example(GOOD_META, GOOD_STARTUP, b"t,speed\n-1e308,1\n1e308,1\n")
def test_mutated_data_set(meta, startup, stop):
    files = {"meta.yaml": meta, "startup.csv": startup}
    if stop is not None:
        files["stop.csv"] = stop
    _load(files)


def test_folder_named_like_a_table():
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        (folder / "meta.yaml").write_bytes(GOOD_META)
        (folder / "startup.csv").write_bytes(GOOD_STARTUP)
        (folder / "stop.csv").mkdir()
        with pytest.raises(DataError, match="stop.csv: not a regular file"):
            load_startup_dataset(folder)


yaml_scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(),
    st.floats(),
    st.text(max_size=20),
    st.binary(max_size=8),
    st.dates(),
    st.datetimes(),
)
yaml_values = st.recursive(
    yaml_scalars,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=4)
    ),
    max_leaves=10,
)
META_KEYS = [
    "kind",
    "pole_pairs",
    "sample_time",
    "input_hold",
    "dc_link_voltage",
    "supply_frequency",
    "inertia",
    "decimate",
]


@FUZZ
@given(st.dictionaries(st.sampled_from(META_KEYS + ["other"]), yaml_values, max_size=8), st.booleans())
def test_meta_yaml_with_arbitrary_values(meta, complete):
    if complete:
        meta = {"pole_pairs": 1, "sample_time": 0.001, **meta}
    try:
        text = yaml.safe_dump(meta).encode()
    except yaml.YAMLError:
        return
    _load({"meta.yaml": text, "startup.csv": GOOD_STARTUP, "stop.csv": GOOD_STOP})
