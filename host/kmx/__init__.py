# SPDX-License-Identifier: Apache-2.0
"""kmx: host package for KINGMAX serial bus servos (docs/protocol.md, protocol
v5.2.0; the tutorial: docs/python-api.md). Modules: frame (codec), transport
(every port through pyserial), bus (master), registers (names, units,
ranges, group reads and writes by name), servo (one servo), products (what
a servo would refuse), update (firmware update), errors (KmxError hierarchy)."""

from .bus import Bus  # noqa: F401
from .errors import KmxError  # noqa: F401
from .registers import Registers  # noqa: F401
from .servo import Servo, open_bus  # noqa: F401

__version__ = "0.1.0"
