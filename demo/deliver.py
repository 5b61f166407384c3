"""The delivery demo's program: `situate demo` runs it, with the arguments it passes.

The program is the package beside this file, `courier` (its layout in courier/__init__.py):
this file only runs it (`courier.main.run`), so that `situate demo`, the physics robot's
delivery and anyone's own commands run the same file as ever. ``--mode`` picks the design:
``sequenced`` (the default) and ``all-active`` the sequencer, ``reactive`` the rule list.
"""

from __future__ import annotations

import os
import sys

from courier.main import run

if __name__ == "__main__":
    status = run()
    # The link is closed and the output written: leave without the interpreter's teardown
    # (collecting every object, stopping Zenoh's threads: some 30 ms of a headless run).
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)
