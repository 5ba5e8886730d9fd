"""Loads a URDF in PyBullet (DIRECT) and prints {"joints": n, "links": n}; exit 1 on failure.

Run in a subprocess: PyBullet segfaults on some malformed files (../shared/VALIDATORS.md).
"""
import json
import sys

import pybullet as p

client = p.connect(p.DIRECT)
try:
    body = p.loadURDF(sys.argv[1], useFixedBase=True)
except Exception as e:  # noqa: BLE001
    print(f"PyBullet could not load {sys.argv[1]}: {e}", file=sys.stderr)
    sys.exit(1)
n = p.getNumJoints(body)
# PyBullet's own warnings end without a newline: start the JSON on a line of its own.
print("\n" + json.dumps({"joints": n, "links": n + 1}))
