"""Build the FMUs with pythonfmu and complete their modelDescription.xml.

pythonfmu writes no units and leaves ModelStructure/InitialUnknowns empty, which ``fmpy
validate`` rejects. After building, this module rewrites the XML from the variable contract:
``<UnitDefinitions>``, a ``unit`` on every Real that has one, the output dependencies (all
inputs for the algebraic bearing FMUs; none for the gear-shaft FMU, whose outputs are states
that change at doStep) and the InitialUnknowns (every output and calculated parameter, depending
on all inputs and parameters). Built FMUs go to a git-ignored folder.
"""

from __future__ import annotations

import shutil
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path
from xml.dom.minidom import parseString
from xml.etree import ElementTree as ET

from fmu_src.contract import BEARING_VARIABLES, GEAR_DEFAULT_CASE, GEAR_VARIABLES, UNITS

HERE = Path(__file__).parent
DEFAULT_DEST = Path("build") / "fmus"
#: the paper's case, shipped in the gear-shaft FMU's resources (its ``case_file`` default)
PAPER_CASE = HERE.parent / "models" / GEAR_DEFAULT_CASE


@dataclass(frozen=True)
class FmuSpec:
    """How to build one FMU."""

    script: str  # slave script in fmu_src
    variables: tuple  # its variable contract (fmu_src.contract)
    feedthrough: bool = True  # outputs depend directly on the inputs (algebraic slave)
    resources: tuple = ()  # extra files packed into resources/


#: FMU file stem -> build specification
FMUS = {
    "BearingHybrid": FmuSpec("bearing_hybrid.py", BEARING_VARIABLES),
    "BearingShort": FmuSpec("bearing_short.py", BEARING_VARIABLES),
    "BearingFd": FmuSpec("bearing_fd.py", BEARING_VARIABLES),
    "BearingLinear": FmuSpec("bearing_linear.py", BEARING_VARIABLES),
    "BearingLumped": FmuSpec("bearing_lumped.py", BEARING_VARIABLES),
    "GearShaft": FmuSpec("gear_shaft.py", GEAR_VARIABLES, feedthrough=False,
                         resources=(PAPER_CASE,)),
}


def _complete_model_description(xml_bytes: bytes, variables, feedthrough: bool = True) -> bytes:
    root = ET.fromstring(xml_bytes)
    units = {v.name: v.unit for v in variables}
    used = sorted({u for u in units.values() if u})
    # FMI 2.0 order: CoSimulation, UnitDefinitions, TypeDefinitions, LogCategories, ...
    unit_defs = ET.Element("UnitDefinitions")
    for name in used:
        u = ET.SubElement(unit_defs, "Unit", name=name)
        ET.SubElement(u, "BaseUnit", {k: str(e) for k, e in UNITS[name].items()})
    children = list(root)
    cs_index = next(i for i, c in enumerate(children) if c.tag == "CoSimulation")
    if root.find("UnitDefinitions") is None:
        root.insert(cs_index + 1, unit_defs)
    inputs = []
    initial_unknowns = []  # outputs and calculated parameters (FMI 2.0 section 2.2.8)
    for i, sv in enumerate(root.find("ModelVariables"), start=1):
        name = sv.get("name")
        real = sv.find("Real")
        if real is not None and units.get(name):
            real.set("unit", units[name])
        if sv.get("causality") == "input":
            inputs.append(i)
        if sv.get("causality") in ("output", "calculatedParameter"):
            initial_unknowns.append(i)
    structure = root.find("ModelStructure")
    for old in structure.findall("InitialUnknowns"):
        structure.remove(old)
    outputs = structure.find("Outputs")
    if outputs is not None:
        deps = " ".join(str(i) for i in inputs) if feedthrough else ""
        for unknown in outputs:
            unknown.set("dependencies", deps)
    if initial_unknowns:
        init = ET.SubElement(structure, "InitialUnknowns")
        for i in initial_unknowns:
            ET.SubElement(init, "Unknown", index=str(i))
    return parseString(ET.tostring(root, encoding="UTF-8")).toprettyxml(encoding="UTF-8")


def _rewrite_model_description(fmu: Path, spec: FmuSpec) -> None:
    tmp = fmu.with_suffix(".tmp")
    with zipfile.ZipFile(fmu) as zin, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "modelDescription.xml":
                data = _complete_model_description(data, spec.variables, spec.feedthrough)
            zout.writestr(item, data)
    tmp.replace(fmu)


def build_fmus(dest: Path | str = DEFAULT_DEST, names=None) -> list[Path]:
    """Build the FMUs named (default: all of :data:`FMUS`) into ``dest``; return their paths."""
    from pythonfmu.builder import FmuBuilder

    dest = Path(dest)
    dest.mkdir(parents=True, exist_ok=True)
    built = []
    for name in names or FMUS:
        if name not in FMUS:
            raise ValueError(f"unknown FMU {name!r}; available: {', '.join(FMUS)}")
        spec = FMUS[name]
        for res in spec.resources:
            if not Path(res).is_file():
                raise FileNotFoundError(f"{name}: resource file not found: {res}")
        with tempfile.TemporaryDirectory(prefix="gsb_fmu_") as tmp:
            # build from a copy so the script's folder (fmu_src) is not packed as a project file
            src = Path(tmp) / spec.script
            shutil.copy2(HERE / spec.script, src)
            fmu = FmuBuilder.build_FMU(src, dest=dest / f"{name}.fmu",
                                       project_files=[Path(r) for r in spec.resources],
                                       canGetAndSetFMUstate=True, canSerializeFMUstate=True,
                                       needsExecutionTool=True)
        _rewrite_model_description(Path(fmu), spec)
        built.append(Path(fmu))
    return built
