"""``python -m orchestrator.cli``: the ``gsb`` command without its script on PATH."""

import sys

from orchestrator.cli import main

sys.exit(main())
