"""The system of a case as an SSP 1.0 archive: five FMU components, plain connections, values.

:func:`write_ssp` writes ``<dest>/<case name>.ssp``: ``SystemStructure.ssd`` (the components
``gear_shaft`` and ``bearing1`` ... ``bearing4``, the connections of
:func:`fmu_src.contract.connections`, each component's parameter values in one inline parameter
set named ``case``, with start values of the connected inputs at the static solution when
given, a default experiment with the case's time step as the fixed step of OSP's master (its
annotation of the default experiment) and of OMSimulator's (its annotation of the system)) and
``resources/`` with the gear-shaft FMU carrying the case and the bearing FMU of the case's
model (the four bearing components share the file). Any SSP tool runs it without this package;
ecos needs ``--parameterSet case`` to apply the values (it applies bindings only by name).

:func:`read_ssp` reads such an archive back (``gsb run X.ssp``): the case the gear-shaft FMU
carries with the SSD's values applied, and the FMU files and parameter values of the bearings,
identified by what is connected to the gear-shaft FMU's law inputs, so any bearing FMU with
the bearing contract may stand in a component.
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
    BEARINGS,
    STATE_NAMES,
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

#: component names in the SSD, and the name of the parameter set
GEAR = "gear_shaft"
BEARING = "bearing{j}"
PARAMETER_SET = "case"
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
        return {}, [{} for _ in BEARINGS]
    import numpy as np

    packed = np.empty(len(law_input_names()))
    pack_laws(laws, packed)
    gear = {n: float(v) for n, v in zip(law_input_names(), packed, strict=True)}
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


def ssd_text(case: Case, gear_source: str, bearing_source: str, laws=None) -> bytes:
    """``SystemStructure.ssd`` of a case, the FMUs at the given paths inside the archive;
    ``laws`` (:class:`bearing_fmu.affine.AffineLaws` linearised at the static solution X0,
    as :meth:`orchestrator.coupling.master.Master.solve_static` leaves them): start values of the
    connected inputs at X0, so that a non-iterative master starts in equilibrium."""
    root = ET.Element(_q("ssd", "SystemStructureDescription"), version="1.0",
                      name=case["case.name"])
    system = ET.SubElement(root, _q("ssd", "System"), name=case["case.name"],
                           description="gear-shaft structure and four journal bearings "
                                       "(Baguet & Jacquenot 2010); global frame, SI units")
    elements = ET.SubElement(system, _q("ssd", "Elements"))
    wiring = connections(GEAR, BEARING)
    gear_conns = [(a_var, "output") for a, a_var, _, _ in wiring if a == GEAR]
    gear_conns += [(b_var, "input") for _, _, b, b_var in wiring if b == GEAR]
    gear_start, bearing_start = _start_values(case, laws)
    _component(elements, GEAR, gear_source, gear_conns,
               {n: v for n, _, v in gear_parameters(case)} | gear_start)
    for j, params, start in zip(BEARINGS, description.bearing_parameters(case), bearing_start,
                                strict=True):
        name = BEARING.format(j=j)
        conns = [(b_var, "input") for _, _, b, b_var in wiring if b == name]
        conns += [(a_var, "output") for a, a_var, _, _ in wiring if a == name]
        _component(elements, name, bearing_source, conns, params | start)
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
    """Build the FMUs of a case (the gear shaft carrying it, the bearing FMU of the model its
    bearings share, ``bearings.*.model``) and write ``dest/<case name>.ssp``; returns its path.
    ``laws``: the bearing laws at the static solution (:func:`ssd_text`)."""
    from fmu_src.contract import bearing_fmu_name
    from fmu_src.build.fmus import build_fmus, readable_entry

    dest = Path(dest)
    dest.mkdir(parents=True, exist_ok=True)
    out = dest / f"{case['case.name']}.ssp"
    model = description.shared_bearing_model(case)
    if model is None:  # TODO(train): one bearing FMU per model in the archive
        raise CaseError(f"{case.source}: an SSP archive takes one bearing model for every "
                        "bearing; this case's bearings have several (bearings.*.model)")
    bearing = bearing_fmu_name(model)
    with tempfile.TemporaryDirectory(prefix="gsb_ssp_") as tmp:
        fmus = build_fmus(tmp, ["GearShaft", bearing], case=case)
        part = Path(tmp) / "system.ssp"
        with zipfile.ZipFile(part, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr(readable_entry("SystemStructure.ssd"),
                       ssd_text(case, "resources/GearShaft.fmu", f"resources/{bearing}.fmu",
                                laws))
            for path in fmus:
                z.write(path, f"resources/{path.name}")  # their mode: 0644 (build_fmus)
        shutil.move(part, out)
    return out


@dataclass
class SspSystem:
    """What ``gsb run`` needs of an SSP archive (:func:`read_ssp`)."""

    case: Case  # the gear FMU's carried case with the SSD's values
    gear_fmu: Path
    bearing_fmus: list  # per bearing 1-4
    bearing_parameters: list  # per bearing 1-4: {name: value} from the SSD
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
    links = {(c.get("endElement"), c.get("endConnector")): c.get("startElement")
             for c in root.iterfind(".//ssd:Connection", NS)}
    gear = next((n for (n, var) in links if var == "F_s_1"), None)
    if gear is None:
        raise CaseError(f"{path}: no component has the gear-shaft FMU's input F_s_1 connected")
    bearings = [links.get((gear, f"F_s_{j}")) for j in BEARINGS]
    if None in bearings:
        raise CaseError(f"{path}: the gear-shaft FMU's inputs F_s_1 ... F_s_4 are not all "
                        "connected to bearing components")
    gear_fmu = folder / comps[gear].get("source")
    with zipfile.ZipFile(gear_fmu) as z:
        carried = z.read("resources/case.toml").decode()
    (folder / "case.toml").write_text(carried)
    base = load_case(folder / "case.toml")
    overrides: dict = {}
    starts = set(law_input_names())
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
    names = base.names("bearings")  # TODO(train): the components per bearing name
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
