"""The experiment's reactive robot as a program of its own: demo/deliver.py ``--mode reactive``.

`situate demo --mode reactive` runs demo/deliver.py with that mode; this runs the same with
the same arguments, for trying the rule list (`courier.reactive.rules`) by hand.
"""

from __future__ import annotations

import os
import sys

from courier.main import run

if __name__ == "__main__":
    status = run(["--mode", "reactive", *sys.argv[1:]])
    # As demo/deliver.py: without the interpreter's teardown.
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)
