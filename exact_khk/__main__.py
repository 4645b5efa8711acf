"""``python -m exact_khk`` and the ``exact-khk`` console script: the command line
(:mod:`exact_khk.cli.main`).

The command line is imported inside :func:`run`, so that an interrupt while it
is still being imported ends like one during a run: one line and exit status
130, no traceback.
"""

import sys


def run():
    try:
        from exact_khk.cli.main import entry_point
    except KeyboardInterrupt:
        print("exact-khk: interrupted: stopped by the user (Ctrl-C)", file=sys.stderr)
        sys.exit(130)
    entry_point()


if __name__ == "__main__":
    run()
