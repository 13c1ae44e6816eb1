"""Imports: nothing is read at import time, and no two modules import each other.

* Importing the component layer and the master opens no ``.toml`` file (the case files are read
  when a value needs them: :func:`fmu_src.contract.bearing_variables`, ...), checked in a fresh
  interpreter by an audit hook (:mod:`tests.probes.import_probe`).
* The module graph of the four packages (grimp, which reads function-level imports as well) has
  no cycle; a failure lists each cycle with the lines of its imports. ``lint-imports`` checks
  the same between sibling packages and the layers of pyproject.toml.
"""

from __future__ import annotations

import itertools
import json
import subprocess
import sys

import grimp
import pytest

from tests.helpers import ROOT

PACKAGES = ("bearing_fmu", "gear_fmu", "fmu_src", "orchestrator")

#: modules whose import must read no file: the component layer and the master (with the
#: slaves and build tools, which an FMU or ``gsb build-fmus`` imports)
LAZY = ["fmu_src.contract", "fmu_src.case", "fmu_src.description", "orchestrator",
        "fmu_src.slaves.bearing", "fmu_src.slaves.gear_shaft", "fmu_src.build.fmus",
        "fmu_src.build.variables_doc", "orchestrator.run.runner", "orchestrator.cli"]


def probe(modules: list[str], call: str | None = None) -> dict:
    """:mod:`tests.probes.import_probe` in a fresh interpreter started in the repository (its
    code is the one imported)."""
    cmd = [sys.executable, "-m", "tests.probes.import_probe", *modules]
    if call is not None:
        cmd += ["--call", call]
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_importing_opens_no_toml_file():
    opened = probe(LAZY, call="fmu_src.contract:bearing_variables")
    assert opened["on_import"] == [], f"opened while importing {LAZY}: {opened['on_import']}"
    # the control: the hook does see the shipped case read once its values are needed
    assert [p for p in opened["on_call"] if p.endswith("baguet2010_spur.toml")], opened


@pytest.mark.parametrize("module", ["fmu_src.contract", "fmu_src.case", "fmu_src.description",
                                    "orchestrator"])
def test_importing_one_module_alone_opens_no_toml_file(module):
    """Each alone too: an import order that loads a file first cannot hide another's read."""
    assert probe([module])["on_import"] == []


def import_cycles(graph) -> list[tuple[list[str], list[str]]]:
    """The cycles of module imports in ``graph``: per strongly connected component of more than
    one module, ``(cycle, members)``: the shortest path from its first module (sorted) back to
    itself, and every module of the component (each on some cycle)."""
    modules = sorted(graph.modules)
    edges = {m: sorted(graph.find_modules_directly_imported_by(m)) for m in modules}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components = []
    for root in modules:  # Tarjan, iterative (no recursion limit on deep chains)
        if root in index:
            continue
        work = [(root, 0)]
        while work:
            node, i = work.pop()
            if i == 0:
                index[node] = low[node] = len(index)
                stack.append(node)
                on_stack.add(node)
            for j in range(i, len(edges[node])):
                nxt = edges[node][j]
                if nxt not in index:
                    work += [(node, j + 1), (nxt, 0)]
                    break
                if nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
            else:
                if low[node] == index[node]:
                    component = set()
                    while True:
                        top = stack.pop()
                        on_stack.discard(top)
                        component.add(top)
                        if top == node:
                            break
                    if len(component) > 1:
                        components.append(component)
                if work:
                    parent = work[-1][0]
                    low[parent] = min(low[parent], low[node])
    cycles = []
    for component in components:
        start = min(component)
        came_from = {start: None}
        frontier = [start]
        end = None
        while frontier and end is None:  # breadth first inside the component
            following = []
            for node in frontier:
                for nxt in edges[node]:
                    if nxt == start:
                        end = node
                        break
                    if nxt in component and nxt not in came_from:
                        came_from[nxt] = node
                        following.append(nxt)
                if end is not None:
                    break
            frontier = following
        path = []  # end, its predecessor, ..., start
        while end is not None:
            path.append(end)
            end = came_from[end]
        cycles.append(([*path[::-1], start], sorted(component)))
    return sorted(cycles)


def describe(graph, cycle: list[str]) -> str:
    """``a -> b (l. 12, 40) -> a (l. 7)``: a cycle with the line numbers of its imports."""
    text = cycle[0]
    for importer, imported in itertools.pairwise(cycle):
        lines = sorted(d["line_number"] for d in graph.get_import_details(
            importer=importer, imported=imported))
        text += f" -> {imported} (l. {', '.join(map(str, lines))})"
    return text


def test_no_import_cycle_between_modules():
    graph = grimp.build_graph(*PACKAGES, include_external_packages=False, cache_dir=None)
    assert len(graph.modules) > 80  # the four packages, their subpackages included
    cycles = import_cycles(graph)
    assert not cycles, "import cycles:\n" + "\n".join(
        f"{describe(graph, cycle)}\n  (modules on cycles with it: {', '.join(members)})"
        for cycle, members in cycles)


def test_the_cycle_check_sees_a_deferred_back_import():
    """The check itself, on a graph with what the packages must not have: a function-level
    import back (p.c -> p.a) closing a -> b -> c -> a, and b -> e -> b, beside an acyclic
    d -> a."""
    graph = grimp.ImportGraph()
    for name in ("p", "p.a", "p.b", "p.c", "p.d", "p.e"):
        graph.add_module(name)
    for importer, imported, line in (("p.a", "p.b", 3), ("p.b", "p.c", 4), ("p.c", "p.a", 40),
                                     ("p.b", "p.e", 5), ("p.e", "p.b", 9), ("p.d", "p.a", 1)):
        graph.add_import(importer=importer, imported=imported, line_number=line,
                         line_contents=f"import {imported}")
    cycles = import_cycles(graph)
    assert cycles == [(["p.a", "p.b", "p.c", "p.a"], ["p.a", "p.b", "p.c", "p.e"])]
    assert describe(graph, cycles[0][0]) == "p.a -> p.b (l. 3) -> p.c (l. 4) -> p.a (l. 40)"
