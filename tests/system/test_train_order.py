"""The paper's case written in the train schema with its shafts and bearings listed in another
order: other node and DOF numbers, the same physics (issue 44, item 7).

The case file's text is rewritten with the ``[shafts.*]`` and ``[bearings.*]`` tables in
reverse order; both cases run 4 mesh periods in-process through the master, and every channel
(each bearing's by its name) agrees with the shipped order within the golden run's tolerance: a
tenth of what halving the time step moves that channel (tests/golden.py, the recorded T/32 and
T/64 runs). Reordering changes only the order of sums in the assembly and the elimination, a
change of arithmetic, which is what that tolerance judges.
"""

from __future__ import annotations

import re

import numpy as np

from fmu_src.case import load_case, shipped_cases
from fmu_src.description import time_step
from orchestrator.coupling.system import build_master
from tests.golden import PERIODS, channel_tolerances, load_fixture


def _reordered_text(text: str) -> str:
    """The case's TOML with the tables of each of [shafts.*] and [bearings.*] in reverse
    order (each table kept whole: its header and its lines up to the next header)."""
    blocks = re.split(r"(?m)^(?=\[)", text)
    head = [b for b in blocks if not b.startswith("[")]
    tables = [b for b in blocks if b.startswith("[")]
    for kind in ("shafts", "bearings"):
        where = [i for i, b in enumerate(tables) if b.startswith(f"[{kind}.")]
        for i, block in zip(where, [tables[i] for i in reversed(where)], strict=True):
            tables[i] = block if block.endswith("\n") else block + "\n"
    return "".join(head + tables)


def _run(case, steps: int) -> dict:
    """Journal states, bearing forces (by bearing name), mesh force and transmission error of
    ``steps`` coupled steps in-process."""
    master = build_master(case, in_process=True)
    master.solve_static()
    master.exit_initialization()
    dt = time_step(case)
    rows, i = [], 0
    while i < steps:
        block = master.steps(i, dt, steps - i)
        assert block.error is None, block.error
        rows.append(block)
        i += block.count
    names = master.bearings.names
    out = {"mesh_force": np.concatenate([b.mesh_force[:, 0] for b in rows]),
           "transmission_error": np.concatenate([b.transmission_error[:, 0] for b in rows])}
    states = np.concatenate([b.states for b in rows])
    force = np.concatenate([b.bearing_force for b in rows])
    for k, name in enumerate(names):
        out[("journal_position", name)] = states[:, k, :2]
        out[("journal_velocity", name)] = states[:, k, 2:]
        out[("bearing_force", name)] = force[:, k]
    return out


def test_the_paper_case_with_its_shafts_and_bearings_in_reverse_order(tmp_path):
    path = shipped_cases()["baguet2010_spur"]
    text = _reordered_text(path.read_text())
    reordered_path = tmp_path / "reordered.toml"
    reordered_path.write_text(text)
    case, reordered = load_case(path), load_case(reordered_path)
    assert reordered.names("bearings") == case.names("bearings")[::-1]
    assert reordered.names("shafts") == case.names("shafts")[::-1]
    steps = 32 * PERIODS
    a, b = _run(case, steps), _run(reordered, steps)
    runs = load_fixture()["runs"]["shipped"]
    tol = channel_tolerances(runs["64"], runs["32"])
    for key, value in a.items():
        name, bearing = key if isinstance(key, tuple) else (key, None)
        t = tol[name]
        if bearing is not None:  # the fixture's bearings 1-4, two components each
            t = t.reshape(4, -1)[case.names("bearings").index(bearing)]
        worst = float((np.abs(b[key] - value).reshape(steps, -1).max(axis=0) / t).max())
        assert worst <= 1.0, (key, worst)
