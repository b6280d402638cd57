# SPDX-License-Identifier: Apache-2.0
"""python3 -m kmx: the kmx command (kmx/cli.py)."""
import _signal  # signal without its enum import: the handler is in place sooner
import os
import sys

# Ctrl-C while Python imports kmx.cli: one line and status 130 (main() then
# puts its own handler in place).
_signal.signal(_signal.SIGINT, lambda signum, frame: (os.write(2, b"kmx: interrupted\n"), os._exit(130)))

from .cli import main  # noqa: E402

sys.exit(main())
