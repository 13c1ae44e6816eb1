"""Saved states are plain numbers: what is written is read back bit for bit, anything else is
refused with the reason, and nothing read can run code.

The bytes are checked against numpy's own npz reader (``np.load(..., allow_pickle=False)``),
an independent reader of the same format. The physics states (every bearing model's warm
start, the structure's, the master's checkpoint) are checked by what they are for: a fresh
object restored from the bytes continues exactly as the original does.
"""

from __future__ import annotations

import io
import pickle
import struct
import zipfile

import numpy as np
import pytest
from numpy.lib import format as npy

from fmu_src.state_codec import FORMAT_VERSION, StateArrays, StateFormatError, decode, encode


class _WritesAFile:
    """Unpickling this creates ``path``: a pickle that runs code when it is loaded."""

    def __init__(self, path):
        self.path = str(path)

    def __reduce__(self):
        return (open, (self.path, "w"))


def _awkward_floats() -> np.ndarray:
    """Floats whose bits a careless copy changes: -0, NaN with a payload, inf, subnormals."""
    bits = np.array([0x8000000000000000, 0x7FF8000000000ABC, 0xFFF0000000000001,
                     0x7FF0000000000000, 0x0000000000000001, 0x3FF0000000000001],
                    dtype=np.uint64)
    return bits.view(np.float64)


def test_arrays_round_trip_bit_for_bit_and_numpy_reads_them_without_pickle():
    floats = _awkward_floats()
    arrays = {"a/floats": floats, "a/matrix": np.arange(12.0).reshape(3, 4).T,  # F order
              "n": np.int64(-(2**62)), "flags": np.array([True, False, True]),
              "blob": np.frombuffer(b"\x00\x80\xff", dtype=np.uint8), "text": "état 1",
              "empty": np.zeros((0, 3))}
    blob = encode("test", arrays)
    assert blob == encode("test", arrays)  # the bytes depend on the content only
    back = decode(blob, "test")
    got = back.array("a/floats", "float64", (6,))
    assert got.view(np.uint64).tolist() == floats.view(np.uint64).tolist()
    assert np.array_equal(back.array("a/matrix", "float64", (4, 3)), arrays["a/matrix"])
    assert back.int("n") == -(2**62) and back.text("text") == "état 1"
    assert back.array("flags", "bool", (3,)).tolist() == [True, False, True]
    assert back.bytes("blob") == b"\x00\x80\xff"
    assert back.array("empty", "float64", (0, 3)).shape == (0, 3)
    back.check_all_read()
    # numpy's reader, pickles forbidden: the same arrays, the version and the kind
    with np.load(io.BytesIO(blob), allow_pickle=False) as z:
        assert int(z["__format_version__"]) == FORMAT_VERSION and str(z["__kind__"]) == "test"
        assert z["a/floats"].view(np.uint64).tolist() == floats.view(np.uint64).tolist()
        assert np.array_equal(z["a/matrix"], arrays["a/matrix"])


def _npz(**arrays) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def _bad_states(tmp_path) -> list[tuple[str, bytes, str]]:
    """(case, bytes, words the refusal must contain)."""
    good = encode("test", {"x": np.zeros(3)})
    objects = io.BytesIO()
    np.savez(objects, __format_version__=np.int64(FORMAT_VERSION), __kind__=np.array("test"),
             x=np.array([{"a": 1}], dtype=object), allow_pickle=True)
    version = io.BytesIO()
    npy.write_array(version, np.int64(FORMAT_VERSION))
    header = io.BytesIO()  # a header claiming 1000 floats, 3 stored
    npy.write_array_header_1_0(header, npy.header_data_from_array_1_0(np.zeros(1000)))
    lying, extra = io.BytesIO(), io.BytesIO()
    with zipfile.ZipFile(lying, "w") as zf:
        zf.writestr("__format_version__.npy", version.getvalue())
        zf.writestr("x.npy", header.getvalue() + np.zeros(3).tobytes())
    with zipfile.ZipFile(extra, "w") as zf:
        zf.writestr("__format_version__.npy", version.getvalue())
        zf.writestr("payload.pkl", pickle.dumps(_WritesAFile(tmp_path / "marker")))
    return [
        ("pickle", pickle.dumps(_WritesAFile(tmp_path / "marker")), ["pickle", "refused"]),
        ("pickle protocol 2", pickle.dumps({"x": 1}, protocol=2), ["pickle (protocol 2)"]),
        ("text", b"not a state", ["not a saved state", "b'not a st"]),
        ("empty", b"", ["not a saved state"]),
        ("truncated zip", good[: len(good) // 2], ["not a readable npz"]),
        ("plain npz", _npz(x=np.zeros(3)), ["no format version"]),
        ("version 2", _npz(__format_version__=np.int64(2), __kind__=np.array("test"),
                           x=np.zeros(3)), ["format version 2", f"reads version {FORMAT_VERSION}"]),
        ("another kind", encode("other", {"x": np.zeros(3)}), ["'other' state", "'test'"]),
        ("object array", objects.getvalue(), ["'x'", "dtype object"]),
        ("float32", _npz(__format_version__=np.int64(FORMAT_VERSION), __kind__=np.array("test"),
                         x=np.zeros(3, dtype=np.float32)), ["'x'", "float32"]),
        ("big-endian", _npz(__format_version__=np.int64(FORMAT_VERSION),
                            __kind__=np.array("test"), x=np.zeros(3, dtype=">f8")),
         ["'x'", ">f8"]),
        ("lying header", lying.getvalue(), ["'x'", "24 bytes", "header says 8000"]),
        ("not an array", extra.getvalue(), ["payload.pkl", "not an array"]),
    ]


def test_anything_but_a_state_of_the_kind_is_refused_with_the_reason(tmp_path):
    for case, data, words in _bad_states(tmp_path):
        with pytest.raises(StateFormatError) as info:
            decode(data, "test", what="the checkpoint")
        message = str(info.value)
        assert message.startswith("the checkpoint"), (case, message)
        for w in words:
            assert w in message, (case, w, message)
    assert not (tmp_path / "marker").exists()  # no pickle was loaded
    # the real pickle does run code when loaded: the refusal is what kept the marker away
    pickle.loads(pickle.dumps(_WritesAFile(tmp_path / "marker"))).close()
    assert (tmp_path / "marker").exists()


def test_readers_refuse_missing_entries_wrong_dtypes_shapes_and_leftovers():
    s = decode(encode("test", {"x": np.zeros((4, 2)), "n": 3, "part/a": 1.0, "part/b": 2.0}),
               "test", what="the checkpoint")
    cases = [(lambda: s.array("y", "float64"), "lacks the entry 'y'"),
             (lambda: s.array("x", "int64"), "entry 'x' has dtype float64, expected int64"),
             (lambda: s.array("x", "float64", (4, 2, 2)),
              "entry 'x' has shape (4, 2), expected (4, 2, 2)"),
             (lambda: s.array("x", "float64", (None, 3)),
              "entry 'x' has shape (4, 2), expected ('any', 3)"),
             (lambda: s.float("n"), "entry 'n' has dtype int64, expected float64"),
             (lambda: s.sub("part").array("c", "float64"), "lacks the entry 'part/c'")]
    for call, words in cases:
        with pytest.raises(StateFormatError, match=None) as info:
            call()
        assert str(info.value) == f"the checkpoint{'' if 'lacks' in words else ':'} {words}"
    assert s.sub("part").float("a") == 1.0 and s.array("x", "float64", (None, 2)).shape == (4, 2)
    with pytest.raises(StateFormatError, match="unexpected entries 'n', 'part/b'"):
        s.check_all_read()


def test_encode_refuses_what_a_reader_would_refuse():
    with pytest.raises(TypeError, match="'x': dtype object is not allowed"):
        encode("test", {"x": np.array([None])})
    with pytest.raises(TypeError, match="'x': dtype float32 is not allowed"):
        encode("test", {"x": np.zeros(2, dtype=np.float32)})
    for name in ("", "__kind__", "a//b", "../x"):
        with pytest.raises(ValueError, match="state entry name"):
            encode("test", {name: 1.0})
    # a struct-packed big-endian float is stored little-endian, the same value
    be = np.frombuffer(struct.pack(">d", 1.5), dtype=">f8")
    assert decode(encode("t", {"x": be}), "t").array("x", "float64").tolist() == [1.5]


# --- physics states: a restored object continues exactly as the original ------------------------
def _bearing(model_name: str, nodes: int = 48):
    """A bearing model of the paper's pinion bearing on a coarse grid; ``"fd-direct"``: the
    FD model with its direct solver (whose active set is part of the state)."""
    from bearing_fmu import BearingData, model_class
    from bearing_fmu.fd.model import FiniteDifferenceBearing

    b = BearingData(0.07, 0.05, 150e-6, 0.0288)
    if model_name == "fd-direct":
        return FiniteDifferenceBearing(b, n_theta=nodes, n_xi=8, linear_solver="direct")
    options = {"nodes": nodes, "axial_intervals": 8}
    cls = model_class(model_name)
    return cls.from_parameters(b, **{o.key: options[o.key] for o in cls.options
                                     if o.key in options})


PATH = [(0.4, -0.3, 1e-3, 0.0), (0.45, -0.28, 2e-3, -1e-3), (-0.3, 0.5, -3e-3, 2e-3)]


@pytest.mark.parametrize("model_name", ["hybrid", "fd", "fd-direct", "linear", "short",
                                        "lumped"])
def test_every_bearing_model_state_restores_its_warm_start_exactly(model_name):
    """Evaluate along a path, save, evaluate on; a fresh model restored from the bytes gives
    the same results to the last bit (the warm start is the state: the hybrid and FD solvers
    start from it, the linear model from its frozen law)."""
    from fmu_src.states import bearing_state_arrays, restore_bearing_state

    c, omega = 150e-6, 325.0
    model = _bearing(model_name)
    for x, y, xd, yd in PATH[:2]:
        model.evaluate(x * c, y * c, xd, yd, omega)
    model.end_initialization(0.45 * c, -0.28 * c, omega)
    blob = encode("bearing", bearing_state_arrays(model))
    if model_name == "fd-direct":  # the direct solver's active set is in the state
        assert decode(blob, "bearing").has("active")
    after = [model.evaluate(x * c, y * c, xd, yd, omega) for x, y, xd, yd in PATH[::-1]]
    fresh = _bearing(model_name)
    arrays = decode(blob, "bearing")
    restore_bearing_state(fresh, arrays)
    arrays.check_all_read()
    assert encode("bearing", bearing_state_arrays(fresh)) == blob
    again = [fresh.evaluate(x * c, y * c, xd, yd, omega) for x, y, xd, yd in PATH[::-1]]
    for a, b in zip(after, again, strict=True):
        for name in ("force", "stiffness", "damping"):
            assert np.array_equal(getattr(a, name), getattr(b, name)), (model_name, name)


def test_a_bearing_state_of_another_size_is_refused_before_anything_changes():
    from fmu_src.states import bearing_state_arrays, restore_bearing_state

    small, large = _bearing("hybrid"), _bearing("hybrid", nodes=64)
    small.evaluate(6e-5, -4e-5, 0.0, 0.0, 325.0)
    before = encode("b", bearing_state_arrays(large))
    with pytest.raises(StateFormatError, match=r"entry 'active' has shape \(48,\), "
                                               r"expected \(64,\)"):
        restore_bearing_state(large, decode(encode("b", bearing_state_arrays(small)), "b"))
    assert encode("b", bearing_state_arrays(large)) == before


def test_master_checkpoint_restores_every_bearing_model_exactly_and_refuses_misfits():
    """In process: checkpoint after 3 steps; a fresh master restored from the bytes writes the
    same bytes and steps on as the original; arrays that do not fit are named."""
    from fmu_src import description
    from fmu_src.case import load_case
    from fmu_src.state_codec import nest
    from orchestrator.coupling.master import CHECKPOINT_KIND
    from orchestrator.run.runner import build_master

    case = load_case("baguet2010_spur", {"simulation.steps_per_mesh_period": 8,
                                         "bearings.*.nodes": 48, "bearings.*.axial_intervals": 8})
    dt = description.time_step(case)

    def started(model):
        m = build_master(case.with_overrides({"bearings.*.model": model}), in_process=True)
        m.solve_static()
        m.exit_initialization()
        return m

    for model in ("hybrid", "fd", "linear"):
        m = started(model)
        for k in range(3):
            m.step(k * dt, dt)
        blob = m.checkpoint()
        ref = [m.step(k * dt, dt).states for k in range(3, 6)]
        fresh = started(model)
        fresh.restore(blob)
        assert fresh.checkpoint() == blob, model
        got = [fresh.step(k * dt, dt).states for k in range(3, 6)]
        assert all(np.array_equal(a, b) for a, b in zip(ref, got, strict=True)), model
    # misfits: a structure state of another size, a checkpoint with an entry too many
    arrays = dict(np.load(io.BytesIO(blob), allow_pickle=False))
    del arrays["__format_version__"], arrays["__kind__"]
    short = arrays | {"structure/x": arrays["structure/x"][:-1]}
    n = arrays["structure/x"].size
    with pytest.raises(StateFormatError, match=rf"the checkpoint: entry 'structure/x' has "
                                               rf"shape \({n - 1},\), expected \({n},\)"):
        started("linear").restore(encode(CHECKPOINT_KIND, short))
    with pytest.raises(StateFormatError, match="unexpected entries 'extra/x'"):
        started("linear").restore(encode(CHECKPOINT_KIND, arrays | nest("extra", {"x": 1.0})))
    with pytest.raises(StateFormatError, match="lacks the entry 'laws/f0'"):
        started("linear").restore(encode(CHECKPOINT_KIND, {k: v for k, v in arrays.items()
                                                           if k != "laws/f0"}))


def test_a_part_taken_for_later_counts_as_read_and_the_rest_does_not():
    """The slaves keep a deserialised part (the model's, the structure's) as plain arrays and
    check it when the instance takes it: the part is not a leftover, other entries are."""
    s = StateArrays({"p/x": np.ones(2), "p/y/z": np.zeros(1), "q": np.zeros(1)}, "the state")
    part = s.part("p")
    assert sorted(part) == ["x", "y/z"] and np.array_equal(part["x"], np.ones(2))
    with pytest.raises(StateFormatError, match=r"unexpected entries 'q'$"):
        s.check_all_read()
