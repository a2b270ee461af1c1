"""planner/validation.py: numbers, outputs, sizes and strict JSON; and the readers' limits that use it."""
from __future__ import annotations

import gzip
import io
import json
import math

import numpy as np
import pytest

from planner.files import OutputError
from planner.decision.io import PomdpxError, pomdpx
from planner.decision.io.sparse_tables import SparseTable
from planner.validation import (
    CappedReader,
    InputError,
    InputLimitError,
    InputLimits,
    OutputExistsError,
    check_number,
    check_output,
    json_loads,
)


@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "1e400", float("nan"), "x", "", None])
def test_non_finite_or_unreadable_numbers_are_refused_with_the_name(value):
    with pytest.raises(InputError, match=r"^--size: must be a finite number"):
        check_number(value, "--size")


@pytest.mark.parametrize("value, low, high, low_open, high_open, integer, ok", [
    ("0", 0, 1, False, True, False, True), ("1", 0, 1, False, True, False, False),   # --discount
    ("0", 0, None, True, False, False, False), ("1e-9", 0, None, True, False, False, True),
    ("1e9", 1, 10 ** 7, False, False, True, False), ("1e3", 1, 10 ** 7, False, False, True, True),
    ("1.5", None, None, False, False, True, False), ("-3", None, None, False, False, True, True),
])
def test_ranges(value, low, high, low_open, high_open, integer, ok):
    if ok:
        number = check_number(value, "--x", low, high, low_open, high_open, integer)
        assert math.isfinite(number) and (isinstance(number, int) if integer else True)
    else:
        with pytest.raises(InputError, match="--x: must be"):
            check_number(value, "--x", low, high, low_open, high_open, integer)


def test_check_output(tmp_path):
    assert check_output(tmp_path / "new.txt") == tmp_path / "new.txt"
    (tmp_path / "old.txt").write_text("x")
    with pytest.raises(OutputExistsError, match="old.txt: the file exists already; pass --force"):
        check_output(tmp_path / "old.txt")
    assert check_output(tmp_path / "old.txt", force=True)
    with pytest.raises(OutputExistsError, match="never replaced"):
        check_output(tmp_path / "old.txt", force=True, replaceable=False)
    with pytest.raises(OutputError, match="create the folder"):
        check_output(tmp_path / "nodir" / "x.txt")
    with pytest.raises(OutputError, match="a folder, but the output is a file"):
        check_output(tmp_path)


def test_strict_json():
    assert json_loads('{"a": [1, 2.5, "[[{"]}', "x") == {"a": [1, 2.5, "[[{"]}
    assert json_loads("[" * 100 + "]" * 100, "x") is not None  # at the limit
    with pytest.raises(InputLimitError, match="x.json: nested 101 levels deep"):
        json_loads("[" * 101 + "]" * 101, "x.json")
    with pytest.raises(InputLimitError, match="nested 100000 levels"):  # no RecursionError
        json_loads("[" * 100000 + "]" * 100000, "x.json")
    for text, problem in (("[1e400]", "1e400"), ("[NaN]", "NaN"), ("[-Infinity]", "Infinity"),
                          ("[" + "9" * 5001 + "]", "5,001 digits")):
        with pytest.raises(InputError, match=problem):
            json_loads(text, "x.json")
    with pytest.raises(json.JSONDecodeError):
        json_loads("{", "x.json")


def test_capped_reader_stops_at_the_limit():
    reader = CappedReader(io.BytesIO(b"x" * 100), 60, "f.gz")
    assert reader.read(50) == b"x" * 50
    with pytest.raises(InputLimitError, match="f.gz: more than 60 bytes"):
        reader.read(50)


def test_a_gzip_bomb_is_decompressed_only_up_to_the_limit(tmp_path):
    path = tmp_path / "bomb.pomdpx.gz"
    with gzip.open(path, "wb") as handle:
        # 4 MiB of comments (the parser drops them: neither an element limit nor memory stops them)
        handle.write(b"<pomdpx>" + (b"<!--" + b"x" * 1016 + b"-->") * 4096 + b"</pomdpx>")
    assert path.stat().st_size < 2 ** 16
    with pytest.raises(PomdpxError, match=r"bomb.pomdpx.gz: more than 1,048,576 bytes \(decompressed\)"):
        pomdpx.read_pomdpx(path, InputLimits(file_bytes=2 ** 20))


def test_spread_cells_are_counted_before_anything_is_allocated():
    table = SparseTable((2, 3000, 3000), cell_limit=5_000_000)
    with pytest.raises(InputLimitError, match="9,000,000 cells"):
        table.set((0, None, None), 1 / 3000)
    assert table.spread_cells == 9_000_000 and not table.listed


def test_spread_cells_limit():
    table = SparseTable((1, 2000, 2000), cell_limit=5_000_000)
    table.set((0, None, None), 0.0)  # zeros spread nothing
    table.set((0, None, None), 1 / 2000)  # 4,000,000 cells
    table.set_identity((0, None, None), (1, 2))  # the diagonal: 2,000 more
    table.set_listed((0, 5, None), (2,), np.ones(2000))  # one row: 2,000 more
    assert table.spread_cells == 4_004_000
    with pytest.raises(InputLimitError, match="8,004,000 cells of a table of shape 1 x 2000 x 2000"):
        table.set_listed((0, None, None), (2,), np.ones(2000) / 2000)  # a row spread over every state
    assert SparseTable((1, 2000, 2000), cell_limit=None).set((0, None, None), 1.0) is None  # no limit
