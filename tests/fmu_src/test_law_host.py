"""A C host without Python gets the hybrid bearing FMU's law bit for bit.

``hosts/law_host.c`` sets the four journal-state inputs and reads the ten law outputs, as the
package's master does in a coupled iteration, along a sequence of states with a journal
outside the clearance among them; it prints what it read as hexadecimal floats. In a C host
the FMU's loader starts the interpreter, and the patched library serves these calls with the
compiled law (fmu_src/native/patches/0011-native-bearing-law.patch; that it does, rather than
the slave's Python, is asserted by tests/fmu_src/test_bearing_fmus.py, where the calls can be
counted). Skipped without a C compiler.
"""

from __future__ import annotations

import math
import subprocess

import numpy as np
import pytest

from fmu_src.contract import DAMPING_NAMES, FORCE_NAMES, STATE_NAMES, STIFFNESS_NAMES
from tests.fmu_src.c_hosts import compile_host, unzip_fmu
from tests.helpers import probe_env

FMU = "BearingHybrid"


@pytest.fixture(scope="module")
def law_host(tmp_path_factory):
    return compile_host("law_host.c", tmp_path_factory.mktemp("law_host") / "law_host")


def _reference(states):
    """The in-process hybrid model at the FMU's start values (the paper's pinion bearing,
    frame angle 0, omega 325 rad/s), evaluated along ``states`` with its warm start: the law
    (10,) at each, or None where it raises."""
    from bearing_fmu import BearingData, model_class
    from bearing_fmu.frames import LocalFrame
    from fmu_src.contract import bearing_variables

    v = {x.name: x.start for x in bearing_variables()}
    cls = model_class("hybrid")
    model = cls.from_parameters(BearingData(v["D"], v["L"], v["C"], v["mu"]),
                                **{o.key: v[o.key] for o in cls.options})
    q = LocalFrame(v["frame_angle"], int(v["rotation_sign"])).q
    laws = []
    for s in states:
        out = np.empty((5, 2))
        try:
            model.evaluate_global(q, np.array(s), v["omega"], out)
            laws.append(out.ravel().tolist())
        except Exception:
            laws.append(None)
    return laws, v["C"]


def test_a_c_host_reads_the_hybrid_law_of_the_in_process_model(law_host, fmu_dir, tmp_path):
    folder = tmp_path / "fmu"
    md, vr = unzip_fmu(fmu_dir / f"{FMU}.fmu", folder)
    _, c = _reference([])
    states = [[(0.3 + 0.01 * k) * c, -0.4 * c, 1e-3 * k, -2e-3] for k in range(5)]
    states.insert(3, [1.2 * c, 0.0, 0.0, 0.0])  # outside the clearance: the read fails
    expected, _ = _reference(states)
    args = [str(folder), FMU, md.guid, *[str(vr[n]) for n in STATE_NAMES],
            *[str(vr[n]) for n in FORCE_NAMES + STIFFNESS_NAMES + DAMPING_NAMES],
            *[repr(x) for s in states for x in s]]
    proc = subprocess.run([str(law_host), *args], capture_output=True, text=True, timeout=300,
                          env=probe_env(), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    lines = proc.stdout.splitlines()
    assert lines[-1] == "terminate 0", proc.stdout
    assert len(lines) == len(states) + 1, proc.stdout
    for k, (line, want) in enumerate(zip(lines, expected, strict=False)):
        set_status, read_status, *hex_values = line.split()
        assert set_status == "0", (k, line)
        if want is None:
            assert read_status == "3", (k, line)  # fmi2Error, the reason in the log
            assert "eccentricity ratio 1.2" in proc.stderr
            continue
        got = [float.fromhex(x) if x not in ("nan", "-nan") else math.nan for x in hex_values]
        assert read_status == "0" and got == want, (k, line, want)
