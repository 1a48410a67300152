"""Fuzzing the readers of user input: every case is a correct result or one
SkinnyInputError, never another exception.

Inputs: trajectory files (.npz, .csv), ASF/AMC and BVH motion capture, training configs
(TrainConfig.from_dict), run files and a sweep's config.json, each made by mutating a
valid file (truncation, dropped/duplicated lines, tokens replaced by NaN/inf/huge/
negative/garbage, latin-1 and random bytes, wrong shapes and dtypes) or from scratch.
The CLI is fuzzed in tests/test_fuzz_cli.py.

Examples per test: ``FUZZ_EXAMPLES`` (small by default; ``HYPOTHESIS_PROFILE=ci-long``
runs 20x as many). ``pytest --hypothesis-show-statistics`` prints how many each tried.
"""

from __future__ import annotations

import io
import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, example, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from skinny_mj.errors import SkinnyInputError  # noqa: E402
from skinny_mj.plant import body  # noqa: E402
from skinny_mj.training.config import LEGACY_KEYS, TrainConfig  # noqa: E402
from skinny_mj.trajectories import Trajectory, load_movement, ymca  # noqa: E402

DATA = Path(__file__).parent / "data"
LONG = os.environ.get("HYPOTHESIS_PROFILE") == "ci-long"
FUZZ_EXAMPLES = 600 if LONG else 12
FUZZ = settings(max_examples=FUZZ_EXAMPLES, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])

#: Tokens a damaged or hostile file may hold where a number belongs.
BAD_TOKENS = ["nan", "NaN", "inf", "-inf", "1e309", "-1e309", "1e300", "-1e300", "-0",
              "0x1f", "", "1,5", "1.2.3", "--1", "\x00", "\u00e9", "9" * 400, "-1", "0",
              "1e-320", "2147483648", "-2147483649"]


def _valid(traj: Trajectory, dof: int | None = None) -> None:
    """What a loader that did not raise must give: a well-formed trajectory."""
    assert isinstance(traj, Trajectory)
    assert traj.angles.ndim == 2 and len(traj) >= 1 and traj.dof == traj.skinny.dof
    assert np.all(np.isfinite(traj.angles)) and math.isfinite(traj.dt) and traj.dt > 0
    if dof is not None:
        assert traj.dof == dof


@st.composite
def mutated_text(draw, text: str) -> bytes:
    """``text`` with a few random edits, as bytes (sometimes not UTF-8)."""
    lines = text.splitlines()
    for _ in range(draw(st.integers(1, 4))):
        if not lines:
            break
        i = draw(st.integers(0, len(lines) - 1))
        op = draw(st.sampled_from(["token", "drop", "dup", "garbage", "truncate", "swap"]))
        if op == "token":
            tok = lines[i].split(",") if "," in lines[i] else lines[i].split()
            if tok:
                tok[draw(st.integers(0, len(tok) - 1))] = draw(
                    st.sampled_from(BAD_TOKENS) | st.text(max_size=8))
                lines[i] = ("," if "," in lines[i] else " ").join(tok)
        elif op == "drop":
            del lines[i]
        elif op == "dup":
            lines.insert(i, lines[i])
        elif op == "garbage":
            lines[i] = draw(st.text(max_size=40))
        elif op == "truncate":
            lines = lines[:i]
        else:
            j = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
    out = "\n".join(lines).encode("utf-8", "surrogatepass")
    if draw(st.booleans()):
        out = out[: draw(st.integers(0, len(out)))]  # cut mid-line, mid-character
    if draw(st.integers(0, 9)) == 0:
        out = out.replace(b"e", b"\xe9")  # latin-1 bytes: not UTF-8
    return out


def _write(data: bytes, suffix: str) -> Path:
    fd, name = tempfile.mkstemp(suffix=suffix)
    with os.fdopen(fd, "wb") as fh:
        fh.write(data)
    return Path(name)


def _loads_or_input_error(path: Path, dof: int | None = None, **kwargs) -> None:
    """The property: a valid trajectory, or one SkinnyInputError; nothing else."""
    try:
        try:
            traj, report = load_movement(str(path), dof or 4, **kwargs)
        except SkinnyInputError as err:
            assert "\n" not in str(err)
            return
        _valid(traj, dof)
    finally:
        path.unlink(missing_ok=True)


def _csv_text(dof: int = 4) -> str:
    tmp = _write(b"", ".csv")
    Trajectory(ymca(dof).angles[:12], name="fuzz").save(tmp)
    text = tmp.read_text()
    tmp.unlink()
    return text


CSV_4 = _csv_text(4)


@FUZZ
@given(data=mutated_text(CSV_4) | st.binary(max_size=300))
def test_fuzz_csv_trajectory(data):
    _loads_or_input_error(_write(data, ".csv"))


def _npz_bytes(**arrays) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


VALID_NPZ = _npz_bytes(angles=ymca(4).angles[:10], meta=np.array(json.dumps(
    {"format_version": 1, "name": "fuzz", "dt": 0.02, "dof": 4,
     "dof_names": list(body.body_of(4).dof_names)})))
_DTYPES = ["float64", "float32", "float16", "int64", "int8", "uint8", "bool", "complex128",
           "U4", "S4", "datetime64[s]"]


@st.composite
def npz_files(draw) -> bytes:
    kind = draw(st.sampled_from(["arrays", "truncated", "bytes", "flipped"]))
    if kind == "truncated":
        return VALID_NPZ[: draw(st.integers(0, len(VALID_NPZ) - 1))]
    if kind == "bytes":
        return draw(st.binary(max_size=200))
    if kind == "flipped":
        data = bytearray(VALID_NPZ)
        for _ in range(draw(st.integers(1, 8))):
            data[draw(st.integers(0, len(data) - 1))] = draw(st.integers(0, 255))
        return bytes(data)
    shape = draw(st.lists(st.integers(0, 9), min_size=0, max_size=3))
    dtype = draw(st.sampled_from(_DTYPES))
    fill = draw(st.sampled_from([0.1, np.nan, np.inf, -np.inf, 1e300, -1e300, -5.0, 7]))
    with np.errstate(all="ignore"):
        angles = np.full(shape, fill).astype(dtype) if dtype[0] not in "US" \
            else np.full(shape, "ab", dtype=dtype)
    meta = draw(st.sampled_from([
        json.dumps({"dt": draw(st.sampled_from([0.02, 0, -1, 1e-300, 1e300, "x", None]))}),
        json.dumps({"dof": draw(st.integers(-3, 9)), "name": "../../escape"}),
        json.dumps({"dof_names": ["a", "b"]}), json.dumps([1, 2]), "{not json", ""]))
    arrays = {"angles": angles, "meta": np.array(meta)}
    if draw(st.booleans()):
        del arrays[draw(st.sampled_from(["angles", "meta"]))]
    if draw(st.integers(0, 5)) == 0:
        arrays["meta"] = np.array([{"pickled": 1}], dtype=object)  # must never be unpickled
    if not arrays:
        return _npz_bytes(other=np.zeros(2))
    return _npz_bytes(**arrays)


@FUZZ
@given(data=npz_files())
def test_fuzz_npz_trajectory(data):
    _loads_or_input_error(_write(data, ".npz"))


ASF_TEXT = (DATA / "tiny.asf").read_text()
AMC_TEXT = (DATA / "tiny.amc").read_text()
BVH_TEXT = (DATA / "arms.bvh").read_text()


@FUZZ
@given(asf=mutated_text(ASF_TEXT) | st.just(ASF_TEXT.encode()),
       amc=mutated_text(AMC_TEXT) | st.binary(max_size=200), dof=st.sampled_from([4, 8]))
@example(asf=ASF_TEXT.encode(), amc=b"\xb9", dof=4)  # a digit (¹) that int() refuses
def test_fuzz_asf_amc(asf, amc, dof):
    asf_path = _write(asf, ".asf")
    try:
        _loads_or_input_error(_write(amc, ".amc"), dof, asf=str(asf_path))
    finally:
        asf_path.unlink()


@FUZZ
@given(data=mutated_text(BVH_TEXT) | st.binary(max_size=200), dof=st.sampled_from([4, 8]))
def test_fuzz_bvh(data, dof):
    _loads_or_input_error(_write(data, ".bvh"), dof)


_FIELDS = sorted({k for choice in ({}, {"method": "true-target"}, {"actuation": "torque"},
                                    {"forward": "parallel"}, {"method": "original"})
                   for k in TrainConfig().override(choice).to_dict()} | set(LEGACY_KEYS))
_VALUES = (st.none() | st.booleans() | st.integers(-10**12, 10**12)
           | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=12)
           | st.lists(st.integers(), max_size=3) | st.dictionaries(st.text(max_size=3),
                                                                    st.integers(), max_size=2))


@FUZZ
@given(changes=st.dictionaries(st.sampled_from(_FIELDS) | st.text(max_size=8), _VALUES,
                               max_size=4))
def test_fuzz_train_config_from_dict(changes):
    """A config file's fields of any type and value: a valid TrainConfig (whose fields
    survive a JSON round trip) or one SkinnyInputError."""
    base = TrainConfig().to_dict()
    try:
        cfg = TrainConfig.from_dict({**base, **changes})
    except SkinnyInputError as err:
        assert "\n" not in str(err)
        return
    again = TrainConfig.from_dict(json.loads(json.dumps(cfg.to_dict())))
    assert again == cfg


_JSON = st.recursive(st.none() | st.booleans() | st.integers() | st.floats() | st.text(),
                     lambda kids: st.lists(kids, max_size=3)
                     | st.dictionaries(st.text(max_size=6), kids, max_size=3), max_leaves=8)


@FUZZ
@given(value=_JSON, key=st.sampled_from(["status", "row", "seed", "metrics", "row_index",
                                          "run_index", "experiment", None]),
       raw=st.none() | st.binary(max_size=60))
def test_fuzz_run_file_is_valid_or_a_clear_error(value, key, raw, tmp_path_factory):
    from skinny_mj.engine.stats import load_run

    rec = {"experiment": "x", "row": "a", "row_index": 0, "run_index": 0, "seed": 1,
           "status": "ok", "metrics": {"m": 1.0}}
    if key is None:
        rec = value
    else:
        rec[key] = value
    path = tmp_path_factory.mktemp("run") / "a-1.json"
    path.write_bytes(raw if raw is not None else json.dumps(rec).encode())
    try:
        got = load_run(path)
    except SkinnyInputError as err:
        assert "\n" not in str(err)
        return
    assert got["status"] in ("ok", "failed", "error") and isinstance(got["metrics"], dict)


@FUZZ
@given(content=st.binary(max_size=80) | _JSON.map(lambda v: json.dumps(v).encode()))
def test_fuzz_resume_config_json(content, tmp_path_factory):
    """--resume reads the folder's config.json: anything there is the same sweep (runs
    it) or one SkinnyInputError; the file is never half-rewritten."""
    from toy import toy

    from skinny_mj.engine.experiment import Row, run_sweep

    out = tmp_path_factory.mktemp("sweep")
    (out / "runs").mkdir()
    (out / "config.json").write_bytes(content)
    exp = toy("fz", (Row("a"),), lambda row, seed: {"m": 1.0}, runs=1)
    try:
        run_sweep(exp, out, workers=1, resume=True, progress=False)
    except SkinnyInputError as err:
        assert "\n" not in str(err)
        assert (out / "config.json").read_bytes() == content
    assert not list(out.rglob("*.tmp"))
