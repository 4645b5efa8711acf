"""``python -m exact_khk``: the command line (:mod:`exact_khk.cli.main`).

An interrupt while the command line is still being imported ends like one
during a run: one line and exit status 130, no traceback.
"""

import sys

try:
    from exact_khk.cli.main import entry_point
except KeyboardInterrupt:
    print("exact-khk: interrupted: stopped by the user (Ctrl-C)", file=sys.stderr)
    sys.exit(130)

entry_point()
