"""``gsb`` whose coupled steps each last at least a given time (:func:`tests.helpers.paced_gsb`).

``python tests/probes/standalone/paced_gsb.py <pace [s]> <gsb arguments>``, run by its path
(the environment of a user's ``gsb``: the package as installed): a sleep of ``pace`` before
every coupled step of the master (the compiled loop takes one step per call),
everything else as in ``gsb``; exits with ``gsb``'s code.
"""

from __future__ import annotations

import sys
import time


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    pace = float(argv[0])
    from orchestrator.coupling import master

    step, steps = master.Master.step, master.Master.steps

    def paced(self, t, dt):
        time.sleep(pace)
        return step(self, t, dt)

    def paced_block(self, first, dt, n):  # blocks of one step, each paced
        time.sleep(pace)
        return steps(self, first, dt, 1)

    master.Master.step = paced
    master.Master.steps = paced_block
    from orchestrator.cli import main as gsb

    return gsb(argv[1:])


if __name__ == "__main__":
    sys.exit(main())
