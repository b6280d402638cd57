# SPDX-License-Identifier: Apache-2.0
"""kmx: host package for KINGMAX serial bus servos (docs/protocol.md, protocol
v5.2.0). Modules: frame (codec), transport (TCP, serial, pty), bus (master),
registers (names, units, ranges), errors (KmxError hierarchy)."""

from .errors import KmxError  # noqa: F401

__version__ = "0.1.0"
