"""The experiment's reactive robot as a program of its own: demo/deliver.py ``--mode reactive``.

`situate demo --mode reactive` runs demo/deliver.py with that mode; this runs the same with
the same arguments, whatever ``--mode`` they name (`situate demo --sequencer
demo/reactive.py` runs the rule list, `courier.reactive.rules`, too).
"""

from __future__ import annotations

import os
import sys

from courier.main import run

if __name__ == "__main__":
    status = run([*sys.argv[1:], "--mode", "reactive"])  # the last --mode counts
    # As demo/deliver.py: without the interpreter's teardown.
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)
