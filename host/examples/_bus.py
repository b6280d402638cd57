# SPDX-License-Identifier: Apache-2.0
"""What every example shares: the bus spec from --bus, else $KMX_BUS, else
the emulated bus of sim/bus/servo-bus. kmx itself comes from an install
(pip install ./host) or from PYTHONPATH=host (docs/python-api.md §0)."""
import os
import sys


def bus_spec():
    """--bus SPEC from the command line, else $KMX_BUS, else tcp:127.0.0.1:7000."""
    if "--bus" in sys.argv[1:-1]:
        return sys.argv[sys.argv.index("--bus") + 1]
    return os.environ.get("KMX_BUS", "tcp:127.0.0.1:7000")
