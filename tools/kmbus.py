# SPDX-License-Identifier: Apache-2.0
"""KINGMAX serial servo frames (docs/protocol.md §2, §3) under their old name:
the codec now lives in the host package, host/kmx/frame.py; this module
re-exports it so the tools and tests that import kmbus (tools/servo-bus,
tools/servo-session, tests/bus/bus_check.py, the test doubles) keep working
unchanged. New code imports kmx.frame."""
import os
import sys

_HOST = os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "host")
if _HOST not in sys.path:
    sys.path.insert(0, _HOST)

from kmx.frame import *  # noqa: E402,F401,F403
from kmx.frame import _frame  # noqa: E402,F401  (kept for any caller of the old private helper)
