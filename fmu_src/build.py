"""Build the FMUs with pythonfmu and complete their modelDescription.xml.

pythonfmu writes no units and leaves ModelStructure/InitialUnknowns empty, which ``fmpy
validate`` rejects. After building, this module rewrites the XML from the variable contract:
``<UnitDefinitions>``, a ``unit`` on every Real that has one, and the InitialUnknowns (every
output, depending on all inputs and parameters). Built FMUs go to a git-ignored folder.
"""

from __future__ import annotations

import shutil
import tempfile
import zipfile
from pathlib import Path
from xml.dom.minidom import parseString
from xml.etree import ElementTree as ET

from fmu_src.contract import BEARING_VARIABLES, UNITS

HERE = Path(__file__).parent
DEFAULT_DEST = Path("build") / "fmus"

#: FMU file stem -> (slave script, variable contract)
FMUS = {
    "BearingHybrid": ("bearing_hybrid.py", BEARING_VARIABLES),
    "BearingShort": ("bearing_short.py", BEARING_VARIABLES),
    "BearingFd": ("bearing_fd.py", BEARING_VARIABLES),
    "BearingLinear": ("bearing_linear.py", BEARING_VARIABLES),
    "BearingLumped": ("bearing_lumped.py", BEARING_VARIABLES),
}


def _complete_model_description(xml_bytes: bytes, variables) -> bytes:
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
    index_of = {}
    inputs = []
    for i, sv in enumerate(root.find("ModelVariables"), start=1):
        name = sv.get("name")
        index_of[name] = i
        real = sv.find("Real")
        if real is not None and units.get(name):
            real.set("unit", units[name])
        if sv.get("causality") == "input":
            inputs.append(i)
    structure = root.find("ModelStructure")
    for old in structure.findall("InitialUnknowns"):
        structure.remove(old)
    outputs = structure.find("Outputs")
    if outputs is not None:
        deps = " ".join(str(i) for i in inputs)
        for unknown in outputs:
            unknown.set("dependencies", deps)
        init = ET.SubElement(structure, "InitialUnknowns")
        for unknown in outputs:
            ET.SubElement(init, "Unknown", index=unknown.get("index"))
    return parseString(ET.tostring(root, encoding="UTF-8")).toprettyxml(encoding="UTF-8")


def _rewrite_model_description(fmu: Path, variables) -> None:
    tmp = fmu.with_suffix(".tmp")
    with zipfile.ZipFile(fmu) as zin, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "modelDescription.xml":
                data = _complete_model_description(data, variables)
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
        script, variables = FMUS[name]
        with tempfile.TemporaryDirectory(prefix="gsb_fmu_") as tmp:
            # build from a copy so the script's folder (fmu_src) is not packed as a project file
            src = Path(tmp) / script
            shutil.copy2(HERE / script, src)
            fmu = FmuBuilder.build_FMU(src, dest=dest / f"{name}.fmu",
                                       canGetAndSetFMUstate=True, canSerializeFMUstate=True,
                                       needsExecutionTool=True)
        _rewrite_model_description(Path(fmu), variables)
        built.append(Path(fmu))
    return built
