"""The FMUs as a system engineer uses them: a bearing FMU of one's own, the SSP archive, the
command line, Ctrl-C, several runs at once and an environment without this package.

FMUs load in the test's process (tests.helpers.run_here) unless the process is the point: a
fresh interpreter (tests.helpers.run_isolated), a ``gsb`` / ``fmpy`` subprocess.
"""

from __future__ import annotations

import os
import random
import shutil
import signal
import stat
import subprocess
import sys
import sysconfig
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

from tests.helpers import film_bounds, paced_gsb, probe_command, probe_env, run_here, run_isolated

GSB = [sys.executable, "-m", "orchestrator.cli"]

PROBES = "tests.probes.fmu_system"
#: a bearing model of one's own with the minimal contract only: the journal state in, the film
#: force out (global frame); here an isotropic spring and damper, the built-in lumped model
SPRING_BEARING = Path(__file__).with_name("springbearing.py")


@pytest.fixture(scope="module")
def spring_fmu(tmp_path_factory):
    """The force-only FMU, built with pythonfmu and given this package's native layer."""
    from pythonfmu.builder import FmuBuilder

    from fmu_src.build.fmus import patch_fmu

    folder = tmp_path_factory.mktemp("byo")
    script = folder / "springbearing.py"
    shutil.copyfile(SPRING_BEARING, script)
    built = FmuBuilder.build_FMU(script, dest=folder / "stock")
    return patch_fmu(built, folder / "SpringBearing.fmu")


def test_a_force_only_bearing_fmu_matches_the_built_in_lumped_model(fmu_dir, spring_fmu,
                                                                     tmp_path):
    """Bring your own bearing: the master gets Kb and Cb by central differences of the FMU's
    force (steps 1e-5 C and 1e-5 C omega) and the run equals the in-process lumped model
    (exact Kb, Cb) over 64 steps, with lumped damping so that Cb matters too."""
    r = run_here(module=PROBES, args=["force_only_bearings", {
        "out_dir": tmp_path, "gear_fmu": fmu_dir / "GearShaft.fmu", "bearing_fmu": spring_fmu}])
    print(f"\nforce-only FMU vs lumped in process, 64 steps: positions {r['position']:.1e}, "
          f"velocities {r['velocity']:.1e}; iterations per step {r['its']}")
    assert r["label"] == "fmu-SpringBearing"  # a bearing FMU of your own, by its file
    assert r["its"] == [1.0, 1.0]  # an affine force: one pass, whatever the FD round-off
    # the master's central differences (steps 1e-5 C, 1e-5 C omega) of an affine force have
    # round-off only: 8 eps of the force's largest term (about |Kb| C here) over twice the
    # step, a relative error of the law that the run carries as film_bounds says (measured
    # 5.0e-12 and 2.3e-11)
    law = 8 * np.finfo(float).eps / (2 * 1e-5)
    bound, v_bound = film_bounds(r["position_scale"], r["velocity_scale"], r["dt"], law)
    print(f"bounds: positions {bound:.1e}, velocities {v_bound:.1e}")
    assert r["position"] < bound and r["velocity"] < v_bound


def test_a_bearing_fmu_without_the_minimal_contract_is_refused(fmu_dir):
    r = run_here(module=PROBES, args=["not_a_bearing", {"fmu": fmu_dir / "GearShaft.fmu"}])
    assert "bearing 1 (GearShaft.fmu) lacks the minimal bearing contract: input s" in r


def test_closed_bearing_fmus_refuse_to_evaluate(fmu_dir):
    """The bearing set reads each law into a buffer of its own: once its FMUs are freed, an
    evaluation is an FmuError, not the last laws read (nor empty arrays, as before)."""
    r = run_here(module=PROBES, args=["closed_bearings", {"fmu_dir": fmu_dir}])
    assert r == ["the bearing FMUs are closed", True]


def test_the_ssp_archive_holds_the_system(ssp_file):
    from fmu_src.build.ssp import NS
    from fmu_src.contract import connections

    with zipfile.ZipFile(ssp_file) as z:
        names = set(z.namelist())
        from xml.etree import ElementTree as ET

        root = ET.fromstring(z.read("SystemStructure.ssd"))
    assert names == {"SystemStructure.ssd", "resources/GearShaft.fmu",
                     "resources/BearingHybrid.fmu"}
    comps = {c.get("name"): c.get("source") for c in root.iterfind(".//ssd:Component", NS)}
    # "gear_shaft_fmu": the paper's case has a shaft named gear_shaft
    # (fmu_src.build.ssp.gear_component: OMSimulator 3.0 would drop it from the variables' names)
    assert comps == {"gear_shaft_fmu": "resources/GearShaft.fmu",
                     **{f"bearing{j}": "resources/BearingHybrid.fmu" for j in range(1, 5)}}
    links = [(c.get("startElement"), c.get("startConnector"), c.get("endElement"),
              c.get("endConnector")) for c in root.iterfind(".//ssd:Connection", NS)]
    from fmu_src.case import shipped_case

    assert links == connections(shipped_case("baguet2010_spur"), "gear_shaft_fmu")
    values = {(c.get("name"), p.get("name")): next(iter(p)).get("value")
              for c in root.iterfind(".//ssd:Component", NS)
              for p in c.iterfind(".//ssv:Parameter", NS)}
    assert values[("bearing3", "rotation_sign")] == "-1"
    from fmu_src.case import load_case

    case = load_case("baguet2010_spur")
    clearance = [case[f"bearings.{b}.clearance"] for b in case.names("bearings")]
    assert [float(values[(f"bearing{j}", "C")]) for j in range(1, 5)] == clearance  # exact
    # the static solution X0 as start values: a non-iterative master starts in equilibrium
    from orchestrator.coupling.system import build_master

    master = build_master(load_case("baguet2010_spur"), in_process=True)
    x0 = master.solve_static().states
    starts = [[float(values[(f"bearing{j}", n)]) for n in ("s", "t")] for j in range(1, 5)]
    assert starts == x0[:, :2].tolist()
    assert float(values[("gear_shaft_fmu", "s_eval_3")]) == x0[2, 0]


def test_the_ssp_carries_the_cases_step_where_tools_look_for_it(ssp_file):
    """The case's time step, to the last bit, wherever a master looks for a fixed step: OSP's
    annotation of the default experiment (ecos) and OMSimulator's annotation of the system
    (its fixed-step master ``oms-ma``, the first ``org.openmodelica`` annotation, which
    OMSimulator needs to import the SSP at all: it decides the system's type from it)."""
    from xml.etree import ElementTree as ET

    from fmu_src import description
    from fmu_src.build.ssp import NS
    from fmu_src.case import load_case

    dt = description.time_step(load_case("baguet2010_spur"))
    with zipfile.ZipFile(ssp_file) as z:
        text = z.read("SystemStructure.ssd").decode()
    root = ET.fromstring(text)
    ns = NS | {"oms": "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/"
                      "schema/oms.xsd"}
    osp = root.findall("ssd:DefaultExperiment/ssd:Annotations/ssc:Annotation"
                       "[@type='com.opensimulationplatform']/osp:Algorithm/"
                       "osp:FixedStepAlgorithm", ns)
    assert [float(a.get("baseStepSize")) for a in osp] == [dt]
    system = root.find("ssd:System", ns)
    annotations = system.find("ssd:Annotations", ns)
    assert list(system)[-1] is annotations  # the SSD schema's order: annotations last
    first = annotations.find("ssc:Annotation", ns)  # OMSimulator reads the first one
    assert first.get("type") == "org.openmodelica"
    masters = first.findall("oms:Annotations/oms:SimulationInformation/oms:FixedStepMaster",
                            ns)
    assert [(m.get("description"), float(m.get("stepSize"))) for m in masters] == [
        ("oms-ma", dt)]
    # OMSimulator (pugixml) matches qualified names as written: the prefixes must be these
    for tag in ("<oms:Annotations>", "<oms:SimulationInformation>", "<oms:FixedStepMaster ",
                "<osp:FixedStepAlgorithm ", "<ssc:Annotation "):
        assert tag in text, tag


def _created_mode() -> int:
    """The mode a file created now gets (0666 less the umask)."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def test_fmus_ssp_and_patched_fmus_are_readable_as_files_written_normally(
        fmu_dir, ssp_file, spring_fmu, tmp_path):
    """Built FMUs, the SSP archive and a patched FMU have the mode of a normally written file
    (readable by others under the usual umask: 0644), not the 0600 of a temporary file; so
    have the files inside them once unpacked with their modes (unzip, a C/C++ host): the FMUs
    in the SSP, every file in an FMU (its modelDescription.xml and libraries too)."""
    from fmu_src.build.fmus import build_fmus

    mode = _created_mode()
    built = build_fmus(tmp_path / "built", ["BearingLumped"])
    for path in [*built, *fmu_dir.glob("*.fmu"), ssp_file, spring_fmu]:
        assert stat.S_IMODE(path.stat().st_mode) == mode, (path, oct(path.stat().st_mode))
    for archive in (ssp_file, built[0], spring_fmu):
        with zipfile.ZipFile(archive) as z:
            modes = {i.filename: i.external_attr >> 16 for i in z.infolist() if not i.is_dir()}
        unreadable = {n: oct(m) for n, m in modes.items()
                      if not stat.S_ISREG(m) or m & 0o444 != 0o444}
        assert not unreadable, (archive.name, unreadable)
    with zipfile.ZipFile(ssp_file) as z:
        inner = [stat.S_IMODE(i.external_attr >> 16) for i in z.infolist()
                 if i.filename.endswith(".fmu")]
    assert inner == [mode, mode]  # as the FMU files were written


@pytest.mark.parametrize("fmu, refused", [("BearingHybrid", "numba"), ("GearShaft", "scipy"),
                                          ("BearingLumped", "numpy")])
def test_an_fmu_in_a_python_without_a_package_it_needs_says_what_to_install(fmu_dir, fmu,
                                                                            refused):
    """fmi2Instantiate in a Python that cannot import numpy, scipy or numba: NULL, and the
    host's logger gets what to install and into which Python (a C host's user sees no
    Python traceback on stderr)."""
    out = run_isolated(module="tests.probes.missing_requirement",
                       args=["instantiate", {"fmu": fmu_dir / f"{fmu}.fmu", "blocked": refused}])
    assert out["null"] and not out["imported"]
    text = "\n".join(m for _, m in out["messages"])
    assert f"{fmu}.fmu" in text and "needs numpy, scipy, numba and threadpoolctl" in text, text
    assert f"lacks {refused}" in text, text
    assert f"{out['executable']} -m pip install {refused}" in text, text


def test_gsb_run_of_the_ssp_equals_gsb_run_of_the_case(fmu_dir, ssp_file, tmp_path):
    """The archive's FMUs and values, run by the iterative master, give the case's run through
    the built FMUs bit for bit (the same code on the same numbers)."""
    from orchestrator.run.results import read_results

    out = {}
    for source, extra in ((str(ssp_file), []),
                          ("baguet2010_spur", ["--fmu-dir", str(fmu_dir)])):
        folder = tmp_path / Path(source).stem
        proc = subprocess.run([*GSB, "run", source, "--periods", "1", "--no-figures",
                               "--quiet", "--out", str(folder), *extra],
                              capture_output=True, text=True, timeout=600, cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr[-2000:]
        out[source] = read_results(next(folder.glob("*.h5")))
    a, b = out.values()
    # named by the bearing model like the direct run, not by the FMU file
    names = [next((tmp_path / Path(s).stem).glob("*.h5")).name for s in out]
    assert all(n.startswith("baguet2010_spur_hybrid_") for n in names), names
    assert a["attrs"]["bearing_model"] == b["attrs"]["bearing_model"] == "hybrid"
    assert np.array_equal(a["journal_position"], b["journal_position"])
    assert np.array_equal(a["journal_velocity"], b["journal_velocity"])


def test_build_fmus_carries_the_case_and_names_a_bad_one(tmp_path):
    proc = subprocess.run([*GSB, "build-fmus", "baguet2010_helical", "--dest", str(tmp_path),
                           "--fmu", "GearShaft"], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    from fmpy import read_model_description

    md = read_model_description(str(tmp_path / "GearShaft.fmu"))
    start = {v.name: v.start for v in md.modelVariables}
    assert start["case.name"] == "baguet2010_helical" and float(
        start["gears.pinion.helix_angle"]) > 0.1
    proc = subprocess.run([*GSB, "build-fmus", "Nope", "--dest", str(tmp_path)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "gsb build-fmus: error: case file not found: Nope" in proc.stderr


def test_two_runs_building_the_fmus_at_once_build_once(tmp_path):
    """Two processes ask for the FMUs of one empty folder at the same moment: the lock makes
    one build and the other wait; both get the same complete files."""
    cmd = probe_command(PROBES, "build_at", {"start": time.time() + 3.0,  # start together
                                             "dest": tmp_path / "fmus"})
    procs = [subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              env=probe_env()) for _ in range(2)]
    outs = [p.communicate(timeout=600) for p in procs]
    assert all(p.returncode == 0 for p in procs), [o[1][-2000:] for o in outs]
    import json

    a, b = (json.loads(o[0].strip().splitlines()[-1]) for o in outs)
    assert a == b  # the same files (one build), valid
    assert all(v[1] == [] for v in a.values())


def _site_packages() -> str:
    return sysconfig.get_paths()["purelib"]


def test_an_fmu_runs_where_this_package_is_not_installed(fmu_dir, tmp_path):
    """``python -S`` with only the site-packages folder on the path: this package (installed
    editable, through a .pth file) is not importable, numpy, scipy, numba and fmpy are; fmpy
    simulates the gear-shaft FMU from its own code."""
    env = dict(os.environ, PYTHONPATH=_site_packages())
    probe = subprocess.run([sys.executable, "-S", "-c", "import fmu_src"], env=env,
                           capture_output=True, text=True, cwd=tmp_path)
    assert probe.returncode != 0 and "No module named 'fmu_src'" in probe.stderr
    out = tmp_path / "out.csv"
    proc = subprocess.run([sys.executable, "-S", "-m", "fmpy", "simulate",
                           str(fmu_dir / "GearShaft.fmu"), "--stop-time", "1.2e-4",
                           "--output-interval", "2.4e-5", "--output-file", str(out)],
                          env=env, capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = out.read_text().splitlines()
    assert len(lines) == 7 and "mesh_force" in lines[0]
    assert all(np.isfinite([float(x) for x in line.split(",")]).all() for line in lines[1:])


INTERRUPT_TRIES = 10


@pytest.mark.slow
def test_ctrl_c_and_sigterm_stop_a_fmu_run_cleanly(fmu_dir, tmp_path):
    """SIGINT or SIGTERM at a random moment of a run through FMUs: exit 130 / 143, no crash
    or traceback, and the results file closed, marked interrupted, with the steps done.
    (Ten random moments: slow; tests/system/test_results_safety.py interrupts each transport
    once per signal in the default run and resumes the runs.)"""
    from orchestrator.run.results import read_results

    rng = random.Random(10)
    outcomes = []
    for k in range(INTERRUPT_TRIES):
        sig = (signal.SIGINT, signal.SIGTERM)[k % 2]
        out = tmp_path / f"run{k}"
        proc = subprocess.Popen(paced_gsb("run", "baguet2010_spur", "--periods", "64",
                                          "--no-figures", "--quiet", "--out", out,
                                          "--fmu-dir", fmu_dir),  # lasts >= 8 s
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                cwd=tmp_path)
        deadline = time.time() + 300
        while not list(out.glob("*.h5")) and time.time() < deadline and proc.poll() is None:
            time.sleep(0.02)  # the results file exists once the static solution is done
        time.sleep(rng.uniform(0.0, 1.5))
        proc.send_signal(sig)
        _, stderr = proc.communicate(timeout=300)
        expected = 128 + int(sig)
        assert proc.returncode == expected, (k, proc.returncode, stderr[-2000:])
        assert "Traceback" not in stderr and "fatal" not in stderr, stderr[-2000:]
        assert f"interrupted by {sig.name}" in stderr
        r = read_results(next(out.glob("*.h5")))
        assert not r["attrs"]["complete"] and r["attrs"]["interrupted"] == sig.name
        assert len(r["time"]) > 0 and np.isfinite(r["journal_position"]).all()
        outcomes.append(len(r["time"]))
    print(f"\n{INTERRUPT_TRIES} interrupted FMU runs: exit codes as expected, steps kept "
          f"{outcomes}")


def test_fmus_built_after_an_fmu_was_loaded_carry_their_binaries(fmu_dir, tmp_path):
    """pythonfmu's library puts an instantiated FMU's resources first on sys.path, where a
    pythonfmu FMU carries a copy of pythonfmu's modules without binaries: once an FMU is loaded
    in a process that has not imported pythonfmu, that copy is the one FMUs built there get.
    Through this package's FMU instances they build whole; after an FMU loaded by fmpy alone,
    the build stops with the reason instead."""
    out = run_isolated(module=PROBES, args=["build_after_a_load", {
        "fmu": fmu_dir / "BearingLumped.fmu", "dest_a": tmp_path / "a", "dest_b": tmp_path / "b"}])
    assert out["whole"]
    assert "has no binaries" in out["refused"] and "fresh process" in out["refused"]
