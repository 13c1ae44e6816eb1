"""The system of a case as an SSP 1.0 archive: the gear-shaft FMU and one bearing FMU per
bearing, plain connections, values.

:func:`write_ssp` writes ``<dest>/<case name>.ssp``: ``SystemStructure.ssd`` (the component
``gear_shaft`` and one component per bearing of the case's gear train, named after it
(:func:`fmu_src.contract.bearing_component`: ``bearing1`` ... ``bearing4`` for the paper's,
``bearing_in_a`` ...), each an instance of the FMU of its own model; the connections of
:func:`fmu_src.contract.connections`; each component's parameter values in one inline parameter
set named ``case``, with start values of the connected inputs at the static solution when
given; a default experiment with the case's time step as the fixed step of OSP's master (its
annotation of the default experiment) and of OMSimulator's (its annotation of the system)) and
``resources/`` with the gear-shaft FMU carrying the case and the bearing FMU of each model the
case's bearings use (the components of one model share its file). Any SSP tool runs it
without this package; ecos needs ``--parameterSet case`` to apply the values (it applies
bindings only by name).

:func:`read_ssp` reads such an archive back (``gsb run X.ssp``): the case the gear-shaft FMU
carries with the SSD's values applied, and the FMU files and parameter values of the bearings,
identified by what is connected to the gear-shaft FMU's law inputs (``F_s_<bearing>``), so
any bearing FMU with the bearing contract may stand in a component.
"""

from __future__ import annotations

import math
import shutil
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path
from xml.dom.minidom import parseString
from xml.etree import ElementTree as ET

from fmu_src import description
from fmu_src.case import Case, CaseError, load_case
from fmu_src.contract import (
    STATE_NAMES,
    bearing_component,
    bearing_fmu_name,
    bearing_names,
    connections,
    gear_parameters,
    law_input_names,
    pack_laws,
    parameter_field,
)

__all__ = ["SspSystem", "read_ssp", "ssd_text", "write_ssp"]

NS = {
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
    "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
    "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
    "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations",
    "oms": "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd",
}
for _prefix, _uri in NS.items():  # ecos and OMSimulator read the prefixes literally
    ET.register_namespace(_prefix, _uri)

#: the gear-shaft FMU's component name in the SSD when no name of its variables holds it
#: (:func:`gear_component`; each bearing's: :func:`fmu_src.contract.bearing_component`), and
#: the name of the parameter set
GEAR = "gear_shaft"
PARAMETER_SET = "case"


def gear_component(variable_names) -> str:
    """The gear-shaft FMU's component name: :data:`GEAR`, or it with ``_fmu`` appended until
    no dot-separated segment of its ``variable_names`` (the parameters and start values the
    SSD sets) equals it, nor ``model`` or ``root``. OMSimulator 3.0 maps a value of the SSD to
    ``model.root.<component>.<variable>`` and drops every segment of the variable's name that
    is one of those three (``instantiated_model.validatePath``): the paper's shaft named
    ``gear_shaft`` lost its ``shafts.gear_shaft.length[1]`` to an unknown
    ``shafts.length[1]``, and the tool crashed."""
    taken = {"model", "root"} | {part.split("[")[0] for name in variable_names
                                 for part in str(name).split(".")}
    name = GEAR
    while name in taken:
        name += "_fmu"
    return name
_SSV_TYPE = {bool: "Boolean", int: "Integer", float: "Real", str: "String"}


def _q(prefix: str, tag: str) -> str:
    return f"{{{NS[prefix]}}}{tag}"


def _text(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)  # shortest round trip: the SSD gives back the same doubles
    return str(value)


def _component(parent, name: str, source: str, connectors: list, params: dict) -> None:
    comp = ET.SubElement(parent, _q("ssd", "Component"), name=name, source=source,
                         type="application/x-fmu-sharedlibrary")
    conns = ET.SubElement(comp, _q("ssd", "Connectors"))
    for var, kind in connectors:
        c = ET.SubElement(conns, _q("ssd", "Connector"), name=var, kind=kind)
        ET.SubElement(c, _q("ssc", "Real"))
    bindings = ET.SubElement(comp, _q("ssd", "ParameterBindings"))
    binding = ET.SubElement(bindings, _q("ssd", "ParameterBinding"))
    values = ET.SubElement(binding, _q("ssd", "ParameterValues"))
    pset = ET.SubElement(values, _q("ssv", "ParameterSet"), version="1.0", name=PARAMETER_SET)
    plist = ET.SubElement(pset, _q("ssv", "Parameters"))
    for key, value in params.items():
        p = ET.SubElement(plist, _q("ssv", "Parameter"), name=key)
        ET.SubElement(p, _q("ssv", _SSV_TYPE[type(value)]), value=_text(value))


def _start_values(case: Case, laws) -> tuple[dict, list[dict]]:
    """Start values of the connected inputs at the static solution: the gear-shaft FMU's law
    inputs (the bearings' outputs at X0) and each bearing's journal state and speed."""
    if laws is None:
        return {}, [{} for _ in bearing_names(case)]
    import numpy as np

    names = law_input_names(case)
    packed = np.empty(len(names))
    pack_laws(laws, packed)
    gear = {n: float(v) for n, v in zip(names, packed, strict=True)}
    states, _, _, _ = laws.expansion()
    bearings = [{**{n: float(v) for n, v in zip(STATE_NAMES, states[j], strict=True)},
                 "omega": float(w)}
                for j, w in enumerate(description.bearing_speeds(case))]
    return gear, bearings


def _omsimulator_master(system, dt: float, tolerance: float) -> None:
    """OMSimulator's annotation of the system (last child, as the SSD schema orders it): its
    fixed-step master ``oms-ma`` at the case's step. OMSimulator takes the system's type from
    this annotation (the first ``ssc:Annotation`` of the system's ``ssd:Annotations``) and
    refuses to import a system without it; ``relativeTolerance`` is the case's coupling
    tolerance (OMSimulator's algebraic loops; the system has none)."""
    ann = ET.SubElement(ET.SubElement(system, _q("ssd", "Annotations")),
                        _q("ssc", "Annotation"), type="org.openmodelica")
    info = ET.SubElement(ET.SubElement(ann, _q("oms", "Annotations")),
                         _q("oms", "SimulationInformation"))
    ET.SubElement(info, _q("oms", "FixedStepMaster"), description="oms-ma", stepSize=repr(dt),
                  relativeTolerance=repr(float(tolerance)))


def ssd_text(case: Case, gear_source: str, bearing_sources, laws=None) -> bytes:
    """``SystemStructure.ssd`` of a case, the FMUs at the given paths inside the archive
    (``bearing_sources``: one per bearing, the layout's order; a single path: every
    bearing's); ``laws`` (:class:`bearing_fmu.affine.AffineLaws` linearised at the static solution X0,
    as :meth:`orchestrator.coupling.master.Master.solve_static` leaves them): start values of the
    connected inputs at X0, so that a non-iterative master starts in equilibrium."""
    root = ET.Element(_q("ssd", "SystemStructureDescription"), version="1.0",
                      name=case["case.name"])
    system = ET.SubElement(root, _q("ssd", "System"), name=case["case.name"],
                           description="gear-shaft structure of a parallel-axis gear train "
                                       "and its journal bearings (Baguet & Jacquenot 2010); "
                                       "global frame, SI units")
    elements = ET.SubElement(system, _q("ssd", "Elements"))
    names = bearing_names(case)
    if isinstance(bearing_sources, str):
        bearing_sources = [bearing_sources] * len(names)
    gear_start, bearing_start = _start_values(case, laws)
    gear_values = {n: v for n, _, v in gear_parameters(case)} | gear_start
    gear = gear_component(gear_values)
    wiring = connections(case, gear)
    gear_conns = [(a_var, "output") for a, a_var, _, _ in wiring if a == gear]
    gear_conns += [(b_var, "input") for _, _, b, b_var in wiring if b == gear]
    _component(elements, gear, gear_source, gear_conns, gear_values)
    for b, source, params, start in zip(names, bearing_sources,
                                        description.bearing_parameters(case), bearing_start,
                                        strict=True):
        name = bearing_component(b)
        conns = [(b_var, "input") for _, _, c, b_var in wiring if c == name]
        conns += [(a_var, "output") for a, a_var, _, _ in wiring if a == name]
        _component(elements, name, source, conns, params | start)
    links = ET.SubElement(system, _q("ssd", "Connections"))
    for a, a_var, b, b_var in wiring:
        ET.SubElement(links, _q("ssd", "Connection"), startElement=a, startConnector=a_var,
                      endElement=b, endConnector=b_var)
    dt = description.time_step(case)
    _omsimulator_master(system, dt, case["simulation.tolerance"])
    stop = dt * case["simulation.steps_per_mesh_period"] * case["simulation.mesh_periods"]
    exp = ET.SubElement(root, _q("ssd", "DefaultExperiment"), startTime="0.0",
                        stopTime=repr(stop))
    ann = ET.SubElement(ET.SubElement(exp, _q("ssd", "Annotations")), _q("ssc", "Annotation"),
                        type="com.opensimulationplatform")
    algo = ET.SubElement(ann, _q("osp", "Algorithm"))
    ET.SubElement(algo, _q("osp", "FixedStepAlgorithm"), baseStepSize=repr(dt))
    return parseString(ET.tostring(root, encoding="UTF-8")).toprettyxml(encoding="UTF-8")


def write_ssp(case: Case, dest: Path | str, laws=None) -> Path:
    """Build the FMUs of a case (the gear shaft carrying it, the bearing FMU of each model its
    bearings use, ``bearings.<name>.model``) and write ``dest/<case name>.ssp``; returns its
    path. ``laws``: the bearing laws at the static solution (:func:`ssd_text`)."""
    from fmu_src.build.fmus import build_fmus, readable_entry
    from fmu_src.contract import check_constant_speed

    check_constant_speed(case, f"the SSP of {case['case.name']}")
    dest = Path(dest)
    dest.mkdir(parents=True, exist_ok=True)
    out = dest / f"{case['case.name']}.ssp"
    models = [bearing_fmu_name(case[f"bearings.{b}.model"]) for b in bearing_names(case)]
    with tempfile.TemporaryDirectory(prefix="gsb_ssp_") as tmp:
        fmus = build_fmus(tmp, ["GearShaft", *dict.fromkeys(models)], case=case)
        part = Path(tmp) / "system.ssp"
        with zipfile.ZipFile(part, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr(readable_entry("SystemStructure.ssd"),
                       ssd_text(case, "resources/GearShaft.fmu",
                                [f"resources/{m}.fmu" for m in models], laws))
            for path in fmus:
                z.write(path, f"resources/{path.name}")  # their mode: 0644 (build_fmus)
        shutil.move(part, out)
    return out


@dataclass
class SspSystem:
    """What ``gsb run`` needs of an SSP archive (:func:`read_ssp`)."""

    case: Case  # the gear FMU's carried case with the SSD's values
    gear_fmu: Path
    bearing_fmus: list  # per bearing (the layout's order)
    bearing_parameters: list  # per bearing: {name: value} from the SSD
    folder: Path  # where the archive was extracted (remove it when done)


def _parameters(comp) -> dict:
    out = {}
    for p in comp.iterfind(".//ssv:Parameter", NS):
        (typed,) = list(p)
        kind = typed.tag.split("}")[1]
        text = typed.get("value")
        out[p.get("name")] = {"Real": float, "Integer": int, "String": str,
                              "Boolean": lambda s: s.strip().lower() in ("true", "1")}[kind](text)
    return out


def read_ssp(path: Path | str, folder: Path | str | None = None) -> SspSystem:
    """Extract an SSP archive (into ``folder``, default a new temporary folder) and read the
    system (module docstring); :class:`~fmu_src.fields.CaseError` naming what does not fit."""
    path = Path(path)
    if not path.is_file():
        raise CaseError(f"SSP file not found: {path}")
    folder = Path(tempfile.mkdtemp(prefix="gsb_ssp_")) if folder is None else Path(folder)
    try:
        with zipfile.ZipFile(path) as z:
            z.extractall(folder)
        root = ET.parse(folder / "SystemStructure.ssd").getroot()
    except (OSError, KeyError, zipfile.BadZipFile, ET.ParseError) as exc:
        raise CaseError(f"{path}: not an SSP archive with a SystemStructure.ssd ({exc})") from None
    comps = {c.get("name"): c for c in root.iterfind(".//ssd:Component", NS)}
    connected = [(c.get("startConnector"), c.get("endElement"), c.get("endConnector"),
                  c.get("startElement")) for c in root.iterfind(".//ssd:Connection", NS)]
    links = {(end, var): start for _, end, var, start in connected}
    # the gear-shaft FMU: the component whose inputs F_s_<bearing> take bearings' F_s
    gear = next((end for out, end, var, _ in connected
                 if out == "F_s" and var.startswith("F_s_")), None)
    if gear is None or gear not in comps:
        raise CaseError(f"{path}: no component has a gear-shaft FMU's input F_s_<bearing> "
                        "connected to a bearing's F_s")
    gear_fmu = folder / comps[gear].get("source")
    try:
        with zipfile.ZipFile(gear_fmu) as z:
            carried = z.read("resources/case.toml").decode()
    except (OSError, KeyError, zipfile.BadZipFile) as exc:
        raise CaseError(f"{path}: component {gear!r} is no gear-shaft FMU carrying its case "
                        f"({exc})") from None
    (folder / "case.toml").write_text(carried)
    base = load_case(folder / "case.toml")
    names = bearing_names(base)
    bearings = [links.get((gear, f"F_s_{b}")) for b in names]
    if None in bearings or not set(bearings) <= set(comps):
        missing = [f"F_s_{b}" for b, c in zip(names, bearings, strict=True) if c not in comps]
        raise CaseError(f"{path}: the gear-shaft FMU's inputs {', '.join(missing)} are not "
                        "connected to bearing components")
    overrides: dict = {}
    starts = set(law_input_names(base))
    for name, value in _parameters(comps[gear]).items():
        if name in starts:
            continue  # start values of the law inputs (the master finds X0 itself)
        key, i = parameter_field(name)
        if i is None:
            overrides[key] = value
        else:
            current = list(overrides.get(key, base[key]))
            current[i] = value
            overrides[key] = current
    params = [{k: v for k, v in _parameters(comps[b]).items()
               if k not in (*STATE_NAMES, "omega")} for b in bearings]
    for key, field in (("diameter", "D"), ("length", "L"), ("clearance", "C"),
                       ("viscosity", "mu")):
        values = [p.get(field, base[f"bearings.{n}.{key}"]) for n, p in zip(names, params,
                                                                            strict=True)]
        if not all(isinstance(v, float) and math.isfinite(v) for v in values):
            raise CaseError(f"{path}: bearing parameter {field} must be a finite number: "
                            f"{values}")
        overrides.update({f"bearings.{n}.{key}": v for n, v in zip(names, values, strict=True)})
    case = Case(base.values, str(path)).with_overrides(overrides)
    return SspSystem(case, gear_fmu, [folder / comps[b].get("source") for b in bearings],
                     params, folder)
