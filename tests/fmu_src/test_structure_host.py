"""A C host without Python steps the gear-shaft FMU bit for bit as the in-process structure.

``hosts/structure_host.c`` sets the law inputs (14 per bearing), steps and reads the journal
outputs (4 per bearing), as the package's master does, with a saved state restored among the
steps; it prints what it read as hexadecimal floats. The paper's gear-shaft FMU (4 bearings) and
another train's (:data:`tests.conftest.TRAIN_CASE`: 6 bearings, 2 meshes) are driven. In a C
host the FMU's loader starts the interpreter, and the patched library serves these sets and
reads while stepping from the slave's buffer
(fmu_src/native/patches/0012-native-structure-io.patch; that it does, rather than the slave's
Python, is asserted by tests/fmu_src/test_gear_fmu.py, where the calls can be counted).
Skipped without a C compiler.
"""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

from fmu_src.case import shipped_case
from fmu_src.contract import GEAR_DEFAULT_CASE, journal_output_names, law_input_names, pack_laws
from tests.conftest import TRAIN_CASE
from tests.fmu_src.c_hosts import compile_host, unzip_fmu
from tests.helpers import probe_env
from tests.probes.gear_fmu import laws

STEPS, SAVE_AT, RESTORE_AT = 8, 2, 5


@pytest.fixture(scope="module")
def structure_host(tmp_path_factory):
    return compile_host("structure_host.c",
                        tmp_path_factory.mktemp("structure_host") / "structure_host")


def _reference(case, law_a, law_b):
    """The in-process structure of the FMU's carried case along the host's calls: the lines
    it prints, each ``(label, the 4 nb journal values)``, and the time step [s]."""
    from fmu_src import description
    from orchestrator.coupling.inprocess import InProcessStructure

    ref = InProcessStructure(description.structure(case))
    dt = ref.structure.mesh_period / 32
    ref.set_bearing_laws(law_a)
    ref.solve_static()
    lines = [("static", ref.journal_states().ravel().tolist())]
    ref.exit_initialization()
    saved, k, restored = None, 0, False
    while k < STEPS:
        ref.set_bearing_laws(law_a if k % 2 else law_b)
        ref.do_step(k * dt, dt)
        lines.append((f"step {k}", ref.journal_states().ravel().tolist()))
        if k == SAVE_AT and saved is None:
            saved = ref.get_state()
        if k == RESTORE_AT and not restored:
            restored = True
            ref.set_state(saved)
            lines.append(("restored", ref.journal_states().ravel().tolist()))
            k = SAVE_AT + 1
            continue
        k += 1
    return lines, dt


@pytest.mark.parametrize("train", [GEAR_DEFAULT_CASE.removesuffix(".toml"), TRAIN_CASE])
def test_a_c_host_steps_the_gear_fmu_as_the_in_process_structure(structure_host, fmu_dir,
                                                                  tmp_path, train):
    from orchestrator.coupling.fmi.cache import gear_fmu_name

    case = shipped_case(train)
    fmu = gear_fmu_name(case)
    folder = tmp_path / "fmu"
    md, vr = unzip_fmu(fmu_dir / f"{fmu}.fmu", folder)
    nb = len(case.names("bearings"))
    law_a, law_b = laws(nb)
    expected, dt = _reference(case, law_a, law_b)
    values = []
    for law in (law_a, law_b):
        packed = np.empty(14 * nb)
        pack_laws(law, packed)
        values += [repr(x) for x in packed.tolist()]
    args = [str(folder), fmu, md.guid, repr(dt), str(STEPS), str(SAVE_AT), str(RESTORE_AT),
            str(nb), *[str(vr[n]) for n in law_input_names(case)],
            *[str(vr[n]) for n in journal_output_names(case)], *values]
    proc = subprocess.run([str(structure_host), *args], capture_output=True, text=True,
                          timeout=300, env=probe_env(), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    lines = proc.stdout.splitlines()
    assert lines[-1] == "terminate 0", proc.stdout
    # the static solution, 6 steps to the restore, the restored state, 5 steps from it
    assert len(lines) == len(expected) + 1 == 1 + 6 + 1 + 5 + 1, proc.stdout
    for line, (label, want) in zip(lines, expected, strict=False):
        words = line.split()
        n_label = len(label.split())
        assert " ".join(words[:n_label]) == label, (line, label)
        statuses = words[n_label:-4 * nb]
        got = [float.fromhex(x) for x in words[-4 * nb:]]
        assert set(statuses) == {"0"}, line  # every call fmi2OK
        assert got == want, (label, got, want)
    moved = np.ptp([want for _, want in expected[1:]], axis=0)
    assert moved.max() > 1e-9  # the journals move from step to step: not a repeated read
